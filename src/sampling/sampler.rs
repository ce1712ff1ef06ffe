//! The per-pixel sampler: which number a given (pixel, sample, effect) gets.
//!
//! Every effect draws from its own *dimension* so that sets for different
//! effects are decorrelated: each dimension gets its own CMJ pattern, hashed
//! from (seed, pixel, dimension). Within a dimension a pixel's `N` samples
//! form one stratified set, and sample `i` depends on nothing but `i`.

use super::cmj::{cmj_2d, stratified_1d, CmjSet};
use super::cmj_lanes::{CmjGrid, CmjLanes, StrataGrid, StratifiedLanes};
use super::hash::{hash_step, hash_step_lanes, unit_float, unit_float_lanes, HASH_WORDS_INIT};
use super::sobol::{sobol_1d, sobol_2d};
use crate::math::lanes::{mask_lanes, LANES};
use glam::Vec2;
use wide::u32x8;

crate::mode::mode_enum! {
    /// `random`: independent uniform numbers. `stratified`: correlated
    /// multi-jittered sets, one per pixel, effect and depth. `sobol`: an
    /// Owen-scrambled Sobol sequence per pixel, effect and depth, whose
    /// every prefix of 2^k samples is stratified (for renders that may stop
    /// a pixel after any pass: `--noise`, `--time`).
    #[derive(Default)]
    pub enum SamplerKind("sampler") {
        Random = "random",
        #[default]
        Stratified = "stratified",
        Sobol = "sobol",
    }
}

/// A sampling dimension: one effect at one path depth (and, for lights, one light).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dim(pub u32);

impl Dim {
    pub const PIXEL: Dim = Dim(1);
    pub const LENS: Dim = Dim(2);
    pub const TIME: Dim = Dim(3);

    /// Light-sample dimension for light `light` at path depth `depth`.
    pub fn light(depth: u32, light: u32) -> Dim {
        Dim(0x1000 + depth * 0x1_0000 + light)
    }

    /// Glossy-reflection dimension at path depth `depth`.
    pub fn glossy(depth: u32) -> Dim {
        Dim(0x2000 + depth * 0x1_0000)
    }

    /// Fresnel / layer choice dimension at path depth `depth`.
    pub fn choice(depth: u32) -> Dim {
        Dim(0x3000 + depth * 0x1_0000)
    }

    /// The environment light's draw beside a glossy reflection's, for
    /// multiple importance sampling, at path depth `depth`.
    pub fn glossy_environment(depth: u32) -> Dim {
        Dim(0x4000 + depth * 0x1_0000)
    }

    /// The path integrator's next direction from the vertex at path
    /// depth `depth` (2D).
    pub fn bounce(depth: u32) -> Dim {
        Dim(0x5000 + depth * 0x1_0000)
    }

    /// The path integrator's choice of a BSDF lobe at path depth `depth` (1D).
    pub fn lobe(depth: u32) -> Dim {
        Dim(0x6000 + depth * 0x1_0000)
    }

    /// Russian roulette's draw at path depth `depth` (1D).
    pub fn roulette(depth: u32) -> Dim {
        Dim(0x7000 + depth * 0x1_0000)
    }
}

/// The sampler for one pixel.
///
/// What every number of the pixel shares is computed once, in
/// [`PixelSampler::new`] and [`PixelSampler::with_sets`]: the hash state
/// after (seed, pixel), and the prepared CMJ grids of the pixel's usual set
/// sizes. The numbers are those of the plain formulas, bit for bit.
#[derive(Debug, Clone, Copy)]
pub struct PixelSampler {
    pub kind: SamplerKind,
    pub seed: u32,
    pub pixel: u32,
    /// `hash_words` state after [seed, pixel].
    prefix: u32,
    /// Prepared grids for set sizes asked often; size 0 is an empty slot.
    sets: [CmjSet; 2],
}

impl PixelSampler {
    pub fn new(kind: SamplerKind, seed: u32, pixel: u32) -> Self {
        Self {
            kind,
            seed,
            pixel,
            prefix: hash_step(hash_step(HASH_WORDS_INIT, seed), pixel),
            sets: [CmjSet::EMPTY; 2],
        }
    }

    /// The prepared CMJ grids of set sizes `counts` (for example a
    /// render's spp, and spp × shadow samples), for
    /// [`PixelSampler::with_sets`]. They depend on the sizes alone, so a
    /// caller prepares them once for many pixels.
    pub fn prepare_sets(counts: [u32; 2]) -> [CmjSet; 2] {
        counts.map(|n| if n > 0 { CmjSet::new(n) } else { CmjSet::EMPTY })
    }

