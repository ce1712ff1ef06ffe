//! Geometry basics: rays, boxes, orthonormal frames, transforms, the robust
//! origin offset for spawned rays, and SIMD lanes: the one lane width
//! ([`lanes::LANES`]), vectors and trigonometry in lanes; points welded
//! into vertices by exact position ([`weld`]).

pub mod aabb;
pub mod frame;
pub mod lanes;
pub mod offset;
pub mod ray;
pub mod transform;
pub mod trig;
pub mod weld;

pub use aabb::Aabb;
pub use frame::{unit_cross, unit_scale, Frame};
pub use ray::Ray;
pub use transform::Transform;
