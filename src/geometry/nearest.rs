//! The point of a mesh nearest to a given point (`closest_point` of the
//! Python package): [`crate::accel`]'s best-first walk over the scene's
//! BVH, whose leaf test finds each triangle's nearest point
//! ([`closest_point_on_triangle`]). A mesh query: analytic shapes and
//! planes are not candidates.
//!
//! Through an instance the distances are world distances, which an
//! object-space distance is not under a non-uniform or sheared map: each
//! candidate triangle is moved to world space as a copy would hold it
//! and measured there (`placed`), so the answer is the copies' bit for
//! bit; only the pruning is done in object space, with a bound that no
//! world distance can beat (`placed::ObjectBound`).

mod placed;

use super::Geometry;
use crate::accel::NearestQueue;
use crate::math::lanes::mask_lanes;
use crate::shape::triangle_lanes::TriangleBlock;
use glam::Vec3;
use wide::f32x8;

/// The nearest point of a mesh to a query point: where it is, how far, and
/// on which triangle (its primitive id, as [`super::Crossing::prim`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    pub point: Vec3,
    pub distance: f32,
    pub prim: u32,
    /// The triangle's leaf slot, as [`super::Crossing::part`]: an
    /// instance's triangle is in its prototype's leaves (read it through
    /// [`Geometry::flat_prim`] or [`Geometry::world_triangle`]).
    pub part: u32,
}

/// The best candidate so far: the least (squared distance, primitive id,
/// triangle id within an instance's prototype), the order of the ids of a
/// mesh of the copies ([`Geometry::flat_prim`]).
#[derive(Debug, Clone, Copy)]
struct Best {
    d2: f32,
    prim: u32,
    within: u32,
    part: u32,
    point: Vec3,
}

impl Best {
    /// Keeps the candidate at `point` (squared distance `d2`) if it is
    /// nearer, or the first within `max_distance`.
    #[inline(always)]
    fn offer(best: &mut Option<Best>, candidate: Best, max_distance: f32) {
        let nearer = match best {
            Some(b) => (candidate.d2, candidate.prim, candidate.within) < (b.d2, b.prim, b.within),
            None => candidate.d2.sqrt() <= max_distance,
        };
        if nearer {
            *best = Some(candidate);
        }
    }
}

/// Below this ratio |ab × ac|² / (|ab|²·|ac|²), the squared sine of the
/// triangle's angle at `a`, a triangle is taken as degenerate and its
/// nearest point sought on its three edges: f32 rounding alone makes the
/// cross product's squared length uncertain by about 12·(ε/2)² of the
/// product, so a plane computed below 64·ε² would be noise. The edges of
/// such a sliver are within about a millionth of its size of all of it.
const DEGENERATE: f32 = 64.0 * f32::EPSILON * f32::EPSILON;

/// The point of triangle `v` nearest to `p`, by the Voronoi regions of
/// its vertices, edges and face: Ericson 2005, "Real-Time Collision
/// Detection", §5.1.5. Each region's test reads dot products already
/// made for the previous ones.
///
/// A degenerate triangle (a segment or a point, or a sliver whose plane
/// f32 cannot tell, `DEGENERATE`) answers the nearest point of its three
/// edges, so its answer is still a point of it.
pub fn closest_point_on_triangle(p: Vec3, v: &[Vec3; 3]) -> Vec3 {
    let [a, b, c] = *v;
    // The regions' tests multiply four coordinates (`vc = d1·d4 − d3·d2`),
    // which overflow f32 for a triangle of size 1e9 and underflow for one
    // of size 1e-10, silently choosing a wrong region. They are made on
    // the differences scaled by a power of two that brings the largest
    // near 1: exact, so every sign and ratio is the unscaled one wherever
    // that did not overflow or underflow; the point is then made from
    // the unscaled differences.
    let (ab, ac) = (b - a, c - a);
    let s = unit_scale(ab.abs().max(ac.abs()).max((p - a).abs()).max_element());
    let region = face_region([ab, ac, p - a, p - b, p - c].map(|d| d * s));
    match region {
        Region::Edges => closest_point_on_edges(p, v),
        Region::Vertex(k) => v[k],
        Region::Edge(from, to, t) => v[from] + (v[to] - v[from]) * t,
        Region::Face(wb, wc) => a + ab * wb + ac * wc,
        Region::Plane(n, k) => p - n * k / s,
    }
}

