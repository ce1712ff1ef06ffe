//! Which rays of a stream walk the tree as bundles ([`crate::accel::bundle`]).
//!
//! A stream is read in spans of [`SPAN`] rays. A span whose rays are
//! alike, all from close origins (a camera's rays) or all in close
//! directions (the shadow rays of neighbouring pixels' hits towards one
//! light), walks as bundles of up to [`BUNDLE_SIZE`] rays. Alike rays
//! share much of their walks, and in a bundle each node on the shared
//! part is read once for all of them. A bundle walks the rays of each
//! direction octant on their own, so a span from many origins is first
//! sorted by octant, as Embree's stream API sorts its rays (its
//! `rtcOccluded1M`; Tsakok 2009, "Faster Incoherent Rays: Multi-BVH Ray
//! Stream Tracing"): its shadow rays change octant from one pixel to the
//! next. A span from one origin keeps its order, since a camera's rays
//! change octant only where the image crosses an axis. The spans whose
//! rays are not alike stay in order, and consecutive ones go on together,
//! so that narrow rays still walk as packets and the rest keep several
//! walks in flight.
//!
//! Rays that are not alike part too soon for a bundle to pay, and sorting
//! a camera's rays by octant costs more than it saves (docs/embree.md,
//! "Bundles").

use super::Geometry;
use crate::accel::bundle::{octant, BUNDLE_MAX_BYTES, BUNDLE_SIZE};
use crate::math::Ray;
use glam::{Vec3, Vec3A};
use std::ops::Range;

/// Rays a span sorts into bundles: Embree's stream API takes its rays in
/// chunks of this size in `tools/embree`, and so does `strata trace`.
pub const SPAN: usize = 256;

/// A span's origins are close together when the diagonal of their box
/// is at most this fraction of the diagonal of the tree's box: a pinhole
/// camera's rays (one point) and a thin lens's (a lens much smaller than
/// the scene) are; random rays, whose origins span the scene's box and
/// more, are not.
pub const CLOSE_ORIGINS: f32 = 1.0 / 8.0;

/// Or a span's directions are close together when the diagonal of the
/// box of their unit vectors is at most this: rays of every direction
/// spread over 3.4 (the diagonal of the cube around the unit sphere), the
/// renderer's shadow rays over 0.62 (median span; docs/embree.md,
/// "Bundles", has the sweep that chose the bound).
pub const CLOSE_DIRECTIONS: f32 = 2.0;

/// A part of a stream, in the order [`Geometry::split_stream`] gives them.
pub enum StreamPart<'a> {
    /// Consecutive rays that are not alike, traced as packets or alone.
    Unlike(Range<usize>),
    /// Up to [`BUNDLE_SIZE`] consecutive rays walked as one bundle.
    Bundle(Range<usize>),
    /// The indices of up to [`BUNDLE_SIZE`] rays of one span, sorted by
    /// direction octant and in stream order within one, walked as one
    /// bundle.
    Sorted(&'a [u32]),
}

/// True where the `count` points `point(k)` lie within `reach` of each
/// other: the diagonal of their box. (The box ignores NaN coordinates; so does this test,
/// which only chooses how rays travel, never their answers.) Four boxes
/// grow side by side, so that the minima and maxima are four chains, not
/// one, and the test stops after the first sixteen points whose box
/// reaches too far (the first sixteen random rays almost always do).
fn within(count: usize, point: impl Fn(usize) -> Vec3, reach: f32) -> bool {
    let mut lo = [Vec3A::INFINITY; 4];
    let mut hi = [Vec3A::NEG_INFINITY; 4];
    for first in (0..count).step_by(16) {
        for k in first..(first + 16).min(count) {
            let p = Vec3A::from(point(k));
            lo[k % 4] = lo[k % 4].min(p);
            hi[k % 4] = hi[k % 4].max(p);
        }
        let low = lo[0].min(lo[1]).min(lo[2].min(lo[3]));
        let high = hi[0].max(hi[1]).max(hi[2].max(hi[3]));
        if (high - low).length() > reach {
            return false;
        }
    }
    true
}

