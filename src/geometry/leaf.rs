//! Leaf kernels: what traversal runs when it reaches a BVH leaf. A leaf
//! is a run of slots inside one [`TriangleBlock`](crate::shape::triangle_lanes::TriangleBlock): its triangles are tested
//! in one 8-wide watertight test ([`crate::shape::triangle_lanes`]), then any
//! analytic shapes the leaf holds one by one.

use super::Geometry;
use crate::accel::hit::{closer, keep_tied, tie_end, tie_ray};
use crate::accel::{PrimHit, PACKET_SIZE};
use crate::math::lanes::LANES;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle_lanes::{self, ShearedRays, TriangleBlock};
use wide::u32x8;

impl Geometry {
    /// The lanes of leaf `start..start + count` in its block.
    #[inline(always)]
    pub(crate) fn leaf_lanes(start: u32, count: u32) -> (usize, u32) {
        let lo = start % LANES as u32;
        ((start / LANES as u32) as usize, ((1u32 << count) - 1) << lo)
    }

    /// The closest hit in leaf `start..start + count`: its triangles in one
    /// 8-wide test, then any analytic shapes it holds. A triangle hit
    /// records its slot in `part`, so [`Geometry::surface`] finds its vertices.
    #[inline(always)]
    pub(super) fn hit_leaf(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        sheared: &ShearedRay,
    ) -> Option<PrimHit> {
        let (b, lanes) = Self::leaf_lanes(start, count);
        self.hit_lanes(b, lanes, ray, sheared)
    }

    /// [`Geometry::hit_leaf`] for the slots `lanes` of block `b`.
    #[inline(always)]
    pub(super) fn hit_lanes(
        &self,
        b: usize,
        lanes: u32,
        ray: &Ray,
        sheared: &ShearedRay,
    ) -> Option<PrimHit> {
        let block = &self.leaf_blocks[b];
        let (triangles, others) = self.split_lanes(block, lanes);
        // A leaf of analytic shapes alone skips the 8-wide test (its
        // lanes' NaN vertices would reject the ray anyway).
        let hit = (triangles != 0)
            .then(|| triangle_lanes::closest(ray, sheared, block, triangles))
            .flatten();
        let mut best = hit.map(|h| PrimHit {
            t: h.t,
            prim: block.id[h.lane],
            u: h.u,
            v: h.v,
            part: (b * LANES + h.lane) as u32,
        });
        if others != 0 {
            let mut ray = tie_ray(ray, best.as_ref());
            let mut m = others;
            while m != 0 {
                let id = block.id[m.trailing_zeros() as usize];
                m &= m - 1;
                if let Some(h) = self.hit_other(id, &ray) {
                    keep_tied(&mut best, &mut ray.tmax, h);
                }
            }
        }
        best
    }

    /// The slots of `lanes` in `block` that hold triangles, and those that
    /// hold anything else (analytic shapes, instances): the ids at or past
    /// the triangles'. A scene of triangles alone asks no id.
    #[inline(always)]
    fn split_lanes(&self, block: &TriangleBlock, lanes: u32) -> (u32, u32) {
        if !self.has_others() {
            return (lanes, 0);
        }
        // The eight ids in one compare: a loop over a leaf's one or two
        // slots mispredicted its count and its compares (a tenth of a
        // lone walk's time on a scene of a few shapes).
        let triangles = u32x8::from(block.id)
            .simd_lt(u32x8::splat(self.triangle_count))
            .to_bitmask();
        (lanes & triangles, lanes & !triangles)
    }

    /// True if something in leaf `start..start + count` other than
    /// primitive `except` blocks the ray.
    #[inline(always)]
    pub(super) fn blocks_leaf(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        sheared: &ShearedRay,
        except: u32,
    ) -> bool {
        let (b, lanes) = Self::leaf_lanes(start, count);
        self.blocks_lanes(b, lanes, ray, sheared, except)
    }

    /// [`Geometry::blocks_leaf`] for the slots `lanes` of block `b`.
    #[inline(always)]
    pub(super) fn blocks_lanes(
        &self,
        b: usize,
        lanes: u32,
        ray: &Ray,
        sheared: &ShearedRay,
        except: u32,
    ) -> bool {
        let block = &self.leaf_blocks[b];
        let (triangles, others) = self.split_lanes(block, lanes);
        let mut hit = if triangles != 0 {
            triangle_lanes::intersect(ray, sheared, block, triangles).0
        } else {
            0
        };
        while hit != 0 {
            let lane = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            if block.id[lane] != except {
                return true;
            }
        }
        let mut m = others;
        while m != 0 {
            let id = block.id[m.trailing_zeros() as usize];
            m &= m - 1;
            if id != except && self.other_blocks(id, ray) {
                return true;
            }
        }
        false
    }

    /// Whether a packet leaf holding `count` primitives is cheaper tested
    /// ray by ray, each ray against the whole leaf as a single ray tests it
    /// (one 8-wide test per ray), than primitive by primitive against the
    /// rays in lanes (one per primitive): where no more rays reach it than
    /// it holds primitives. One or two rays reach most of a camera
    /// packet's leaves (docs/embree.md, "Narrow groups as packets").
    #[inline(always)]
    fn ray_by_ray(rays_mask: u32, count: u32) -> bool {
        rays_mask.count_ones() <= count
    }

