//! What traversal reports for a hit, and the order that decides which of
//! two hits is the closer.

use crate::math::Ray;

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

/// The ray a candidate is tested with once `best` is known: its interval
/// includes `best.t` itself, so a candidate at exactly the same distance is
/// seen and [`closer`] can break the tie.
#[inline(always)]
pub fn tie_ray(ray: &Ray, best: Option<&PrimHit>) -> Ray {
    match best {
        Some(b) => Ray {
            tmax: b.t.next_up(),
            ..*ray
        },
        None => *ray,
    }
}

/// The closest-hit order: smaller t, and on equal t (a ray through an edge
/// shared by two triangles) the smaller primitive id. A total order, so the
/// answer does not depend on the order the traversal visits leaves in:
/// single rays and packets return identical hits.
#[inline(always)]
pub fn closer(h: &PrimHit, best: Option<&PrimHit>) -> bool {
    match best {
        Some(b) => h.t < b.t || (h.t == b.t && h.prim < b.prim),
        None => true,
    }
}