    /// The same sampler with `sets` (from [`PixelSampler::prepare_sets`]):
    /// each [`PixelSampler::get_2d`] of one of their sizes then divides by
    /// multiplying.
    pub fn with_sets(mut self, sets: [CmjSet; 2]) -> Self {
        if self.kind == SamplerKind::Stratified {
            self.sets = sets;
        }
        self
    }

    /// `hash_words(&[seed, pixel, dim])`, from the kept prefix.
    #[inline]
    fn pattern(&self, dim: Dim) -> u32 {
        hash_step(self.prefix, dim.0)
    }

    /// Point `index` of a `count`-point set in [0,1)² for dimension `dim`.
    /// For effects with several samples per camera sample, pass
    /// `index = sample * m + j` and `count = spp * m`, so that the pixel's
    /// spp·m points form one stratified set.
    #[inline]
    pub fn get_2d(&self, dim: Dim, index: u32, count: u32) -> Vec2 {
        self.dim_2d(dim, count).get_2d(index)
    }

    pub fn get_1d(&self, dim: Dim, index: u32, count: u32) -> f32 {
        let p = self.pattern(dim);
        match self.kind {
            SamplerKind::Stratified => stratified_1d(index, count, p),
            SamplerKind::Random => unit_float(hash_step(random_prefix(p, index), 2)),
            SamplerKind::Sobol => sobol_1d(index, p),
        }
    }

    /// Points `index[i]` of `count`-point 1D sets of dimension `dim` for
    /// the lanes `i` in mask `wanted` (zero in the others): exactly
    /// [`PixelSampler::get_1d`] of each. Where two or more lanes are wanted
    /// the stratified sampler draws all eight at once in SIMD lanes, so
    /// every `index[i]` must then be below `count`, wanted or not.
    #[inline]
    pub fn get_1d_lanes(
        &self,
        dim: Dim,
        index: [u32; LANES],
        count: u32,
        wanted: u32,
    ) -> [f32; LANES] {
        if wanted.count_ones() > 1 && self.kind == SamplerKind::Stratified {
            if let Some(lanes) = StratifiedLanes::new(count, self.pattern(dim)) {
                return lanes.sample(index);
            }
        }
        let mut out = [0.0; LANES];
        for i in mask_lanes(wanted) {
            out[i] = self.get_1d(dim, index[i], count);
        }
        out
    }

    /// Whether `other` draws exactly the numbers `self` draws (the same
    /// kind, seed and pixel), so that one [`DimSampler`] serves both.
    #[inline]
    pub fn same_numbers(&self, other: &PixelSampler) -> bool {
        (self.kind, self.seed, self.pixel) == (other.kind, other.seed, other.pixel)
    }

    /// Dimension `dim`'s sets of `count` points: what every draw of them
    /// shares (the dimension's pattern, and the random sampler's hash state
    /// after it or the stratified sampler's prepared set), worked out once
    /// for [`DimSampler::get_2d`], which [`PixelSampler::get_2d`] calls.
    #[inline]
    pub fn dim_2d(&self, dim: Dim, count: u32) -> DimSampler {
        let pattern = self.pattern(dim);
        let (random_state, set) = match self.kind {
            SamplerKind::Stratified => (
                0,
                self.sets
                    .iter()
                    .find(|set| set.n == count)
                    .copied()
                    .unwrap_or(CmjSet::EMPTY),
            ),
            SamplerKind::Random => (hash_step(HASH_WORDS_INIT, pattern), CmjSet::EMPTY),
            SamplerKind::Sobol => (0, CmjSet::EMPTY),
        };
        DimSampler {
            kind: self.kind,
            count,
            pattern,
            random_state,
            set,
        }
    }
}

/// One pixel's numbers of one dimension, in sets of one size (see
/// [`PixelSampler::dim_2d`]).
#[derive(Debug, Clone, Copy)]
pub struct DimSampler {
    kind: SamplerKind,
    count: u32,
    pattern: u32,
    /// `hash_words(&[pattern])`, the random sampler's state before the
    /// index (random sampler only).
    random_state: u32,
    /// The prepared grid of `count` points, or [`CmjSet::EMPTY`]
    /// (stratified sampler only).
    set: CmjSet,
}

