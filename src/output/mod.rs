//! Writing results: images (PNG, EXR), SVG charts, and any file through a
//! temporary name beside its target that is renamed into place, so an
//! interrupted run never leaves a truncated file. This layer only writes:
//! it knows nothing of scenes, shading or rendering.

pub mod atomic;
pub mod chart;
pub mod exr;
pub mod image;
pub mod tonemap;