    /// [`Geometry::hit_leaf`] for the packet rays in the bits of `rays_mask`:
    /// each triangle of the leaf against all those rays in one 8-wide test
    /// (rays in lanes), or ray by ray where [`Geometry::ray_by_ray`] says.
    /// Updates `out[ray]` with any hit [`closer`] than it and returns
    /// whether any changed. The result per ray is the minimum of the same
    /// total order over the same candidates as [`Geometry::hit_leaf`], so
    /// it is bit for bit the single-ray answer.
    #[inline(always)]
    pub(super) fn hit_leaf_packet(
        &self,
        rays: &[Ray],
        sheared: &ShearedRays,
        start: u32,
        count: u32,
        rays_mask: u32,
        out: &mut [Option<PrimHit>],
    ) -> bool {
        let mut changed = false;
        if Self::ray_by_ray(rays_mask, count) {
            let mut r = rays_mask;
            while r != 0 {
                let i = r.trailing_zeros() as usize;
                r &= r - 1;
                // Up to and including the best t, for ties, as below.
                let ray = tie_ray(&rays[i], out[i].as_ref());
                if let Some(h) = self.hit_leaf(start, count, &ray, &ShearedRay::new(&ray)) {
                    if closer(&h, out[i].as_ref()) {
                        out[i] = Some(h);
                        changed = true;
                    }
                }
            }
            return changed;
        }
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        // Each ray's interval: up to and including its best t, for ties.
        let mut tmax = [f32::NEG_INFINITY; PACKET_SIZE];
        for (i, r) in rays.iter().enumerate() {
            tmax[i] = tie_end(r.tmax, out[i].as_ref());
        }
        let mut m = lanes;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let id = block.id[lane];
            if id < self.triangle_count {
                let tri = block.triangle(lane);
                let (mut hit, t, u, v) = sheared.intersect(&tri, tmax.into(), rays_mask);
                while hit != 0 {
                    let i = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    let h = PrimHit {
                        t: t[i],
                        prim: id,
                        u: u[i],
                        v: v[i],
                        part: (b * LANES + lane) as u32,
                    };
                    changed |= keep_tied(&mut out[i], &mut tmax[i], h);
                }
            } else if id >= self.first_instance() {
                // The packet's rays enter the instance together
                // (`super::instance_bundle`).
                let ray_of = |i: usize| {
                    Some(Ray {
                        tmax: tmax[i],
                        ..rays[i]
                    })
                };
                let found = self.hit_instance_rays(id, u64::from(rays_mask), ray_of);
                for (i, h) in found.hits() {
                    changed |= keep_tied(&mut out[i], &mut tmax[i], h);
                }
            } else {
                let mut r = rays_mask;
                while r != 0 {
                    let i = r.trailing_zeros() as usize;
                    r &= r - 1;
                    let ray = Ray {
                        tmax: tmax[i],
                        ..rays[i]
                    };
                    if let Some(h) = self.hit_analytic(id, &ray) {
                        changed |= keep_tied(&mut out[i], &mut tmax[i], h);
                    }
                }
            }
        }
        changed
    }

    /// [`Geometry::blocks_leaf`] for the packet rays in the bits of
    /// `rays_mask`, by triangle or by ray as [`Geometry::ray_by_ray`] says;
    /// returns the rays blocked.
    #[inline(always)]
    pub(super) fn blocks_leaf_packet(
        &self,
        rays: &[Ray],
        sheared: &ShearedRays,
        start: u32,
        count: u32,
        rays_mask: u32,
        except: u32,
    ) -> u32 {
        if Self::ray_by_ray(rays_mask, count) {
            let mut blocked = 0;
            let mut r = rays_mask;
            while r != 0 {
                let i = r.trailing_zeros() as usize;
                r &= r - 1;
                let ray = &rays[i];
                if self.blocks_leaf(start, count, ray, &ShearedRay::new(ray), except) {
                    blocked |= 1 << i;
                }
            }
            return blocked;
        }
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        let mut tmax = [f32::NEG_INFINITY; PACKET_SIZE];
        for (i, r) in rays.iter().enumerate() {
            tmax[i] = r.tmax;
        }
        let tmax = tmax.into();
        let mut open = rays_mask;
        let mut m = lanes;
        while m != 0 && open != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let id = block.id[lane];
            if id == except {
                continue;
            }
            if id < self.triangle_count {
                open &= !sheared.intersect(&block.triangle(lane), tmax, open).0;
            } else if id >= self.first_instance() {
                let ray_of = |i: usize| Some(rays[i]);
                open &= !(self.instance_blocks_rays(id, u64::from(open), ray_of) as u32);
            } else {
                let mut r = open;
                while r != 0 {
                    let i = r.trailing_zeros() as usize;
                    r &= r - 1;
                    if self.other_blocks(id, &rays[i]) {
                        open &= !(1 << i);
                    }
                }
            }
        }
        rays_mask & !open
    }
}
