//! Deterministic sampling: every random number a render draws is a pure
//! function of (seed, pixel, sample index, dimension), so any sample can be
//! recomputed alone, any split of the work gives the same image, and a
//! slice of a pixel's samples is part of that pixel's one global
//! stratification. That is why rendering uses counter-based hashes
//! ([`hash`], [`cmj`], [`sampler`]) and not a sequential generator, whose
//! number `i` exists only after numbers `0..i`.
//!
//! Inputs that are naturally sequential (ray sets, test fixtures, benchmark
//! rays) come from seeded `rand` streams instead ([`stream`]).

pub mod cmj;
pub mod cmj_lanes;
pub mod distribution;
pub mod hash;
pub mod mis;
pub mod sampler;
pub mod sobol;
pub mod spherical_rect;
pub mod spherical_rect_lanes;
pub mod stream;
pub mod warp;

pub use sampler::{Dim, PixelSampler, SamplerKind};
