//! Packet traversal: up to eight coherent rays walk the tree together.
//!
//! A node is tested once for the whole packet with interval arithmetic over
//! the packet's origins and reciprocal directions (the "frustum" of the
//! packet; Wald, Boulos and Shirley 2007, "Ray Tracing Deformable Scenes
//! Using Dynamic Bounding Volume Hierarchies", and Reshetov, Soupikov and
//! Hurley 2005 use the same idea). Slab distances are monotone in the origin
//! and linear in the reciprocal direction, and rounding is monotone, so the
//! interval test computed in f32 accepts every box that any lane's own
//! single-ray test accepts. Children the packet enters are then tested lane
//! by lane (eight rays in the `f32x8` lanes against one box) to find which
//! rays continue into them, and leaves run the same leaf test as single
//! rays for those lanes only.
//!
//! Exactness: every lane tests a superset of the primitives its single ray
//! would test, with the same leaf test, and the closest hit is the minimum
//! of a total order (t, then primitive id; see [`super::traverse::closer`]),
//! so each lane's answer is bit-identical to [`Bvh8::closest`] /
//! [`Bvh8::any_hit`] on that ray.
//!
//! The interval test needs every lane's direction to have the same sign on
//! an axis. An axis where the signs differ (the lens samples of a pixel
//! whose rays run nearly parallel to a coordinate plane) is left out of it:
//! the reciprocals there span both signs and huge magnitudes, so that axis
//! would cull nothing anyway, and the lane tests, which pick each lane's
//! near and far slab by min/max, still cull on it exactly. Only where all
//! three axes are mixed does [`Packet::new`] return `None`, and the caller
//! traces the rays one by one.

use super::build::Bvh8;
use super::node::{decode, ChildRef};
use super::traverse::{Stack, WIDEN};
use crate::math::offset::gamma;
use crate::math::Ray;
use crate::shape::PrimHit;
use wide::f32x8;

/// Rays per packet: one per `f32x8` lane.
pub const PACKET_SIZE: usize = 8;

/// Up to eight rays in SoA form, with the packet's interval bounds.
pub struct Packet<'r> {
    rays: &'r [Ray],
    /// Lanes holding a ray.
    live: u32,
    origin: [f32x8; 3],
    inv: [f32x8; 3],
    tmin: f32x8,
    /// Per axis: the origin bound and box side for the near and far slabs.
    near_o: [f32x8; 3],
    far_o: [f32x8; 3],
    inv_lo: [f32x8; 3],
    inv_hi: [f32x8; 3],
    near: [usize; 3],
    far: [usize; 3],
    /// Bit `axis` set: the lanes' directions differ in sign on that axis.
    mixed: u32,
    packet_tmin: f32x8,
}

