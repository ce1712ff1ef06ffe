//! What a walk asks at a node: its *node test*, which of the node's eight
//! children to enter and how far each one is, from their boxes alone.
//!
//! The walks (depth first, nearest first or in any order: `walk`; best
//! first: `nearest`) are generic over their node test as over their
//! query, and monomorphised, as obvhs's `traverse!` takes both: a ray's
//! slab test (`RayBoxes`), a whole line's (`LineBoxes`) and the
//! distance to a point (`PointBoxes`) here; geometry's slab grown by an
//! instance's rounding and its lower bound of world distance there. A
//! test reads the children's boxes through [`ChildBoxes`] and nothing
//! else of the node, so a test outside `accel` needs no node layout.
//!
//! Box tests for rays are made conservative by widening the far distance
//! by 1 + 2γ(3) (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2)), so a
//! ray that grazes a box corner is never culled before its triangle test.
//! Zero direction components are replaced by ±f32::MAX reciprocals so no
//! slab computes 0·∞ = NaN.

use crate::math::offset::gamma;
use crate::math::Ray;
use glam::{Vec3, Vec3A};
use wide::f32x8;

/// The factor far distances are widened by, 1 + 2γ(3) (Ize 2013).
pub(crate) const WIDEN: f32 = 1.0 + 2.0 * gamma(3);

/// A node's eight child boxes, read only, one 8-wide register per side
/// and axis. An empty slot's box is inverted and infinite (min +∞, max
/// −∞).
#[derive(Clone, Copy)]
pub struct ChildBoxes<'n> {
    /// Row 2·axis holds the minima, 2·axis + 1 the maxima.
    rows: &'n [[f32; 8]; 6],
}

impl<'n> ChildBoxes<'n> {
    #[inline(always)]
    pub(super) fn new(rows: &'n [[f32; 8]; 6]) -> Self {
        Self { rows }
    }

    /// The eight boxes' minima on `axis` (0, 1, 2: x, y, z).
    #[inline(always)]
    pub fn lo(&self, axis: usize) -> f32x8 {
        self.row(2 * axis)
    }

    /// The eight boxes' maxima on `axis`.
    #[inline(always)]
    pub fn hi(&self, axis: usize) -> f32x8 {
        self.row(2 * axis + 1)
    }

    /// Row `row`: the minima on axis `row / 2` if it is even, else the
    /// maxima, for a test that picks its side by a sign it computed once.
    #[inline(always)]
    fn row(&self, row: usize) -> f32x8 {
        f32x8::from(self.rows[row])
    }
}

/// A test of a node's eight children for a walk.
///
/// A depth-first walk needs its test to reject an empty slot, which every
/// slab test does (its entry is +∞, or NaN once widened); the best-first
/// walk skips empty slots itself, since a distance of +∞ is within an
/// unbounded reach.
pub trait NodeTest {
    /// How far each child is (a ray's entry distance, a squared distance
    /// to a point: the key the walk orders children by), and the mask of
    /// the children to enter within `reach` (a ray's end, a squared
    /// distance).
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32);

    /// The largest key a deferred child may have and still be visited
    /// once the walk's reach has become `reach`: the test's own widening
    /// of its far end, so that a child the test entered at that reach is
    /// not culled when it is popped.
    #[inline(always)]
    fn widened(&self, reach: f32) -> f32 {
        reach
    }
}

/// A ray's slab test: the values every node test of one ray reuses.
#[derive(Clone, Copy)]
pub(crate) struct RayBoxes {
    origin: [f32x8; 3],
    /// Minus the reciprocal direction. A slab is computed as
    /// (origin − bound)·(−1/d): the value of (bound − origin)·(1/d), since
    /// negation is exact (only a zero's sign may differ), with the bound as
    /// the subtraction's second operand, which x86 reads straight from
    /// memory (six fewer loads per node test).
    neg_inv: [f32x8; 3],
    near: [usize; 3],
    far: [usize; 3],
    /// The ray's start, which no hit moves; its end is the walk's reach.
    tmin: f32,
}

