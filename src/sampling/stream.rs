//! Sequential random streams for *inputs*: the ray sets of `strata rays`,
//! test fixtures and benchmark inputs. Each is a [`StreamRng`] (rand's
//! xoshiro256++, which rand documents as reproducible across platforms and
//! versions) seeded through `SeedableRng::seed_from_u64`, so one seed gives
//! the same numbers everywhere.
//!
//! Rendering never draws from a stream: a render's numbers must be
//! computable one sample at a time, in any order, on any thread or machine,
//! so they are counter-based hashes of (seed, pixel, sample, dimension)
//! instead (see [`super::sampler`]).

use glam::Vec3;
use rand::{Rng, RngExt, SeedableRng};

pub use rand::rngs::Xoshiro256PlusPlus as StreamRng;

/// The stream of `seed`.
pub fn seeded(seed: u64) -> StreamRng {
    StreamRng::seed_from_u64(seed)
}

/// The stream of item `index` of the set `set` under `seed`: one stream
/// per item, so item `i` does not depend on how many items are drawn or in
/// what order (SplitMix64 spreads the three words over the 64-bit seed;
/// distinct triples collide with probability about 2⁻⁶⁴).
pub fn item_stream(seed: u32, set: u32, index: u32) -> StreamRng {
    let mut key = u64::from(seed);
    for word in [set, index] {
        key = splitmix64(key ^ u64::from(word).rotate_left(29));
    }
    seeded(key)
}

/// SplitMix64's output function (Steele, Lea and Flood 2014): a bijection
/// of u64 that mixes every input bit into every output bit.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The draws fixtures and inputs need, on any rand generator.
pub trait Draw: Rng {
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        self.random::<f32>()
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// A point of the cube of side `scale` centred on the origin.
    fn cube(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.unit() - 0.5, self.unit() - 0.5, self.unit() - 0.5) * scale
    }

    /// A unit vector, uniform on the sphere (rejection from the cube).
    fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

impl<R: Rng + ?Sized> Draw for R {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_repeat_by_seed_and_differ_by_item() {
        let a: Vec<f32> = (0..4).map(|_| seeded(7).unit()).collect();
        assert!(
            a.windows(2).all(|w| w[0] == w[1]),
            "same seed, same numbers"
        );
        let first = |s: u32, set: u32, i: u32| item_stream(s, set, i).random::<u64>();
        let mut seen = std::collections::HashSet::new();
        for s in 0..8 {
            for set in 0..5 {
                for i in 0..200 {
                    assert!(seen.insert(first(s, set, i)), "({s}, {set}, {i})");
                }
            }
        }
    }

    #[test]
    fn draws_stay_in_their_ranges() {
        let mut rng = seeded(1);
        for _ in 0..10_000 {
            let u = rng.unit();
            assert!((0.0..1.0).contains(&u));
            let r = rng.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&r));
            assert!(rng.cube(2.0).abs().max_element() <= 1.0);
            assert!((rng.unit_vector().length() - 1.0).abs() < 1e-5);
        }
    }
}
