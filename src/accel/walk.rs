//! The depth-first walk: one ray through the 8-wide BVH, generic over its
//! node test ([`NodeTest`]), its order ([`WalkOrder`]) and its [`Query`],
//! all monomorphised. One step (a node or a leaf, then the next) is
//! written twice over the same helpers ([`Bvh8::descend_nearest`],
//! `next_deferred`): as [`Walk::step`], whose state is a value that
//! [`super::in_flight`] interleaves across several rays, and as the loop
//! of [`Bvh8::walk_by`] (and so of [`Bvh8::walk`], [`Bvh8::closest_hit`],
//! [`Bvh8::occluded`] and [`Bvh8::visit_line`]), whose state is in locals
//! and whose way down the inner nodes is a loop of its own, so the ray's
//! values stay in registers from leaf to leaf (docs/performance.md, "The
//! lone walk"). With the same node test both visit the same leaves in
//! the same order; the tie rule (`super::hit`) would make any order give
//! the same answer anyway. A ray's node test, alone or in flight, is
//! `RayPlanes` (one fused multiply-add per slab), the test Embree's
//! one-ray kernel makes.
//!
//! Nearest first ([`NearestFirst`], [`super::descend`]), a closest-hit
//! walk skips a deferred child beyond its nearest hit; an occlusion walk
//! ends at its first blocker, and sorting its children still pays: the
//! nearest boxes hold the blocker a little more often (docs/embree.md,
//! "Sorted occlusion"). In any order ([`AnyOrder`]) nothing is sorted,
//! for queries that visit every leaf they reach (every crossing of a
//! line).

use super::build::Bvh8;
use super::descend::{descend_any, nearest_last, order_key};
use super::hit::{tie_ray, PrimHit};
use super::node::{is_leaf, leaf_range};
use super::node_test::{ChildBoxes, LineBoxes, NodeTest, RayPlanes};
use super::query::{keep_closer, ClosestHit, EveryLeaf, Occlusion, Query};
use super::stack::Stack;
use crate::math::Ray;

/// The order a depth-first walk visits the children it enters in.
pub trait WalkOrder {
    /// Nearest first, each deferred child keyed by its distance, so that
    /// a walk whose ray a hit shortens skips those beyond its end; else
    /// no order, and nothing sorted.
    const NEAREST_FIRST: bool;
}

/// Nearest child first, the others deferred farthest first: closest hit
/// and occlusion.
#[derive(Debug, Clone, Copy, Default)]
pub struct NearestFirst;

/// In any order, nothing sorted: for a query that visits every leaf its
/// walk reaches.
#[derive(Debug, Clone, Copy, Default)]
pub struct AnyOrder;

impl WalkOrder for NearestFirst {
    const NEAREST_FIRST: bool = true;
}

impl WalkOrder for AnyOrder {
    const NEAREST_FIRST: bool = false;
}

/// Where a walk stands: its ray (whose `tmax` a closest hit lowers), its
/// node test, the children it deferred, the node or leaf its next step
/// visits, and its query's state.
pub(crate) struct Walk<T, S> {
    ray: Ray,
    test: T,
    stack: Stack<u64>,
    current: u32,
    state: S,
}

impl<T: NodeTest, S> Walk<T, S> {
    /// A walk that starts at the root of a tree with at least one node.
    #[inline(always)]
    pub(crate) fn new(ray: &Ray, test: T, state: S) -> Self {
        Self {
            ray: *ray,
            test,
            stack: Stack::new(),
            current: 0,
            state,
        }
    }

    /// Starts the walk over for `ray`, reusing the stack's memory.
    #[inline(always)]
    pub(crate) fn restart(&mut self, ray: &Ray, test: T, state: S) {
        self.ray = *ray;
        self.test = test;
        self.stack.clear();
        self.current = 0;
        self.state = state;
    }

