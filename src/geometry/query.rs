//! The queries: closest hit and occlusion, for one ray or a packet of up
//! to [`PACKET_SIZE`]. Packets return bit for bit the single-ray answers.

use super::Geometry;
use crate::accel::{Packet, PrimHit, PACKET_SIZE};
use crate::math::ray::ray_lanes;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle8::ShearedRays;

/// The packet of up to [`PACKET_SIZE`] rays, whose lanes a leaf test makes
/// the per-lane shears from ([`ShearedRays::from_lanes`]) once a leaf is
/// reached; `None` where the rays cannot travel as a packet (see
/// [`Packet::new`]).
#[inline(always)]
fn packet_of(rays: &[Ray]) -> Option<Packet<'_>> {
    if rays.is_empty() || rays.len() > PACKET_SIZE {
        return None;
    }
    Packet::from_lanes(rays, &ray_lanes(rays))
}

impl Geometry {
    /// The closest hit in `(ray.tmin, ray.tmax)`. Planes report prim ids
    /// `u32::MAX - plane index`.
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        // The shear is made at the first leaf: most rays of a sparse view
        // miss every leaf box.
        let mut sheared = None;
        let best = self.bvh.closest(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.hit_leaf(start, count, r, s)
        });
        self.closest_plane(ray, best)
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

    /// Closest hits of up to [`PACKET_SIZE`] rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. The rays traverse as one packet unless
    /// [`Packet::new`] refuses them (directions differing in sign on every
    /// axis).
    pub fn intersect_packet(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        let Some(packet) = packet_of(rays) else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.intersect(r);
            }
            return;
        };
        let mut sheared = None;
        self.bvh.closest_packet(
            &packet,
            out,
            &self.leaf_blocks,
            |start, count, lanes, out| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.hit_leaf_packet(rays, s, start, count, lanes, out)
            },
        );
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.closest_plane(r, *o);
            }
        }
    }

    /// True if anything blocks the ray in `(ray.tmin, ray.tmax)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        // No primitive has id u32::MAX (planes count down from it, outside the BVH).
        self.occluded_except(ray, u32::MAX)
    }

    /// Occlusion of up to [`PACKET_SIZE`] rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. One packet unless the
    /// rays' directions differ in sign on every axis ([`Packet::new`]).
    pub fn occluded_packet(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        let Some(packet) = packet_of(rays) else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.occluded_except(r, except);
            }
            return;
        };
        let mut sheared = None;
        self.bvh
            .any_hit_packet(&packet, out, &self.leaf_blocks, |start, count, lanes| {
                let s = sheared.get_or_insert_with(|| ShearedRays::from_lanes(packet.lanes()));
                self.blocks_leaf_packet(rays, s, start, count, lanes, except)
            });
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = *o || self.planes.iter().any(|p| p.intersect(r).is_some());
            }
        }
    }

    /// True if anything other than primitive `except` (the light being
    /// sampled) blocks the ray. Skipping the light's own primitive is exact,
    /// where stopping the shadow ray a little short of it would need an epsilon.
    pub fn occluded_except(&self, ray: &Ray, except: u32) -> bool {
        if self.planes.iter().any(|p| p.intersect(ray).is_some()) {
            return true;
        }
        let mut sheared = None;
        self.bvh.any_hit(ray, &self.leaf_blocks, |start, count, r| {
            let s = sheared.get_or_insert_with(|| ShearedRay::new(ray));
            self.blocks_leaf(start, count, r, s, except)
        })
    }

    /// Closest hits of any number of rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. Where the BVH prefetches (a tree that
    /// outgrows the caches, [`crate::accel::prefetch`]) several rays are
    /// in flight at once ([`crate::accel::stream`]); on a tree that fits
    /// the caches there is no wait to overlap, and one ray at a time is as
    /// fast or faster (bunny, 300,000 rays: random 7.4–7.5 Mrays/s in
    /// flight against 7.1–8.0, camera 10.8–14.3 against 14.7–14.9).
    pub fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        if !self.bvh.prefetch {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.intersect(r);
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
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.closest_plane(r, *o);
            }
        }
    }

    /// Occlusion of any number of rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. Several rays in flight
    /// where the BVH prefetches, as for [`Geometry::intersect_stream`].
    pub fn occluded_stream(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        if !self.bvh.prefetch {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = self.occluded_except(r, except);
            }
            return;
        }
        for (o, r) in out.iter_mut().zip(rays) {
            *o = self.planes.iter().any(|p| p.intersect(r).is_some());
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
