//! strata: a data-oriented Monte Carlo distribution ray tracer.
//!
//! The data flow is describe → compile → accelerate → sample → shade →
//! schedule → output. docs/ARCHITECTURE.md maps the modules onto it: each
//! imports only modules of lower layers (checked by tests/suite/architecture.rs).

// `!(x > 0.0)` is how this crate says "not positive, or NaN": rejecting NaN
// is the point, so the partial-order lint would make the code wrong.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// `unsafe` lives in one module, `accel::simd` (software prefetch and the
// runtime AVX-512 dispatch), which allows it for itself.
#![deny(unsafe_code)]

/// This build: the package version, plus `+git.<commit>` when built from a
/// git checkout. Partial files record it, and merging or resuming parts of
/// different builds is refused unless forced.
pub const VERSION: &str = env!("STRATA_VERSION");

pub mod accel;
pub mod camera;
pub mod error;
pub mod experiment;
pub mod geometry;
pub mod light;
pub mod material;
pub mod math;
pub mod mode;
pub mod output;
pub mod partial;
pub mod raycast;
pub mod rays;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shade;
pub mod shape;
pub mod system;
pub mod texture;
