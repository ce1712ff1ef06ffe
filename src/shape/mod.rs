//! Leaf primitives, one file each: the intersection and surface code of
//! each shape in its own object space (a transformed sphere is still an
//! exact sphere). They know nothing of scenes or BVHs and import only
//! the math layer; the geometry layer puts them together.
//!
//! Traversal needs only `t` and a little bookkeeping; the full surface
//! (point, error bound, normals) is computed once, for the closest hit only.

pub mod cylinder;
pub mod disk;
pub mod plane;
pub mod plane_lanes;
pub mod rect;
pub mod sphere;
pub mod triangle;
pub mod triangle_lanes;
