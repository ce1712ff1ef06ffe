//! A progressive stratified sequence: the first two dimensions of Sobol's
//! sequence, Owen-scrambled, with the index shuffled per dimension.
//!
//! The correlated multi-jittered sets ([`super::cmj`]) are stratified as a
//! whole set of `count` points, so the first 16 of a 64-point set are not a
//! stratified 16-point set. Where a pixel may stop after any pass (a noise
//! target, a time budget) its samples must be good at every prefix: here
//! every prefix of 2^k points is a (0, k, 2)-net (one point in each of the
//! 2^k elementary intervals of every shape), and a prefix of 24 points is a
//! 16-point net and half of the next. Point `i` is a pure function of
//! (pattern, i), like every number a render draws.
//!
//! - Sobol (1967)'s second dimension, from the direction numbers of the
//!   primitive polynomial x + 1 (its generator matrix is Pascal's triangle
//!   mod 2); the first is the van der Corput sequence.
//! - Owen (1995)'s nested uniform scrambling, computed as Burley (2020),
//!   "Practical Hash-based Owen Scrambling" (JCGT 9(4)), does it: a
//!   Laine-Karras style hash on the bit-reversed value, in which each bit
//!   is flipped by a function of the bits above it. A scramble keeps the
//!   net property and makes the points of different patterns independent.
//! - Burley's padding: each dimension draws its own scrambling, and the
//!   same scrambling applied to the index shuffles the order of the points
//!   across dimensions while mapping every aligned block of 2^k indices
//!   onto an aligned block of 2^k points, which is itself a net.

use super::hash::hash_u32;
use glam::Vec2;

/// Point `index` of Sobol's second dimension, as 32 bits of a fraction
/// (the reference formula; [`sobol_second_reversed`] is what draws use).
#[cfg(test)]
fn sobol_second(mut index: u32) -> u32 {
    // Direction numbers of x + 1: v₁ = 1/2, and each next one is the last
    // xor itself shifted right by one.
    let mut v = 1u32 << 31;
    let mut bits = 0u32;
    while index != 0 {
        if index & 1 != 0 {
            bits ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    bits
}

/// The xor of the (bit-reversed) direction numbers each byte of an index
/// selects: the point is linear in the index's bits over GF(2), so four
/// lookups make it, where a loop over 32 bits would take 32 steps.
const SOBOL_BYTES: [[u32; 256]; 4] = sobol_bytes();

const fn sobol_bytes() -> [[u32; 256]; 4] {
    let mut directions = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut j = 0;
    while j < 32 {
        directions[j] = v.reverse_bits();
        v ^= v >> 1;
        j += 1;
    }
    let mut table = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            let mut bits = 0u32;
            let mut j = 0;
            while j < 8 {
                if b >> j & 1 != 0 {
                    bits ^= directions[8 * k + j];
                }
                j += 1;
            }
            table[k][b] = bits;
            b += 1;
        }
        k += 1;
    }
    table
}

/// Point `index` of Sobol's second dimension with its bits reversed (so
/// that the scramble, which works on reversed values, needs no reversal).
#[inline]
fn sobol_second_reversed(index: u32) -> u32 {
    let [a, b, c, d] = index.to_le_bytes();
    SOBOL_BYTES[0][a as usize]
        ^ SOBOL_BYTES[1][b as usize]
        ^ SOBOL_BYTES[2][c as usize]
        ^ SOBOL_BYTES[3][d as usize]
}

/// Burley (2020)'s Laine-Karras hash: bit `b` of the result depends on
/// bits `0..=b` of `x` alone (additions carry up, and multiplications by
/// even constants shift up), as a nested scramble of the reversed value
/// needs.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen's nested uniform scramble of the 32-bit fraction `x`: each bit is
/// flipped by a function of `seed` and the bits above it.
#[inline]
pub fn nested_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// Point `index` in [0,1)² of the sequence that `pattern` scrambles.
///
/// The nested scramble of a value v is reverse(LK(reverse(v))), so that of
/// the van der Corput point reverse(i) is reverse(LK(i)), and that of the
/// second dimension is reverse(LK(its reversed bits)): one reversal each.
#[inline]
pub fn sobol_2d(index: u32, pattern: u32) -> Vec2 {
    let seeds = [1, 2, 3].map(|k| hash_u32(pattern ^ (k * 0x9e37_79b9)));
    let i = nested_scramble(index, seeds[0]);
    let x = laine_karras(i, seeds[1]).reverse_bits();
    let y = laine_karras(sobol_second_reversed(i), seeds[2]).reverse_bits();
    Vec2::new(to_unit(x), to_unit(y))
}

