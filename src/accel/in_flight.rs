//! Several single-ray walks in flight on one thread.
//!
//! One ray's walk is a chain of dependent loads: a node's boxes decide
//! which node is read next, and on a mesh that outgrows the caches most of
//! those reads miss. An out-of-order core cannot look past that chain into
//! the next ray, whose first instruction is hundreds of instructions away.
//! Advancing [`IN_FLIGHT`] independent rays one step each in turn, each
//! prefetching the node or leaf it will read at its next step, keeps that
//! many chains' misses in flight at once: the interleaving of independent
//! lookups of Kocberber, Falsafi and Grot 2015 ("Asynchronous Memory
//! Access Chaining", PVLDB 9(4)), applied to BVH walks.
//!
//! Each ray takes exactly the steps of its own [`Bvh8::walk`]
//! ([`super::walk`]), so its answer is bit for bit the single-ray one;
//! only the order of memory accesses across rays changes.

use super::build::Bvh8;
use super::node_test::RayPlanes;
use super::query::Query;
use super::walk::{NearestFirst, Walk, WalkOrder};
use crate::math::Ray;

/// Rays in flight at once: a batch's width; more would spend registers
/// and cache on walks of rays that finish early (docs/embree.md, "Rays in
/// flight").
pub const IN_FLIGHT: usize = 8;

impl Bvh8 {
    /// `out[i] = self.walk(&rays[i], ..)` for every ray whose `out[i]` is
    /// not already an answer by `done` (for occlusion, a ray a cheaper
    /// test found blocked), with up to [`IN_FLIGHT`] rays in flight and
    /// one `query` shared by all.
    #[inline(always)]
    pub fn walk_in_flight<Q, L>(
        &self,
        rays: &[Ray],
        leaf_data: &[L],
        query: &mut Q,
        out: &mut [Q::Answer],
        done: impl Fn(&Q::Answer) -> bool,
    ) where
        Q: Query,
    {
        self.walk_in_flight_by::<_, _, _, IN_FLIGHT>(
            rays,
            NearestFirst,
            leaf_data,
            query,
            out,
            done,
        );
    }