    /// Visits the current node or leaf and picks the next; once nothing is
    /// left to visit, or the query ends the walk, the query's answer. With
    /// `prefetch_next` the node or leaf picked is prefetched at once: worth
    /// it only when other rays' steps run before this walk's next one.
    #[inline(always)]
    pub(crate) fn step<O, Q, L>(
        &mut self,
        bvh: &Bvh8,
        leaf_data: &[L],
        query: &mut Q,
        prefetch_next: bool,
    ) -> Option<Q::Answer>
    where
        O: WalkOrder,
        Q: Query<State = S>,
    {
        if !is_leaf(self.current) {
            // An inner node: into one child the ray enters (nearest
            // first: the nearest), the others pushed (farthest first). A
            // ray that enters one child per level never touches the stack.
            let node = &bvh.nodes[self.current as usize];
            let (tn, mask) = self.test.test(ChildBoxes::new(&node.bounds), self.ray.tmax);
            if mask != 0 {
                self.current = if O::NEAREST_FIRST {
                    bvh.descend_nearest(&mut self.stack, leaf_data, &node.child, tn, mask)
                } else {
                    descend_any(&mut self.stack, &node.child, mask)
                };
                // Nearest first, the child picked may be among those
                // `descend_nearest` just prefetched.
                let prefetched = O::NEAREST_FIRST && bvh.prefetches_entered(mask);
                if prefetch_next && !prefetched {
                    bvh.prefetch_child(self.current, leaf_data);
                }
                return None;
            }
        } else {
            let (start, count) = leaf_range(self.current);
            if query.leaf(&mut self.state, start, count, &mut self.ray) {
                return Some(query.answer(&self.state, true));
            }
        }
        match next_deferred::<O, Q>(&mut self.stack, self.test.widened(self.ray.tmax)) {
            None => Some(query.answer(&self.state, false)),
            Some(next) => {
                self.current = next;
                if prefetch_next {
                    bvh.prefetch_child(self.current, leaf_data);
                }
                None
            }
        }
    }
}

/// The largest entry key (`entry >> 32`) a walk whose (widened) reach is
/// `reach` still visits: the reach's key with the slot bits set, so that
/// no child whose entry is within it is culled (see `nearest_last`).
#[inline(always)]
fn reach_key(reach: f32) -> u32 {
    order_key(reach) | 7
}

/// The nearest deferred child a walk whose (widened) reach is `reach` can
/// still reach, popped off `stack`; `None` once the stack is empty. The
/// entry distance carries rounding error like the box test's far
/// distance, so it is compared with the same widening: a child whose box
/// holds a triangle at exactly the best t (a ray along an edge shared
/// across two leaves) must still be visited, or the tie would go to
/// whichever leaf came first. Keys carry a slot in their low bits (see
/// `nearest_last`). An occlusion ray's end never moves, so every child it
/// pushed is still in reach.
#[inline(always)]
fn next_deferred<O: WalkOrder, Q: Query>(stack: &mut Stack<u64>, reach: f32) -> Option<u32> {
    let reach = reach_key(reach);
    loop {
        let entry = stack.pop()?;
        if !O::NEAREST_FIRST || !Q::SHORTENS || (entry >> 32) as u32 <= reach {
            return Some(entry as u32);
        }
    }
}

