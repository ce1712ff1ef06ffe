//! Eight samples of one correlated multi-jittered set at once: the
//! arithmetic of [`super::cmj`] (Kensler 2013) in `wide::u32x8` lanes, for
//! the samples of one batch of camera samples (one pixel's pixel or light
//! samples), each lane under its own pattern where the batch holds the
//! samples of several pixels (the sets' sizes, and so their grids, are the
//! same; the patterns that scramble them are each pixel's own).
//!
//! A CMJ sample is three hashed permutations and two hashed floats: chains
//! of dependent 32-bit multiplications, about a hundred cycles each, where
//! eight lanes run eight chains in the time of one. What the scalar code
//! does per sample with 64-bit multiplications (the remainder that ends a
//! permutation, the column and row of a cell) is done here with 32-bit
//! lanes, exactly:
//!
//! - `(i + p) mod len` (wrapping add) from `p mod len` and `2³² mod len`,
//!   made once per set and pattern, and at most two subtractions;
//! - `s / m` for a cell `s` as `⌊(s + ½) / m⌋` in `f32`, which is exact
//!   while the set has fewer than 2²² cells (the quotient's rounding error
//!   stays below the distance ½/m to the nearest integer).
//!
//! The floats are computed in the scalar code's order with IEEE operations
//! and exact integer-to-float conversions, so every lane is bit for bit
//! [`super::cmj::cmj_2d`]; the tests check that.

use super::cmj::{
    sample_patterns, CmjSet, FastDiv, JITTER_PATTERN, ONE_MINUS_EPSILON, STRATA_PATTERN,
};
use super::hash::unit_float_lanes;
use crate::math::lanes::LANES;
use glam::Vec2;
use wide::{f32x8, u32x8};

/// Sets with this many cells or more are drawn one sample at a time (the
/// `f32` quotient is exact below it, see the module docs).
const MAX_CELLS: u32 = 1 << 22;

/// One of a sample's permutations of `0..len`, each lane under its own
/// pattern (the same one in every lane for one pixel's samples).
#[derive(Debug, Clone, Copy)]
struct PermuteLanes {
    len: u32,
    /// The cycle-walking mask (all ones up to the top bit of `len - 1`).
    w: u32,
    p: u32x8,
    /// `p mod len` (unused, and zero, where `len` is a power of two).
    p_mod: u32x8,
    /// `len - (2³² mod len)`: what a wrapped `i + p` adds, modulo `len`.
    wrap_add: u32,
}

/// What a permutation of `0..len` shares under every pattern: the
/// length as a prepared divisor (its cycle-walking mask, and the
/// remainder of a pattern by multiplications) and `len − 2³² mod len`.
#[derive(Debug, Clone, Copy)]
struct LenLanes {
    len: FastDiv,
    wrap_add: u32,
}

impl LenLanes {
    /// `two32_mod` is 2³² mod the length.
    fn new(len: FastDiv, two32_mod: u32) -> Self {
        Self {
            len,
            wrap_add: len.divisor() - two32_mod,
        }
    }

    /// The permutation under pattern `p` in every lane.
    #[inline(always)]
    fn with_pattern(&self, p: u32) -> PermuteLanes {
        PermuteLanes {
            len: self.len.divisor(),
            w: self.len.walk_mask(),
            p: u32x8::splat(p),
            p_mod: u32x8::splat(self.len.remainder(p)),
            wrap_add: self.wrap_add,
        }
    }

    /// The permutation under pattern `p[i]` in lane `i`.
    #[inline(always)]
    fn with_patterns(&self, p: u32x8) -> PermuteLanes {
        let len = self.len.divisor();
        let w = self.len.walk_mask();
        // A power of two's permutation never reads the remainders.
        let p_mod = if w.wrapping_add(1) == len {
            u32x8::ZERO
        } else {
            u32x8::new(p.to_array().map(|p| self.len.remainder(p)))
        };
        PermuteLanes {
            len,
            w,
            p,
            p_mod,
            wrap_add: self.wrap_add,
        }
    }
}