impl RayBoxes {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        // The whole ray in one register: [o, d, tmin, tmax]. Lanes 3 to 5
        // become the reciprocal direction, with zero components replaced
        // by ±f32::MAX (the zero's sign) so no slab computes 0·∞ = NaN
        // (the other lanes' quotients are unused).
        let c = f32x8::from(ray.components());
        let zero_d = c.simd_eq(f32x8::ZERO);
        let signed_max = (c & f32x8::splat(-0.0)) | f32x8::splat(f32::MAX);
        let inv = zero_d.select(signed_max, f32x8::splat(1.0) / c);
        // Row 2·axis holds the minima and 2·axis + 1 the maxima: a negative
        // direction (the reciprocal keeps its sign) enters through the maximum.
        let neg = inv.to_bitmask() as usize >> 3;
        let inv = inv.to_array();
        let near = [neg & 1, 2 | (neg >> 1 & 1), 4 | (neg >> 2 & 1)];
        let far = near.map(|row| row ^ 1);
        let c = c.to_array();
        Self {
            origin: [c[0], c[1], c[2]].map(f32x8::splat),
            neg_inv: [-inv[3], -inv[4], -inv[5]].map(f32x8::splat),
            near,
            far,
            tmin: ray.tmin,
        }
    }

    /// The eight children's entry and exit distances, clipped to
    /// [tmin, tmax].
    #[inline(always)]
    fn slabs(&self, boxes: ChildBoxes<'_>, tmax: f32) -> (f32x8, f32x8) {
        let slab =
            |axis: usize, side: usize| (self.origin[axis] - boxes.row(side)) * self.neg_inv[axis];
        // No slab is NaN (finite bounds or ±∞ for empty slots, finite
        // nonzero reciprocals), so the plain min/max instructions suffice;
        // `f32x8::max` would add a NaN check and a blend to each.
        let tn = slab(0, self.near[0])
            .fast_max(slab(1, self.near[1]))
            .fast_max(slab(2, self.near[2]).fast_max(f32x8::splat(self.tmin)));
        let tf = slab(0, self.far[0])
            .fast_min(slab(1, self.far[1]))
            .fast_min(slab(2, self.far[2]).fast_min(f32x8::splat(tmax)));
        (tn, tf)
    }
}

impl NodeTest for RayBoxes {
    /// Entry distances and the children the ray may enter before `reach`,
    /// its end.
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        let (tn, tf) = self.slabs(boxes, reach);
        let tf = tf * f32x8::splat(WIDEN);
        (tn, tn.simd_le(tf).to_bitmask())
    }

    #[inline(always)]
    fn widened(&self, reach: f32) -> f32 {
        reach * WIDEN
    }
}

/// A ray's slab test as the fastest one-ray kernels make it (Embree's
/// one-ray BVH8 node test): the near and far rows of each axis chosen once
/// per ray, and each slab one fused multiply-add, bound·(1/d) − o·(1/d),
/// with o·(1/d) made once per ray. What a lone walk asks at a node.
///
/// Conservative as [`RayBoxes`] is, by the same widening of the far end:
/// o·(1/d) is rounded once, per ray, with an error of at most u·|o/d|
/// (u = 2⁻²⁴), so the near plane's addend is moved down by 4u·|o/d| and
/// the far plane's up by as much, which leaves each slab with relative
/// errors alone (the reciprocal's and the multiply-add's rounding, within
/// γ(2)), and those 1 + 2γ(3) covers. A box the ray meets is never culled,
/// so every hit is the one [`RayBoxes`] finds; a box is sometimes entered
/// that the other test culls, and the other way round, which the tie rule
/// makes harmless (`super::hit`).
///
/// A reciprocal beyond 2¹⁰⁰/max(|o|, 1) (a zero or nearly zero direction
/// component) is clamped there with the direction's sign, so o·(1/d) stays
/// finite: over any distance below 2⁷⁶ such a ray moves less than a
/// rounding step of its origin on that axis, so it is tested as parallel
/// to it (a slab of ±2⁷⁶ or more, or everything when the origin lies in it).
///
/// Without hardware FMA (the portable build) a multiply-add would round
/// twice, which a per-ray addend cannot cover: the slab is then
/// (bound − o)·(1/d), [`RayBoxes`]'s operations.
#[derive(Clone, Copy)]
pub(crate) struct RayPlanes {
    inv: [f32x8; 3],
    /// −o·(1/d) moved down (near) and up (far) by its rounding bound.
    #[cfg(target_feature = "fma")]
    add: [[f32x8; 3]; 2],
    #[cfg(not(target_feature = "fma"))]
    origin: [f32x8; 3],
    /// 1 where the direction is negative on the axis: its near plane is the
    /// box's maximum (row 2·axis + 1).
    flip: [usize; 3],
    tmin: f32,
}

