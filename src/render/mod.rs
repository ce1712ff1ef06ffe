//! Scheduling samples onto threads, accumulating them, and reporting progress.

pub mod converge;
pub mod debug;
pub mod film;
pub mod progress;
pub mod schedule;

pub use film::Film;
pub use schedule::{render, RenderOptions, RenderOutcome, Schedule, SliceSpec};
