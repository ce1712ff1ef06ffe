//! Primitives, one file each. Analytic shapes live in their own object space
//! (a transformed sphere is still an exact sphere); triangles are baked into
//! world space.
//!
//! Traversal needs only `t` and a little bookkeeping ([`PrimHit`]); the full
//! [`Surface`] (point, error bound, normals) is computed once, for the
//! closest hit only.

pub mod csg;
pub mod cylinder;
pub mod disk;
pub mod plane;
pub mod rect;
pub mod sphere;
pub mod triangle;
pub mod triangle8;

use glam::Vec3;

/// What traversal reports for the closest hit so far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrimHit {
    pub t: f32,
    /// Global primitive id (triangles first, then analytic shapes).
    pub prim: u32,
    /// Barycentrics of v1 and v2 for triangles; shape-specific otherwise.
    pub u: f32,
    pub v: f32,
    /// Which part of a shape was hit (a cylinder cap, a CSG operand); for a
    /// scene triangle, the BVH leaf slot that stores its vertices.
    pub part: u32,
}

/// The local geometry at a hit, in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub p: Vec3,
    /// Conservative per-axis bound on the rounding error of `p`.
    pub p_error: Vec3,
    /// Unit geometric normal, pointing out of the solid (or along the
    /// triangle's winding for open surfaces).
    pub geometric_normal: Vec3,
    /// Unit shading normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    pub material: u32,
}
