//! Geometry basics: rays, boxes, orthonormal frames, transforms, and the
//! robust origin offset for spawned rays.

pub mod aabb;
pub mod frame;
pub mod offset;
pub mod ray;
pub mod transform;

pub use aabb::Aabb;
pub use frame::Frame;
pub use ray::Ray;
pub use transform::Transform;
