//! Shading: the integrator, which turns a camera sample into radiance.

pub mod integrator;
