//! What traversal reports for a hit, and the order that decides which of
//! two hits is the closer.

use crate::math::ray::hit_before;
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

/// Where the interval a candidate is tested in ends once `best` is known:
/// just past `best.t`, so that a candidate at exactly the same distance
/// is seen and [`closer`] can break the tie; `tmax` while there is none.
#[inline(always)]
pub fn tie_end(tmax: f32, best: Option<&PrimHit>) -> f32 {
    match best {
        Some(b) => b.t.next_up(),
        None => tmax,
    }
}

/// The ray a candidate is tested with once `best` is known: `ray` ending
/// at [`tie_end`]. A branch, not a select: a walk's first leaf has no
/// best yet, and a select would compute `next_up` for it too.
#[inline(always)]
pub fn tie_ray(ray: &Ray, best: Option<&PrimHit>) -> Ray {
    match best {
        Some(_) => Ray {
            tmax: tie_end(ray.tmax, best),
            ..*ray
        },
        None => *ray,
    }
}

/// The closest-hit order: smaller t, and on equal t (a ray through an edge
/// shared by two triangles) the smaller primitive id
/// ([`crate::math::ray::hit_before`], which the 8-wide triangle test
/// decides by too). A total order, so the answer does not depend on the
/// order the traversal visits leaves in: single rays and packets return
/// identical hits.
#[inline(always)]
pub fn closer(h: &PrimHit, best: Option<&PrimHit>) -> bool {
    match best {
        Some(b) => hit_before(h.t, h.prim, b.t, b.prim),
        None => true,
    }
}

/// Keeps `hit` in `best` if it is [`closer`], and then ends the interval
/// later candidates are tested in, `end`, at its [`tie_end`]: the step of
/// a leaf test that tries its candidates one by one. True if it kept it.
#[inline(always)]
pub fn keep_tied(best: &mut Option<PrimHit>, end: &mut f32, hit: PrimHit) -> bool {
    let kept = closer(&hit, best.as_ref());
    if kept {
        *end = tie_end(*end, Some(&hit));
        *best = Some(hit);
    }
    kept
}
