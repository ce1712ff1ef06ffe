//! strata: a data-oriented Monte Carlo distribution ray tracer.
//!
//! The data flow is describe → compile → accelerate → sample → shade →
//! schedule → output; see the README's architecture section.

pub mod accel;
pub mod camera;
pub mod error;
pub mod math;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shade;
pub mod shape;