impl DimSampler {
    /// Point `index` of the set (see [`PixelSampler::get_2d`]).
    #[inline]
    pub fn get_2d(&self, index: u32) -> Vec2 {
        match self.kind {
            SamplerKind::Stratified if self.set.n == self.count => {
                self.set.sample(index, self.pattern)
            }
            SamplerKind::Stratified => cmj_2d(index, self.count, self.pattern),
            SamplerKind::Random => {
                let h = hash_step(self.random_state, index);
                Vec2::new(unit_float(hash_step(h, 0)), unit_float(hash_step(h, 1)))
            }
            // A sequence, not a set: the count does not matter.
            SamplerKind::Sobol => sobol_2d(index, self.pattern),
        }
    }
}

impl DimSampler {
    /// Points `index[i]` of the set for the lanes `i` in mask `wanted`
    /// (zero in the others): exactly [`DimSampler::get_2d`] of each. Where
    /// two or more lanes are wanted, all eight are drawn at once in SIMD
    /// lanes, so every `index[i]` must then be below the set's size,
    /// wanted or not.
    #[inline]
    pub fn get_2d_lanes(&self, index: [u32; LANES], wanted: u32) -> [Vec2; LANES] {
        if wanted.count_ones() > 1 {
            match self.kind {
                SamplerKind::Stratified => {
                    // A set not prepared is prepared here: three 64-bit
                    // divisions, against the scalar code's three 32-bit
                    // divisions per sample.
                    let set = if self.set.n == self.count {
                        self.set
                    } else {
                        CmjSet::new(self.count)
                    };
                    if let Some(lanes) = CmjLanes::new(&set, self.pattern) {
                        return lanes.sample(index);
                    }
                }
                SamplerKind::Random => {
                    let state = u32x8::splat(self.random_state);
                    let h = hash_step_lanes(state, u32x8::new(index));
                    let [x, y] =
                        [0, 1].map(|k| unit_float_lanes(hash_step_lanes(h, u32x8::splat(k))));
                    let (x, y) = (x.to_array(), y.to_array());
                    return std::array::from_fn(|i| Vec2::new(x[i], y[i]));
                }
                // One point at a time, below.
                SamplerKind::Sobol => {}
            }
        }
        let mut points = [Vec2::ZERO; LANES];
        for i in mask_lanes(wanted) {
            points[i] = self.get_2d(index[i]);
        }
        points
    }
}

/// One pixel's sets of `count` points, prepared for drawing eight points
/// of any dimension at once ([`PixelSampler::set_lanes`]): what every
/// draw of a batch of the pixel's camera samples shares whatever its
/// dimension (the set's grids, their masks and divisors), worked out
/// once per batch rather than once per draw. Each point is exactly
/// [`PixelSampler::get_2d`]'s or [`PixelSampler::get_1d`]'s.
#[derive(Debug, Clone, Copy)]
pub struct SetLanes {
    sampler: PixelSampler,
    /// Where the lanes draw for several pixels ([`SetLanes::each_pixel`]):
    /// lane `i`'s hash state after (seed, its pixel), from which its
    /// dimensions' patterns are hashed.
    prefixes: Option<u32x8>,
    count: u32,
    /// The stratified sampler's 2D set (prepared), and its grids in lanes
    /// where the set is drawn in lanes.
    set: CmjSet,
    cmj: Option<CmjGrid>,
    strata: Option<StrataGrid>,
}

impl PixelSampler {
    /// The pixel's sets of `count` points, prepared for [`SetLanes`].
    pub fn set_lanes(&self, count: u32) -> SetLanes {
        let (set, cmj, strata) = match self.kind {
            SamplerKind::Stratified if count > 0 => {
                let set = match self.sets.iter().find(|set| set.n == count) {
                    Some(set) => *set,
                    None => CmjSet::new(count),
                };
                (set, CmjGrid::new(&set), StrataGrid::new(count))
            }
            _ => (CmjSet::EMPTY, None, None),
        };
        SetLanes {
            sampler: *self,
            prefixes: None,
            count,
            set,
            cmj,
            strata,
        }
    }
}

impl SetLanes {
    /// The same sets drawn with lane `i` as `samplers[i]` draws: several
    /// pixels' samples in one batch (a pass of fewer samples a pixel than
    /// lanes), each lane under its own pixel's patterns, eight points still
    /// drawn at once. `None` unless every sampler is a stratified one of
    /// this seed (the sets' size, and so their grids, is the same for all).
    pub fn each_pixel(&self, samplers: [&PixelSampler; LANES]) -> Option<SetLanes> {
        let alike =
            |s: &&PixelSampler| (s.kind, s.seed) == (SamplerKind::Stratified, self.sampler.seed);
        (self.sampler.kind == SamplerKind::Stratified && samplers.iter().all(alike)).then(|| {
            SetLanes {
                prefixes: Some(u32x8::new(samplers.map(|s| s.prefix))),
                ..*self
            }
        })
    }

