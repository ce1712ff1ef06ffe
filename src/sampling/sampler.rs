//! The per-pixel sampler: which number a given (pixel, sample, effect) gets.
//!
//! Every effect draws from its own *dimension* so that sets for different
//! effects are decorrelated: each dimension gets its own CMJ pattern, hashed
//! from (seed, pixel, dimension). Within a dimension a pixel's `N` samples
//! form one stratified set, and sample `i` depends on nothing but `i`.

use super::cmj::{cmj_2d, stratified_1d};
use super::hash::{hash_words, unit_float};
use glam::Vec2;

crate::mode::mode_enum! {
    /// `random`: independent uniform numbers. `stratified`: correlated
    /// multi-jittered sets, one per pixel, effect and depth.
    #[derive(Default)]
    pub enum SamplerKind("sampler") {
        Random = "random",
        #[default]
        Stratified = "stratified",
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
}

/// The sampler for one pixel.
#[derive(Debug, Clone, Copy)]
pub struct PixelSampler {
    pub kind: SamplerKind,
    pub seed: u32,
    pub pixel: u32,
}

impl PixelSampler {
    pub fn new(kind: SamplerKind, seed: u32, pixel: u32) -> Self {
        Self { kind, seed, pixel }
    }

    fn pattern(&self, dim: Dim) -> u32 {
        hash_words(&[self.seed, self.pixel, dim.0])
    }

    /// Point `index` of a `count`-point set in [0,1)² for dimension `dim`.
    /// For effects with several samples per camera sample, pass
    /// `index = sample * m + j` and `count = spp * m`, so that the pixel's
    /// spp·m points form one stratified set.
    pub fn get_2d(&self, dim: Dim, index: u32, count: u32) -> Vec2 {
        let p = self.pattern(dim);
        match self.kind {
            SamplerKind::Stratified => cmj_2d(index, count, p),
            SamplerKind::Random => Vec2::new(
                unit_float(hash_words(&[p, index, 0])),
                unit_float(hash_words(&[p, index, 1])),
            ),
        }
    }

    pub fn get_1d(&self, dim: Dim, index: u32, count: u32) -> f32 {
        let p = self.pattern(dim);
        match self.kind {
            SamplerKind::Stratified => stratified_1d(index, count, p),
            SamplerKind::Random => unit_float(hash_words(&[p, index, 2])),
        }
    }
}
