//! Packet traversal: up to eight coherent rays walk the tree together.
//!
//! A node is tested once for the whole packet with interval arithmetic
//! (the "frustum" of the packet; Wald, Boulos and Shirley 2007, "Ray
//! Tracing Deformable Scenes Using Dynamic Bounding Volume Hierarchies",
//! and Reshetov, Soupikov and Hurley 2005 use the same idea). Children the
//! packet may enter are then tested lane by lane (eight rays in the `f32x8`
//! lanes against one box) to find which rays continue into them, and
//! leaves run the same leaf test as single rays for those lanes.
//!
//! The interval test measures slabs from an apex F, a point the rays pass
//! near (for a pixel's lens samples the focus point, for rays from one
//! origin that origin): lane i's slab distance to plane x is
//! (x − oᵢ)·invᵢ = (x − F)·invᵢ + cᵢ with cᵢ = (F − oᵢ)·invᵢ, bounded over
//! the lanes by (x − F)·[inv_lo, inv_hi] + [c_lo, c_hi]. Rays through one
//! point share cᵢ, so that bound is exact on each axis. Bounding origins
//! and reciprocals separately instead, as a ray with the largest origin and
//! the smallest reciprocal that no lane has, let three times as many
//! children through to the lane tests as entered them (bench camera
//! batches), and the lane tests were a third of a packet's instructions.
//! Rounding is covered by widening both intervals (see `SLACK`).
//!
//! Exactness: the interval test accepts every box a lane's own test
//! accepts, every lane tests a superset of the primitives its single ray
//! would test, with the same leaf test, and the closest hit is the minimum
//! of a total order (t, then primitive id; see [`super::hit::closer`]),
//! so each lane's answer is bit-identical to [`Bvh8::closest_hit`] /
//! [`Bvh8::occluded`] on that ray.
//!
//! The interval test needs every lane's direction to have the same sign on
//! an axis. An axis where the signs differ (the lens samples of a pixel
//! whose rays run nearly parallel to a coordinate plane) is left out of it:
//! the reciprocals there span both signs and huge magnitudes, so that axis
//! would cull nothing anyway, and the lane tests, which pick each lane's
//! near and far slab by min/max, still cull on it exactly. So is an axis
//! whose reciprocals or offsets are too large to bound without overflow (a
//! direction component of zero). Only where all three axes are left out
//! does [`Packet::new`] return `None`, and the caller traces the rays one
//! by one.

use super::build::Bvh8;
use super::node::{decode, ChildRef};
use super::node_test::WIDEN;
use super::query::PacketQuery;
use super::stack::Stack;
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::offset::gamma;
use crate::math::{Aabb, Ray};
use glam::DVec3;
use wide::f32x8;

/// Rays per packet: one per lane.
pub const PACKET_SIZE: usize = LANES;

/// Up to eight rays in SoA form, with the packet's interval bounds.
pub struct Packet<'r> {
    rays: &'r [Ray],
    /// Lanes holding a ray.
    live: u32,
    /// The rays in lanes ([`crate::math::ray::ray_lanes`]): origin,
    /// direction, tmin, tmax.
    lanes: [f32x8; 8],
    inv: [f32x8; 3],
    /// Per axis: the apex, and the widened bounds of the lanes'
    /// reciprocals and of their offsets cᵢ (module docs). Scalars, which
    /// the node test broadcasts from memory: stored as splats they cost
    /// the setup a broadcast and a 32-byte store each.
    apex: [f32; 3],
    /// Minus the reciprocal bounds, so the node test computes (F − x)·(−r),
    /// the value of (x − F)·r (negation is exact), with the bound x as the
    /// subtraction's memory operand, as `RayBoxes` does.
    neg_inv_lo: [f32; 3],
    neg_inv_hi: [f32; 3],
    c_lo: [f32; 3],
    c_hi: [f32; 3],
    near: [usize; 3],
    far: [usize; 3],
    /// Bit `axis` set: the interval test leaves the axis out (mixed signs
    /// or unbounded values) and the lane tests take min/max of its slabs.
    skipped: u32,
    packet_tmin: f32,
}

