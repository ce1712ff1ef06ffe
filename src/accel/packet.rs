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
//! The interval test needs every lane's direction to have the same sign per
//! axis; [`Packet::new`] returns `None` otherwise and the caller traces the
//! rays one by one.

use super::build::Bvh8;
use super::node::{decode, ChildRef};
use super::traverse::{closer, safe_recip, tie_ray, Stack};
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
    packet_tmin: f32x8,
}

impl<'r> Packet<'r> {
    /// `None` if there are no rays, more than eight, or their directions
    /// differ in sign on some axis.
    pub fn new(rays: &'r [Ray]) -> Option<Self> {
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return None;
        }
        let inv: Vec<glam::Vec3> = rays.iter().map(|r| safe_recip(r.direction)).collect();
        let mut near = [0; 3];
        let mut far = [0; 3];
        let mut lanes = [[0.0f32; 8]; 7];
        let mut bounds = [[0.0f32; 4]; 3]; // o_lo, o_hi, inv_lo, inv_hi per axis
        for axis in 0..3 {
            let neg = inv[0][axis] < 0.0;
            if inv.iter().any(|i| (i[axis] < 0.0) != neg) {
                return None;
            }
            near[axis] = 2 * axis + neg as usize;
            far[axis] = 2 * axis + 1 - neg as usize;
            let mut b = [
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::NEG_INFINITY,
            ];
            for (r, i) in rays.iter().zip(&inv) {
                b[0] = b[0].min(r.origin[axis]);
                b[1] = b[1].max(r.origin[axis]);
                b[2] = b[2].min(i[axis]);
                b[3] = b[3].max(i[axis]);
            }
            bounds[axis] = b;
        }
        // Unused lanes repeat ray 0 (they are never active).
        let ray_of = |lane: usize| if lane < rays.len() { lane } else { 0 };
        for (c, component) in lanes.iter_mut().enumerate() {
            *component = std::array::from_fn(|lane| {
                let k = ray_of(lane);
                match c {
                    0..=2 => rays[k].origin[c],
                    3..=5 => inv[k][c - 3],
                    _ => rays[k].tmin,
                }
            });
        }
        let sel = |axis: usize, near_side: bool| {
            // inv > 0: the near slab is smallest at the largest origin.
            let neg = inv[0][axis] < 0.0;
            let b = bounds[axis];
            f32x8::splat(if near_side != neg { b[1] } else { b[0] })
        };
        let packet_tmin = rays.iter().map(|r| r.tmin).fold(f32::INFINITY, f32::min);
        Some(Self {
            rays,
            live: (1u32 << rays.len()) - 1,
            origin: [0, 1, 2].map(|a| f32x8::from(lanes[a])),
            inv: [0, 1, 2].map(|a| f32x8::from(lanes[3 + a])),
            tmin: f32x8::from(lanes[6]),
            near_o: [0, 1, 2].map(|a| sel(a, true)),
            far_o: [0, 1, 2].map(|a| sel(a, false)),
            inv_lo: [0, 1, 2].map(|a| f32x8::splat(bounds[a][2])),
            inv_hi: [0, 1, 2].map(|a| f32x8::splat(bounds[a][3])),
            near,
            far,
            packet_tmin: f32x8::splat(packet_tmin),
        })
    }

    /// Entry distances (lower bounds over the packet) and the mask of the
    /// node's children that some ray with tmax ≤ `tmax` may enter.
    #[inline(always)]
    fn test_node(&self, bounds: &[[f32; 8]; 6], tmax: f32) -> (f32x8, u32) {
        let mut tn = self.packet_tmin;
        let mut tf = f32x8::splat(tmax);
        for axis in 0..3 {
            let dn = f32x8::from(bounds[self.near[axis]]) - self.near_o[axis];
            let df = f32x8::from(bounds[self.far[axis]]) - self.far_o[axis];
            tn = tn.max((dn * self.inv_lo[axis]).min(dn * self.inv_hi[axis]));
            tf = tf.min((df * self.inv_lo[axis]).max(df * self.inv_hi[axis]));
        }
        let tf = tf * f32x8::splat(1.0 + 2.0 * gamma(3));
        (tn, tn.simd_le(tf).to_bitmask())
    }

    /// Which lanes enter child `slot` of a node: each lane's own slab test,
    /// the same arithmetic as the single-ray test.
    #[inline(always)]
    fn test_lanes(&self, bounds: &[[f32; 8]; 6], slot: usize, tmax: f32x8) -> u32 {
        let mut tn = self.tmin;
        let mut tf = tmax;
        for axis in 0..3 {
            let bn = f32x8::splat(bounds[self.near[axis]][slot]);
            let bf = f32x8::splat(bounds[self.far[axis]][slot]);
            tn = tn.max((bn - self.origin[axis]) * self.inv[axis]);
            tf = tf.min((bf - self.origin[axis]) * self.inv[axis]);
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
    /// [`Bvh8::closest`] returns for `packet`'s ray `i`. `hit_leaf(lane,
    /// start, count, ray)` is the per-ray leaf test of [`Bvh8::closest`].
    pub fn closest_packet<F>(&self, packet: &Packet, out: &mut [Option<PrimHit>], mut hit_leaf: F)
    where
        F: FnMut(usize, u32, u32, &Ray) -> Option<PrimHit>,
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
            if t_enter > packet_tmax {
                continue;
            }
            match decode(child) {
                ChildRef::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let (tn, mut hit) = packet.test_node(&node.bounds, packet_tmax);
                    let tn = tn.to_array();
                    let mut order = [(0u32, 0.0f32, 0u32); 8];
                    let mut count = 0;
                    while hit != 0 {
                        let slot = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        let m = mask & packet.test_lanes(&node.bounds, slot, tmax_v);
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
                    let mut changed = false;
                    for lane in lanes(mask) {
                        let mut ray = rays[lane];
                        ray.tmax = tmax[lane];
                        let best = out[lane].as_ref();
                        let test = tie_ray(&ray, best);
                        if let Some(h) = hit_leaf(lane, start, count, &test) {
                            if closer(&h, best) {
                                tmax[lane] = h.t;
                                out[lane] = Some(h);
                                changed = true;
                            }
                        }
                    }
                    if changed {
                        tmax_v = f32x8::from(tmax);
                        packet_tmax = max_lane(&tmax);
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }

    /// Occlusion for a packet: `out[i]` is exactly what [`Bvh8::any_hit`]
    /// returns for ray `i`, with `blocks_leaf(lane, start, count, ray)` its
    /// leaf test. Lanes stop as soon as they are blocked.
    pub fn any_hit_packet<F>(&self, packet: &Packet, out: &mut [bool], mut blocks_leaf: F)
    where
        F: FnMut(usize, u32, u32, &Ray) -> bool,
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
                    let (_, mut hit) = packet.test_node(&node.bounds, packet_tmax);
                    while hit != 0 {
                        let slot = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        let m = mask & packet.test_lanes(&node.bounds, slot, tmax_v);
                        if m != 0 {
                            stack.push((node.child[slot], m));
                        }
                    }
                }
                ChildRef::Leaf { start, count } => {
                    for lane in lanes(mask) {
                        if blocks_leaf(lane, start, count, &rays[lane]) {
                            out[lane] = true;
                            open &= !(1 << lane);
                        }
                    }
                    if open == 0 {
                        return;
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }
}