/// The largest |o·(1/d)| [`RayPlanes`] lets a ray have: 2¹⁰⁰.
const PLANE_LIMIT: f32 = (1u128 << 100) as f32;

impl RayPlanes {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        // The three axes at once in SSE lanes: a lone ray pays this setup
        // for every walk, as many instructions as a few node tests.
        let o = Vec3A::from(ray.origin);
        let d = Vec3A::from(ray.direction);
        let scale = o.abs().max(Vec3A::ONE);
        let r = Vec3A::ONE / d;
        // |1/d| beyond 2¹⁰⁰/max(|o|, 1) (an infinite one too): clamped there.
        let clamp = (r * scale).abs().cmpgt(Vec3A::splat(PLANE_LIMIT));
        let inv = Vec3A::select(clamp, (PLANE_LIMIT / scale).copysign(d), r);
        let lanes = |v: Vec3A| v.to_array().map(f32x8::splat);
        #[cfg(target_feature = "fma")]
        let add = {
            let product = o * inv;
            // 4u·|p| bounds the product's rounding, u·|o·(1/d)|, and the
            // rounding of these sums too (the analysis above).
            let err = product.abs() * (4.0 * f32::EPSILON / 2.0);
            [lanes(-product - err), lanes(-product + err)]
        };
        let flip = inv.is_negative_bitmask() as usize;
        Self {
            inv: lanes(inv),
            #[cfg(target_feature = "fma")]
            add,
            #[cfg(not(target_feature = "fma"))]
            origin: lanes(o),
            flip: [flip & 1, flip >> 1 & 1, flip >> 2 & 1],
            tmin: ray.tmin,
        }
    }

    /// The slab of axis `axis` at the boxes' side `side` (0: the near
    /// plane, 1: the far one).
    #[inline(always)]
    fn slab(&self, boxes: &ChildBoxes<'_>, axis: usize, side: usize) -> f32x8 {
        // 2·axis + (0 or 1): within the six rows, no bounds check.
        let row = boxes.row(2 * axis + ((self.flip[axis] ^ side) & 1));
        #[cfg(target_feature = "fma")]
        {
            row.mul_add(self.inv[axis], self.add[side & 1][axis])
        }
        #[cfg(not(target_feature = "fma"))]
        {
            (row - self.origin[axis]) * self.inv[axis]
        }
    }
}

impl NodeTest for RayPlanes {
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        // No slab is NaN (finite bounds or ±∞ for empty slots, finite
        // nonzero reciprocals): plain min and max suffice, as in RayBoxes.
        let tn = self
            .slab(&boxes, 0, 0)
            .fast_max(self.slab(&boxes, 1, 0))
            .fast_max(self.slab(&boxes, 2, 0).fast_max(f32x8::splat(self.tmin)));
        let tf = self
            .slab(&boxes, 0, 1)
            .fast_min(self.slab(&boxes, 1, 1))
            .fast_min(self.slab(&boxes, 2, 1).fast_min(f32x8::splat(reach)));
        let tf = tf * f32x8::splat(WIDEN);
        (tn, tn.simd_le(tf).to_bitmask())
    }

    #[inline(always)]
    fn widened(&self, reach: f32) -> f32 {
        reach * WIDEN
    }
}

/// [`RayBoxes`] for a line that may run through boxes at negative t:
/// both ends are widened by their own magnitude, so a box behind the
/// origin is not culled by rounding either.
#[derive(Clone, Copy)]
pub(crate) struct LineBoxes(RayBoxes);

impl LineBoxes {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        Self(RayBoxes::new(ray))
    }
}

impl NodeTest for LineBoxes {
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        let (tn, tf) = self.0.slabs(boxes, reach);
        let g = f32x8::splat(2.0 * gamma(3));
        (
            tn,
            (tn - g * tn.abs()).simd_le(tf + g * tf.abs()).to_bitmask(),
        )
    }
}