/// The relative widening of the reciprocal and offset intervals. A lane's
/// slab distance and the interval bound each carry a few roundings
/// relative to |x − F|·max|inv| + max|c| (the differences, the products,
/// the offsets, the sum): γ(6) covers them to first order; γ(12) doubles
/// that, and still costs nothing measurable in culling.
const SLACK: f32 = gamma(12);

/// Values the interval bounds may reach without overflowing to ±∞ on
/// the way (and so without ∞ − ∞ = NaN).
const BOUNDED: f32 = 1e30;

/// A point both lines pass near: the point of `a`'s line closest to
/// `b`'s (Eberly's line distance formulas, in f64). For rays from one
/// origin that origin; for a pixel's lens samples the focus point; `a`'s
/// origin where the lines are near parallel or the result is not finite,
/// which makes the offsets cᵢ the origins' spread in t.
fn apex(a: &Ray, b: &Ray) -> DVec3 {
    let (oa, da) = (a.origin.as_dvec3(), a.direction.as_dvec3());
    let (ob, db) = (b.origin.as_dvec3(), b.direction.as_dvec3());
    let w = oa - ob;
    let (aa, ab, bb) = (da.dot(da), da.dot(db), db.dot(db));
    let denom = aa * bb - ab * ab;
    if !(denom > 1e-12 * aa * bb) {
        return oa;
    }
    let s = (ab * db.dot(w) - bb * da.dot(w)) / denom;
    let p = oa + s * da;
    if p.is_finite() {
        p
    } else {
        oa
    }
}

