//! Writing results: images (PNG, EXR), statistics JSON, SVG charts. Every file is written
//! to a temporary name beside its target and renamed into place, so an
//! interrupted run never leaves a truncated file.

pub mod atomic;
pub mod chart;
pub mod image;
pub mod stats;
