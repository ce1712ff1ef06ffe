//! One ray's walk through the 8-wide BVH, one node or leaf per step: the
//! loops of [`Bvh8::closest`] and [`Bvh8::any_hit`], and the unit that
//! [`super::stream`] interleaves across several rays. Keeping a walk's
//! state in a value rather than in a loop's locals is what lets both run
//! the same steps, so a ray's answer does not depend on which of them
//! traced it.

use super::build::Bvh8;
use super::hit::{closer, tie_ray, PrimHit};
use super::node::{is_leaf, leaf_range};
use super::traverse::{order_key, RayBoxes, Stack, WIDEN};
use crate::math::Ray;

/// Where a walk of either kind stands: the ray's slab constants, the
/// children it deferred, and the node or leaf its next step visits.
struct Cursor {
    boxes: RayBoxes,
    stack: Stack<u64>,
    current: u32,
}

impl Cursor {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        Self {
            boxes: RayBoxes::new(ray),
            stack: Stack::new(),
            current: 0,
        }
    }

    /// Back at the root for `ray`, reusing the stack's memory.
    #[inline(always)]
    fn restart(&mut self, ray: &Ray) {
        self.boxes = RayBoxes::new(ray);
        self.stack.clear();
        self.current = 0;
    }

    /// At an inner node: moves into its nearest child `ray` enters in
    /// `[ray.tmin, ray.tmax]`, pushing the others (farthest first), and returns
    /// true; false if it enters none. A ray that enters one child per
    /// level never touches the stack.
    #[inline(always)]
    fn enter_node<L>(
        &mut self,
        bvh: &Bvh8,
        leaf_data: &[L],
        ray: &Ray,
        prefetch_next: bool,
    ) -> bool {
        let node = &bvh.nodes[self.current as usize];
        let (tn, mask) = self.boxes.test(&node.bounds, ray.tmin, ray.tmax);
        if mask == 0 {
            return false;
        }
        self.current = bvh.descend_nearest(&mut self.stack, leaf_data, &node.child, tn, mask);
        if prefetch_next {
            bvh.prefetch_child(self.current, leaf_data);
        }
        true
    }

    /// Moves to a stack entry popped for the next step.
    #[inline(always)]
    fn resume<L>(&mut self, entry: u64, bvh: &Bvh8, leaf_data: &[L], prefetch_next: bool) {
        self.current = entry as u32;
        if prefetch_next {
            bvh.prefetch_child(self.current, leaf_data);
        }
    }
}

/// A closest-hit walk in progress. `state` is the leaf test's own data for
/// this ray (a scene keeps the ray's shear there, made at its first leaf).
pub(crate) struct ClosestWalk<S> {
    ray: Ray,
    at: Cursor,
    best: Option<PrimHit>,
    state: S,
}

impl<S> ClosestWalk<S> {
    /// A walk that starts at the root of a tree with at least one node.
    #[inline(always)]
    pub(crate) fn new(ray: &Ray, state: S) -> Self {
        Self {
            ray: *ray,
            at: Cursor::new(ray),
            best: None,
            state,
        }
    }

    /// Starts the walk over for `ray`, reusing the stack's memory.
    #[inline(always)]
    pub(crate) fn restart(&mut self, ray: &Ray, state: S) {
        self.ray = *ray;
        self.at.restart(ray);
        self.best = None;
        self.state = state;
    }

    /// Visits the current node or leaf and picks the next; the closest hit
    /// once nothing is left to visit. `hit_leaf(state, start, count, ray)`
    /// as for [`Bvh8::closest`]. With `prefetch_next` the node or leaf
    /// picked is prefetched at once: worth it only when other rays' steps
    /// run before this walk's next one.
    #[inline(always)]
    pub(crate) fn step<L, F>(
        &mut self,
        bvh: &Bvh8,
        leaf_data: &[L],
        hit_leaf: &mut F,
        prefetch_next: bool,
    ) -> Option<Option<PrimHit>>
    where
        F: FnMut(&mut S, u32, u32, &Ray) -> Option<PrimHit>,
    {
        if !is_leaf(self.at.current) {
            if self.at.enter_node(bvh, leaf_data, &self.ray, prefetch_next) {
                return None;
            }
        } else {
            let (start, count) = leaf_range(self.at.current);
            let test = tie_ray(&self.ray, self.best.as_ref());
            if let Some(h) = hit_leaf(&mut self.state, start, count, &test) {
                if closer(&h, self.best.as_ref()) {
                    self.ray.tmax = h.t;
                    self.best = Some(h);
                }
            }
        }
        // Next: the nearest pushed child the ray can still reach. The
        // entry distance carries rounding error like the box test's far
        // distance, so it is compared with the same widening: a child
        // whose box holds a triangle at exactly the best t (a ray along
        // an edge shared across two leaves) must still be visited, or
        // the tie would go to whichever leaf came first.
        // Keys carry a slot in their low bits (see `nearest_last`).
        let reach = order_key(self.ray.tmax * WIDEN) | 7;
        loop {
            match self.at.stack.pop() {
                None => return Some(self.best),
                Some(entry) if (entry >> 32) as u32 <= reach => {
                    self.at.resume(entry, bvh, leaf_data, prefetch_next);
                    return None;
                }
                Some(_) => {}
            }
        }
    }
}