impl<'r> Packet<'r> {
    /// `None` if there are no rays, more than eight, or the interval test
    /// would skip every axis (directions differ in sign, or have a zero
    /// component, on each; module docs).
    pub fn new(rays: &'r [Ray]) -> Option<Self> {
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return None;
        }
        Self::from_lanes(rays, &crate::math::ray::ray_lanes(rays))
    }

    /// [`Packet::new`] given `rays` already in lanes
    /// ([`crate::math::ray::ray_lanes`]; unused lanes repeat ray 0).
    #[inline(always)]
    pub fn from_lanes(rays: &'r [Ray], soa: &[f32x8; 8]) -> Option<Self> {
        Self::from_parts(rays, soa, &reciprocals(soa))
    }

    /// [`Packet::from_lanes`] given the lanes' [`reciprocals`] too.
    #[inline(always)]
    pub fn from_parts(rays: &'r [Ray], soa: &[f32x8; 8], inv: &[f32x8; 3]) -> Option<Self> {
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return None;
        }
        let inv = *inv;
        let origin = [soa[0], soa[1], soa[2]];
        // Lanes past the last ray repeat ray 0, so the first and last ray
        // give the apex.
        let f = apex(&rays[0], &rays[rays.len() - 1]).as_vec3();
        let apex = [f.x, f.y, f.z].map(f32x8::splat);
        let c: [f32x8; 3] = std::array::from_fn(|a| (apex[a] - origin[a]) * inv[a]);
        // Lane minima and maxima of offsets and reciprocals, all at once:
        // transposed, lane k of the vertical min (max) over the eight
        // vectors is the minimum (maximum) of quantity k over the rays.
        // Offsets may be ±∞ or NaN (a zero direction component gives a
        // reciprocal of ±f32::MAX); such an axis is skipped below. The
        // last slot only pads the eight.
        let quantities = [c[0], c[1], c[2], inv[0], inv[1], inv[2], soa[6], soa[6]];
        let across = f32x8::transpose(quantities);
        let (mut lo, mut hi) = (across[0], across[0]);
        for v in &across[1..] {
            lo = lo.fast_min(*v);
            hi = hi.fast_max(*v);
        }
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let mut near = [0; 3];
        let mut far = [0; 3];
        let mut skipped = 0;
        let mut bounds = [[0.0f32; 4]; 3];
        for axis in 0..3 {
            let (inv_lo, inv_hi) = (lo[3 + axis], hi[3 + axis]);
            let (c_lo, c_hi) = (lo[axis], hi[axis]);
            let neg = inv_hi < 0.0;
            let mixed = inv_lo < 0.0 && !neg;
            let inv_max = inv_lo.abs().max(inv_hi.abs());
            let c_max = c_lo.abs().max(c_hi.abs());
            // fast_min/fast_max may drop a NaN: check every lane's offset.
            let every = (1 << PACKET_SIZE) - 1;
            let bounded = inv_max < BOUNDED
                && c[axis].abs().simd_lt(f32x8::splat(BOUNDED)).to_bitmask() == every;
            skipped |= ((mixed || !bounded) as u32) << axis;
            near[axis] = 2 * axis + neg as usize;
            far[axis] = 2 * axis + 1 - neg as usize;
            let (gi, gc) = (SLACK * inv_max, SLACK * c_max);
            bounds[axis] = [inv_lo - gi, inv_hi + gi, c_lo - gc, c_hi + gc];
        }
        if skipped == 0b111 {
            return None;
        }
        Some(Self {
            rays,
            live: (1u32 << rays.len()) - 1,
            lanes: *soa,
            inv,
            apex: f.to_array(),
            neg_inv_lo: bounds.map(|b| -b[0]),
            neg_inv_hi: bounds.map(|b| -b[1]),
            c_lo: bounds.map(|b| b[2]),
            c_hi: bounds.map(|b| b[3]),
            near,
            far,
            skipped,
            packet_tmin: lo[6],
        })
    }

    /// The point the rays pass near (module docs).
    #[inline(always)]
    pub(super) fn apex(&self) -> [f32; 3] {
        self.apex
    }

    /// The packet's rays, one per lane from lane 0.
    #[inline(always)]
    pub fn rays(&self) -> &'r [Ray] {
        self.rays
    }

    /// The rays in lanes: `[ox, oy, oz, dx, dy, dz, tmin, tmax][lane]`.
    #[inline(always)]
    pub fn lanes(&self) -> &[f32x8; 8] {
        &self.lanes
    }

    /// Entry distances (lower bounds over the packet) and the mask of the
    /// node's children that some ray with tmax ≤ `tmax` may enter.
    /// `SKIP`: whether any axis is skipped, a constant so that the common
    /// case compiles without the per-axis checks.
    /// An empty slot (an inverted infinite box) may pass where an interval
    /// spans zero; its lane test rejects it on an axis that is not skipped.
    #[inline(always)]
    fn test_node<const SKIP: bool>(&self, bounds: &[[f32; 8]; 6], tmax: f32) -> (f32x8, u32) {
        let mut tn = f32x8::splat(self.packet_tmin);
        let mut tf = f32x8::splat(tmax);
        for axis in 0..3 {
            if SKIP && self.skipped & (1 << axis) != 0 {
                continue;
            }
            let apex = f32x8::splat(self.apex[axis]);
            let dn = apex - f32x8::from(bounds[self.near[axis]]);
            let df = apex - f32x8::from(bounds[self.far[axis]]);
            // No NaN on a real box (finite sides, bounded intervals).
            let lo = f32x8::splat(self.neg_inv_lo[axis]);
            let hi = f32x8::splat(self.neg_inv_hi[axis]);
            let entry = (dn * lo).fast_min(dn * hi);
            let exit = (df * lo).fast_max(df * hi);
            tn = tn.fast_max(entry + f32x8::splat(self.c_lo[axis]));
            tf = tf.fast_min(exit + f32x8::splat(self.c_hi[axis]));
        }
        let tf = tf * f32x8::splat(WIDEN);
        (tn, tn.simd_le(tf).to_bitmask())
    }

    /// Which lanes enter child `slot` of a node: each lane's own slab test,
    /// the same arithmetic as the single-ray test. On a skipped axis each
    /// lane takes the smaller of its two slab distances as near and the
    /// larger as far; rounding is monotone and the box's min ≤ max, so that
    /// is exactly the slab the single-ray test picks by the sign of its
    /// direction. Only empty slots have min > max, and an axis that is not
    /// skipped rejects them (its near slab is +∞).
    #[inline(always)]
    fn test_lanes<const SKIP: bool>(
        &self,
        bounds: &[[f32; 8]; 6],
        slot: usize,
        tmax: f32x8,
    ) -> u32 {
        let mut tn = self.lanes[6];
        let mut tf = tmax;
        for axis in 0..3 {
            let bn = f32x8::splat(bounds[self.near[axis]][slot]);
            let bf = f32x8::splat(bounds[self.far[axis]][slot]);
            let tnear = (bn - self.lanes[axis]) * self.inv[axis];
            let tfar = (bf - self.lanes[axis]) * self.inv[axis];
            if SKIP && self.skipped & (1 << axis) != 0 {
                tn = tn.fast_max(tnear.fast_min(tfar));
                tf = tf.fast_min(tnear.fast_max(tfar));
            } else {
                tn = tn.fast_max(tnear);
                tf = tf.fast_min(tfar);
            }
        }
        let tf = tf * f32x8::splat(WIDEN);
        tn.simd_le(tf).to_bitmask()
    }
}