/// The power of two that brings `m` (a finite magnitude, or 0) into
/// [1, 2), within f32's normal range: 1 for 0 or a value not finite.
fn unit_scale(m: f32) -> f32 {
    if !(m.is_finite() && m > 0.0) {
        return 1.0;
    }
    let exponent = ((m.to_bits() >> 23) as i32 - 127).clamp(-126, 126);
    f32::from_bits(((127 - exponent) as u32) << 23)
}

/// Which part of a triangle holds the point nearest to `p`, and where on
/// it: what [`closest_point_on_triangle`] makes the point from.
enum Region {
    /// Degenerate: the nearest point of the three edges.
    Edges,
    /// Corner `k`.
    Vertex(usize),
    /// Edge from corner `from` to `to`, at `t` along it.
    Edge(usize, usize, f32),
    /// The face, at barycentric weights of `b` and `c`.
    Face(f32, f32),
    /// `p`'s projection on the plane: `p − n·k` (the normal and the
    /// factor of the scaled triangle).
    Plane(Vec3, f32),
}

/// Ericson's region tests on a triangle abc for a point p, given as the
/// differences `[ab, ac, ap, bp, cp]` (Ericson 2005, §5.1.5; each
/// region's test reads dot products already made for the previous ones).
fn face_region(differences: [Vec3; 5]) -> Region {
    let [ab, ac, ap, bp, cp] = differences;
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    if !(n2 > DEGENERATE * ab.length_squared() * ac.length_squared()) {
        return Region::Edges;
    }
    // Vertex a's region.
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return Region::Vertex(0);
    }
    // Vertex b's region.
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return Region::Vertex(1);
    }
    // Edge ab's region. Its weight's denominator d1 − d3 is |ab|² > 0.
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return Region::Edge(0, 1, d1 / (d1 - d3));
    }
    // Vertex c's region.
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return Region::Vertex(2);
    }
    // Edge ac's region.
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return Region::Edge(0, 2, d2 / (d2 - d6));
    }
    // Edge bc's region.
    let va = d3 * d6 - d5 * d4;
    let (e4, e5) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e4 >= 0.0 && e5 >= 0.0 {
        return Region::Edge(1, 2, e4 / (e4 + e5));
    }
    // The face's, from its barycentric weights, so that the point lies in
    // the triangle's span to rounding of its own coordinates. Far from a
    // small triangle the weights cancel; where their sum has lost its
    // sign, p's projection onto the plane.
    let sum = va + vb + vc;
    if sum > 0.0 {
        return Region::Face(vb / sum, vc / sum);
    }
    Region::Plane(n, n.dot(ap) / n2)
}

/// The point of the edges of triangle `v` nearest to `p` (the first edge
/// of ab, bc, ca on a tie).
fn closest_point_on_edges(p: Vec3, v: &[Vec3; 3]) -> Vec3 {
    let mut best = closest_point_on_segment(p, v[0], v[1]);
    let mut best_d2 = (p - best).length_squared();
    for (a, b) in [(v[1], v[2]), (v[2], v[0])] {
        let q = closest_point_on_segment(p, a, b);
        let d2 = (p - q).length_squared();
        if d2 < best_d2 {
            (best, best_d2) = (q, d2);
        }
    }
    best
}

