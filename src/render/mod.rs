//! The render core: scheduling samples onto threads ([`schedule`]),
//! stopping each pixel at a noise target ([`adaptive`]),
//! accumulating them exactly ([`film`]), telling the caller how it goes
//! ([`progress`]) and what to warn of ([`warning`]), replaying one sample
//! ([`replay`]), the statistics of a run ([`stats`]) and its timeline
//! ([`timeline`]). It prints nothing: the front ends (`strata`'s `cli/`,
//! the Python package) say what it reports.

pub mod adaptive;
pub mod aov;
pub mod film;
pub mod progress;
pub mod replay;
pub mod schedule;
pub mod stats;
pub mod timeline;
pub mod warning;
pub mod window;
mod workers;

pub use film::Film;
pub use progress::{each_pass, Observer};
pub use schedule::{render, RenderOptions, RenderOutcome, Schedule, SliceSpec};
pub use warning::Warning;
pub use window::Window;
pub use workers::{is_current_pool, on_current_pool};