impl PermuteLanes {
    /// `permute(i, len, p)` of [`super::cmj`] in each lane (every `i < len`).
    #[inline(always)]
    fn apply(&self, i: u32x8) -> u32x8 {
        if self.len == 1 {
            return u32x8::ZERO;
        }
        let (p, w) = (self.p, u32x8::splat(self.w));
        let splat = u32x8::splat;
        if self.w.wrapping_add(1) == self.len {
            // A power of two (a pixel's usual sample counts and their
            // grids): the hash, masked to the length's bits, lands in
            // 0..len at once (`x ^ x >> 5` keeps within the mask), so no
            // lane walks a second step; and 2³² is a multiple of the
            // length, so the wrapping (i + p) mod len is its low bits.
            return (self.hash(i) + p) & w;
        }
        let len = u32x8::splat(self.len);
        let mut i = i;
        // Cycle walking: each lane steps until it lands in 0..len; lanes
        // that have landed keep their value while the others walk on.
        let mut walking = u32x8::splat(u32::MAX);
        loop {
            let x = self.hash(i);
            i = walking.select(x, i);
            walking &= !x.simd_lt(len);
            if !walking.any() {
                break;
            }
        }
        // (i + p) mod len with the scalar code's wrapping add: i + p mod len,
        // plus len − 2³² mod len where the add wrapped; below 3·len.
        let wrapped = (i + p).simd_lt(p);
        let mut r = i + self.p_mod + (wrapped & splat(self.wrap_add));
        for _ in 0..2 {
            r = r - (r.simd_ge(len) & len);
        }
        r
    }

    /// One step of the permutation's hash in each lane, masked to the
    /// length's bits (Kensler 2013, listing 3).
    #[inline(always)]
    fn hash(&self, i: u32x8) -> u32x8 {
        let (p, w) = (self.p, u32x8::splat(self.w));
        let splat = u32x8::splat;
        let mut x = i ^ p;
        x *= splat(0xe170_893d);
        x ^= p >> 16;
        x ^= (x & w) >> 4;
        x ^= p >> 8;
        x *= splat(0x0929_eb3f);
        x ^= p >> 23;
        x ^= (x & w) >> 1;
        x *= splat(1) | p >> 27;
        x *= splat(0x6935_fa69);
        x ^= (x & w) >> 11;
        x *= splat(0x74dc_b303);
        x ^= (x & w) >> 2;
        x *= splat(0x9e50_1cc3);
        x ^= (x & w) >> 2;
        x *= splat(0xc860_a3df);
        x &= w;
        x ^ (x >> 5)
    }
}

