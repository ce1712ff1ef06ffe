//! Correlated multi-jittered sampling: Kensler 2013, "Correlated
//! Multi-Jittered Sampling" (Pixar Technical Memo 13-01).
//!
//! Sample `s` of an `N`-sample set is computed on its own, with no table and
//! no loop over earlier samples, for any `N` (not only squares). The set is
//! jittered in 2D and stratified in both 1D projections (Latin hypercube).
//! That is what sample slicing needs: a slice is a range of indices of the
//! one N-sample set.

use glam::Vec2;

/// A divisor of the sampling arithmetic: a plain `u32`, or a [`FastDiv`]
/// prepared once for a sample set. Both give the same quotients.
trait Divisor: Copy {
    fn get(self) -> u32;
    fn div(self, n: u32) -> u32;
    fn rem(self, n: u32) -> u32;
    /// All ones up to the highest set bit of `get() - 1` (the cycle-walking mask).
    fn mask(self) -> u32;
}

pub(super) fn mask_of(len: u32) -> u32 {
    let mut w = len.wrapping_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    w
}

impl Divisor for u32 {
    #[inline(always)]
    fn get(self) -> u32 {
        self
    }
    #[inline(always)]
    fn div(self, n: u32) -> u32 {
        n / self
    }
    #[inline(always)]
    fn rem(self, n: u32) -> u32 {
        n % self
    }
    #[inline(always)]
    fn mask(self) -> u32 {
        mask_of(self)
    }
}

/// Division and remainder by a fixed `d ≥ 1` with multiplications only,
/// exact for every 32-bit numerator: with M = ⌈2⁶⁴ / d⌉, n / d is the high
/// 64 bits of M·n, and n mod d the high 64 bits of (M·n mod 2⁶⁴)·d
/// (Lemire, Kaser and Kurz 2019, "Faster Remainder by Direct Computation:
/// Applications to Compilers and Software Libraries", SPE 49(6)).
#[derive(Debug, Clone, Copy)]
pub struct FastDiv {
    /// ⌈2⁶⁴ / d⌉, or 0 for d = 1 (which `div` handles alone).
    m: u64,
    d: u32,
    w: u32,
}

impl FastDiv {
    pub fn new(d: u32) -> Self {
        assert!(d > 0);
        let m = if d > 1 { u64::MAX / d as u64 + 1 } else { 0 };
        Self {
            m,
            d,
            w: mask_of(d),
        }
    }
}

impl FastDiv {
    /// The divisor.
    pub(super) fn divisor(self) -> u32 {
        self.d
    }

    /// `n mod d`, exactly `n % d`.
    #[inline(always)]
    pub(super) fn remainder(self, n: u32) -> u32 {
        Divisor::rem(self, n)
    }

    /// The cycle-walking mask of a permutation of `0..d` (see [`mask_of`]).
    pub(super) fn walk_mask(self) -> u32 {
        self.w
    }
}

impl Divisor for FastDiv {
    #[inline(always)]
    fn get(self) -> u32 {
        self.d
    }
    #[inline(always)]
    fn div(self, n: u32) -> u32 {
        if self.d == 1 {
            n
        } else {
            ((self.m as u128 * n as u128) >> 64) as u32
        }
    }
    #[inline(always)]
    fn rem(self, n: u32) -> u32 {
        let low = self.m.wrapping_mul(n as u64);
        ((low as u128 * self.d as u128) >> 64) as u32
    }
    #[inline(always)]
    fn mask(self) -> u32 {
        self.w
    }
}

/// A pseudo-random permutation of `0..len`, indexed by `i`, chosen by
/// `pattern`. Hash steps that are bijective on the low bits, cycle-walked
/// into range (Kensler 2013, listing 3).
pub fn permute(i: u32, len: u32, pattern: u32) -> u32 {
    permute_by(i, len, pattern)
}

#[inline(always)]
fn permute_by<D: Divisor>(mut i: u32, len: D, pattern: u32) -> u32 {
    let len_ = len.get();
    debug_assert!(len_ > 0 && i < len_);
    if len_ == 1 {
        return 0;
    }
    let p = pattern;
    let w = len.mask();
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len_ {
            break;
        }
    }
    len.rem(i.wrapping_add(p))
}

/// A hashed float in [0, 1) for index `i` under `pattern` (Kensler 2013, listing 4).
pub fn rand_float(mut i: u32, p: u32) -> f32 {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc_4795);
    i ^= 0xdf6e_307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | p >> 18);
    super::hash::unit_float(i)
}

