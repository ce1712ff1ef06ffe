//! The render core: scheduling samples onto threads ([`schedule`]),
//! accumulating them exactly ([`film`]), reporting progress ([`progress`]),
//! replaying one sample ([`replay`]), the statistics of a run ([`stats`])
//! and its timeline ([`timeline`]).

pub mod aov;
pub mod film;
pub mod progress;
pub mod replay;
pub mod schedule;
pub mod stats;
pub mod timeline;
pub mod window;

pub use film::Film;
pub use schedule::{render, RenderOptions, RenderOutcome, Schedule, SliceSpec};
pub use window::Window;