impl<'r> Packet<'r> {
    /// `None` if there are no rays, more than eight, or their directions
    /// differ in sign on every axis.
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
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return None;
        }
        let origin = [soa[0], soa[1], soa[2]];
        let dir = [soa[3], soa[4], soa[5]];
        // The single-ray reciprocal, lane by lane: zero components become
        // ±f32::MAX with the zero's sign (see `safe_recip`).
        let inv = dir.map(|d| {
            let max = f32x8::splat(f32::MAX) | (d & f32x8::splat(-0.0));
            d.simd_eq(f32x8::ZERO).select(max, f32x8::splat(1.0) / d)
        });
        // Lane minima and maxima of origins and reciprocals, all at once:
        // transposed, lane k of the vertical min (max) over the eight
        // vectors is the minimum (maximum) of quantity k over the rays.
        // All finite (reciprocals are ±f32::MAX at worst): no NaN handling.
        // The last slot only pads the eight.
        let quantities = [
            origin[0], origin[1], origin[2], inv[0], inv[1], inv[2], soa[6], soa[6],
        ];
        let across = f32x8::transpose(quantities);
        let (mut lo, mut hi) = (across[0], across[0]);
        for v in &across[1..] {
            lo = lo.fast_min(*v);
            hi = hi.fast_max(*v);
        }
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let mut near = [0; 3];
        let mut far = [0; 3];
        let mut mixed = 0;
        let mut near_o = [f32x8::ZERO; 3];
        let mut far_o = [f32x8::ZERO; 3];
        for axis in 0..3 {
            // Both signs present: the smallest reciprocal is negative and
            // the largest positive.
            let neg = hi[3 + axis] < 0.0;
            mixed |= ((lo[3 + axis] < 0.0 && !neg) as u32) << axis;
            near[axis] = 2 * axis + neg as usize;
            far[axis] = 2 * axis + 1 - neg as usize;
            // inv > 0: the near slab is smallest at the largest origin.
            let (o_near, o_far) = if neg {
                (lo[axis], hi[axis])
            } else {
                (hi[axis], lo[axis])
            };
            near_o[axis] = f32x8::splat(o_near);
            far_o[axis] = f32x8::splat(o_far);
        }
        if mixed == 0b111 {
            return None;
        }
        Some(Self {
            rays,
            live: (1u32 << rays.len()) - 1,
            origin,
            inv,
            tmin: soa[6],
            near_o,
            far_o,
            inv_lo: [0, 1, 2].map(|a| f32x8::splat(lo[3 + a])),
            inv_hi: [0, 1, 2].map(|a| f32x8::splat(hi[3 + a])),
            near,
            far,
            mixed,
            packet_tmin: f32x8::splat(lo[6]),
        })
    }

    /// Entry distances (lower bounds over the packet) and the mask of the
    /// node's children that some ray with tmax ≤ `tmax` may enter.
    /// `MIXED`: whether any axis is mixed, a constant so that the common
    /// case compiles without the per-axis checks (they cost 20% there).
    #[inline(always)]
    fn test_node<const MIXED: bool>(&self, bounds: &[[f32; 8]; 6], tmax: f32) -> (f32x8, u32) {
        let mut tn = self.packet_tmin;
        let mut tf = f32x8::splat(tmax);
        for axis in 0..3 {
            if MIXED && self.mixed & (1 << axis) != 0 {
                continue;
            }
            let dn = f32x8::from(bounds[self.near[axis]]) - self.near_o[axis];
            let df = f32x8::from(bounds[self.far[axis]]) - self.far_o[axis];
            // No NaN arises (see `RayBoxes::slabs`): plain min/max.
            tn = tn.fast_max((dn * self.inv_lo[axis]).fast_min(dn * self.inv_hi[axis]));
            tf = tf.fast_min((df * self.inv_lo[axis]).fast_max(df * self.inv_hi[axis]));
        }
        let tf = tf * f32x8::splat(1.0 + 2.0 * gamma(3));
        (tn, tn.simd_le(tf).to_bitmask())
    }

    /// Which lanes enter child `slot` of a node: each lane's own slab test,
    /// the same arithmetic as the single-ray test. On a mixed axis each
    /// lane takes the smaller of its two slab distances as near and the
    /// larger as far; rounding is monotone and the box's min ≤ max, so that
    /// is exactly the slab the single-ray test picks by the sign of its
    /// direction. (Only empty slots have min > max, and [`Packet::test_node`] rejects
    /// those on an axis that is not mixed.)
    #[inline(always)]
    fn test_lanes<const MIXED: bool>(
        &self,
        bounds: &[[f32; 8]; 6],
        slot: usize,
        tmax: f32x8,
    ) -> u32 {
        let mut tn = self.tmin;
        let mut tf = tmax;
        for axis in 0..3 {
            let bn = f32x8::splat(bounds[self.near[axis]][slot]);
            let bf = f32x8::splat(bounds[self.far[axis]][slot]);
            let tnear = (bn - self.origin[axis]) * self.inv[axis];
            let tfar = (bf - self.origin[axis]) * self.inv[axis];
            if MIXED && self.mixed & (1 << axis) != 0 {
                tn = tn.fast_max(tnear.fast_min(tfar));
                tf = tf.fast_min(tnear.fast_max(tfar));
            } else {
                tn = tn.fast_max(tnear);
                tf = tf.fast_min(tfar);
            }
        }
        let tf = tf * f32x8::splat(1.0 + 2.0 * gamma(3));
        tn.simd_le(tf).to_bitmask()
    }
}

#[inline(always)]
fn max_lane(t: &[f32; 8]) -> f32 {
    t.iter().copied().fold(f32::NEG_INFINITY, f32::max)
}