    /// [`Bvh8::walk_in_flight`] in `order`, with `W` rays in flight (1 to
    /// 32): each ray's walk is `walk_by(ray, RayPlanes, order, ..)`'s.
    /// Walks that never end early (every crossing) take more than
    /// [`IN_FLIGHT`] (`geometry::crossings`).
    #[inline(always)]
    pub fn walk_in_flight_by<O, Q, L, const W: usize>(
        &self,
        rays: &[Ray],
        _order: O,
        leaf_data: &[L],
        query: &mut Q,
        out: &mut [Q::Answer],
        done: impl Fn(&Q::Answer) -> bool,
    ) where
        O: WalkOrder,
        Q: Query,
    {
        const { assert!(W >= 1 && W <= 32, "the live walks are the bits of a u32") };
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        if rays.is_empty() {
            return;
        }
        if self.nodes.is_empty() {
            for (o, ray) in out.iter_mut().zip(rays) {
                if !done(o) {
                    let state = query.start(ray);
                    *o = query.answer(&state, false);
                }
            }
            return;
        }
        let mut next = 0;
        // Restarts `walk` for the next ray to walk; its index, or None
        // once every ray has been started.
        let mut launch =
            |walk: &mut Walk<RayPlanes, Q::State>, query: &mut Q, out: &[Q::Answer]| {
                while next < rays.len() {
                    let i = next;
                    next += 1;
                    if !done(&out[i]) {
                        walk.restart(&rays[i], RayPlanes::new(&rays[i]), query.start(&rays[i]));
                        return Some(i);
                    }
                }
                None
            };
        let boxes = RayPlanes::new(&rays[0]);
        let mut walks: [Walk<RayPlanes, Q::State>; W] =
            std::array::from_fn(|_| Walk::new(&rays[0], boxes, query.start(&rays[0])));
        let mut index = [0; W];
        let mut live = 0u32;
        for (k, (walk, i)) in walks.iter_mut().zip(&mut index).enumerate() {
            if let Some(first) = launch(walk, query, out) {
                *i = first;
                live |= 1 << k;
            }
        }
        while live != 0 {
            let mut m = live;
            while m != 0 {
                let k = m.trailing_zeros() as usize % W;
                m &= m - 1;
                let step = walks[k].step::<O, Q, L>(self, leaf_data, query, self.prefetch);
                if let Some(a) = step {
                    out[index[k]] = a;
                    match launch(&mut walks[k], query, out) {
                        Some(i) => index[k] = i,
                        None => live &= !(1 << k),
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::super::hit::PrimHit;
    use super::super::query::{ClosestHit, Occlusion};
    use super::super::walk::tests::{sphere_cloud, sphere_hit, spheres_block};
    use super::super::walk::AnyOrder;
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use crate::shape::sphere::Sphere;
    use glam::Vec3;
    use std::cell::RefCell;
    use std::collections::HashMap;

    const NO_DATA: &[()] = &[];

    /// Random spheres, and a clump of identical ones deep enough that the
    /// rays through it spill their stacks to the heap, and their tree.
    fn cloud() -> (Vec<Sphere>, Bvh8) {
        sphere_cloud(3, 600, 0.6, (Vec3::new(4.0, 4.0, 4.0), 0.5, 3000))
    }

    /// Rays through the cloud, a third of them aimed at the clump; every
    /// origin differs, so a leaf test can tell which ray called it.
    fn rays(n: usize) -> Vec<Ray> {
        let mut rng = seeded(4);
        (0..n)
            .map(|i| {
                let o = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 30.0 - 15.0;
                let d = if i % 3 == 0 {
                    Vec3::new(4.0, 4.0, 4.0) - o
                } else {
                    Vec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5
                };
                let mut ray = Ray::new(o, d);
                ray.tmax = 5.0 + rng.unit() * 40.0;
                ray
            })
            .collect()
    }

    type Visits = RefCell<HashMap<[u32; 3], Vec<(u32, u32)>>>;

    fn key(r: &Ray) -> [u32; 3] {
        r.origin.to_array().map(f32::to_bits)
    }

    /// Notes that the ray with `r`'s origin visited leaf `start..start + count`.
    fn record(visits: &Visits, r: &Ray, start: u32, count: u32) {
        visits
            .borrow_mut()
            .entry(key(r))
            .or_default()
            .push((start, count));
    }

    /// Every ray's answer and the leaves it visited, in order, are those of
    /// its own single-ray walk, for any number of rays (fewer than
    /// [`IN_FLIGHT`] too); each walk's state starts fresh.
    #[test]
    fn walks_in_flight_answer_and_visit_what_single_rays_do() {
        let (spheres, bvh) = cloud();
        let hit = |id: u32, r: &Ray| sphere_hit(&spheres, id, r);
        for n in [0, 1, 3, IN_FLIGHT, IN_FLIGHT + 1, 1001] {
            let rays = rays(n);
            let (single, in_flight): (Visits, Visits) = Default::default();
            let expected: Vec<Option<PrimHit>> = rays
                .iter()
                .map(|ray| {
                    bvh.closest_hit(ray, NO_DATA, |start, count, r| {
                        record(&single, r, start, count);
                        bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                    })
                })
                .collect();
            let mut got = vec![None; n];
            let mut query = ClosestHit::new(|calls: &mut u32, start, count, r: &Ray| {
                *calls += 1;
                assert_eq!(
                    *calls as usize,
                    in_flight.borrow().get(&key(r)).map_or(0, Vec::len) + 1,
                    "a walk's state is its own ray's"
                );
                record(&in_flight, r, start, count);
                bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
            });
            bvh.walk_in_flight(&rays, NO_DATA, &mut query, &mut got, |_| false);
            assert_eq!(got, expected, "{n} rays");
            assert_eq!(in_flight.into_inner(), single.into_inner(), "{n} rays");
        }
    }

    /// Any number of walks in flight (one, a few, more than the default,
    /// the most) answers and visits as single rays do, in either order.
    #[test]
    fn every_width_answers_and_visits_what_single_rays_do() {
        fn check<const W: usize, O: WalkOrder + Default>(bvh: &Bvh8, spheres: &[Sphere]) {
            let rays = rays(301);
            let hit = |id: u32, r: &Ray| sphere_hit(spheres, id, r);
            let (single, in_flight): (Visits, Visits) = Default::default();
            let expected: Vec<Option<PrimHit>> = rays
                .iter()
                .map(|ray| {
                    let mut query = ClosestHit::new(|_: &mut (), start, count, r: &Ray| {
                        record(&single, r, start, count);
                        bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                    });
                    bvh.walk_by(ray, RayPlanes::new(ray), O::default(), NO_DATA, &mut query)
                })
                .collect();
            let mut got = vec![None; rays.len()];
            let mut query = ClosestHit::new(|_: &mut (), start, count, r: &Ray| {
                record(&in_flight, r, start, count);
                bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
            });
            bvh.walk_in_flight_by::<O, _, _, W>(
                &rays,
                O::default(),
                NO_DATA,
                &mut query,
                &mut got,
                |_| false,
            );
            assert_eq!(got, expected, "{W} in flight");
            assert_eq!(in_flight.into_inner(), single.into_inner(), "{W} in flight");
        }
        let (spheres, bvh) = cloud();
        check::<1, NearestFirst>(&bvh, &spheres);
        check::<3, NearestFirst>(&bvh, &spheres);
        check::<16, AnyOrder>(&bvh, &spheres);
        check::<32, AnyOrder>(&bvh, &spheres);
    }

    /// Occlusion likewise, with rays already answered (`out` true) left
    /// unwalked, and with walks that stop at a blocker while their stacks
    /// still hold entries, spilled ones included, before the next ray reuses them.
    #[test]
    fn occlusion_walks_in_flight_answer_and_visit_what_single_rays_do() {
        let (spheres, bvh) = cloud();
        let blocks = |start, count, r: &Ray| spheres_block(&bvh, &spheres, start, count, r);
        for n in [0, 1, 5, 1001] {
            let rays = rays(n);
            let skipped = |i: usize| i % 4 == 1;
            let (single, in_flight): (Visits, Visits) = Default::default();
            let expected: Vec<bool> = rays
                .iter()
                .enumerate()
                .map(|(i, ray)| {
                    skipped(i)
                        || bvh.occluded(ray, NO_DATA, |start, count, r| {
                            record(&single, r, start, count);
                            blocks(start, count, r)
                        })
                })
                .collect();
            let mut got: Vec<bool> = (0..n).map(skipped).collect();
            let mut query = Occlusion::new(|_: &mut (), start, count, r: &Ray| {
                record(&in_flight, r, start, count);
                blocks(start, count, r)
            });
            bvh.walk_in_flight(&rays, NO_DATA, &mut query, &mut got, |&b| b);
            assert_eq!(got, expected, "{n} rays");
            assert_eq!(in_flight.into_inner(), single.into_inner(), "{n} rays");
            if n > 100 {
                let blocked = expected.iter().filter(|&&b| b).count();
                assert!(
                    blocked > n / 3 && blocked < n,
                    "both answers occur: {blocked} of {n}"
                );
            }
        }
    }

    /// An empty tree answers every ray without a walk.
    #[test]
    fn empty_trees_answer_every_ray() {
        let bvh = Bvh8::build(&[], BuildQuality::Medium);
        let rays = rays(20);
        let mut closest = vec![
            Some(PrimHit {
                t: 1.0,
                prim: 0,
                u: 0.0,
                v: 0.0,
                part: 0
            });
            20
        ];
        let mut query = ClosestHit::new(|_: &mut (), _, _, _: &Ray| unreachable!());
        bvh.walk_in_flight(&rays, NO_DATA, &mut query, &mut closest, |_| false);
        assert!(closest.iter().all(Option::is_none));
        let mut blocked: Vec<bool> = (0..20).map(|i| i % 2 == 0).collect();
        let mut query = Occlusion::new(|_: &mut (), _, _, _: &Ray| unreachable!());
        bvh.walk_in_flight(&rays, NO_DATA, &mut query, &mut blocked, |&b| b);
        assert_eq!(blocked, (0..20).map(|i| i % 2 == 0).collect::<Vec<_>>());
    }
}