/// `rand_float(i, p)` of [`super::cmj`] in each lane, lane `k` under
/// pattern `p[k]`.
#[inline(always)]
fn rand_float(i: u32x8, p: u32x8) -> f32x8 {
    let splat = u32x8::splat;
    let mut i = i ^ p;
    i ^= i >> 17;
    i ^= i >> 10;
    i *= splat(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i *= splat(0x93fc_4795);
    i ^= splat(0xdf6e_307f);
    i ^= i >> 17;
    i *= splat(1) | p >> 18;
    unit_float_lanes(i)
}

/// Lanes below 2²⁴ as exact floats.
#[inline(always)]
fn to_f32(v: u32x8) -> f32x8 {
    v.cast_signed().round_float()
}

/// What the draws of one prepared CMJ set under one pattern share, for
/// drawing eight samples at a time.
#[derive(Debug, Clone, Copy)]
pub struct CmjLanes {
    n: u32,
    cells: PermuteLanes,
    columns: PermuteLanes,
    rows: PermuteLanes,
    jitter_x: u32x8,
    jitter_y: u32x8,
}

/// What the draws of one CMJ set share under every pattern (every
/// dimension of a pixel): its grid's permutation lengths with their
/// masks and remainders prepared, so that a dimension's [`CmjLanes`]
/// (from [`CmjGrid::lanes`]) does only what its pattern changes.
#[derive(Debug, Clone, Copy)]
pub struct CmjGrid {
    n: u32,
    cells: LenLanes,
    columns: LenLanes,
    rows: LenLanes,
}

impl CmjGrid {
    /// The grid of `set`, or `None` for an empty set or one of
    /// [`MAX_CELLS`] cells or more.
    pub fn new(set: &CmjSet) -> Option<Self> {
        let (_, _, cells) = set.grid();
        if set.n == 0 || cells >= MAX_CELLS {
            return None;
        }
        let [m, rows, cells] = set.divisors();
        let [m_wrap, rows_wrap, cells_wrap] = set.two32_mods();
        Some(Self {
            n: set.n,
            cells: LenLanes::new(cells, cells_wrap),
            columns: LenLanes::new(m, m_wrap),
            rows: LenLanes::new(rows, rows_wrap),
        })
    }

    /// The set's draws under `pattern`: exactly [`CmjLanes::new`]'s.
    #[inline]
    pub fn lanes(&self, pattern: u32) -> CmjLanes {
        let [p_cells, p_columns, p_rows, jitter_x, jitter_y] = sample_patterns(pattern);
        CmjLanes {
            n: self.n,
            cells: self.cells.with_pattern(p_cells),
            columns: self.columns.with_pattern(p_columns),
            rows: self.rows.with_pattern(p_rows),
            jitter_x: u32x8::splat(jitter_x),
            jitter_y: u32x8::splat(jitter_y),
        }
    }

    /// The set's draws with lane `i` under `patterns[i]` (several pixels'
    /// sets of one size): lane by lane exactly [`CmjGrid::lanes`] of its
    /// own pattern.
    #[inline]
    pub fn lanes_each(&self, patterns: u32x8) -> CmjLanes {
        // sample_patterns multiplies a pattern by constants: those of 1.
        let [p_cells, p_columns, p_rows, jitter_x, jitter_y] =
            sample_patterns(1).map(|k| patterns * u32x8::splat(k));
        CmjLanes {
            n: self.n,
            cells: self.cells.with_patterns(p_cells),
            columns: self.columns.with_patterns(p_columns),
            rows: self.rows.with_patterns(p_rows),
            jitter_x,
            jitter_y,
        }
    }
}

impl CmjLanes {
    /// The lanes of `set` under `pattern`, or `None` for an empty set or
    /// one of [`MAX_CELLS`] cells or more.
    pub fn new(set: &CmjSet, pattern: u32) -> Option<Self> {
        CmjGrid::new(set).map(|grid| grid.lanes(pattern))
    }

    /// Samples `s[i]` of the set (each below its size), lane by lane
    /// exactly [`CmjSet::sample`].
    pub fn sample(&self, s: [u32; LANES]) -> [Vec2; LANES] {
        debug_assert!(s.iter().all(|&s| s < self.n));
        let s = self.cells.apply(u32x8::new(s));
        let (m, rows) = (self.columns.len as f32, self.rows.len as f32);
        let (mf, rows_f) = (f32x8::splat(m), f32x8::splat(rows));
        let row = ((to_f32(s) + f32x8::splat(0.5)) / mf)
            .trunc_int()
            .cast_unsigned();
        let col = s - row * u32x8::splat(self.columns.len);
        let sx = self.columns.apply(col);
        let sy = self.rows.apply(row);
        let jx = rand_float(s, self.jitter_x);
        let jy = rand_float(s, self.jitter_y);
        let x = (to_f32(sx) + (to_f32(sy) + jx) / rows_f) / mf;
        let y = (to_f32(row) + (to_f32(col) + jy) / mf) / rows_f;
        let limit = f32x8::splat(ONE_MINUS_EPSILON);
        let (x, y) = (x.fast_min(limit).to_array(), y.fast_min(limit).to_array());
        std::array::from_fn(|i| Vec2::new(x[i], y[i]))
    }
}

/// What the draws of one stratified 1D set of `n` samples under one
/// pattern share, for drawing eight samples at a time: lane by lane
/// exactly [`super::cmj::stratified_1d`] (a permutation of the strata and
/// a hashed jitter, in the scalar code's order).
#[derive(Debug, Clone, Copy)]
pub struct StratifiedLanes {
    n: u32,
    strata: PermuteLanes,
    jitter: u32x8,
}

/// What the draws of one stratified 1D set of `n` samples share under
/// every pattern, as [`CmjGrid`] for 2D sets.
#[derive(Debug, Clone, Copy)]
pub struct StrataGrid {
    n: u32,
    strata: LenLanes,
}

impl StrataGrid {
    /// The `n`-sample set, or `None` for an empty set or one of
    /// [`MAX_CELLS`] samples or more (whose strata are not all exact
    /// floats).
    pub fn new(n: u32) -> Option<Self> {
        if n == 0 || n >= MAX_CELLS {
            return None;
        }
        let two32_mod = ((1u64 << 32) % n as u64) as u32;
        Some(Self {
            n,
            strata: LenLanes::new(FastDiv::new(n), two32_mod),
        })
    }

    /// The set's draws under `pattern`: exactly [`StratifiedLanes::new`]'s.
    #[inline]
    pub fn lanes(&self, pattern: u32) -> StratifiedLanes {
        StratifiedLanes {
            n: self.n,
            strata: self
                .strata
                .with_pattern(pattern.wrapping_mul(STRATA_PATTERN)),
            jitter: u32x8::splat(pattern.wrapping_mul(JITTER_PATTERN)),
        }
    }

    /// The set's draws with lane `i` under `patterns[i]`, as
    /// [`CmjGrid::lanes_each`] for 2D sets.
    #[inline]
    pub fn lanes_each(&self, patterns: u32x8) -> StratifiedLanes {
        StratifiedLanes {
            n: self.n,
            strata: self
                .strata
                .with_patterns(patterns * u32x8::splat(STRATA_PATTERN)),
            jitter: patterns * u32x8::splat(JITTER_PATTERN),
        }
    }
}

impl StratifiedLanes {
    /// The lanes of the `n`-sample set under `pattern`, or `None` for an
    /// empty set or one of [`MAX_CELLS`] samples or more (whose strata
    /// are not all exact floats).
    pub fn new(n: u32, pattern: u32) -> Option<Self> {
        StrataGrid::new(n).map(|grid| grid.lanes(pattern))
    }

    /// Samples `s[i]` of the set (each below its size).
    pub fn sample(&self, s: [u32; LANES]) -> [f32; LANES] {
        debug_assert!(s.iter().all(|&s| s < self.n));
        let s = u32x8::new(s);
        let stratum = self.strata.apply(s);
        let j = rand_float(s, self.jitter);
        let x = (to_f32(stratum) + j) / f32x8::splat(self.n as f32);
        x.fast_min(f32x8::splat(ONE_MINUS_EPSILON)).to_array()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::cmj::cmj_2d;
    use crate::sampling::hash::hash_u32;

    fn assert_lanes_match(n: u32, pattern: u32, s: [u32; LANES]) {
        let set = CmjSet::new(n);
        let got = CmjLanes::new(&set, pattern).expect("fits").sample(s);
        for (lane, &s) in s.iter().enumerate() {
            let want = cmj_2d(s, n, pattern);
            assert_eq!(
                got[lane].to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "n {n} pattern {pattern:#x} sample {s}"
            );
        }
    }

    /// The inverse of odd `k` modulo 2³² (Newton's iteration).
    fn inverse(k: u32) -> u32 {
        let mut x = k;
        for _ in 0..5 {
            x = x.wrapping_mul(2u32.wrapping_sub(k.wrapping_mul(x)));
        }
        x
    }

    /// Every sample of many set sizes (squares, partial grids, primes,
    /// sizes whose cycle walking takes several steps) under hashed
    /// patterns, and under patterns that make one permutation's pattern
    /// just below 2³², so that its final `i + p` wraps.
    #[test]
    fn stratified_lanes_are_the_scalar_samples_bit_for_bit() {
        use crate::sampling::cmj::stratified_1d;
        for n in [1u32, 2, 3, 7, 16, 17, 48, 100, 1000, 65_537, (1 << 22) - 1] {
            for pattern in [0u32, 1, 0xdead_beef, u32::MAX, hash_u32(n)] {
                let lanes = StratifiedLanes::new(n, pattern).expect("fits");
                let s: [u32; LANES] = std::array::from_fn(|k| hash_u32(k as u32 ^ pattern) % n);
                let got = lanes.sample(s);
                for (lane, &s) in s.iter().enumerate() {
                    assert_eq!(
                        got[lane].to_bits(),
                        stratified_1d(s, n, pattern).to_bits(),
                        "n {n} pattern {pattern:#x} sample {s}"
                    );
                }
            }
        }
        assert!(StratifiedLanes::new(0, 1).is_none());
        assert!(StratifiedLanes::new(MAX_CELLS, 1).is_none());
    }

    #[test]
    fn lanes_are_the_scalar_samples_bit_for_bit() {
        let multipliers = sample_patterns(1);
        assert!(multipliers.iter().all(|&k| inverse(k).wrapping_mul(k) == 1));
        let wrapping = multipliers[..3]
            .iter()
            .flat_map(|&k| [1u32, 3, 40, 1000].map(|j| inverse(k).wrapping_mul(j.wrapping_neg())));
        let patterns: Vec<u32> = [0, u32::MAX, 0x8000_0000]
            .into_iter()
            .chain(wrapping)
            .chain((0..8).map(|k| hash_u32(k * 7919)))
            .collect();
        let sizes = (1u32..=70).chain([100, 127, 128, 129, 255, 1000, 1024, 4097, 65_537]);
        for n in sizes {
            for &pattern in &patterns {
                let mut s = 0;
                while s < n {
                    let lanes = std::array::from_fn(|i| (s + i as u32 * n.div_ceil(8)) % n);
                    assert_lanes_match(n, pattern, lanes);
                    s += (n / 64).max(1);
                }
            }
        }
    }

    /// Lanes under patterns of their own (several pixels' sets of one
    /// size) are each the scalar sample of its own pattern, 2D and 1D:
    /// powers of two and sizes whose permutations walk and wrap, patterns
    /// hashed and extreme side by side.
    #[test]
    fn lanes_under_their_own_patterns_are_each_its_scalar_sample() {
        use crate::sampling::cmj::stratified_1d;
        for n in [1u32, 2, 3, 4, 7, 16, 17, 35, 64, 100, 1000, 65_537] {
            let set = CmjSet::new(n);
            let (grid, strata) = (
                CmjGrid::new(&set).expect("fits"),
                StrataGrid::new(n).expect("fits"),
            );
            for round in 0..20u32 {
                let patterns: [u32; LANES] =
                    std::array::from_fn(|k| match (k + round as usize) % 4 {
                        0 => u32::MAX - k as u32,
                        _ => hash_u32(round * 31 + k as u32 * 7 + n),
                    });
                let s: [u32; LANES] = std::array::from_fn(|k| hash_u32(k as u32 ^ round) % n);
                let got = grid.lanes_each(u32x8::new(patterns)).sample(s);
                let got_1d = strata.lanes_each(u32x8::new(patterns)).sample(s);
                for lane in 0..LANES {
                    let (s, p) = (s[lane], patterns[lane]);
                    assert_eq!(
                        got[lane].to_array().map(f32::to_bits),
                        cmj_2d(s, n, p).to_array().map(f32::to_bits),
                        "n {n} pattern {p:#x} sample {s}"
                    );
                    assert_eq!(got_1d[lane].to_bits(), stratified_1d(s, n, p).to_bits());
                }
            }
        }
    }

    /// The largest sets drawn in lanes, where the f32 quotient's margin is
    /// thinnest: the last cells of every row.
    #[test]
    fn the_largest_sets_still_find_every_row_exactly() {
        for n in [MAX_CELLS - 5000, 4_000_000, 3_999_999] {
            for pattern in [1u32, 0xdead_beef, 0x1234_5678] {
                let lanes = std::array::from_fn(|i| n - 1 - i as u32 * 977);
                assert_lanes_match(n, pattern, lanes);
            }
        }
        assert!(CmjLanes::new(&CmjSet::new(MAX_CELLS), 1).is_none());
        assert!(CmjLanes::new(&CmjSet::EMPTY, 1).is_none());
    }

    /// The cell quotient itself, over the first and last cells of grids of
    /// nearly [`MAX_CELLS`] cells, where its rounding error is largest.
    #[test]
    fn float_quotients_of_cells_are_exact() {
        for m in [1u32, 2, 3, 7, 64, 1023, 2047, 2048] {
            let cells = (MAX_CELLS - 1) / m * m;
            let mf = f32x8::splat(m as f32);
            let ends = (0..100_000).chain(cells - 100_000..cells);
            for s in ends.step_by(8) {
                let lanes = u32x8::new(std::array::from_fn(|i| (s + i as u32).min(cells - 1)));
                let q = ((to_f32(lanes) + f32x8::splat(0.5)) / mf)
                    .trunc_int()
                    .cast_unsigned()
                    .to_array();
                for (i, q) in q.iter().enumerate() {
                    let v = (s + i as u32).min(cells - 1);
                    assert_eq!(*q, v / m, "{v} / {m}");
                }
            }
        }
    }
}