impl Bvh8 {
    /// Walks `ray` through the tree depth first, entering the children
    /// `test` accepts within the ray's end (as a closest hit lowers it)
    /// in `order`, and asking `query` at every leaf it reaches; returns
    /// the query's answer.
    ///
    /// `leaf_data[start / LANES]` is what the query reads for the leaf
    /// at `start` (a scene's triangle blocks), prefetched when the leaf is
    /// deferred nearest first; a caller whose leaf tests read nothing
    /// block-shaped passes an empty slice, and only nodes are prefetched.
    #[inline(always)]
    pub fn walk_by<T, O, Q, L>(
        &self,
        ray: &Ray,
        test: T,
        _order: O,
        leaf_data: &[L],
        query: &mut Q,
    ) -> Q::Answer
    where
        T: NodeTest,
        O: WalkOrder,
        Q: Query,
    {
        let mut state = query.start(ray);
        if self.nodes.is_empty() {
            return query.answer(&state, false);
        }
        if self.nodes.len() == 1 {
            return self.walk_root_leaves::<T, O, Q>(ray, test, state, query);
        }
        // The steps of `Walk::step` with the walk's state in locals, and
        // the way down the inner nodes a loop of its own: between two
        // leaves the ray's values stay in registers (in one loop with the
        // leaf test they were reloaded from memory at every node).
        let mut ray = *ray;
        let mut stack = Stack::new();
        let mut current = 0u32;
        loop {
            while !is_leaf(current) {
                let node = &self.nodes[current as usize];
                let (tn, mask) = test.test(ChildBoxes::new(&node.bounds), ray.tmax);
                current = if mask == 0 {
                    match next_deferred::<O, Q>(&mut stack, test.widened(ray.tmax)) {
                        Some(next) => next,
                        None => return query.answer(&state, false),
                    }
                } else if O::NEAREST_FIRST {
                    self.descend_nearest(&mut stack, leaf_data, &node.child, tn, mask)
                } else {
                    descend_any(&mut stack, &node.child, mask)
                };
            }
            let (start, count) = leaf_range(current);
            if query.leaf(&mut state, start, count, &mut ray) {
                return query.answer(&state, true);
            }
            current = match next_deferred::<O, Q>(&mut stack, test.widened(ray.tmax)) {
                Some(next) => next,
                None => return query.answer(&state, false),
            };
        }
    }

    /// [`Bvh8::walk_by`] of a tree of one node (up to eight leaves, a
    /// scene of a few shapes): the leaves its ray enters, in the walk's
    /// order, without a stack. Each leaf past the ray's reach when its turn
    /// comes is skipped, as the walk skips a deferred child it pops, so
    /// the same leaves are tested with the same interval.
    #[inline(always)]
    fn walk_root_leaves<T, O, Q>(
        &self,
        ray: &Ray,
        test: T,
        mut state: Q::State,
        query: &mut Q,
    ) -> Q::Answer
    where
        T: NodeTest,
        O: WalkOrder,
        Q: Query,
    {
        let node = &self.nodes[0];
        let mut ray = *ray;
        let (tn, mask) = test.test(ChildBoxes::new(&node.bounds), ray.tmax);
        if mask & mask.wrapping_sub(1) == 0 {
            // One leaf entered, or none: nothing to order.
            let hit = mask != 0 && {
                let (start, count) = leaf_range(node.child[mask.trailing_zeros() as usize % 8]);
                query.leaf(&mut state, start, count, &mut ray)
            };
            return query.answer(&state, hit);
        }
        // A one-node tree's children are all leaves (no other node to
        // refer to).
        if O::NEAREST_FIRST {
            // Farthest first, so nearest first from the back.
            let entries = nearest_last(tn, mask, &node.child);
            for &entry in entries[..mask.count_ones() as usize].iter().rev() {
                if Q::SHORTENS && (entry >> 32) as u32 > reach_key(test.widened(ray.tmax)) {
                    break;
                }
                let (start, count) = leaf_range(entry as u32);
                if query.leaf(&mut state, start, count, &mut ray) {
                    return query.answer(&state, true);
                }
            }
        } else {
            let mut rest = mask;
            while rest != 0 {
                let (start, count) = leaf_range(node.child[rest.trailing_zeros() as usize % 8]);
                rest &= rest - 1;
                if query.leaf(&mut state, start, count, &mut ray) {
                    return query.answer(&state, true);
                }
            }
        }
        query.answer(&state, false)
    }

    /// The walk of a ray: [`Bvh8::walk_by`] with the ray's slab test,
    /// nearest child first.
    #[inline(always)]
    pub fn walk<Q, L>(&self, ray: &Ray, leaf_data: &[L], query: &mut Q) -> Q::Answer
    where
        Q: Query,
    {
        self.walk_by(ray, RayPlanes::new(ray), NearestFirst, leaf_data, query)
    }