/// Point `index` in [0,1) of the one-dimensional sequence (scrambled van
/// der Corput) that `pattern` scrambles.
#[inline]
pub fn sobol_1d(index: u32, pattern: u32) -> f32 {
    let seeds = [4, 5].map(|k| hash_u32(pattern ^ (k * 0x9e37_79b9)));
    let i = nested_scramble(index, seeds[0]);
    to_unit(laine_karras(i, seeds[1]).reverse_bits())
}

/// The top 24 bits as a float in [0, 1), exactly.
#[inline]
fn to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `points` (2^m of them) put one point in every elementary
    /// interval [a/2^p, (a+1)/2^p) × [b/2^q, (b+1)/2^q) with p + q = m.
    fn is_net(points: &[Vec2]) -> bool {
        let m = points.len().trailing_zeros();
        assert_eq!(points.len(), 1 << m);
        (0..=m).all(|p| {
            let q = m - p;
            let mut seen = vec![false; points.len()];
            points.iter().all(|v| {
                let a = (v.x * (1u64 << p) as f32) as usize;
                let b = (v.y * (1u64 << q) as f32) as usize;
                let cell = (a << q) | b;
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn every_power_of_two_prefix_and_aligned_block_is_a_net() {
        for pattern in [0u32, 1, 0xdead_beef, 12_345] {
            let points: Vec<Vec2> = (0..512).map(|i| sobol_2d(i, pattern)).collect();
            for k in 0..=8 {
                let n = 1usize << k;
                assert!(is_net(&points[..n]), "prefix {n}, pattern {pattern}");
                // A pixel's m light samples per camera sample are an
                // aligned block of the sequence: a net too.
                assert!(is_net(&points[n..2 * n]), "block {n}..{}", 2 * n);
            }
            // One dimension: each prefix of 2^k has one point per 1/2^k.
            let line: Vec<f32> = (0..64).map(|i| sobol_1d(i, pattern)).collect();
            for k in 0..=6 {
                let n = 1usize << k;
                let mut cells: Vec<usize> =
                    line[..n].iter().map(|x| (x * n as f32) as usize).collect();
                cells.sort_unstable();
                assert_eq!(cells, (0..n).collect::<Vec<_>>());
            }
        }
    }

    /// The fast forms (byte tables, reversals cancelled) are the reference
    /// formulas bit for bit.
    #[test]
    fn the_fast_forms_are_the_reference_formulas() {
        let mut x = 1u32;
        for _ in 0..100_000 {
            x = hash_u32(x);
            assert_eq!(sobol_second_reversed(x), sobol_second(x).reverse_bits());
            let pattern = x.rotate_left(11);
            let seeds = [1, 2, 3].map(|k| hash_u32(pattern ^ (k * 0x9e37_79b9)));
            let i = nested_scramble(x, seeds[0]);
            let reference = Vec2::new(
                to_unit(nested_scramble(i.reverse_bits(), seeds[1])),
                to_unit(nested_scramble(sobol_second(i), seeds[2])),
            );
            assert_eq!(sobol_2d(x, pattern), reference);
        }
    }

    /// The scramble flips each bit by the bits above it only, so it maps
    /// aligned blocks onto aligned blocks (the shuffle keeps prefixes nets).
    #[test]
    fn the_nested_scramble_keeps_aligned_blocks() {
        for seed in [0u32, 7, 0x8000_0001] {
            for k in [1u32, 3, 5] {
                let block = |x: u32| x >> (32 - k);
                let a: Vec<u32> = (0..64u32).map(|i| i << 20).collect();
                for pair in a.windows(2) {
                    let same = block(pair[0]) == block(pair[1]);
                    let scrambled = [0, 1].map(|j| block(nested_scramble(pair[j], seed)));
                    assert_eq!(same, scrambled[0] == scrambled[1]);
                }
                // As an index shuffle: 0..2^k onto one aligned block.
                let blocks: std::collections::BTreeSet<u32> = (0..1u32 << k)
                    .map(|i| nested_scramble(i, seed) >> k)
                    .collect();
                assert_eq!(blocks.len(), 1);
            }
        }
    }

    /// Different patterns give uncorrelated points: the mean product of
    /// centred coordinates of two dimensions is near 0, and each mean near 1/2.
    #[test]
    fn patterns_are_independent_and_uniform() {
        let n = 4096u32;
        let (mut sx, mut sy, mut cross) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..n {
            let a = sobol_2d(i, 11);
            let b = sobol_2d(i, 12);
            sx += f64::from(a.x);
            sy += f64::from(b.y);
            cross += (f64::from(a.x) - 0.5) * (f64::from(b.x) - 0.5);
        }
        let n = f64::from(n);
        assert!((sx / n - 0.5).abs() < 1e-3 && (sy / n - 0.5).abs() < 1e-3);
        // Independent uniforms: the mean product has standard deviation
        // (1/12)/√n ≈ 0.0013.
        assert!((cross / n).abs() < 0.006, "{}", cross / n);
    }
}