/// The single-ray reciprocal directions of rays in lanes
/// ([`crate::math::ray::ray_lanes`]), lane by lane: zero components become
/// ±f32::MAX with the zero's sign, as `RayBoxes::new` makes them.
#[inline(always)]
pub fn reciprocals(soa: &[f32x8; 8]) -> [f32x8; 3] {
    [soa[3], soa[4], soa[5]].map(|d| {
        let max = f32x8::splat(f32::MAX) | (d & f32x8::splat(-0.0));
        d.simd_eq(f32x8::ZERO).select(max, f32x8::splat(1.0) / d)
    })
}

/// Whether every ray in lanes `soa`, with reciprocals `inv`, misses
/// `bounds` (the box of a whole tree): each lane's slab test, the
/// arithmetic of the single-ray node test (the nearer and farther slab of
/// each axis by min/max, which is the slab its direction's sign picks, as
/// for a skipped axis in `test_lanes`; the exit widened by `WIDEN`).
/// Every node's boxes lie inside the tree's box and each step of that
/// arithmetic is monotone in the bounds, so a ray that misses the tree's
/// box enters no node either: rays this test turns away need no walk,
/// and their answers are the single rays' (no hit in the tree). For camera
/// rays that see past a mesh this test replaces the packet's setup and its
/// root visit. A lane with a NaN anywhere in its test counts as entering, so
/// such rays keep their usual path.
#[inline(always)]
pub fn misses_box(soa: &[f32x8; 8], inv: &[f32x8; 3], bounds: &Aabb) -> bool {
    lanes_missing_box(soa, inv, bounds) == (1 << PACKET_SIZE) - 1
}

/// The lanes that [`misses_box`]'s test finds missing `bounds`, as a bit
/// mask: rays that enter no node of a tree whose box that is.
#[inline(always)]
pub fn lanes_missing_box(soa: &[f32x8; 8], inv: &[f32x8; 3], bounds: &Aabb) -> u32 {
    let (lo, hi) = (bounds.min.to_array(), bounds.max.to_array());
    let mut tn = soa[6];
    let mut tf = soa[7];
    let mut nan = tn.simd_ne(tn) | tf.simd_ne(tf);
    for axis in 0..3 {
        let a = (f32x8::splat(lo[axis]) - soa[axis]) * inv[axis];
        let b = (f32x8::splat(hi[axis]) - soa[axis]) * inv[axis];
        nan |= a.simd_ne(a) | b.simd_ne(b);
        tn = tn.fast_max(a.fast_min(b));
        tf = tf.fast_min(a.fast_max(b));
    }
    tn.simd_gt(tf * f32x8::splat(WIDEN)).to_bitmask() & !nan.to_bitmask()
}

#[inline(always)]
fn max_lane(t: &[f32; 8]) -> f32 {
    t.iter().copied().fold(f32::NEG_INFINITY, f32::max)
}

