//! The queries: closest hit and occlusion, for one ray, a packet of up to
//! [`PACKET_SIZE`], or a stream of any number. Packets and streams return
//! bit for bit the single-ray answers.

use super::bundles::StreamPart;
use super::Geometry;
use crate::accel::beam::{split_narrow, Travel};
use crate::accel::bundle::BUNDLE_SIZE;
use crate::accel::packet::{misses_box, reciprocals};
use crate::accel::{Packet, PrimHit, PACKET_SIZE};
use crate::math::ray::ray_lanes;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle_lanes::ShearedRays;

/// How a batch of up to [`PACKET_SIZE`] rays is traced. Made and matched
/// on the stack within one query, so the packet stays unboxed: boxing it
/// would allocate once per batch.
#[allow(clippy::large_enum_variant)]
enum Batch<'r> {
    /// As one packet, whose lanes a leaf test makes the per-lane shears
    /// from ([`ShearedRays::from_lanes`]) once a leaf is reached.
    Packet(Packet<'r>),
    /// Not at all: every ray misses the tree's box ([`misses_box`]).
    Outside,
    /// One ray at a time: the rays cannot travel as a packet (see
    /// [`Packet::new`]).
    Alone,
}

impl Geometry {
    /// How `rays` travel: not at all where they all miss the tree's box,
    /// else as a packet where they can.
    #[inline(always)]
    fn batch_of<'r>(&self, rays: &'r [Ray]) -> Batch<'r> {
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return Batch::Alone;
        }
        let lanes = ray_lanes(rays);
        let inv = reciprocals(&lanes);
        if misses_box(&lanes, &inv, &self.bvh.bounds) {
            return Batch::Outside;
        }
        match Packet::from_parts(rays, &lanes, &inv) {
            Some(packet) => Batch::Packet(packet),
            None => Batch::Alone,
        }
    }

    /// The closest hit in `(ray.tmin, ray.tmax)`. Planes report prim ids
    /// `u32::MAX - plane index`.
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.closest_plane(ray, self.closest_in_bvh(ray))
    }

    /// The BVH's closest hit (planes aside).
    #[inline]
    fn closest_in_bvh(&self, ray: &Ray) -> Option<PrimHit> {
        // The shear is made at the first leaf: most rays of a sparse view
        // miss every leaf box.
        let mut sheared = None;
        self.bvh.closest(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.hit_leaf(start, count, r, s)
        })
    }

    /// `best`, or a plane hit nearer than it.
    #[inline]
    fn closest_plane(&self, ray: &Ray, mut best: Option<PrimHit>) -> Option<PrimHit> {
        let mut tmax = best.map_or(ray.tmax, |h| h.t);
        for (i, plane) in self.planes.iter().enumerate() {
            let r = Ray { tmax, ..*ray };
            if let Some(t) = plane.intersect(&r) {
                tmax = t;
                best = Some(PrimHit {
                    t,
                    prim: u32::MAX - i as u32,
                    u: 0.0,
                    v: 0.0,
                    part: 0,
                });
            }
        }
        best
    }

    /// `out[i]`, or a plane hit nearer than it, for every ray.
    #[inline]
    fn closest_planes(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.closest_plane(r, *o);
            }
        }
    }

    /// Closest hits of up to [`PACKET_SIZE`] rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. The rays traverse as one packet unless
    /// they all miss the tree's box (then not at all) or [`Packet::new`]
    /// refuses them (directions differing in sign on every axis).
    pub fn intersect_packet(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        match self.batch_of(rays) {
            Batch::Packet(packet) => self.closest_in_packet(&packet, rays, out),
            Batch::Outside => out[..rays.len()].fill(None),
            Batch::Alone => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self.closest_in_bvh(r);
                }
            }
        }
        self.closest_planes(rays, out);
    }

    /// The BVH's closest hits of `packet`, whose rays are `rays` (planes
    /// aside).
    fn closest_in_packet(&self, packet: &Packet, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        let mut sheared = None;
        self.bvh.closest_packet(
            packet,
            out,
            &self.leaf_blocks,
            |start, count, lanes, out| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.hit_leaf_packet(rays, s, start, count, lanes, out)
            },
        );
    }

    /// True if anything blocks the ray in `(ray.tmin, ray.tmax)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        // No primitive has id u32::MAX (planes count down from it, outside the BVH).
        self.occluded_except(ray, u32::MAX)
    }

    /// Occlusion of up to [`PACKET_SIZE`] rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. One packet unless the
    /// rays all miss the tree's box or their directions differ in sign on
    /// every axis ([`Packet::new`]).
    pub fn occluded_packet(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        match self.batch_of(rays) {
            Batch::Packet(packet) => self.blocked_in_packet(&packet, rays, except, out),
            Batch::Outside => out[..rays.len()].fill(false),
            Batch::Alone => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self.blocked_in_bvh(r, except);
                }
            }
        }
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = *o || self.blocked_by_planes(r);
            }
        }
    }

    /// Whether the BVH blocks each of `packet`'s rays, `rays` (planes
    /// aside).
    fn blocked_in_packet(&self, packet: &Packet, rays: &[Ray], except: u32, out: &mut [bool]) {
        let mut sheared = None;
        self.bvh
            .any_hit_packet(packet, out, &self.leaf_blocks, |start, count, lanes| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.blocks_leaf_packet(rays, s, start, count, lanes, except)
            });
    }

    /// True if anything other than primitive `except` (the light being
    /// sampled) blocks the ray. Skipping the light's own primitive is exact,
    /// where stopping the shadow ray a little short of it would need an epsilon.
    pub fn occluded_except(&self, ray: &Ray, except: u32) -> bool {
        self.blocked_by_planes(ray) || self.blocked_in_bvh(ray, except)
    }

    /// Whether a plane (outside the BVH) blocks the ray.
    #[inline]
    fn blocked_by_planes(&self, ray: &Ray) -> bool {
        self.planes.iter().any(|p| p.intersect(ray).is_some())
    }

    /// Whether the BVH blocks the ray (planes aside).
    #[inline]
    fn blocked_in_bvh(&self, ray: &Ray, except: u32) -> bool {
        let mut sheared = None;
        self.bvh.any_hit(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.blocks_leaf(start, count, r, s, except)
        })
    }

    /// Closest hits of any number of rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. Windows of rays from close origins or
    /// with close directions walk as bundles ([`crate::accel::bundle`],
    /// [`Geometry::split_stream`]). Of the rest, groups of eight
    /// consecutive rays narrow enough to share their walk travel as packets
    /// ([`crate::accel::beam`]); the others walk alone, several in flight
    /// at once where the BVH prefetches (a tree that outgrows the caches,
    /// [`crate::accel::prefetch`]; [`crate::accel::stream`]). On a tree
    /// that fits the caches there is no wait to overlap, and one ray at a
    /// time is as fast or faster (bunny, 300,000 rays: random 7.4–7.5
    /// Mrays/s in flight against 7.1–8.0, camera 10.8–14.3 against
    /// 14.7–14.9).
    pub fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        self.split_stream(rays, |part| match part {
            StreamPart::Run(range) => {
                self.closest_narrow_or_alone(&rays[range.clone()], &mut out[range]);
            }
            StreamPart::Bundle(range) => {
                self.closest_in_bundle(&rays[range.clone()], &mut out[range]);
            }
            StreamPart::Sorted(ids) => {
                on_gathered(rays, ids, out, |r, o| self.closest_in_bundle(r, o));
            }
        });
        self.closest_planes(rays, out);
    }

    /// The BVH's closest hits (planes aside): narrow groups as packets,
    /// the rest alone.
    fn closest_narrow_or_alone(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        split_narrow(rays, &self.bvh.bounds, |range, travel| {
            let (rays, out) = (&rays[range.clone()], &mut out[range]);
            match travel {
                Travel::Packet(packet) => self.closest_in_packet(packet, rays, out),
                Travel::Outside => out.fill(None),
                Travel::Alone => self.closest_alone(rays, out),
            }
        });
    }

    /// The BVH's closest hits of up to [`BUNDLE_SIZE`] rays walked as
    /// bundles (planes aside).
    fn closest_in_bundle(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        let mut sheared: [Option<ShearedRay>; BUNDLE_SIZE] = [None; BUNDLE_SIZE];
        self.bvh
            .closest_bundle(rays, out, &self.leaf_blocks, |i, start, count, r| {
                let s = sheared[i].get_or_insert_with(|| ShearedRay::new(&rays[i]));
                self.hit_leaf(start, count, r, s)
            });
    }

    /// The BVH's closest hits of rays that walk alone (planes aside).
    /// Not inlined into the stream's split: inlined there, next to the
    /// packet code, it compiled to 2% more instructions per random ray
    /// and ran 3% slower (dragon, one thread).
    #[inline(never)]
    fn closest_alone(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        if !self.bvh.prefetch {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.closest_in_bvh(r);
            }
            return;
        }
        self.bvh.closest_stream(
            rays,
            &self.leaf_blocks,
            |sheared: &mut Option<ShearedRay>, start, count, r| {
                let s = sheared.get_or_insert_with(|| ShearedRay::new(r));
                self.hit_leaf(start, count, r, s)
            },
            out,
        );
    }

    /// Occlusion of any number of rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. Bundles, packets and
    /// single rays as for [`Geometry::intersect_stream`].
    pub fn occluded_stream(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.blocked_by_planes(r);
        }
        self.split_stream(rays, |part| match part {
            StreamPart::Run(range) => {
                self.blocked_narrow_or_alone(&rays[range.clone()], except, &mut out[range]);
            }
            StreamPart::Bundle(range) => {
                self.blocked_in_bundle(&rays[range.clone()], except, &mut out[range]);
            }
            StreamPart::Sorted(ids) => {
                on_gathered(rays, ids, out, |r, o| self.blocked_in_bundle(r, except, o));
            }
        });
    }

    /// `out[i] |= ` whether the BVH blocks ray `i` (planes aside): narrow
    /// groups as packets, the rest alone.
    fn blocked_narrow_or_alone(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        split_narrow(rays, &self.bvh.bounds, |range, travel| {
            let (rays, out) = (&rays[range.clone()], &mut out[range]);
            match travel {
                Travel::Packet(packet) => {
                    let mut blocked = [false; PACKET_SIZE];
                    self.blocked_in_packet(packet, rays, except, &mut blocked);
                    for (o, b) in out.iter_mut().zip(blocked) {
                        *o |= b;
                    }
                }
                // Planes aside (already in `out`), nothing can block them.
                Travel::Outside => {}
                Travel::Alone => self.blocked_alone(rays, except, out),
            }
        });
    }

    /// `out[i] |= ` whether the BVH blocks ray `i` (planes aside), for up
    /// to [`BUNDLE_SIZE`] rays walked as bundles.
    fn blocked_in_bundle(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        let mut sheared: [Option<ShearedRay>; BUNDLE_SIZE] = [None; BUNDLE_SIZE];
        self.bvh
            .any_hit_bundle(rays, out, &self.leaf_blocks, |i, start, count| {
                let s = sheared[i].get_or_insert_with(|| ShearedRay::new(&rays[i]));
                self.blocks_leaf(start, count, &rays[i], s, except)
            });
    }

    /// `out[i] |= ` whether the BVH blocks ray `i` (planes aside), for
    /// rays that walk alone; rays already blocked are not walked. Not
    /// inlined, as for [`Geometry::closest_alone`].
    #[inline(never)]
    fn blocked_alone(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        if !self.bvh.prefetch {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = *o || self.blocked_in_bvh(r, except);
            }
            return;
        }
        self.bvh.any_hit_stream(
            rays,
            &self.leaf_blocks,
            |sheared: &mut Option<ShearedRay>, start, count, r| {
                let s = sheared.get_or_insert_with(|| ShearedRay::new(r));
                self.blocks_leaf(start, count, r, s, except)
            },
            out,
        );
    }
}

/// Runs `walk` on the rays `ids` names (up to [`BUNDLE_SIZE`], not
/// consecutive in the stream) gathered in that order, with their answers
/// in `out` gathered beside them (an occlusion bundle skips the rays a
/// plane already blocks), then scatters the answers back to `out`.
fn on_gathered<T: Copy + Default>(
    rays: &[Ray],
    ids: &[u32],
    out: &mut [T],
    walk: impl FnOnce(&[Ray], &mut [T]),
) {
    let n = ids.len();
    let filler = rays[ids[0] as usize];
    let group: [Ray; BUNDLE_SIZE] =
        std::array::from_fn(|k| ids.get(k).map_or(filler, |&i| rays[i as usize]));
    let mut answers: [T; BUNDLE_SIZE] =
        std::array::from_fn(|k| ids.get(k).map_or(T::default(), |&i| out[i as usize]));
    walk(&group[..n], &mut answers[..n]);
    for (&i, a) in ids.iter().zip(answers) {
        out[i as usize] = a;
    }
}
