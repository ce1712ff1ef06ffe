//! Deterministic sampling: every random number is a pure function of
//! (seed, pixel, sample index, dimension), so any sample can be recomputed
//! alone, any split of the work gives the same image, and a slice of a
//! pixel's samples is part of that pixel's one global stratification.

pub mod cmj;
pub mod hash;
pub mod sampler;
pub mod spherical_rect;
pub mod warp;

pub use sampler::{Dim, PixelSampler, SamplerKind};