/// Sample `s` of an `n`-sample correlated multi-jittered set in [0,1)².
///
/// The grid is m × rows cells with m × rows = n wherever n has a divisor
/// that makes a grid no more than four times as tall as wide
/// ([`grid_columns`]): every power of two, square and most round counts.
/// For other `n` (primes above [`ANY_DIVISOR_MAX`], and a few others) the
/// grid has a few more cells than samples. Kensler fills cells 0..n and
/// leaves the last row partial, which under-weights that row: every
/// sample's marginal is then *not* uniform, a bias that shows in
/// penumbrae at n = 32 or 128. We instead let the pattern's permutation
/// choose n distinct cells out of all m × rows, so each sample lies in a
/// uniformly chosen cell (unbiased), and no two share a cell or a fine 1D
/// stratum (stratified).
pub fn cmj_2d(s: u32, n: u32, pattern: u32) -> Vec2 {
    debug_assert!(s < n);
    let m = grid_columns(n);
    cmj_point(s, pattern, m, n.div_ceil(m), m * n.div_ceil(m))
}

/// Up to this many samples any divisor makes the grid (one column of n
/// rows for a prime) rather than a grid with empty cells: both
/// projections are still stratified into n, and an empty cell (an eighth
/// of a 7-sample pixel) cost more than the lost 2D jitter (cornell-planes'
/// RMSE at 7, 13 and 31 spp 0.072, 0.055, 0.030 with empty cells, 0.055,
/// 0.035, 0.020 in one column; soft-shadow at 127 spp was the other way
/// round, 0.0016 against 0.0022; docs/converge.md).
const ANY_DIVISOR_MAX: u32 = 32;

/// Columns of the CMJ grid for `n` samples: the largest divisor of `n` up
/// to √n, where it is at least √n / 2 (a grid of no empty cell, at most
/// four times as tall as wide) or `n` is small ([`ANY_DIVISOR_MAX`]);
/// else ⌊√n⌋, a grid of a few empty cells. An empty cell leaves part of
/// the pixel unsampled, which at 32 spp (5 × 7 cells against 4 × 8) made
/// cornell-planes' squared error 2.3 times larger. At most eight
/// candidates are tried (a draw of an unprepared set calls this), and a
/// power of two is found at once.
#[inline]
fn grid_columns(n: u32) -> u32 {
    if n.is_power_of_two() {
        // 2^k: 2^⌊k/2⌋ columns, as many rows or twice as many.
        return 1 << (n.trailing_zeros() / 2);
    }
    let root = ((n as f32).sqrt() as u32).max(1);
    (root.saturating_sub(7).max(1)..=root)
        .rev()
        .find(|&m| n.is_multiple_of(m))
        .filter(|&m| n <= ANY_DIVISOR_MAX || 4 * (m as u64) * (m as u64) >= n as u64)
        .unwrap_or(root)
}

/// The patterns a set's `pattern` gives a sample's permutation of cells,
/// of columns and of rows, and its x and y jitter.
#[inline(always)]
pub(super) fn sample_patterns(pattern: u32) -> [u32; 5] {
    [
        0x5163_3e2d,
        0x68bc_21eb,
        0x02e5_be93,
        0x967a_889b,
        0x368c_c8b7,
    ]
    .map(|k| pattern.wrapping_mul(k))
}

/// Sample `s` of the set on a grid of `m` columns, `rows` rows and `cells` = m × rows.
#[inline(always)]
fn cmj_point<D: Divisor>(s: u32, pattern: u32, m: D, rows: D, cells: D) -> Vec2 {
    let [p_cells, p_columns, p_rows, p_jitter_x, p_jitter_y] = sample_patterns(pattern);
    let s = permute_by(s, cells, p_cells);
    let (col, row) = (m.rem(s), m.div(s));
    let sx = permute_by(col, m, p_columns);
    let sy = permute_by(row, rows, p_rows);
    let jx = rand_float(s, p_jitter_x);
    let jy = rand_float(s, p_jitter_y);
    let (m, rows) = (m.get() as f32, rows.get() as f32);
    // Each coordinate is a coarse stratum and a fine one within it: x the
    // permuted column, then the permuted row; y the row, then the column.
    // Each cell has a fine stratum of its own in each 1D projection (of
    // m × rows), so no two samples share one (Kensler 2013's correlated
    // multi-jitter; until 29 November 2026 y had no fine stratum, and a
    // pixel's samples were spread over only `rows` strata vertically).
    let x = (sx as f32 + (sy as f32 + jx) / rows) / m;
    let y = (row as f32 + (col as f32 + jy) / m) / rows;
    Vec2::new(x.min(ONE_MINUS_EPSILON), y.min(ONE_MINUS_EPSILON))
}