    /// Each lane's pattern of dimension `dim`: `PixelSampler::pattern` of
    /// its own pixel's sampler.
    #[inline]
    fn patterns(&self, dim: Dim) -> u32x8 {
        match self.prefixes {
            Some(prefixes) => hash_step_lanes(prefixes, u32x8::splat(dim.0)),
            None => u32x8::splat(self.sampler.pattern(dim)),
        }
    }

    /// Points `index[i]` of dimension `dim`'s set for the lanes `i` of
    /// `wanted`: exactly [`PixelSampler::get_2d`] of each. Where two or
    /// more lanes are wanted all eight may be drawn at once, so every
    /// `index[i]` must be below the set's size, wanted or not; the lanes
    /// not wanted hold no promised value.
    #[inline]
    pub fn get_2d(&self, dim: Dim, index: &[u32; LANES], wanted: u32) -> [Vec2; LANES] {
        let sampler = &self.sampler;
        if sampler.kind != SamplerKind::Stratified {
            return sampler.dim_2d(dim, self.count).get_2d_lanes(*index, wanted);
        }
        if wanted.count_ones() > 1 {
            if let Some(grid) = &self.cmj {
                let lanes = match self.prefixes {
                    Some(_) => grid.lanes_each(self.patterns(dim)),
                    None => grid.lanes(sampler.pattern(dim)),
                };
                return lanes.sample(*index);
            }
        }
        let patterns = self.patterns(dim).to_array();
        let mut points = [Vec2::ZERO; LANES];
        for i in mask_lanes(wanted) {
            // `CmjSet::sample` is `cmj_2d` of a prepared set.
            points[i] = if self.set.n == self.count {
                self.set.sample(index[i], patterns[i])
            } else {
                cmj_2d(index[i], self.count, patterns[i])
            };
        }
        points
    }

    /// Points `index[i]` of dimension `dim`'s 1D set for the lanes `i`
    /// of `wanted`, as [`SetLanes::get_2d`] draws 2D points: exactly
    /// [`PixelSampler::get_1d`] of each.
    #[inline]
    pub fn get_1d(&self, dim: Dim, index: &[u32; LANES], wanted: u32) -> [f32; LANES] {
        let sampler = &self.sampler;
        if sampler.kind != SamplerKind::Stratified {
            return sampler.get_1d_lanes(dim, *index, self.count, wanted);
        }
        if wanted.count_ones() > 1 {
            if let Some(grid) = &self.strata {
                let lanes = match self.prefixes {
                    Some(_) => grid.lanes_each(self.patterns(dim)),
                    None => grid.lanes(sampler.pattern(dim)),
                };
                return lanes.sample(*index);
            }
        }
        let patterns = self.patterns(dim).to_array();
        let mut out = [0.0; LANES];
        for i in mask_lanes(wanted) {
            out[i] = stratified_1d(index[i], self.count, patterns[i]);
        }
        out
    }
}