/// An any-hit walk in progress; `state` as in [`ClosestWalk`].
pub(crate) struct AnyHitWalk<S> {
    at: Cursor,
    state: S,
}

impl<S> AnyHitWalk<S> {
    /// A walk that starts at the root of a tree with at least one node.
    #[inline(always)]
    pub(crate) fn new(ray: &Ray, state: S) -> Self {
        Self {
            at: Cursor::new(ray),
            state,
        }
    }

    /// Starts the walk over for `ray`, reusing the stack's memory.
    #[inline(always)]
    pub(crate) fn restart(&mut self, ray: &Ray, state: S) {
        self.at.restart(ray);
        self.state = state;
    }

    /// Like [`ClosestWalk::step`] for occlusion: `Some(true)` at the first
    /// blocker, `Some(false)` once nothing is left to visit. The walk does
    /// not keep its ray (nothing about it changes), so each step is given it.
    #[inline(always)]
    pub(crate) fn step<L, F>(
        &mut self,
        bvh: &Bvh8,
        ray: &Ray,
        leaf_data: &[L],
        blocks_leaf: &mut F,
        prefetch_next: bool,
    ) -> Option<bool>
    where
        F: FnMut(&mut S, u32, u32, &Ray) -> bool,
    {
        if !is_leaf(self.at.current) {
            if self.at.enter_node(bvh, leaf_data, ray, prefetch_next) {
                return None;
            }
        } else {
            let (start, count) = leaf_range(self.at.current);
            if blocks_leaf(&mut self.state, start, count, ray) {
                return Some(true);
            }
        }
        match self.at.stack.pop() {
            Some(entry) => {
                self.at.resume(entry, bvh, leaf_data, prefetch_next);
                None
            }
            None => Some(false),
        }
    }
}

impl Bvh8 {
    /// Closest hit in `(ray.tmin, ray.tmax)`. `hit_leaf(start, count, ray)`
    /// tests the leaf holding slots `start..start + count` of `prim_ids`
    /// (where a scene keeps the vertices the test reads, in the same
    /// order) and returns its closest hit nearer than `ray.tmax`, ties
    /// broken by the smaller primitive id ([`Bvh8::closest_in_leaf`] does
    /// that for a per-primitive test).
    ///
    /// `leaf_data[start / LEAF_BLOCK]` is what `hit_leaf` reads for the leaf
    /// at `start` (a scene's triangle blocks), prefetched when the leaf is
    /// deferred; a caller whose leaf tests read nothing block-shaped passes
    /// an empty slice, and only nodes are prefetched.
    #[inline(always)]
    pub fn closest<L, F>(&self, ray: &Ray, leaf_data: &[L], mut hit_leaf: F) -> Option<PrimHit>
    where
        F: FnMut(u32, u32, &Ray) -> Option<PrimHit>,
    {
        if self.nodes.is_empty() {
            return None;
        }
        let mut walk = ClosestWalk::new(ray, ());
        let mut leaf = |_: &mut (), start, count, r: &Ray| hit_leaf(start, count, r);
        loop {
            if let Some(best) = walk.step(self, leaf_data, &mut leaf, false) {
                return best;
            }
        }
    }

    /// True if any leaf reports a blocker in `(tmin, tmax)`;
    /// `leaf_data` and `blocks_leaf(start, count, ray)` as for
    /// [`Bvh8::closest`].
    ///
    /// Children are visited nearest first, as in [`Bvh8::closest`] (no
    /// culling: the first blocker ends the walk). The sort costs 9–17% more
    /// instructions than pushing the children unsorted, yet on the dragon's
    /// `strata rays` sets it was faster in wall time on every kind (camera
    /// +17%, edges +5–7%, inside +3–5%, random +2–4%, grazing +1%), even on
    /// `strata bench`'s sets, and mixed on the bunny (edges +9%, camera
    /// +1%, random even, grazing −2%, inside −8%: from inside a closed mesh
    /// every direction is blocked, so any order finds a blocker and the
    /// sort is pure cost). The branch-free network replaces
    /// a push loop whose trip count mispredicts (dragon camera rays: 1.49 →
    /// 1.09 mispredicted branches per ray in callgrind's simulation), and
    /// the nearest boxes hold the blocker a little more often (about 5%
    /// fewer node and leaf tests there). On the greedy tree before the SAH
    /// collapse it had been a wash.
    #[inline(always)]
    pub fn any_hit<L, F>(&self, ray: &Ray, leaf_data: &[L], mut blocks_leaf: F) -> bool
    where
        F: FnMut(u32, u32, &Ray) -> bool,
    {
        if self.nodes.is_empty() {
            return false;
        }
        let mut walk = AnyHitWalk::new(ray, ());
        let mut leaf = |_: &mut (), start, count, r: &Ray| blocks_leaf(start, count, r);
        loop {
            if let Some(blocked) = walk.step(self, ray, leaf_data, &mut leaf, false) {
                return blocked;
            }
        }
    }
}
