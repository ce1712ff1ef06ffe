//! Integer hashing: the source of every random number a render draws
//! (counter-based, so any number can be computed alone; see the module
//! docs of [`super`]).

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