    /// [`Bvh8::walk`] of `ray` with its end moved to `tmax`: the node test
    /// made from `ray` as the caller holds it. Made from a copy with the
    /// new end, just written, its loads of the direction waited on the
    /// copy's narrower stores (a failed store-to-load forward, a tenth of
    /// a lone closest-hit walk's time on a small scene).
    #[inline(always)]
    pub fn walk_to<Q, L>(&self, ray: &Ray, tmax: f32, leaf_data: &[L], query: &mut Q) -> Q::Answer
    where
        Q: Query,
    {
        let test = RayPlanes::new(ray);
        self.walk_by(&Ray { tmax, ..*ray }, test, NearestFirst, leaf_data, query)
    }

    /// Closest hit in `(ray.tmin, ray.tmax)`: [`Bvh8::walk`] with
    /// [`ClosestHit`], whose leaf test is `hit_leaf(start, count, ray)`.
    #[inline(always)]
    pub fn closest_hit<L, F>(&self, ray: &Ray, leaf_data: &[L], mut hit_leaf: F) -> Option<PrimHit>
    where
        F: FnMut(u32, u32, &Ray) -> Option<PrimHit>,
    {
        let mut query =
            ClosestHit::new(|_: &mut (), start, count, r: &Ray| hit_leaf(start, count, r));
        self.walk(ray, leaf_data, &mut query)
    }

    /// True if any leaf reports a blocker in `(tmin, tmax)`: [`Bvh8::walk`]
    /// with [`Occlusion`], whose leaf test is `blocks_leaf(start, count, ray)`.
    #[inline(always)]
    pub fn occluded<L, F>(&self, ray: &Ray, leaf_data: &[L], mut blocks_leaf: F) -> bool
    where
        F: FnMut(u32, u32, &Ray) -> bool,
    {
        let mut query =
            Occlusion::new(|_: &mut (), start, count, r: &Ray| blocks_leaf(start, count, r));
        self.walk(ray, leaf_data, &mut query)
    }

    /// A leaf test for [`Bvh8::closest_hit`] from a per-primitive one:
    /// `hit_prim(slot, id, ray)` must return a hit only if it is nearer
    /// than `ray.tmax`.
    #[inline(always)]
    pub fn closest_in_leaf<F>(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        mut hit_prim: F,
    ) -> Option<PrimHit>
    where
        F: FnMut(u32, u32, &Ray) -> Option<PrimHit>,
    {
        let mut ray = *ray;
        let mut best: Option<PrimHit> = None;
        for slot in start..start + count {
            let test = tie_ray(&ray, best.as_ref());
            let hit = hit_prim(slot, self.prim_ids[slot as usize], &test);
            keep_closer(&mut best, &mut ray, hit);
        }
        best
    }

    /// The primitives of leaf `start..start + count`, for per-primitive
    /// tests: (slot, id).
    #[inline(always)]
    pub fn leaf_prims(&self, start: u32, count: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        (start..start + count).map(|slot| (slot, self.prim_ids[slot as usize]))
    }

    /// Calls `visit` for every primitive whose box the line
    /// `origin + t·direction` may meet for t in `[tmin, tmax]`, which may be
    /// infinite: CSG needs the crossings of the whole line, behind the
    /// origin too. [`Bvh8::walk_by`] in any order with the line's test
    /// (`LineBoxes`); `visit` sees each candidate once.
    pub fn visit_line<F>(&self, ray: &Ray, mut visit: F)
    where
        F: FnMut(u32),
    {
        let mut query = EveryLeaf(|start: u32, count: u32| {
            for &prim in &self.prim_ids[start as usize..(start + count) as usize] {
                visit(prim);
            }
        });
        self.walk_by(ray, LineBoxes::new(ray), AnyOrder, &[] as &[()], &mut query);
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::build::BuildQuality;
    use super::*;
    use crate::accel::NO_PRIM;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};
    use crate::shape::sphere::Sphere;
    use glam::Vec3;

