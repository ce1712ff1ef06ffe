//! Shading: materials, lights and the integrator.

pub mod integrator;
pub mod light;
pub mod material;
