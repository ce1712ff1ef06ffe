//! What a walk asks at the leaves it reaches: its *query*.
//!
//! Each traversal order (one ray, rays in flight, a bundle, a packet) is
//! written once, generic over its query and monomorphised, as obvhs's
//! `traverse!` takes its leaf action: closest hit and occlusion are two
//! queries of the same walks, not copies of them. A query is one value
//! for a whole call (what the leaf test needs: a scene, the primitive to
//! skip); what it keeps per ray between leaves (the closest hit so far, a
//! scene's sheared ray) is its [`Query::State`], so several walks in
//! flight or a bundle's rays share one query.

use super::hit::{closer, tie_ray, PrimHit};
use crate::math::lanes::mask_lanes;
use crate::math::Ray;

/// A question asked of the leaves of a single ray's walk (alone, in
/// flight or in a bundle).
pub trait Query {
    /// What the query keeps for one ray between leaves.
    type State;
    /// What a finished walk answers.
    type Answer;
    /// True where a hit shortens the ray (closest hit): deferred children
    /// beyond the ray's new end are then skipped. An occlusion query ends
    /// the walk instead.
    const SHORTENS: bool;

    /// The state of a walk that starts for `ray`.
    fn start(&mut self, ray: &Ray) -> Self::State;

    /// Tests the leaf holding slots `start..start + count` of the tree's
    /// `prim_ids` for `ray`. A shortening query lowers `ray.tmax` to a hit
    /// it keeps; true ends the walk at once.
    fn leaf(&mut self, state: &mut Self::State, start: u32, count: u32, ray: &mut Ray) -> bool;

    /// The answer of a walk whose last leaf returned `ended` (false: every
    /// reachable leaf was tested).
    fn answer(&mut self, state: &Self::State, ended: bool) -> Self::Answer;

    /// [`Query::leaf`] for the rays of a bundle that reach the leaf: each
    /// ray `i` of `mask` (bit i) with a state, tested as `rays[i]` ending
    /// at `ends[i]`, which a shortening query lowers; returns the rays
    /// whose walks end. Each ray's own [`Query::leaf`] in turn
    /// ([`leaf_each`]) unless a query answers a leaf's rays together
    /// (a scene's instances, whose prototypes they then walk together),
    /// which must give each ray the same answer at the walk's end.
    #[inline(always)]
    fn leaf_bundle(
        &mut self,
        states: &mut [Option<Self::State>],
        rays: &[Ray],
        ends: &mut [f32],
        start: u32,
        count: u32,
        mask: u64,
    ) -> u64
    where
        Self: Sized,
    {
        leaf_each(self, states, rays, ends, start, count, mask)
    }
}

/// [`Query::leaf_bundle`] ray by ray: each ray of `mask` with a state
/// through [`Query::leaf`]. A ray without one (its answer settled before
/// the walk) ends.
#[inline(always)]
pub fn leaf_each<Q: Query>(
    query: &mut Q,
    states: &mut [Option<Q::State>],
    rays: &[Ray],
    ends: &mut [f32],
    start: u32,
    count: u32,
    mask: u64,
) -> u64 {
    let mut ended = 0u64;
    let mut m = mask;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let Some(state) = &mut states[i] else {
            ended |= 1 << i;
            continue;
        };
        let mut ray = Ray {
            tmax: ends[i],
            ..rays[i]
        };
        if query.leaf(state, start, count, &mut ray) {
            ended |= 1 << i;
        }
        ends[i] = ray.tmax;
    }
    ended
}

/// The closest hit in `(tmin, tmax)`, from a leaf test
/// `hit_leaf(state, start, count, ray)` that returns the leaf's closest hit
/// nearer than `ray.tmax`, ties broken by the smaller primitive id
/// ([`super::Bvh8::closest_in_leaf`] does that for a per-primitive test).
/// `S` is the leaf test's own data for one ray, `S::default()` at its start.
///
/// Leaves are tested with the ray's interval reaching the best hit's t
/// itself ([`tie_ray`]), so the answer is the least hit in a total order
/// ([`closer`]) whatever order the walk visits leaves in: every traversal
/// order returns the same hit, bit for bit.
pub struct ClosestHit<F, S = ()> {
    hit_leaf: F,
    state: std::marker::PhantomData<S>,
}

impl<F, S> ClosestHit<F, S>
where
    F: FnMut(&mut S, u32, u32, &Ray) -> Option<PrimHit>,
{
    pub fn new(hit_leaf: F) -> Self {
        Self {
            hit_leaf,
            state: std::marker::PhantomData,
        }
    }
}

/// A ray's closest hit so far and its leaf test's data.
pub struct ClosestState<S> {
    pub best: Option<PrimHit>,
    pub leaf: S,
}

impl<F, S> Query for ClosestHit<F, S>
where
    S: Default,
    F: FnMut(&mut S, u32, u32, &Ray) -> Option<PrimHit>,
{
    type State = ClosestState<S>;
    type Answer = Option<PrimHit>;
    const SHORTENS: bool = true;

    #[inline(always)]
    fn start(&mut self, _: &Ray) -> Self::State {
        ClosestState {
            best: None,
            leaf: S::default(),
        }
    }

    #[inline(always)]
    fn leaf(&mut self, state: &mut Self::State, start: u32, count: u32, ray: &mut Ray) -> bool {
        let test = tie_ray(ray, state.best.as_ref());
        let hit = (self.hit_leaf)(&mut state.leaf, start, count, &test);
        keep_closer(&mut state.best, ray, hit);
        false
    }

    #[inline(always)]
    fn answer(&mut self, state: &Self::State, _: bool) -> Option<PrimHit> {
        state.best
    }
}