    /// Leaf tests here read spheres by id: no block-shaped leaf data.
    const NO_DATA: &[()] = &[];

    /// Whether a sphere of leaf `start..start + count` of `bvh` blocks `r`:
    /// the occlusion leaf test of the walk tests here and in `stream` and
    /// `bundle`.
    pub(in crate::accel) fn spheres_block(
        bvh: &Bvh8,
        spheres: &[Sphere],
        start: u32,
        count: u32,
        r: &Ray,
    ) -> bool {
        bvh.leaf_prims(start, count)
            .any(|(_, id)| sphere_hit(spheres, id, r).is_some())
    }

    /// Random spheres in the 20-unit cube around the origin (`count` of
    /// them, radii from 0.05 to 0.05 + `spread`), then `copies` identical
    /// spheres of radius `radius` at `center` (hits at equal t, which the
    /// primitive id decides), and their tree: the scene of the walk tests
    /// in `stream` and `bundle`.
    pub(in crate::accel) fn sphere_cloud(
        seed: u64,
        count: usize,
        spread: f32,
        (center, radius, copies): (Vec3, f32, usize),
    ) -> (Vec<Sphere>, Bvh8) {
        let mut rng = seeded(seed);
        let mut spheres: Vec<Sphere> = (0..count)
            .map(|_| Sphere {
                center: Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 20.0 - 10.0,
                radius: 0.05 + rng.unit() * spread,
            })
            .collect();
        spheres.extend((0..copies).map(|_| Sphere { center, radius }));
        let boxes: Vec<Aabb> = spheres.iter().map(|s| s.bounds()).collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        (spheres, bvh)
    }

    /// Sphere `id`'s hit on `r` as traversal reports it: the leaf test of
    /// the traversal tests here and in `stream` and `bundle`.
    pub(in crate::accel) fn sphere_hit(spheres: &[Sphere], id: u32, r: &Ray) -> Option<PrimHit> {
        spheres[id as usize].intersect(r).map(|t| PrimHit {
            t,
            prim: id,
            u: 0.0,
            v: 0.0,
            part: 0,
        })
    }

    /// Random spheres, checked against brute force for every preset: a
    /// tree of many nodes, and trees of one node (a few spheres), which
    /// walk their root's leaves without a stack.
    #[test]
    fn closest_hit_and_occlusion_agree_with_brute_force_for_every_quality() {
        for n in [500, 6, 1] {
            brute_force_agrees(n);
        }
    }

    fn brute_force_agrees(n: usize) {
        let mut spheres = Vec::new();
        let mut rng = seeded(1);
        let mut rnd = || rng.unit();
        for _ in 0..n {
            let c = Vec3::new(rnd(), rnd(), rnd()) * 20.0 - 10.0;
            spheres.push(Sphere {
                center: c,
                radius: 0.05 + rnd() * if n < 10 { 5.0 } else { 0.5 },
            });
        }
        let boxes: Vec<Aabb> = spheres.iter().map(|s| s.bounds()).collect();
        for quality in [
            BuildQuality::Preview,
            BuildQuality::Fastest,
            BuildQuality::Fast,
            BuildQuality::Medium,
            BuildQuality::High,
        ] {
            let bvh = Bvh8::build(&boxes, quality);
            assert_eq!(bvh.nodes.len() == 1, n <= 8, "{n} spheres, {quality:?}");
            let mut seen: Vec<u32> = bvh
                .prim_ids
                .iter()
                .copied()
                .filter(|&id| id != NO_PRIM)
                .collect();
            seen.sort();
            assert_eq!(
                seen,
                (0..n as u32).collect::<Vec<_>>(),
                "each primitive in exactly one leaf"
            );
            for _ in 0..2000 {
                let o = Vec3::new(rnd(), rnd(), rnd()) * 30.0 - 15.0;
                let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                let mut ray = Ray::new(o, d);
                ray.tmax = 5.0 + rnd() * 40.0;
                let hit = |id: u32, r: &Ray| sphere_hit(&spheres, id, r);
                let brute = (0..n as u32)
                    .filter_map(|i| hit(i, &ray))
                    .min_by(|a, b| a.t.total_cmp(&b.t));
                let got = bvh.closest_hit(&ray, NO_DATA, |start, count, r| {
                    bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                });
                assert_eq!(got.map(|h| h.prim), brute.map(|h| h.prim), "{quality:?}");
                assert_eq!(
                    bvh.occluded(&ray, NO_DATA, |start, count, r| {
                        spheres_block(&bvh, &spheres, start, count, r)
                    }),
                    brute.is_some()
                );
            }
        }
    }

