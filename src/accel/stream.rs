//! Several rays in flight on one thread.
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
//! Each ray takes exactly the steps of its own [`Bvh8::closest`] or
//! [`Bvh8::any_hit`] walk ([`super::walk`]), so its answer is bit for bit
//! the single-ray one; only the order of memory accesses across rays
//! changes.

use super::build::Bvh8;
use super::hit::PrimHit;
use super::walk::{AnyHitWalk, ClosestWalk};
use crate::math::Ray;

/// Rays in flight at once. Random dragon rays that enter the mesh's box,
/// occlusion, one thread, Mrays/s (medians of three): 2.7 for one ray at
/// a time, 3.3 for two, 3.4 for three, 3.5 to 3.6 for six to twelve
/// without the prefetch of each walk's next node, and with it 4.4 for
/// six, 4.7 for eight and twelve, 4.9 for sixteen. Eight matches a render
/// batch's width, and more would spend registers and cache on walk state
/// for rays that finish early.
pub const IN_FLIGHT: usize = 8;

/// Runs `step` round-robin over up to [`IN_FLIGHT`] walks until every
/// index of `out` is answered. Walks are made once by `make` and reused:
/// `start(walk, i, &out[i])` restarts `walk` for ray `i`, or returns false
/// if `out[i]` already holds its answer; `step(walk, i)` advances ray `i`'s
/// walk by one node or leaf and returns its answer when it is over.
#[inline(always)]
fn interleave<W, O>(
    out: &mut [O],
    make: impl Fn() -> W,
    mut start: impl FnMut(&mut W, usize, &O) -> bool,
    mut step: impl FnMut(&mut W, usize) -> Option<O>,
) {
    let mut next = 0;
    // Starts the next ray that needs a walk in `walk`; its index, or None
    // once every ray has been started.
    let mut launch = |walk: &mut W, out: &[O]| {
        while next < out.len() {
            let i = next;
            next += 1;
            if start(walk, i, &out[i]) {
                return Some(i);
            }
        }
        None
    };
    let mut walks: [W; IN_FLIGHT] = std::array::from_fn(|_| make());
    let mut index = [0; IN_FLIGHT];
    let mut live = 0u32;
    for (k, (walk, i)) in walks.iter_mut().zip(&mut index).enumerate() {
        if let Some(first) = launch(walk, out) {
            *i = first;
            live |= 1 << k;
        }
    }
    while live != 0 {
        let mut m = live;
        while m != 0 {
            let k = m.trailing_zeros() as usize % IN_FLIGHT;
            m &= m - 1;
            if let Some(answer) = step(&mut walks[k], index[k]) {
                out[index[k]] = answer;
                match launch(&mut walks[k], out) {
                    Some(i) => index[k] = i,
                    None => live &= !(1 << k),
                }
            }
        }
    }
}

impl Bvh8 {
    /// `out[i] = self.closest(&rays[i], ..)` for every ray, with up to
    /// [`IN_FLIGHT`] rays in flight. `hit_leaf(state, start, count, ray)`
    /// as for [`Bvh8::closest`], plus `state`: the leaf test's own data for
    /// the ray, `S::default()` when its walk starts.
    pub fn closest_stream<L, S, F>(
        &self,
        rays: &[Ray],
        leaf_data: &[L],
        mut hit_leaf: F,
        out: &mut [Option<PrimHit>],
    ) where
        S: Default,
        F: FnMut(&mut S, u32, u32, &Ray) -> Option<PrimHit>,
    {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        if self.nodes.is_empty() || rays.is_empty() {
            out.fill(None);
            return;
        }
        interleave(
            out,
            || ClosestWalk::new(&rays[0], S::default()),
            |walk, i, _| {
                walk.restart(&rays[i], S::default());
                true
            },
            |walk, _| walk.step(self, leaf_data, &mut hit_leaf, self.prefetch),
        );
    }

    /// `out[i] |= self.any_hit(&rays[i], ..)` for every ray, with up to
    /// [`IN_FLIGHT`] rays in flight; rays whose `out` is already true (a
    /// caller's cheaper test found a blocker) are not walked.
    /// `blocks_leaf(state, start, count, ray)` as for [`Bvh8::any_hit`],
    /// `state` as for [`Bvh8::closest_stream`].
    pub fn any_hit_stream<L, S, F>(
        &self,
        rays: &[Ray],
        leaf_data: &[L],
        mut blocks_leaf: F,
        out: &mut [bool],
    ) where
        S: Default,
        F: FnMut(&mut S, u32, u32, &Ray) -> bool,
    {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        if self.nodes.is_empty() || rays.is_empty() {
            return;
        }
        interleave(
            out,
            || AnyHitWalk::new(&rays[0], S::default()),
            |walk, i, &blocked| {
                if !blocked {
                    walk.restart(&rays[i], S::default());
                }
                !blocked
            },
            |walk, i| walk.step(self, &rays[i], leaf_data, &mut blocks_leaf, self.prefetch),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::super::traverse::tests::{sphere_cloud, sphere_hit, spheres_block};
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
    fn streams_answer_and_visit_what_single_rays_do() {
        let (spheres, bvh) = cloud();
        let hit = |id: u32, r: &Ray| sphere_hit(&spheres, id, r);
        for n in [0, 1, 3, IN_FLIGHT, IN_FLIGHT + 1, 1001] {
            let rays = rays(n);
            let (single, in_flight): (Visits, Visits) = Default::default();
            let expected: Vec<Option<PrimHit>> = rays
                .iter()
                .map(|ray| {
                    bvh.closest(ray, NO_DATA, |start, count, r| {
                        record(&single, r, start, count);
                        bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                    })
                })
                .collect();
            let mut got = vec![None; n];
            bvh.closest_stream(
                &rays,
                NO_DATA,
                |calls: &mut u32, start, count, r| {
                    *calls += 1;
                    assert_eq!(
                        *calls as usize,
                        in_flight.borrow().get(&key(r)).map_or(0, Vec::len) + 1,
                        "a walk's state is its own ray's"
                    );
                    record(&in_flight, r, start, count);
                    bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                },
                &mut got,
            );
            assert_eq!(got, expected, "{n} rays");
            assert_eq!(in_flight.into_inner(), single.into_inner(), "{n} rays");
        }
    }

    /// Occlusion likewise, with rays already answered (`out` true) left
    /// unwalked, and with walks that stop at a blocker while their stacks
    /// still hold entries, spilled ones included, before the next ray reuses them.
    #[test]
    fn any_hit_streams_answer_and_visit_what_single_rays_do() {
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
                        || bvh.any_hit(ray, NO_DATA, |start, count, r| {
                            record(&single, r, start, count);
                            blocks(start, count, r)
                        })
                })
                .collect();
            let mut got: Vec<bool> = (0..n).map(skipped).collect();
            bvh.any_hit_stream(
                &rays,
                NO_DATA,
                |_: &mut (), start, count, r| {
                    record(&in_flight, r, start, count);
                    blocks(start, count, r)
                },
                &mut got,
            );
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
        bvh.closest_stream(
            &rays,
            NO_DATA,
            |_: &mut (), _, _, _| unreachable!(),
            &mut closest,
        );
        assert!(closest.iter().all(Option::is_none));
        let mut blocked: Vec<bool> = (0..20).map(|i| i % 2 == 0).collect();
        bvh.any_hit_stream(
            &rays,
            NO_DATA,
            |_: &mut (), _, _, _| unreachable!(),
            &mut blocked,
        );
        assert_eq!(blocked, (0..20).map(|i| i % 2 == 0).collect::<Vec<_>>());
    }
}