/// The random sampler's `hash_words(&[p, index, k])` state before `k`, which
/// a sample's coordinates (k = 0, 1 in 2D, 2 in 1D) share.
#[inline]
fn random_prefix(p: u32, index: u32) -> u32 {
    hash_step(hash_step(HASH_WORDS_INIT, p), index)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::hash::hash_words;
    use rand::RngExt;

    /// The numbers of the plain formulas: a pattern hashed from (seed,
    /// pixel, dim), then CMJ or hashed floats.
    fn plain_2d(kind: SamplerKind, seed: u32, pixel: u32, dim: Dim, i: u32, n: u32) -> Vec2 {
        let p = hash_words(&[seed, pixel, dim.0]);
        match kind {
            SamplerKind::Stratified => cmj_2d(i, n, p),
            SamplerKind::Random => Vec2::new(
                unit_float(hash_words(&[p, i, 0])),
                unit_float(hash_words(&[p, i, 1])),
            ),
            SamplerKind::Sobol => sobol_2d(i, p),
        }
    }

    /// A [`SetLanes`] draws exactly the plain formulas' numbers in every
    /// wanted lane, for each kind of sampler, prepared and unprepared set
    /// sizes, one lane or many, and every lane's own index.
    #[test]
    fn set_lanes_draw_the_plain_numbers() {
        let mut rng = crate::sampling::stream::seeded(99);
        let mut next = |n: u32| rng.random_range(0..n);
        let kinds = SamplerKind::ALL;
        for round in 0..3000u32 {
            let kind = kinds[round as usize % kinds.len()];
            let (seed, pixel) = (next(1 << 20), next(1 << 20));
            let n = [1u32, 2, 5, 16, 17, 64, 100, 4096][next(8) as usize];
            let plain = PixelSampler::new(kind, seed, pixel);
            let sampler = if round % 2 == 0 {
                plain.with_sets(PixelSampler::prepare_sets([n, 2 * n]))
            } else {
                plain
            };
            let lanes = sampler.set_lanes(n);
            let dim = Dim(next(0x8_0000));
            let index: [u32; LANES] = std::array::from_fn(|_| next(n));
            let wanted = [1 << next(8), next(256), 0xff][next(3) as usize];
            let (two, one) = (
                lanes.get_2d(dim, &index, wanted),
                lanes.get_1d(dim, &index, wanted),
            );
            let p = hash_words(&[seed, pixel, dim.0]);
            for i in mask_lanes(wanted) {
                let want_2d = plain_2d(kind, seed, pixel, dim, index[i], n);
                let want_1d = match kind {
                    SamplerKind::Stratified => stratified_1d(index[i], n, p),
                    SamplerKind::Random => unit_float(hash_words(&[p, index[i], 2])),
                    SamplerKind::Sobol => sobol_1d(index[i], p),
                };
                assert_eq!(
                    two[i].to_array().map(f32::to_bits),
                    want_2d.to_array().map(f32::to_bits),
                    "round {round}, lane {i}"
                );
                assert_eq!(one[i].to_bits(), want_1d.to_bits(), "round {round}");
            }
        }
    }

    #[test]
    fn same_numbers_means_same_kind_seed_and_pixel() {
        let a = PixelSampler::new(SamplerKind::Random, 7, 12);
        assert!(a.same_numbers(&a.with_sets(PixelSampler::prepare_sets([4, 8]))));
        for other in [
            PixelSampler::new(SamplerKind::Stratified, 7, 12),
            PixelSampler::new(SamplerKind::Random, 8, 12),
            PixelSampler::new(SamplerKind::Random, 7, 13),
        ] {
            assert!(!a.same_numbers(&other) && !other.same_numbers(&a));
        }
    }

    #[test]
    fn kept_prefixes_and_prepared_sets_change_no_number() {
        for kind in [
            SamplerKind::Stratified,
            SamplerKind::Random,
            SamplerKind::Sobol,
        ] {
            for (seed, pixel) in [(0u32, 0u32), (7, 12_345), (0xffff_ffff, 76_799)] {
                let plain = PixelSampler::new(kind, seed, pixel);
                let prepared = plain.with_sets(PixelSampler::prepare_sets([16, 64]));
                for dim in [Dim::PIXEL, Dim::LENS, Dim::light(0, 0), Dim::glossy(2)] {
                    for n in [1u32, 5, 16, 64, 100] {
                        for i in 0..n {
                            let want = plain_2d(kind, seed, pixel, dim, i, n).to_array();
                            for got in [
                                plain.get_2d(dim, i, n),
                                prepared.get_2d(dim, i, n),
                                plain.dim_2d(dim, n).get_2d(i),
                                prepared.dim_2d(dim, n).get_2d(i),
                            ] {
                                assert_eq!(
                                    got.to_array().map(f32::to_bits),
                                    want.map(f32::to_bits)
                                );
                            }
                        }
                        // Eight at a time, lanes in any order, from
                        // prepared sets (drawn in SIMD lanes) and plain ones.
                        for first in 0..n {
                            let index = std::array::from_fn(|k| (first + 3 * k as u32) % n);
                            for (sampler, wanted) in
                                [(plain, 0xff), (prepared, 0xff), (prepared, 0b1000)]
                            {
                                let got = sampler.dim_2d(dim, n).get_2d_lanes(index, wanted);
                                for i in mask_lanes(wanted) {
                                    let (got, i) = (got[i], index[i]);
                                    let want = plain_2d(kind, seed, pixel, dim, i, n);
                                    assert_eq!(
                                        got.to_array().map(f32::to_bits),
                                        want.to_array().map(f32::to_bits)
                                    );
                                }
                            }
                        }
                    }
                    let p = hash_words(&[seed, pixel, dim.0]);
                    let want = match kind {
                        SamplerKind::Stratified => stratified_1d(3, 10, p),
                        SamplerKind::Random => unit_float(hash_words(&[p, 3, 2])),
                        SamplerKind::Sobol => sobol_1d(3, p),
                    };
                    assert_eq!(plain.get_1d(dim, 3, 10).to_bits(), want.to_bits());
                }
            }
        }
    }
}
