//! Integer hashing: the source of every random number a render draws
//! (counter-based, so any number can be computed alone; see the module
//! docs of [`super`]).

use wide::{f32x8, u32x8};

/// A 32-bit integer hash with low bias: Chris Wellons' "lowbias32" from his
/// hash-prospector search (2018).
#[inline]
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// The state [`hash_words`] starts from.
pub const HASH_WORDS_INIT: u32 = 0x9e37_79b9;

/// One step of [`hash_words`]: the state after word `w`, from state `h`.
/// A caller hashing many sequences with a common prefix can keep the state
/// after the prefix and continue from it, with the same result.
#[inline]
pub fn hash_step(h: u32, w: u32) -> u32 {
    hash_u32(h ^ hash_u32(w.wrapping_add(0x632b_e5ab)))
}

/// Hash a sequence of words into one (a chained, order-sensitive combine).
#[inline]
pub fn hash_words(words: &[u32]) -> u32 {
    words.iter().fold(HASH_WORDS_INIT, |h, &w| hash_step(h, w))
}

/// Map 32 random bits to a float in [0, 1).
#[inline]
pub fn unit_float(bits: u32) -> f32 {
    // The top 24 bits fill the mantissa exactly; the result is < 1.
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// [`hash_u32`] in each of eight lanes.
#[inline(always)]
pub fn hash_u32_lanes(mut x: u32x8) -> u32x8 {
    x ^= x >> 16;
    x *= u32x8::splat(0x7feb_352d);
    x ^= x >> 15;
    x *= u32x8::splat(0x846c_a68b);
    x ^ (x >> 16)
}

/// [`hash_step`] in each of eight lanes.
#[inline(always)]
pub fn hash_step_lanes(h: u32x8, w: u32x8) -> u32x8 {
    hash_u32_lanes(h ^ hash_u32_lanes(w + u32x8::splat(0x632b_e5ab)))
}

/// [`unit_float`] in each of eight lanes: the same floats, since the top
/// 24 bits convert exactly.
#[inline(always)]
pub fn unit_float_lanes(bits: u32x8) -> f32x8 {
    let top: u32x8 = bits >> 8;
    top.cast_signed().round_float() * f32x8::splat(1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_hash_and_convert_as_the_scalar_functions() {
        let mut x = 1u32;
        for _ in 0..10_000 {
            let v: [u32; 8] = std::array::from_fn(|i| {
                x = hash_u32(x.wrapping_add(i as u32));
                if i == 7 {
                    u32::MAX - (x & 3)
                } else {
                    x
                }
            });
            let w = v.map(|v| v.rotate_left(7));
            let (h, s, f) = (
                hash_u32_lanes(u32x8::new(v)).to_array(),
                hash_step_lanes(u32x8::new(v), u32x8::new(w)).to_array(),
                unit_float_lanes(u32x8::new(v)).to_array(),
            );
            for i in 0..8 {
                assert_eq!(h[i], hash_u32(v[i]));
                assert_eq!(s[i], hash_step(v[i], w[i]));
                assert_eq!(f[i].to_bits(), unit_float(v[i]).to_bits());
            }
        }
    }
}