/// An `n`-sample CMJ set's grid with its divisions prepared (three 64-bit
/// divisions, once), so that each [`CmjSet::sample`] divides by
/// multiplying. Same samples as [`cmj_2d`]; worth it when a set is reused
/// for several samples (a pixel's samples in one pass).
#[derive(Debug, Clone, Copy)]
pub struct CmjSet {
    pub n: u32,
    m: FastDiv,
    rows: FastDiv,
    cells: FastDiv,
}

impl CmjSet {
    /// A set of no samples: matches no count.
    pub const EMPTY: CmjSet = CmjSet {
        n: 0,
        m: FastDiv { m: 0, d: 1, w: 0 },
        rows: FastDiv { m: 0, d: 1, w: 0 },
        cells: FastDiv { m: 0, d: 1, w: 0 },
    };

    pub fn new(n: u32) -> Self {
        let m = grid_columns(n.max(1));
        let rows = n.max(1).div_ceil(m);
        Self {
            n,
            m: FastDiv::new(m),
            rows: FastDiv::new(rows),
            cells: FastDiv::new(m * rows),
        }
    }

    /// The grid's columns, rows and cells.
    pub(super) fn grid(&self) -> (u32, u32, u32) {
        (self.m.d, self.rows.d, self.cells.d)
    }

    /// The grid's columns, rows and cells as prepared divisors.
    pub(super) fn divisors(&self) -> [FastDiv; 3] {
        [self.m, self.rows, self.cells]
    }

    /// 2³² modulo the grid's columns, rows and cells (from 2³² − 1's
    /// remainders, which multiplications give).
    pub(super) fn two32_mods(&self) -> [u32; 3] {
        [self.m, self.rows, self.cells].map(|d| {
            let r = d.rem(u32::MAX) + 1;
            if r == d.d {
                0
            } else {
                r
            }
        })
    }

    /// Exactly `cmj_2d(s, self.n, pattern)`.
    #[inline]
    pub fn sample(&self, s: u32, pattern: u32) -> Vec2 {
        debug_assert!(s < self.n);
        cmj_point(s, pattern, self.m, self.rows, self.cells)
    }
}

/// What a 1D set's pattern is multiplied by for its permutation of the
/// strata and for its jitter.
pub(super) const STRATA_PATTERN: u32 = 0x2d2a_8cd3;
pub(super) const JITTER_PATTERN: u32 = 0x7a3f_c10b;

/// Sample `s` of an `n`-sample stratified (jittered) set in [0,1).
pub fn stratified_1d(s: u32, n: u32, pattern: u32) -> f32 {
    let stratum = permute(s, n, pattern.wrapping_mul(STRATA_PATTERN));
    let j = rand_float(s, pattern.wrapping_mul(JITTER_PATTERN));
    ((stratum as f32 + j) / n as f32).min(ONE_MINUS_EPSILON)
}

pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_permutation_for_many_lengths() {
        for len in [1u32, 2, 3, 5, 7, 16, 17, 100, 1000] {
            for pattern in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, pattern) as usize;
                    assert!(!seen[j], "len {len} pattern {pattern}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn cmj_is_stratified_in_both_projections_for_any_n() {
        for (n, pattern) in [1u32, 2, 3, 4, 5, 7, 9, 16, 30, 32, 37, 64, 100, 127]
            .into_iter()
            .flat_map(|n| [12345, 7, 0x9e37_79b9].map(|p| (n, p)))
        {
            let pts: Vec<Vec2> = (0..n).map(|s| cmj_2d(s, n, pattern)).collect();
            let m = grid_columns(n);
            let rows = n.div_ceil(m);
            // Each column of width 1/m holds at most `rows` samples, each
            // row of height 1/rows at most m samples.
            let mut cols = vec![0; m as usize];
            let mut rws = vec![0; rows as usize];
            for p in &pts {
                assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                cols[(p.x * m as f32) as usize] += 1;
                rws[(p.y * rows as f32) as usize] += 1;
            }
            assert!(cols.iter().all(|&c| c <= rows), "n {n} cols {cols:?}");
            assert!(rws.iter().all(|&c| c <= m), "n {n} rows {rws:?}");
            // The fine 1D strata (m × rows of them, n for full grids) hold
            // at most one sample each, in both projections.
            let cells = (m * rows) as f32;
            let (mut fine_x, mut fine_y) =
                (vec![0; (m * rows) as usize], vec![0; (m * rows) as usize]);
            for p in &pts {
                fine_x[(p.x * cells) as usize] += 1;
                fine_y[(p.y * cells) as usize] += 1;
            }
            assert!(
                fine_x.iter().all(|&c| c <= 1),
                "n {n} x-projection {fine_x:?}"
            );
            assert!(
                fine_y.iter().all(|&c| c <= 1),
                "n {n} y-projection {fine_y:?}"
            );
        }
    }

    /// The grid has no empty cell wherever a divisor of n makes one no
    /// more than four times as tall as wide, or n is small; else it is
    /// ⌊√n⌋ columns wide.
    #[test]
    fn grids_are_exact_where_a_divisor_allows() {
        for n in 1u32..=5000 {
            let m = grid_columns(n);
            let root = ((n as f32).sqrt() as u32).max(1);
            assert!((1..=root).contains(&m), "n {n}: {m} columns");
            let exact = (1..=root)
                .rev()
                .find(|&d| n.is_multiple_of(d))
                .filter(|&d| n <= ANY_DIVISOR_MAX || 4 * d * d >= n);
            match exact {
                // The largest such divisor; a power of two's is found at once.
                Some(d) if d + 7 >= root || n.is_power_of_two() => assert_eq!(m, d, "n {n}"),
                // Beyond the eight candidates tried: a partial grid.
                Some(_) => assert_eq!(m, root, "n {n}"),
                None => assert_eq!(m, root, "n {n}"),
            }
        }
        let shapes = [
            (5, 1),
            (7, 1),
            (32, 4),
            (37, 6),
            (100, 10),
            (127, 11),
            (128, 8),
            (1000, 25),
        ];
        for (n, m) in shapes {
            assert_eq!(grid_columns(n), m, "n {n}");
        }
    }

    #[test]
    fn every_sample_is_uniform_over_patterns_even_for_partial_grids() {
        // n = 37 uses a 6 × 7 grid, 127 an 11 × 12 one, with empty cells:
        // the top row must not be under-weighted.
        for n in [7u32, 32, 37, 127, 128] {
            let mut top = 0usize;
            let trials = 4000u32;
            for p in 0..trials {
                for s in 0..n {
                    if cmj_2d(s, n, crate::sampling::hash::hash_u32(p)).y >= 0.9 {
                        top += 1;
                    }
                }
            }
            let frac = top as f64 / (trials * n) as f64;
            assert!(
                (frac - 0.1).abs() < 0.004,
                "n {n}: {frac} of samples in the top 10%"
            );
        }
    }

    #[test]
    fn prepared_sets_give_the_same_samples_bit_for_bit() {
        for n in [1u32, 2, 3, 5, 7, 16, 17, 32, 64, 100, 1000, 4096, 65_537] {
            let set = CmjSet::new(n);
            for pattern in [0u32, 1, 0xdead_beef, 0xffff_ffff, 12345] {
                for s in (0..n).step_by((n as usize / 97).max(1)).chain([n - 1]) {
                    let (a, b) = (cmj_2d(s, n, pattern), set.sample(s, pattern));
                    assert_eq!(
                        a.to_array().map(f32::to_bits),
                        b.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }

    #[test]
    fn fast_division_is_exact() {
        let mut d = 1u32;
        while d < u32::MAX / 3 {
            let f = FastDiv::new(d);
            for n in [
                0u32,
                1,
                d - 1,
                d,
                d + 1,
                2 * d + 1,
                u32::MAX,
                u32::MAX - 1,
                0x8000_0000,
                12_345_678,
            ] {
                assert_eq!(f.div(n), n / d, "{n} / {d}");
                assert_eq!(f.rem(n), n % d, "{n} % {d}");
            }
            d = d * 3 + 1;
        }
        for d in [
            2u32,
            3,
            7,
            8,
            9,
            15,
            16,
            17,
            255,
            256,
            257,
            65_535,
            u32::MAX,
        ] {
            let f = FastDiv::new(d);
            for n in (0..100_000u32).chain((0..100_000).map(|k| u32::MAX - k)) {
                assert_eq!((f.div(n), f.rem(n)), (n / d, n % d), "{n} by {d}");
            }
        }
    }

    #[test]
    fn stratified_1d_has_one_sample_per_stratum() {
        for n in [1u32, 3, 10, 33] {
            let mut strata = vec![0; n as usize];
            for s in 0..n {
                strata[(stratified_1d(s, n, 77) * n as f32) as usize] += 1;
            }
            assert!(strata.iter().all(|&c| c == 1));
        }
    }
}
