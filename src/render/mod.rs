//! Scheduling samples onto threads, accumulating them, and reporting progress.

pub mod converge;
pub mod cputime;
pub mod debug;
pub mod film;
pub mod fingerprint;
pub mod merge;
pub mod partial;
pub mod progress;
pub mod scaling;
pub mod schedule;

pub use film::Film;
pub use schedule::{render, RenderOptions, RenderOutcome, Schedule, SliceSpec};