impl Bvh8 {
    /// The walk of a packet: `out[i]` ends as [`Bvh8::walk`]'s answer for
    /// `packet`'s ray `i` with the same query, which `query` answers for
    /// the rays in lanes. `leaf_data` as for [`Bvh8::walk`]: the children
    /// pushed for later are prefetched.
    pub fn walk_packet<Q, L>(
        &self,
        packet: &Packet,
        out: &mut [Q::Answer],
        leaf_data: &[L],
        query: &mut Q,
    ) where
        Q: PacketQuery,
    {
        if packet.skipped == 0 {
            self.walk_packet_in::<false, Q, L>(packet, out, leaf_data, query)
        } else {
            self.walk_packet_in::<true, Q, L>(packet, out, leaf_data, query)
        }
    }

    #[inline(always)]
    fn walk_packet_in<const SKIP: bool, Q, L>(
        &self,
        packet: &Packet,
        out: &mut [Q::Answer],
        leaf_data: &[L],
        query: &mut Q,
    ) where
        Q: PacketQuery,
    {
        let rays = packet.rays;
        out[..rays.len()].fill(Q::Answer::default());
        if self.nodes.is_empty() {
            return;
        }
        // The rays' ends straight from the lanes (unused lanes repeat ray
        // 0, which leaves the maximum alone): filling an array lane by lane
        // and loading it whole would stall on store forwarding.
        let mut tmax_v = packet.lanes[7];
        let mut tmax = tmax_v.to_array();
        if Q::SHORTENS {
            // Lanes without a ray must not hold the end of a ray whose hit
            // has since shortened it.
            tmax[rays.len()..].fill(f32::NEG_INFINITY);
            tmax_v = f32x8::from(tmax);
        }
        let mut packet_tmax = max_lane(&tmax);
        // Rays still walking: an occlusion ray leaves at its first blocker.
        let mut open = packet.live;
        let mut stack: Stack<(u32, f32, u32)> = Stack::new();
        stack.push((0, f32::NEG_INFINITY, open));
        while let Some((child, t_enter, mask)) = stack.pop() {
            let mask = if Q::SHORTENS {
                // Widened as in `Bvh8::walk`, so ties across leaves are seen.
                if t_enter > packet_tmax * WIDEN {
                    continue;
                }
                mask
            } else {
                mask & open
            };
            if mask == 0 {
                continue;
            }
            match decode(child) {
                ChildRef::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let (tn, mut hit) = packet.test_node::<SKIP>(&node.bounds, packet_tmax);
                    if !Q::SHORTENS {
                        // Children in slot order: the first blocker ends a
                        // ray wherever it is.
                        while hit != 0 {
                            let slot = hit.trailing_zeros() as usize;
                            hit &= hit - 1;
                            let m = mask & packet.test_lanes::<SKIP>(&node.bounds, slot, tmax_v);
                            if m != 0 {
                                if self.prefetch {
                                    self.prefetch_child(node.child[slot], leaf_data);
                                }
                                stack.push((node.child[slot], 0.0, m));
                            }
                        }
                        continue;
                    }
                    // Nearest last on the stack, so it is visited first.
                    let tn = tn.to_array();
                    let mut order = [(0u32, 0.0f32, 0u32); 8];
                    let mut count = 0;
                    while hit != 0 {
                        let slot = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        let m = mask & packet.test_lanes::<SKIP>(&node.bounds, slot, tmax_v);
                        if m == 0 {
                            continue;
                        }
                        let mut j = count;
                        while j > 0 && order[j - 1].1 < tn[slot] {
                            order[j] = order[j - 1];
                            j -= 1;
                        }
                        order[j] = (node.child[slot], tn[slot], m);
                        count += 1;
                    }
                    for &e in &order[..count] {
                        if self.prefetch {
                            self.prefetch_child(e.0, leaf_data);
                        }
                        stack.push(e);
                    }
                }
                ChildRef::Leaf { start, count } => {
                    let changed = query.leaf(start, count, mask, out);
                    if Q::SHORTENS {
                        if changed != 0 {
                            for lane in mask_lanes(changed) {
                                tmax[lane] = Q::end(&out[lane]).unwrap_or(rays[lane].tmax);
                            }
                            tmax_v = f32x8::from(tmax);
                            packet_tmax = max_lane(&tmax);
                        }
                    } else {
                        open &= !changed;
                        if open == 0 {
                            return;
                        }
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::node::Node8;
    use super::super::node_test::{ChildBoxes, NodeTest, RayBoxes};
    use super::*;
    use crate::sampling::stream::{seeded, Draw, StreamRng as Rng};
    use glam::Vec3;
    use rand::RngExt;

    /// Eight rays of one kind around `centre` at `scale`.
    fn packet_rays(rng: &mut Rng, kind: usize, centre: Vec3, scale: f32) -> Vec<Ray> {
        let eye = centre + Vec3::new(0.3, -0.2, -3.0) * scale;
        let focus = centre + rng.cube(1.0) * scale;
        let axis = focus - eye + rng.cube(1.0) * 0.2 * scale;
        (0..PACKET_SIZE)
            .map(|lane| {
                let mut ray = match kind {
                    // A pixel's lens samples, converging on the focus.
                    0 => {
                        let o = eye + rng.cube(1.0) * 0.05 * scale;
                        Ray::new(o, focus - o)
                    }
                    // One origin (pinhole pixel, shadow rays).
                    1 => Ray::new(eye, axis + rng.cube(1.0) * 0.05 * scale),
                    // Parallel (orthographic pixel).
                    2 => Ray::new(eye + rng.cube(1.0) * 0.05 * scale, axis),
                    // Skew: neither.
                    _ => Ray::new(
                        eye + rng.cube(1.0) * 0.1 * scale,
                        axis + rng.cube(1.0) * 0.1 * scale,
                    ),
                };
                if lane == 3 && kind != 1 && kind != 3 {
                    ray.direction.x = 0.0; // ±f32::MAX reciprocal: axis skipped
                }
                if lane % 3 == 1 {
                    ray.tmax = (0.5 + 3.0 * rng.unit()) * if kind == 0 { 1.0 } else { scale };
                }
                ray
            })
            .collect()
    }

    /// A node whose boxes sit on or near the rays: small, large, flat,
    /// a point on a ray (entered or not by rounding alone) and an empty
    /// slot.
    fn node_near(rng: &mut Rng, rays: &[Ray], scale: f32) -> Node8 {
        let mut node = Node8::EMPTY;
        for slot in 0..7 {
            let ray = rays[(slot + rng.random::<u32>() as usize) % rays.len()];
            let t = rng.unit()
                * 3.0
                * if ray.tmax.is_finite() {
                    1.0
                } else {
                    1.0 / ray.direction.length() * scale
                };
            let on_ray = ray.origin + ray.direction * t.min(ray.tmax);
            if slot == 6 {
                for axis in 0..3 {
                    node.bounds[2 * axis][slot] = on_ray[axis];
                    node.bounds[2 * axis + 1][slot] = on_ray[axis];
                }
                continue;
            }
            let c = on_ray + rng.cube(1.0) * 0.02 * scale;
            let half = Vec3::new(rng.unit(), rng.unit(), rng.unit())
                * scale
                * [1e-6, 1e-3, 0.05][slot % 3];
            let half = if slot == 5 {
                half * Vec3::new(1.0, 0.0, 1.0)
            } else {
                half
            };
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = c[axis] - half[axis];
                node.bounds[2 * axis + 1][slot] = c[axis] + half[axis];
            }
        }
        node
    }

    /// Round `round`'s rays, of kind `round % 4` ([`packet_rays`]), at one
    /// of four places and scales, from the origin's to far from it and
    /// small: (kind, scale, rays).
    fn round_rays(rng: &mut Rng, round: usize) -> (usize, f32, Vec<Ray>) {
        let kind = round % 4;
        let (centre, scale) = [
            (Vec3::ZERO, 1.0),
            (Vec3::splat(1e5), 10.0),
            (Vec3::new(3e5, -2e5, 1e5), 1e-2),
            (Vec3::splat(-3.0), 1e-3),
        ][round / 4 % 4];
        (kind, scale, packet_rays(rng, kind, centre, scale))
    }

    /// A group that `misses_box` turns away enters none of the boxes
    /// inside the box it tested, by any lane's single-ray test: boxes near
    /// the rays, moved aside by up to their own scale so that many groups
    /// miss, and the tested box exactly their union (the tightest box a
    /// tree can have).
    #[test]
    fn a_group_that_misses_the_box_enters_nothing_inside_it() {
        let mut rng = seeded(8);
        let (mut missed, mut kept) = (0, 0);
        for round in 0..4000 {
            let (kind, scale, rays) = round_rays(&mut rng, round);
            let mut node = node_near(&mut rng, &rays, scale);
            if round % 3 == 0 {
                // Only the point on a ray, entered or not by rounding
                // alone: the box is exactly that point.
                for row in 0..6 {
                    node.bounds[row][..6].copy_from_slice(&Node8::EMPTY.bounds[row][..6]);
                }
            }
            let shift = rng.cube(1.0) * scale * [0.0, 0.01, 0.1, 1.0][round / 16 % 4];
            let mut bounds = Aabb::EMPTY;
            for slot in (0..7).filter(|&slot| round % 3 != 0 || slot == 6) {
                for axis in 0..3 {
                    node.bounds[2 * axis][slot] += shift[axis];
                    node.bounds[2 * axis + 1][slot] += shift[axis];
                }
                let corner = |row: usize| {
                    Vec3::from_array(std::array::from_fn(|axis| {
                        node.bounds[2 * axis + row][slot]
                    }))
                };
                bounds = bounds.union(Aabb {
                    min: corner(0),
                    max: corner(1),
                });
            }
            let lanes = crate::math::ray::ray_lanes(&rays);
            if !misses_box(&lanes, &reciprocals(&lanes), &bounds) {
                kept += 1;
                continue;
            }
            missed += 1;
            for (i, ray) in rays.iter().enumerate() {
                let (_, single) = RayBoxes::new(ray).test(ChildBoxes::new(&node.bounds), ray.tmax);
                assert_eq!(single, 0, "kind {kind}, lane {i}: {ray:?} enters {node:?}");
            }
        }
        assert!(missed > 500 && kept > 500, "{missed} missed, {kept} kept");
    }

    /// Every child a lane's single-ray test enters passes the packet's
    /// interval test and that lane's lane test, whatever the packet: the
    /// bound behind the packet/single identity.
    #[test]
    fn interval_and_lane_tests_accept_every_box_a_lane_enters() {
        let mut rng = seeded(5);
        let (mut entered, mut skipped) = (0, 0);
        for round in 0..4000 {
            let (kind, scale, rays) = round_rays(&mut rng, round);
            let Some(packet) = Packet::new(&rays) else {
                continue;
            };
            let node = node_near(&mut rng, &rays, scale);
            let tmax_v = f32x8::from(std::array::from_fn(|i| rays[i].tmax));
            let packet_tmax = rays
                .iter()
                .map(|r| r.tmax)
                .fold(f32::NEG_INFINITY, f32::max);
            let check = |node_mask: u32, lanes: &dyn Fn(usize) -> u32| {
                let mut n = 0;
                for (i, ray) in rays.iter().enumerate() {
                    let (_, single) =
                        RayBoxes::new(ray).test(ChildBoxes::new(&node.bounds), ray.tmax);
                    for slot in 0..8 {
                        if single >> slot & 1 == 1 {
                            n += 1;
                            assert_eq!(
                                node_mask >> slot & 1,
                                1,
                                "kind {kind}: slot {slot} lane {i}"
                            );
                            assert_eq!(
                                lanes(slot) >> i & 1,
                                1,
                                "kind {kind}: slot {slot} lane {i}"
                            );
                        }
                    }
                }
                n
            };
            entered += if packet.skipped == 0 {
                let (_, m) = packet.test_node::<false>(&node.bounds, packet_tmax);
                check(m, &|slot| {
                    packet.test_lanes::<false>(&node.bounds, slot, tmax_v)
                })
            } else {
                let (_, m) = packet.test_node::<true>(&node.bounds, packet_tmax);
                check(m, &|slot| {
                    packet.test_lanes::<true>(&node.bounds, slot, tmax_v)
                })
            };
            skipped += (packet.skipped != 0) as usize;
        }
        assert!(entered > 10_000, "the cases must enter boxes: {entered}");
        assert!(skipped > 500, "and exercise skipped axes: {skipped}");
    }
}
