//! Geometry basics: rays, boxes, orthonormal frames, transforms, the robust
//! origin offset for spawned rays, and vectors and trigonometry in SIMD
//! lanes.

pub mod aabb;
pub mod frame;
pub mod lanes3;
pub mod offset;
pub mod ray;
pub mod transform;
pub mod trig;

pub use aabb::Aabb;
pub use frame::Frame;
pub use ray::Ray;
pub use transform::Transform;