/// Lanes `mask` selects, as indices.
#[inline(always)]
fn lanes(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

impl Bvh8 {
    /// Closest hits of a packet: `out[i]` is exactly what
    /// [`Bvh8::closest`] returns for `packet`'s ray `i`.
    /// `hit_leaf(start, count, lanes, out)` tests the leaf for the rays in
    /// the bits of `lanes`, replacing `out[lane]` by any hit [`closer`](super::traverse::closer)
    /// than it within the ray's interval, and returns whether any changed.
    pub fn closest_packet<F>(&self, packet: &Packet, out: &mut [Option<PrimHit>], hit_leaf: F)
    where
        F: FnMut(u32, u32, u32, &mut [Option<PrimHit>]) -> bool,
    {
        if packet.mixed == 0 {
            self.closest_packet_in::<false, F>(packet, out, hit_leaf)
        } else {
            self.closest_packet_in::<true, F>(packet, out, hit_leaf)
        }
    }

    #[inline(always)]
    fn closest_packet_in<const MIXED: bool, F>(
        &self,
        packet: &Packet,
        out: &mut [Option<PrimHit>],
        mut hit_leaf: F,
    ) where
        F: FnMut(u32, u32, u32, &mut [Option<PrimHit>]) -> bool,
    {
        let rays = packet.rays;
        out[..rays.len()].fill(None);
        if self.nodes.is_empty() {
            return;
        }
        let mut tmax = [f32::NEG_INFINITY; 8];
        for (t, r) in tmax.iter_mut().zip(rays) {
            *t = r.tmax;
        }
        let mut tmax_v = f32x8::from(tmax);
        let mut packet_tmax = max_lane(&tmax);
        let mut stack: Stack<(u32, f32, u32)> = Stack::new();
        stack.push((0, f32::NEG_INFINITY, packet.live));
        while let Some((child, t_enter, mask)) = stack.pop() {
            // Widened as in `Bvh8::closest`, so ties across leaves are seen.
            if t_enter > packet_tmax * WIDEN {
                continue;
            }
            match decode(child) {
                ChildRef::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let (tn, mut hit) = packet.test_node::<MIXED>(&node.bounds, packet_tmax);
                    let tn = tn.to_array();
                    let mut order = [(0u32, 0.0f32, 0u32); 8];
                    let mut count = 0;
                    while hit != 0 {
                        let slot = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        let m = mask & packet.test_lanes::<MIXED>(&node.bounds, slot, tmax_v);
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
                        stack.push(e);
                    }
                }
                ChildRef::Leaf { start, count } => {
                    if hit_leaf(start, count, mask, out) {
                        for lane in lanes(mask) {
                            tmax[lane] = out[lane].map_or(rays[lane].tmax, |h| h.t);
                        }
                        tmax_v = f32x8::from(tmax);
                        packet_tmax = max_lane(&tmax);
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }

    /// Occlusion for a packet: `out[i]` is exactly what [`Bvh8::any_hit`]
    /// returns for ray `i`, with `blocks_leaf(start, count, lanes)` its
    /// leaf test for the rays in the bits of `lanes`, returning the lanes
    /// it blocks. Lanes stop as soon as they are blocked.
    pub fn any_hit_packet<F>(&self, packet: &Packet, out: &mut [bool], blocks_leaf: F)
    where
        F: FnMut(u32, u32, u32) -> u32,
    {
        if packet.mixed == 0 {
            self.any_hit_packet_in::<false, F>(packet, out, blocks_leaf)
        } else {
            self.any_hit_packet_in::<true, F>(packet, out, blocks_leaf)
        }
    }

    #[inline(always)]
    fn any_hit_packet_in<const MIXED: bool, F>(
        &self,
        packet: &Packet,
        out: &mut [bool],
        mut blocks_leaf: F,
    ) where
        F: FnMut(u32, u32, u32) -> u32,
    {
        let rays = packet.rays;
        out[..rays.len()].fill(false);
        if self.nodes.is_empty() {
            return;
        }
        let mut tmax = [f32::NEG_INFINITY; 8];
        for (t, r) in tmax.iter_mut().zip(rays) {
            *t = r.tmax;
        }
        let tmax_v = f32x8::from(tmax);
        let packet_tmax = max_lane(&tmax);
        let mut open = packet.live;
        let mut stack: Stack<(u32, u32)> = Stack::new();
        stack.push((0, open));
        while let Some((child, mask)) = stack.pop() {
            let mask = mask & open;
            if mask == 0 {
                continue;
            }
            match decode(child) {
                ChildRef::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let (_, mut hit) = packet.test_node::<MIXED>(&node.bounds, packet_tmax);
                    while hit != 0 {
                        let slot = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        let m = mask & packet.test_lanes::<MIXED>(&node.bounds, slot, tmax_v);
                        if m != 0 {
                            stack.push((node.child[slot], m));
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    let blocked = blocks_leaf(start, count, mask) & mask;
                    for lane in lanes(blocked) {
                        out[lane] = true;
                    }
                    open &= !blocked;
                    if open == 0 {
                        return;
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }
}