/// The squared distance from a point to each box (0 inside; +∞ for an
/// empty slot), against a squared reach: what the nearest-point walk
/// orders and prunes by.
#[derive(Clone, Copy)]
pub(crate) struct PointBoxes {
    point: [f32x8; 3],
}

impl PointBoxes {
    #[inline(always)]
    pub(crate) fn new(point: Vec3) -> Self {
        Self {
            point: point.to_array().map(f32x8::splat),
        }
    }
}

impl NodeTest for PointBoxes {
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        let mut d2 = f32x8::ZERO;
        for (axis, &p) in self.point.iter().enumerate() {
            let below = boxes.lo(axis) - p;
            let above = p - boxes.hi(axis);
            let d = below.max(above).max(f32x8::ZERO);
            d2 += d * d;
        }
        (d2, d2.simd_le(f32x8::splat(reach)).to_bitmask())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::build::{BuildQuality, Bvh8};
    use super::super::node::Node8;
    use super::super::query::EveryLeaf;
    use super::super::walk::{AnyOrder, NearestFirst};
    use super::super::NearestQueue;
    use super::*;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};
    use std::collections::BTreeSet;

    /// Random boxes, small and large, in the 20-unit cube, and their tree.
    fn boxes_and_tree(seed: u64, n: usize) -> (Vec<Aabb>, Bvh8) {
        let mut rng = seeded(seed);
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| {
                let c = rng.cube(20.0);
                let h = rng.cube(1.0).abs() * if i % 10 == 0 { 4.0 } else { 0.4 };
                Aabb::new(c - h, c + h)
            })
            .collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        (boxes, bvh)
    }

    /// Whether `ray` meets `b` grown by `margin` somewhere in `[tmin, tmax]`,
    /// in f64: the answer every conservative f32 test must not deny (also
    /// geometry's grown slab's tests).
    pub(crate) fn meets_grown(ray: &Ray, b: &Aabb, margin: f32) -> bool {
        let (mut near, mut far) = (ray.tmin as f64, ray.tmax as f64);
        for axis in 0..3 {
            let (o, d) = (ray.origin[axis] as f64, ray.direction[axis] as f64);
            let lo = b.min[axis] as f64 - margin as f64;
            let hi = b.max[axis] as f64 + margin as f64;
            if d == 0.0 {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let (a, c) = ((lo - o) / d, (hi - o) / d);
            near = near.max(a.min(c));
            far = far.min(a.max(c));
        }
        near <= far
    }

    fn meets(ray: &Ray, b: &Aabb) -> bool {
        meets_grown(ray, b, 0.0)
    }

    /// The nearest of `points` to `q` within squared distance `limit`, by
    /// brute force: (squared distance, index), the smaller index on a tie.
    pub(crate) fn brute_nearest(points: &[Vec3], q: Vec3, limit: f32) -> Option<(f32, u32)> {
        (0..points.len())
            .map(|k| ((points[k] - q).length_squared(), k as u32))
            .filter(|&(d2, _)| d2 <= limit)
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
    }

    /// The best-first walk's answer over point primitives (their index is
    /// their id in `bvh`) under `test`, as [`brute_nearest`] gives it, and
    /// how many leaves it opened.
    pub(crate) fn walk_nearest<T: NodeTest>(
        bvh: &Bvh8,
        test: T,
        limit: f32,
        queue: &mut NearestQueue,
        points: &[Vec3],
        q: Vec3,
    ) -> (Option<(f32, u32)>, usize) {
        let mut best: Option<(f32, u32)> = None;
        let mut opened = 0;
        bvh.nearest_by(test, limit, &[] as &[()], queue, |start, count, bound| {
            opened += 1;
            for (_, id) in bvh.leaf_prims(start, count) {
                if id == crate::accel::NO_PRIM {
                    continue;
                }
                let d2 = (points[id as usize] - q).length_squared();
                if d2 <= bound && best.is_none_or(|b| (d2, id) < b) {
                    best = Some((d2, id));
                }
            }
            best.map_or(bound, |b| b.0)
        });
        (best, opened)
    }

    /// The leaves (by start) a walk of `ray` with `test` in `order` reaches.
    fn leaves<T: NodeTest, O: super::super::WalkOrder>(
        bvh: &Bvh8,
        ray: &Ray,
        test: T,
        order: O,
    ) -> BTreeSet<u32> {
        let mut seen = BTreeSet::new();
        let mut every = EveryLeaf(|start, _| assert!(seen.insert(start), "leaf twice"));
        bvh.walk_by(ray, test, order, &[] as &[()], &mut every);
        seen
    }

    /// The order changes which leaf comes first, never which are reached:
    /// the ray's slab test in any order and nearest first reach the same
    /// leaves, each once, and among them every leaf holding a box the ray
    /// meets; the line's test reaches those too, and the boxes behind the
    /// origin that the line meets.
    #[test]
    fn any_order_reaches_what_nearest_first_does_and_every_box_met() {
        let (boxes, bvh) = boxes_and_tree(3, 3000);
        let mut rng = seeded(4);
        let mut met = 0;
        for i in 0..400 {
            // Through the cloud, from outside it or inside.
            let origin = rng.cube(40.0);
            let mut ray = Ray::new(origin, rng.cube(20.0) - origin);
            if i % 4 == 0 {
                ray.direction[i / 4 % 3] = 0.0;
            }
            ray.tmax = if i % 3 == 0 {
                f32::INFINITY
            } else {
                rng.range(0.2, 1.5)
            };
            let nearest = leaves(&bvh, &ray, RayBoxes::new(&ray), NearestFirst);
            let any = leaves(&bvh, &ray, RayBoxes::new(&ray), AnyOrder);
            assert_eq!(any, nearest, "ray {i}");
            let line = Ray {
                tmin: f32::NEG_INFINITY,
                ..ray
            };
            let whole = leaves(&bvh, &line, LineBoxes::new(&line), AnyOrder);
            assert!(whole.is_superset(&nearest), "ray {i}");
            for slot in 0..bvh.prim_ids.len() as u32 {
                let id = bvh.prim_ids[slot as usize];
                if id == crate::accel::NO_PRIM {
                    continue;
                }
                let start = leaf_start(&bvh, slot);
                if meets(&ray, &boxes[id as usize]) {
                    met += 1;
                    assert!(nearest.contains(&start), "ray {i}: box {id} met");
                }
                if meets(&line, &boxes[id as usize]) {
                    assert!(whole.contains(&start), "line {i}: box {id} met");
                }
            }
        }
        assert!(met > 1000, "the rays meet boxes: {met}");
    }

    /// The lone walk's fused test never culls a box the ray meets (in
    /// f64), for origins near and far from the boxes (where o·(1/d) is
    /// large against the distance to a box), directions with zero and
    /// tiny components, boxes touching the ray's path and rays ending at a
    /// box's face; and it culls most boxes the ray misses.
    #[test]
    fn the_fused_ray_test_never_culls_a_box_the_ray_meets() {
        let mut rng = seeded(21);
        let (mut met, mut culled) = (0, 0);
        for i in 0..20000 {
            let scale = [1.0, 1e3, 1e6, 1e-3][i % 4];
            let center = rng.cube(scale * [1.0, 100.0][i / 4 % 2]);
            let origin = center + rng.cube(scale * 2.0);
            let mut direction = rng.unit_vector();
            match i / 8 % 4 {
                0 => direction[i % 3] = 0.0,
                1 => direction[i % 3] = [1e-30, -1e-38, 1e-42][i % 3],
                _ => {}
            }
            let mut ray = Ray::new(origin, direction);
            // Boxes around points on the ray's line (met or narrowly
            // missed), some flat, some reaching exactly the ray's end.
            let boxes: Vec<Aabb> = (0..8)
                .map(|slot| {
                    let t = rng.range(-0.5, 4.0) * scale;
                    let p = origin + direction * t;
                    let h = rng.cube(scale).abs() * if slot % 3 == 0 { 0.0 } else { 0.3 };
                    let shift = rng.cube(scale) * if slot % 2 == 0 { 0.0 } else { 0.5 };
                    Aabb::new(p - h + shift, p + h + shift)
                })
                .collect();
            let mut rows = Node8::EMPTY.bounds;
            for (slot, b) in boxes.iter().enumerate() {
                for axis in 0..3 {
                    rows[2 * axis][slot] = b.min[axis];
                    rows[2 * axis + 1][slot] = b.max[axis];
                }
            }
            ray.tmax = match i % 3 {
                0 => f32::INFINITY,
                1 => rng.range(0.0, 3.0) * scale,
                _ => {
                    // Ends on a box face: where the box's near slab begins.
                    let b = &boxes[i % 8];
                    let axis = (0..3)
                        .max_by(|&a, &c| direction[a].abs().total_cmp(&direction[c].abs()))
                        .unwrap();
                    let face = if direction[axis] > 0.0 {
                        b.min[axis]
                    } else {
                        b.max[axis]
                    };
                    ((face - origin[axis]) / direction[axis]).max(0.0)
                }
            };
            let (_, mask) = RayPlanes::new(&ray).test(ChildBoxes::new(&rows), ray.tmax);
            for (slot, b) in boxes.iter().enumerate() {
                if meets(&ray, b) {
                    met += 1;
                    assert_eq!(mask >> slot & 1, 1, "ray {i} {ray:?} meets box {b:?}");
                } else if mask >> slot & 1 == 0 {
                    culled += 1;
                }
            }
            // Empty slots are never entered.
            let (_, mask) =
                RayPlanes::new(&ray).test(ChildBoxes::new(&Node8::EMPTY.bounds), ray.tmax);
            assert_eq!(mask, 0, "ray {i} enters an empty slot");
        }
        assert!(met > 20000 && culled > 50000, "{met} met, {culled} culled");
    }

    /// The start of the leaf holding slot `slot`.
    fn leaf_start(bvh: &Bvh8, slot: u32) -> u32 {
        let mut starts = BTreeSet::new();
        for node in &bvh.nodes {
            for &c in &node.child {
                if c != super::super::node::EMPTY && super::super::node::is_leaf(c) {
                    let (start, count) = super::super::node::leaf_range(c);
                    if (start..start + count).contains(&slot) {
                        starts.insert(start);
                    }
                }
            }
        }
        assert_eq!(starts.len(), 1, "slot {slot} in one leaf");
        starts.into_iter().next().unwrap()
    }

    /// A node test written as a caller outside `accel` would, from the
    /// child boxes' sides alone: the squared distance from `point` after
    /// every coordinate is scaled by `scale` (positive), exact for boxes
    /// since a box scaled is the box of its scaled corners.
    struct Scaled {
        point: [f32; 3],
        scale: [f32; 3],
    }

    impl NodeTest for Scaled {
        fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
            let mut d2 = f32x8::ZERO;
            for axis in 0..3 {
                let (p, s) = (
                    f32x8::splat(self.point[axis]),
                    f32x8::splat(self.scale[axis]),
                );
                let d = (boxes.lo(axis) * s - p)
                    .fast_max(p - boxes.hi(axis) * s)
                    .fast_max(f32x8::ZERO);
                d2 += d * d;
            }
            (d2, d2.simd_le(f32x8::splat(reach)).to_bitmask())
        }
    }

    /// The best-first walk with a caller's node test finds the nearest
    /// point in the scaled space that brute force does, with or without
    /// a bound, reusing one queue; it opens few leaves.
    #[test]
    fn the_best_first_walk_with_a_caller_s_test_finds_what_brute_force_does() {
        let mut rng = seeded(12);
        let points: Vec<Vec3> = (0..3000).map(|_| rng.cube(20.0)).collect();
        let boxes: Vec<Aabb> = points.iter().map(|&p| Aabb::new(p, p)).collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        let mut queue = NearestQueue::new();
        for i in 0..500 {
            let scale = [
                rng.range(0.1, 3.0),
                rng.range(0.1, 3.0),
                rng.range(0.1, 3.0),
            ];
            let scaled = |p: Vec3| p * Vec3::from_array(scale);
            let q = rng.cube(40.0);
            let limit = if i % 2 == 0 {
                f32::INFINITY
            } else {
                rng.range(0.0, 20.0)
            };
            let moved: Vec<Vec3> = points.iter().map(|&p| scaled(p)).collect();
            let brute = brute_nearest(&moved, q, limit);
            let test = Scaled {
                point: q.to_array(),
                scale,
            };
            let (best, opened) = walk_nearest(&bvh, test, limit, &mut queue, &moved, q);
            assert_eq!(best, brute, "query {i}, limit {limit}");
            assert!(opened < 200, "{opened} leaves: the walk is not pruned");
        }
    }
}