/// The point of segment ab nearest to `p` (`a` where the segment has no
/// length).
fn closest_point_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if !(len2 > 0.0) {
        return a;
    }
    let t = (ab.dot(p - a) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// The lanes of `block` whose triangle's bounding box lies within squared
/// distance `bound` of `p`, in one 8-wide test: the others a leaf need
/// not test, as the walk skips boxes. (Padding lanes answer anything;
/// the caller masks them.)
#[inline(always)]
pub(super) fn boxes_within(block: &TriangleBlock, p: Vec3, bound: f32) -> u32 {
    let mut d2 = f32x8::ZERO;
    for axis in 0..3 {
        let [a, b, c] = [0, 1, 2].map(|k| f32x8::from(block.v[3 * k + axis]));
        let p = f32x8::splat(p[axis]);
        let below = a.fast_min(b).fast_min(c) - p;
        let above = p - a.fast_max(b).fast_max(c);
        let d = below.fast_max(above).fast_max(f32x8::ZERO);
        d2 += d * d;
    }
    d2.simd_le(f32x8::splat(bound)).to_bitmask()
}

impl Geometry {
    /// The point of any triangle nearest to `point`, if one is no farther
    /// than `max_distance` (`f32::INFINITY`: no limit); `None` for an
    /// empty mesh, nothing that close, or a point or limit that is not a
    /// number. Equally near triangles go to the smallest primitive id
    /// (of an instance's, the smallest of its prototype's ids: the order
    /// of [`Geometry::flat_prim`]). Triangles only, the world's and the
    /// instances' (in world distances): analytic shapes and planes are
    /// not candidates.
    ///
    /// A best-first walk of the BVH ([`crate::accel::Bvh8::nearest`]),
    /// each triangle's point by [`closest_point_on_triangle`] where its
    /// bounding box is within the walk's bound (most of an opened leaf's
    /// triangles are not; the test is eight boxes at once): the answer
    /// is the least (squared distance, primitive id) that a test of every
    /// triangle would find, bit for bit.
    pub fn nearest(&self, point: Vec3, max_distance: f32) -> Option<Nearest> {
        let empty = self.triangle_count == 0 && self.instances.is_empty();
        if empty || !point.is_finite() || !(max_distance >= 0.0) {
            return None;
        }
        let reach = self.reach(point);
        let instances = self.first_instance()..self.primitive_count() as u32;
        let mut best: Option<Best> = None;
        let mut queue = NearestQueue::new();
        self.bvh.nearest(
            point,
            reach(max_distance),
            &self.leaf_blocks,
            |start, count, bound| {
                let (b, lanes) = Self::leaf_lanes(start, count);
                let block = &self.leaf_blocks[b];
                if self.triangle_count > 0 {
                    for lane in mask_lanes(boxes_within(block, point, bound) & lanes) {
                        let prim = block.id[lane];
                        if prim >= self.triangle_count {
                            continue;
                        }
                        let q = closest_point_on_triangle(point, &block.triangle(lane));
                        let candidate = Best {
                            d2: (point - q).length_squared(),
                            prim,
                            within: 0,
                            part: Self::slot(b, lane),
                            point: q,
                        };
                        Best::offer(&mut best, candidate, max_distance);
                    }
                }
                if !self.instances.is_empty() {
                    for lane in mask_lanes(lanes) {
                        let id = block.id[lane];
                        if instances.contains(&id) {
                            let bound = best.map_or(bound, |c| reach(c.d2.sqrt()));
                            self.instance_nearest(
                                id,
                                point,
                                bound,
                                &reach,
                                max_distance,
                                &mut best,
                                &mut queue,
                            );
                        }
                    }
                }
                best.map_or(bound, |c| reach(c.d2.sqrt()))
            },
        );
        best.map(|c| Nearest {
            point: c.point,
            distance: c.d2.sqrt(),
            prim: c.prim,
            part: c.part,
        })
    }

    /// The squared box distance the walk must still open for a candidate
    /// at distance `d` from `point`: `d` widened by the rounding of the
    /// box distances and of a triangle's nearest point (a few ε of the
    /// largest coordinate in play), so no box that may hold a triangle at
    /// the same computed distance (a tie) or a slightly nearer one is
    /// skipped.
    fn reach(&self, point: Vec3) -> impl Fn(f32) -> f32 {
        let bounds = &self.bvh.bounds;
        let scale = point
            .abs()
            .max(bounds.min.abs())
            .max(bounds.max.abs())
            .max_element();
        let slack = 16.0 * f32::EPSILON * scale;
        let grow = 1.0 + 8.0 * f32::EPSILON;
        move |d: f32| {
            let r = d * grow + slack;
            r * r * grow
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// The nearest of many points of the triangle (a fine grid of
    /// barycentric weights, its edges included): no answer may be farther
    /// than it, and the answer must lie on the triangle.
    fn check_against_samples(p: Vec3, v: &[Vec3; 3]) {
        let q = closest_point_on_triangle(p, v);
        let d = (p - q).length();
        let size = (v[1] - v[0]).length().max((v[2] - v[0]).length());
        let tol = 1e-5 * (size + (p - v[0]).length());
        let n = 60;
        let mut sampled = f32::INFINITY;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, w) = (i as f32 / n as f32, j as f32 / n as f32);
                let s = v[0] + (v[1] - v[0]) * u + (v[2] - v[0]) * w;
                sampled = sampled.min((p - s).length());
            }
        }
        assert!(d <= sampled + tol, "{p} {v:?}: {d} > sampled {sampled}");
        // On the triangle: its distance to the triangle's plane is nil and
        // the point is within the triangle's barycentric range.
        let nrm = (v[1] - v[0]).cross(v[2] - v[0]);
        if nrm.length_squared() > 0.0 {
            let off = nrm.normalize().dot(q - v[0]).abs();
            assert!(off <= tol, "{q} is {off} off the plane");
        }
    }

    #[test]
    fn nearest_points_of_random_triangles_beat_every_sample_of_them() {
        let mut rng = seeded(5);
        for _ in 0..3000 {
            let v = [rng.cube(2.0), rng.cube(2.0), rng.cube(2.0)];
            check_against_samples(rng.cube(6.0), &v);
        }
    }

    /// The same triangles and points scaled by powers of two from 2⁻⁶⁰
    /// to 2⁶⁰ (1e-18 to 1e18) answer the scaled point bit for bit: the
    /// regions' products of four coordinates overflowed f32 from about
    /// 1e9 and underflowed below 1e-10, and chose wrong regions there
    /// (the Python package's `closest_point` on a mesh scaled by 1e10 was
    /// off by up to 270%).
    #[test]
    fn the_nearest_point_scales_with_the_triangle() {
        let mut rng = seeded(9);
        for round in 0..2000 {
            let v = [rng.cube(2.0), rng.cube(2.0), rng.cube(2.0)];
            let p = rng.cube(6.0);
            let q = closest_point_on_triangle(p, &v);
            for k in (-60..=60).step_by(4) {
                let s = 2f32.powi(k);
                let scaled = closest_point_on_triangle(p * s, &v.map(|x| x * s));
                assert_eq!(
                    scaled.to_array().map(f32::to_bits),
                    (q * s).to_array().map(f32::to_bits),
                    "round {round}, scale 2^{k}"
                );
            }
        }
    }

    #[test]
    fn each_region_answers_its_analytic_point() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let cases = [
            (Vec3::new(-1.0, -1.0, 0.5), Vec3::ZERO),
            (Vec3::new(2.0, -0.5, 0.0), Vec3::X),
            (Vec3::new(-0.5, 2.0, -1.0), Vec3::Y),
            (Vec3::new(0.5, -1.0, 3.0), Vec3::new(0.5, 0.0, 0.0)),
            (Vec3::new(-2.0, 0.25, 0.0), Vec3::new(0.0, 0.25, 0.0)),
            (Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0)),
            (Vec3::new(0.25, 0.25, -7.0), Vec3::new(0.25, 0.25, 0.0)),
        ];
        for (p, want) in cases {
            let q = closest_point_on_triangle(p, &v);
            assert!((q - want).length() < 1e-6, "{p}: {q}, not {want}");
        }
    }

    #[test]
    fn degenerate_triangles_answer_a_point_of_their_segments() {
        let mut rng = seeded(9);
        for i in 0..2000 {
            let (a, b) = (rng.cube(2.0), rng.cube(2.0));
            let v = match i % 4 {
                0 => [a, b, a + (b - a) * rng.unit()],
                1 => [a, a, b],
                2 => [a, a, a],
                _ => [a + (b - a) * 2.0, a, b],
            };
            let p = rng.cube(6.0);
            let q = closest_point_on_triangle(p, &v);
            assert!(q.is_finite(), "{v:?}");
            // The farthest-apart pair of corners spans the segment.
            let (s0, s1) = [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])]
                .into_iter()
                .max_by(|x, y| (x.0 - x.1).length().total_cmp(&(y.0 - y.1).length()))
                .unwrap();
            let want = closest_point_on_segment(p, s0, s1);
            assert!(
                ((p - q).length() - (p - want).length()).abs() < 1e-5,
                "{v:?} {p}: {q} vs {want}"
            );
        }
    }
}