    /// Pushes past the inline part spill to the heap and come back in
    /// last-in first-out order, with block pushes mixed in.
    #[test]
    fn axis_parallel_rays_and_empty_trees() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        let bvh = Bvh8::build(&boxes, BuildQuality::Auto);
        // A ray along +x exactly in the box's bottom face plane.
        let ray = Ray::new(Vec3::new(-1.0, 0.0, 0.5), Vec3::X);
        let hit = bvh.closest_hit(&ray, NO_DATA, |start, _, _| {
            Some(PrimHit {
                t: 1.0,
                prim: bvh.prim_ids[start as usize],
                u: 0.0,
                v: 0.0,
                part: 0,
            })
        });
        assert!(hit.is_some());
        let empty = Bvh8::build(&[], BuildQuality::Auto);
        assert!(empty.closest_hit(&ray, NO_DATA, |_, _, _| None).is_none());
        assert!(!empty.occluded(&ray, NO_DATA, |_, _, _| true));
    }

    #[test]
    fn visit_line_finds_every_box_the_line_meets_on_both_sides_of_the_origin() {
        let boxes: Vec<Aabb> = (0..200)
            .map(|i| {
                let c = Vec3::new(i as f32 - 100.0, (i % 7) as f32, 0.0);
                Aabb::new(c - Vec3::splat(0.4), c + Vec3::splat(0.4))
            })
            .collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Auto);
        let mut line = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
        line.tmin = f32::NEG_INFINITY;
        let mut seen = Vec::new();
        bvh.visit_line(&line, |id| seen.push(id));
        seen.sort();
        let expected: Vec<u32> = (0..200).filter(|i| i % 7 == 0).collect();
        assert!(expected.iter().all(|i| seen.contains(i)), "{seen:?}");
        // Clipped to t ≥ 0 only the boxes ahead remain candidates.
        line.tmin = 0.0;
        let mut ahead = Vec::new();
        bvh.visit_line(&line, |id| ahead.push(id));
        assert!(ahead.iter().all(|&i| boxes[i as usize].max.x >= 0.0));
        // A tree of one node, whose leaves the walk visits without a stack.
        let few: Vec<Aabb> = (0..6)
            .map(|i| {
                let c = Vec3::new(2.0 * i as f32 - 5.0, (i % 2) as f32, 0.0);
                Aabb::new(c - Vec3::splat(0.4), c + Vec3::splat(0.4))
            })
            .collect();
        let bvh = Bvh8::build(&few, BuildQuality::Auto);
        assert_eq!(bvh.nodes.len(), 1);
        line.tmin = f32::NEG_INFINITY;
        let mut seen = Vec::new();
        bvh.visit_line(&line, |id| seen.push(id));
        assert!([0, 2, 4].iter().all(|i| seen.contains(i)), "{seen:?}");
    }

    #[test]
    fn many_identical_boxes_build_and_are_all_found() {
        // Degenerate input: 10k identical boxes (e.g. duplicate triangles).
        let boxes = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 10_000];
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        let ray = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        let mut visited = 0;
        bvh.occluded(&ray, NO_DATA, |_, count, _| {
            visited += count;
            false
        });
        assert_eq!(visited, 10_000, "no node dropped however deep the tree");
    }
}