/// The second half of every closest-hit query's leaf step: `hit`, found
/// with `ray`'s interval reaching the best hit's t ([`tie_ray`], the
/// first half), is kept if it is [`closer`], and `ray` ends there.
#[inline(always)]
pub fn keep_closer(best: &mut Option<PrimHit>, ray: &mut Ray, hit: Option<PrimHit>) {
    if let Some(h) = hit {
        if closer(&h, best.as_ref()) {
            ray.tmax = h.t;
            *best = Some(h);
        }
    }
}

/// Whether anything blocks the ray in `(tmin, tmax)`, from a leaf test
/// `blocks_leaf(state, start, count, ray)`; `S` as for [`ClosestHit`]. The
/// first blocker ends the walk.
pub struct Occlusion<F, S = ()> {
    blocks_leaf: F,
    state: std::marker::PhantomData<S>,
}

impl<F, S> Occlusion<F, S>
where
    F: FnMut(&mut S, u32, u32, &Ray) -> bool,
{
    pub fn new(blocks_leaf: F) -> Self {
        Self {
            blocks_leaf,
            state: std::marker::PhantomData,
        }
    }
}

impl<F, S> Query for Occlusion<F, S>
where
    S: Default,
    F: FnMut(&mut S, u32, u32, &Ray) -> bool,
{
    type State = S;
    type Answer = bool;
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, _: &Ray) -> S {
        S::default()
    }

    #[inline(always)]
    fn leaf(&mut self, state: &mut S, start: u32, count: u32, ray: &mut Ray) -> bool {
        (self.blocks_leaf)(state, start, count, ray)
    }

    #[inline(always)]
    fn answer(&mut self, _: &S, ended: bool) -> bool {
        ended
    }
}

/// Every leaf a walk reaches: `visit(start, count)` at each, and nothing
/// ends the walk or shortens the ray (every crossing of a line, every
/// leaf near a ray; [`super::AnyOrder`] walks them unsorted).
pub struct EveryLeaf<F>(pub F);

impl<F> Query for EveryLeaf<F>
where
    F: FnMut(u32, u32),
{
    type State = ();
    type Answer = ();
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, _: &Ray) {}

    #[inline(always)]
    fn leaf(&mut self, _: &mut (), start: u32, count: u32, _: &mut Ray) -> bool {
        (self.0)(start, count);
        false
    }

    #[inline(always)]
    fn answer(&mut self, _: &(), _: bool) {}
}

/// A question asked of the leaves of a packet's walk, for the packet's
/// rays in lanes.
pub trait PacketQuery {
    /// One ray's answer, kept in the caller's `out` while the walk goes on.
    type Answer: Copy + Default;
    /// As [`Query::SHORTENS`]: a closest-hit packet sorts the children it
    /// enters nearest first and skips those beyond every open ray's end;
    /// an occlusion packet closes a ray at its first blocker.
    const SHORTENS: bool;

    /// Tests the leaf at `start..start + count` for the rays in the bits
    /// of `lanes`, updating `out`; returns the lanes whose answer changed
    /// (a nearer hit, or a blocker).
    fn leaf(&mut self, start: u32, count: u32, lanes: u32, out: &mut [Self::Answer]) -> u32;

    /// Where a ray whose answer is `answer` now ends, if a hit moved its end.
    fn end(answer: &Self::Answer) -> Option<f32>;
}

/// Closest hits of a packet: `hit_leaf(start, count, lanes, out)` replaces
/// `out[lane]` by any hit [`closer`] than it within the ray's interval and
/// returns whether any changed.
pub struct ClosestHitPacket<F>(pub F);

impl<F> PacketQuery for ClosestHitPacket<F>
where
    F: FnMut(u32, u32, u32, &mut [Option<PrimHit>]) -> bool,
{
    type Answer = Option<PrimHit>;
    const SHORTENS: bool = true;

    #[inline(always)]
    fn leaf(&mut self, start: u32, count: u32, lanes: u32, out: &mut [Option<PrimHit>]) -> u32 {
        if (self.0)(start, count, lanes, out) {
            lanes
        } else {
            0
        }
    }

    #[inline(always)]
    fn end(answer: &Option<PrimHit>) -> Option<f32> {
        answer.map(|h| h.t)
    }
}

/// Occlusion of a packet: `blocks_leaf(start, count, lanes)` returns the
/// lanes the leaf blocks.
pub struct OcclusionPacket<F>(pub F);

impl<F> PacketQuery for OcclusionPacket<F>
where
    F: FnMut(u32, u32, u32) -> u32,
{
    type Answer = bool;
    const SHORTENS: bool = false;

    #[inline(always)]
    fn leaf(&mut self, start: u32, count: u32, lanes: u32, out: &mut [bool]) -> u32 {
        let blocked = (self.0)(start, count, lanes) & lanes;
        mask_lanes(blocked).for_each(|lane| out[lane] = true);
        blocked
    }

    #[inline(always)]
    fn end(_: &bool) -> Option<f32> {
        None
    }
}