/// True where the rays of a span are alike enough to walk as bundles:
/// their origins lie within `reach` of each other, or their directions
/// within [`CLOSE_DIRECTIONS`]. A direction is made a unit vector only
/// when the test reaches it.
fn alike(rays: &[Ray], reach: f32) -> bool {
    within(rays.len(), |k| rays[k].origin, reach)
        || within(
            rays.len(),
            |k| rays[k].direction.normalize_or_zero(),
            CLOSE_DIRECTIONS,
        )
}

impl Geometry {
    /// Calls `visit` with the parts of a stream of rays: every ray in
    /// exactly one part, unlike rays in stream order, and each span of alike
    /// rays as bundles ([module docs](self)) where the tree is small
    /// enough for them to pay ([`BUNDLE_MAX_BYTES`]).
    pub fn split_stream(&self, rays: &[Ray], mut visit: impl FnMut(StreamPart)) {
        if self.traversal_bytes() > BUNDLE_MAX_BYTES || self.bvh.is_empty() {
            visit(StreamPart::Unlike(0..rays.len()));
            return;
        }
        let bounds = &self.bvh.bounds;
        let reach = (bounds.max - bounds.min).length() * CLOSE_ORIGINS;
        let mut unlike_from = 0;
        let mut octants = [0u8; SPAN];
        let mut sorted = [0u32; SPAN];
        for start in (0..rays.len()).step_by(SPAN) {
            let end = (start + SPAN).min(rays.len());
            let span = &rays[start..end];
            // Without branches, so that the rays' first loads (misses, in
            // a long stream) overlap.
            let first_origin = span[0].origin;
            let one_origin = span.iter().fold(true, |same, r| {
                let p = r.origin;
                same & (p.x == first_origin.x) & (p.y == first_origin.y) & (p.z == first_origin.z)
            });
            if !one_origin && !alike(span, reach) {
                continue;
            }
            if unlike_from < start {
                visit(StreamPart::Unlike(unlike_from..start));
            }
            unlike_from = end;
            if one_origin {
                // In stream order (module docs).
                for first in (start..end).step_by(BUNDLE_SIZE) {
                    visit(StreamPart::Bundle(first..(first + BUNDLE_SIZE).min(end)));
                }
                continue;
            }
            // A counting sort by octant keeps each octant's rays in order.
            let mut first = [0usize; 9];
            for (o, r) in octants.iter_mut().zip(span) {
                *o = octant(r) as u8;
                first[*o as usize + 1] += 1;
            }
            for o in 0..8 {
                first[o + 1] += first[o];
            }
            let mut next = first;
            for (k, &o) in octants[..span.len()].iter().enumerate() {
                sorted[next[o as usize]] = (start + k) as u32;
                next[o as usize] += 1;
            }
            // A bundle may hold the end of one octant's rays and the start
            // of the next: a span then makes as few bundles as it can.
            for ids in sorted[..span.len()].chunks(BUNDLE_SIZE) {
                visit(StreamPart::Sorted(ids));
            }
        }
        if unlike_from < rays.len() {
            visit(StreamPart::Unlike(unlike_from..rays.len()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_measures_the_box_diagonal() {
        let points = [Vec3::ZERO, Vec3::new(3.0, 4.0, 0.0)];
        assert!(within(2, |k| points[k], 5.0));
        assert!(!within(2, |k| points[k], 4.99));
        assert!(within(1, |k| points[k], 0.0));
        // The last of 40 points, past the first sixteen, decides.
        let mut many: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(i as f32 * 0.1, 0.0, 0.0))
            .collect();
        assert!(within(40, |k| many[k], 3.9));
        many[39].y = 5.0;
        assert!(!within(40, |k| many[k], 3.9 * 1.5));
    }
}
