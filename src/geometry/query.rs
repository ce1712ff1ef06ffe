//! The scene's queries, closest hit and occlusion, for one ray, a packet
//! of up to [`PACKET_SIZE`] rays, or a stream of any number. Each query is
//! written once, generic over a [`SceneQuery`]: the query's leaf tests
//! ([`crate::accel::Query`] for single rays, in flight or in bundles;
//! [`PacketQuery`] for packets) and what the planes outside the BVH add.
//! How the rays travel is [`super::travel`]'s choice, which this runs.
//! Packets and streams return bit for bit the single-ray answers.
//!
//! # The interval
//!
//! Every query of a ray answers for `(tmin, tmax]`: a hit at `tmin` itself
//! does not count, a hit at `tmax` itself does. That holds for
//! [`Geometry::intersect`] and [`Geometry::occluded`] (alone, in packets,
//! in streams) as for [`Geometry::crossings`] and
//! [`Geometry::count_crossings`], for triangles, analytic shapes, planes
//! and instances alike, so that a caller who asks for `(0, t_max]` (the
//! Python package, Embree, Open3D) asks every query the same way.
//!
//! The leaf kernels test an interval open at both ends (`t < tmax`), so the
//! closest-hit and occlusion queries test each leaf with `tmax` moved one
//! step up (`next_up`: no float lies between): before a hit, the ray's own
//! end; after one, the best hit's t, so a tie is seen and [`closer`] breaks
//! it. A ray walked alone has its end moved once, before its walk, which
//! then takes `tmax` as it comes ([`SceneQuery::Open`]); the rays of a
//! packet, of a bundle or in flight, read from the caller's slice, are
//! moved where a leaf is tested. An instance's prototype is walked with
//! the ray its leaf was tested with, whose end is already moved, so that
//! walk too takes `tmax` as it comes (`Geometry::intersect_open_end`).
//! Every `scenes/*.toml` render and every `strata trace` hit file stayed
//! the same when the end was closed:
//! the ray sets end at infinity, where both rules agree, and a shadow ray
//! ends at its light sample, where only the light lies, which it skips
//! ([`Geometry::occluded_except`]).
//!
//! [`closer`]: crate::accel::hit::closer

use super::travel::Travel;
use super::Geometry;
use crate::accel::bundle::BUNDLE_SIZE;
use crate::accel::hit::tie_ray;
use crate::accel::query::{keep_closer, leaf_each, ClosestState};
use crate::accel::{Kernel, Packet, PacketQuery, PrimHit, Query, PACKET_SIZE};
use crate::math::lanes::mask_lanes;
use crate::math::Ray;
use crate::shape::plane_lanes::LANES_FROM;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle_lanes::ShearedRays;

/// A question asked of the scene, the same in every way of tracing.
trait SceneQuery<'g>: Query<Answer: Copy + Default> + Copy {
    /// The query's leaf tests for a packet's rays.
    type Packet<'p>: PacketQuery<Answer = Self::Answer>
    where
        'g: 'p;

    fn packet<'p>(self, packet: &'p Packet<'p>) -> Self::Packet<'p>
    where
        'g: 'p;

    /// What the planes (outside the BVH) answer before the BVH is walked.
    fn planes_first(self, ray: &Ray) -> Self::Answer;

    /// Whether `answer` is final, so the ray is not walked.
    fn done(answer: &Self::Answer) -> bool;

    /// The answer once the planes have been asked after the BVH.
    fn planes_last(self, ray: &Ray, answer: Self::Answer) -> Self::Answer;

    /// The same question for a ray whose end the caller already closed
    /// ([`closed_end`]), walked as it comes: a ray walked alone is closed
    /// once, before its walk, rather than at every leaf it reaches.
    type Open: Query<Answer = Self::Answer>;

    fn open(self) -> Self::Open;
}

/// `ray` with its interval's end closed: `(tmin, tmax]` tested as the
/// kernels' open `(tmin, next_up(tmax))`, the same set of floats.
#[inline(always)]
fn closed_end(ray: &Ray) -> Ray {
    Ray {
        tmax: ray.tmax.next_up(),
        ..*ray
    }
}

/// The ray a closest-hit query tests a leaf with: up to and including the
/// best hit's t once there is one (a tie is seen, [`crate::accel::hit::closer`]
/// breaks it), else up to the ray's end, included where the interval is
/// `CLOSED` (module docs).
#[inline(always)]
pub(super) fn leaf_ray<const CLOSED: bool>(ray: &Ray, best: Option<&PrimHit>) -> Ray {
    match best {
        None if CLOSED => closed_end(ray),
        _ => tie_ray(ray, best),
    }
}

/// The closest hit: the walk's leaf test is [`Geometry::hit_leaf`], with the
/// ray's shear made at its first leaf (most rays of a sparse view miss every
/// leaf box). Planes report prim ids `u32::MAX - plane index`. `CLOSED`:
/// the ray's end is in its interval (every caller's query); else it is
/// not (a prototype's walk, module docs).
#[derive(Clone, Copy)]
struct ClosestHit<'g, const CLOSED: bool>(&'g Geometry);

impl<const CLOSED: bool> Query for ClosestHit<'_, CLOSED> {
    type State = ClosestState<Option<ShearedRay>>;
    type Answer = Option<PrimHit>;
    const SHORTENS: bool = true;

    #[inline(always)]
    fn start(&mut self, _: &Ray) -> Self::State {
        ClosestState {
            best: None,
            leaf: None,
        }
    }

    #[inline(always)]
    fn leaf(&mut self, state: &mut Self::State, start: u32, count: u32, ray: &mut Ray) -> bool {
        let test = leaf_ray::<CLOSED>(ray, state.best.as_ref());
        let s = state.leaf.get_or_insert_with(|| ShearedRay::new(&test));
        let hit = self.0.hit_leaf(start, count, &test, s);
        keep_closer(&mut state.best, ray, hit);
        false
    }

    #[inline(always)]
    fn answer(&mut self, state: &Self::State, _: bool) -> Option<PrimHit> {
        state.best
    }

    /// A bundle's rays enter a leaf's instances together
    /// (`super::instance_bundle`).
    #[inline(always)]
    fn leaf_bundle(
        &mut self,
        states: &mut [Option<Self::State>],
        rays: &[Ray],
        ends: &mut [f32],
        start: u32,
        count: u32,
        mask: u64,
    ) -> u64 {
        match self.0.instance_parts(start, count, mask) {
            Some(parts) => {
                self.0
                    .hit_leaf_together::<CLOSED>(states, rays, ends, parts, mask);
                0
            }
            None => leaf_each(self, states, rays, ends, start, count, mask),
        }
    }
}

/// A packet's rays as its leaves test them: their shears in lanes and the
/// rays with their ends closed, made at the packet's first leaf.
struct LeafRays {
    sheared: ShearedRays,
    rays: [Ray; PACKET_SIZE],
}

impl LeafRays {
    #[inline(always)]
    fn new(packet: &Packet) -> Self {
        let rays = packet.rays();
        Self {
            sheared: ShearedRays::from_lanes(packet.lanes()),
            rays: std::array::from_fn(|i| closed_end(&rays[i.min(rays.len() - 1)])),
        }
    }
}

/// [`ClosestHit`] for a packet's rays.
struct ClosestHitPacket<'p> {
    geometry: &'p Geometry,
    packet: &'p Packet<'p>,
    leaf: Option<LeafRays>,
}

impl PacketQuery for ClosestHitPacket<'_> {
    type Answer = Option<PrimHit>;
    const SHORTENS: bool = true;

    #[inline(always)]
    fn leaf(&mut self, start: u32, count: u32, lanes: u32, out: &mut [Option<PrimHit>]) -> u32 {
        let packet = self.packet;
        let leaf = self.leaf.get_or_insert_with(|| LeafRays::new(packet));
        let rays = &leaf.rays[..packet.rays().len()];
        let changed = self
            .geometry
            .hit_leaf_packet(rays, &leaf.sheared, start, count, lanes, out);
        if changed {
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

impl<'g> SceneQuery<'g> for ClosestHit<'g, true> {
    type Packet<'p>
        = ClosestHitPacket<'p>
    where
        'g: 'p;

    fn packet<'p>(self, packet: &'p Packet<'p>) -> ClosestHitPacket<'p>
    where
        'g: 'p,
    {
        ClosestHitPacket {
            geometry: self.0,
            packet,
            leaf: None,
        }
    }

    #[inline(always)]
    fn planes_first(self, _: &Ray) -> Option<PrimHit> {
        None
    }

    #[inline(always)]
    fn done(_: &Option<PrimHit>) -> bool {
        false
    }

    #[inline(always)]
    fn planes_last(self, ray: &Ray, best: Option<PrimHit>) -> Option<PrimHit> {
        self.0.closest_plane(&closed_end(ray), best)
    }

    type Open = ClosestHit<'g, false>;

    #[inline(always)]
    fn open(self) -> ClosestHit<'g, false> {
        ClosestHit(self.0)
    }
}

/// Occlusion by anything but primitive `except` (the light being sampled;
/// `u32::MAX`: none): skipping the light's own primitive is exact, where
/// stopping the shadow ray a little short of it would need an epsilon. The
/// ray's shear is made when its walk starts: a shadow ray nearly always
/// reaches a leaf. `CLOSED` as for [`ClosestHit`].
#[derive(Clone, Copy)]
struct Occlusion<'g, const CLOSED: bool> {
    geometry: &'g Geometry,
    except: u32,
}

/// An occlusion walk's ray: its shear, and the end its leaves are tested
/// up to (made once: the walk never moves it).
pub(super) struct OcclusionState {
    pub(super) sheared: ShearedRay,
    pub(super) tmax: f32,
}

impl<const CLOSED: bool> Query for Occlusion<'_, CLOSED> {
    type State = OcclusionState;
    type Answer = bool;
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, ray: &Ray) -> OcclusionState {
        OcclusionState {
            sheared: ShearedRay::new(ray),
            tmax: if CLOSED {
                closed_end(ray).tmax
            } else {
                ray.tmax
            },
        }
    }

    // Always inlined, so that the leaf test is compiled into each kernel's
    // copy of the walk (`accel::kernel`), not left behind in the build's.
    #[inline(always)]
    fn leaf(&mut self, state: &mut OcclusionState, start: u32, count: u32, ray: &mut Ray) -> bool {
        if !CLOSED {
            return self
                .geometry
                .blocks_leaf(start, count, ray, &state.sheared, self.except);
        }
        let test = Ray {
            tmax: state.tmax,
            ..*ray
        };
        self.geometry
            .blocks_leaf(start, count, &test, &state.sheared, self.except)
    }

    #[inline(always)]
    fn answer(&mut self, _: &OcclusionState, ended: bool) -> bool {
        ended
    }

    /// As [`ClosestHit`]'s.
    #[inline(always)]
    fn leaf_bundle(
        &mut self,
        states: &mut [Option<OcclusionState>],
        rays: &[Ray],
        ends: &mut [f32],
        start: u32,
        count: u32,
        mask: u64,
    ) -> u64 {
        match self.geometry.instance_parts(start, count, mask) {
            Some(parts) => {
                self.geometry
                    .blocks_leaf_together::<CLOSED>(states, rays, parts, mask, self.except)
            }
            None => leaf_each(self, states, rays, ends, start, count, mask),
        }
    }
}

/// [`Occlusion`] for a packet's rays.
struct OcclusionPacket<'p> {
    geometry: &'p Geometry,
    packet: &'p Packet<'p>,
    leaf: Option<LeafRays>,
    except: u32,
}

impl PacketQuery for OcclusionPacket<'_> {
    type Answer = bool;
    const SHORTENS: bool = false;

    #[inline(always)]
    fn leaf(&mut self, start: u32, count: u32, lanes: u32, out: &mut [bool]) -> u32 {
        let packet = self.packet;
        let leaf = self.leaf.get_or_insert_with(|| LeafRays::new(packet));
        let rays = &leaf.rays[..packet.rays().len()];
        let blocked =
            self.geometry
                .blocks_leaf_packet(rays, &leaf.sheared, start, count, lanes, self.except)
                & lanes;
        mask_lanes(blocked).for_each(|lane| out[lane] = true);
        blocked
    }

    #[inline(always)]
    fn end(_: &bool) -> Option<f32> {
        None
    }
}

impl<'g> SceneQuery<'g> for Occlusion<'g, true> {
    type Packet<'p>
        = OcclusionPacket<'p>
    where
        'g: 'p;

    fn packet<'p>(self, packet: &'p Packet<'p>) -> OcclusionPacket<'p>
    where
        'g: 'p,
    {
        OcclusionPacket {
            geometry: self.geometry,
            packet,
            leaf: None,
            except: self.except,
        }
    }

    #[inline(always)]
    fn planes_first(self, ray: &Ray) -> bool {
        let planes = &self.geometry.planes;
        if planes.len() >= LANES_FROM {
            return self.geometry.plane_lanes.any_hit(&closed_end(ray));
        }
        planes
            .iter()
            .any(|p| p.intersect(&closed_end(ray)).is_some())
    }

    #[inline(always)]
    fn done(&blocked: &bool) -> bool {
        blocked
    }

    #[inline(always)]
    fn planes_last(self, _: &Ray, blocked: bool) -> bool {
        blocked
    }

    type Open = Occlusion<'g, false>;

    #[inline(always)]
    fn open(self) -> Occlusion<'g, false> {
        Occlusion {
            geometry: self.geometry,
            except: self.except,
        }
    }
}

impl Geometry {
    /// The closest hit in `(ray.tmin, ray.tmax]` (module docs), walked
    /// by the process's kernel ([`Kernel::selected`]).
    // Inlined into the caller: the choice of kernel is a load and a
    // branch there, and the walk one call, as before there was a choice.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.intersect_in(Kernel::selected(), ray)
    }

    /// [`Geometry::intersect`] walked by `kernel`: the same hit whichever.
    #[inline]
    pub fn intersect_in(&self, kernel: Kernel, ray: &Ray) -> Option<PrimHit> {
        kernel.run(
            #[inline(always)]
            move || self.one(ClosestHit::<true>(self), ray),
        )
    }

    /// True if anything blocks the ray in `(ray.tmin, ray.tmax]`.
    // Inlined into the caller: the choice of kernel is a load and a
    // branch there, and the walk one call, as before there was a choice.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        // No primitive has id u32::MAX (planes count down from it, outside the BVH).
        self.occluded_except(ray, u32::MAX)
    }

    /// True if anything other than primitive `except` blocks the ray in
    /// `(ray.tmin, ray.tmax]`.
    // Inlined into the caller: the choice of kernel is a load and a
    // branch there, and the walk one call, as before there was a choice.
    #[inline]
    pub fn occluded_except(&self, ray: &Ray, except: u32) -> bool {
        self.occluded_except_in(Kernel::selected(), ray, except)
    }

    /// [`Geometry::occluded_except`] walked by `kernel`: the same answer
    /// whichever.
    #[inline]
    pub fn occluded_except_in(&self, kernel: Kernel, ray: &Ray, except: u32) -> bool {
        kernel.run(
            #[inline(always)]
            move || self.one(self.occlusion(except), ray),
        )
    }

    /// The closest hit in `(ray.tmin, ray.tmax)`, its end left out: the
    /// walk of a prototype (no planes) with the ray an instance's leaf
    /// was tested with, whose end that test already closed (module docs).
    /// In the process's kernel ([`Kernel::selected`]), whichever kernel
    /// the scene's walk that reached the instance runs in.
    #[inline]
    pub(super) fn intersect_open_end(&self, ray: &Ray) -> Option<PrimHit> {
        debug_assert!(self.planes.is_empty());
        Kernel::selected().run(
            #[inline(always)]
            move || {
                self.bvh
                    .walk(ray, &self.leaf_blocks, &mut ClosestHit::<false>(self))
            },
        )
    }

    /// [`Geometry::intersect_open_end`] for occlusion.
    #[inline]
    pub(super) fn occluded_open_end(&self, ray: &Ray) -> bool {
        debug_assert!(self.planes.is_empty());
        let mut query = Occlusion::<false> {
            geometry: self,
            except: u32::MAX,
        };
        Kernel::selected().run(
            #[inline(always)]
            move || self.bvh.walk(ray, &self.leaf_blocks, &mut query),
        )
    }

    /// [`Geometry::intersect_open_end`] of each of the rays an instance's
    /// leaf test gathered ([`Geometry::open_end_rays`]).
    pub(super) fn intersect_open_end_rays(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        self.open_end_rays(ClosestHit::<false>(self), rays, out, |r| {
            self.intersect_open_end(r)
        });
    }

    /// [`Geometry::occluded_open_end`] of each of the rays an instance's
    /// leaf test gathered ([`Geometry::open_end_rays`]).
    pub(super) fn occluded_open_end_rays(&self, rays: &[Ray], out: &mut [bool]) {
        let query = Occlusion::<false> {
            geometry: self,
            except: u32::MAX,
        };
        self.open_end_rays(query, rays, out, |r| self.occluded_open_end(r));
    }

    /// `out[i] = alone(&rays[i])`, the answer of `query`'s walk of this
    /// prototype for a ray whose end its instance's leaf test closed: the
    /// rays walked together as a bundle where [`Geometry::enter_together`]
    /// says, else one at a time by `alone`.
    #[inline(always)]
    fn open_end_rays<Q: Query<Answer: Default>>(
        &self,
        mut query: Q,
        rays: &[Ray],
        out: &mut [Q::Answer],
        alone: impl Fn(&Ray) -> Q::Answer,
    ) {
        if self.enter_together(rays.len()) {
            out.fill_with(Q::Answer::default);
            self.bvh
                .walk_bundle(rays, &self.leaf_blocks, &mut query, out, |_| false);
        } else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = alone(r);
            }
        }
    }

    /// Closest hits of up to [`PACKET_SIZE`] rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. The rays traverse as one packet unless
    /// they all miss the tree's box (then not at all) or [`Packet::new`]
    /// refuses them ([`Geometry::travel_packet`]).
    pub fn intersect_packet(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        self.packet(ClosestHit::<true>(self), rays, out);
    }

    /// Occlusion of up to [`PACKET_SIZE`] rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`; one packet as for
    /// [`Geometry::intersect_packet`].
    pub fn occluded_packet(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        self.packet(self.occlusion(except), rays, out);
    }

    /// Closest hits of any number of rays: `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. Bundles, narrow packets, single rays
    /// in flight or one at a time, as [`Geometry::travel_stream`] decides.
    pub fn intersect_stream(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        self.stream(ClosestHit::<true>(self), rays, out);
    }

    /// Occlusion of any number of rays, ignoring primitive `except`
    /// (`u32::MAX`: none): `out[i]` is exactly
    /// `self.occluded_except(&rays[i], except)`. Rays travel as for
    /// [`Geometry::intersect_stream`].
    pub fn occluded_stream(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        self.stream(self.occlusion(except), rays, out);
    }

    /// Closest hits of a few rays a caller traces together (a path
    /// batch's bounce rays, up to a packet's worth of unlike directions
    /// from nearby points): `out[i]` is bit for bit
    /// `self.intersect(&rays[i])`. The rays walk one after another: a
    /// stream's span sorting and bundles cost more than they saved on
    /// eight such rays (cornell-planes: 31% more instructions), and so did
    /// walks in flight, whose rays here share cached nodes anyway (the
    /// dragon's render 4% slower; docs/mitsuba.md, "Path-traced scenes").
    pub fn intersect_few(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        self.few(ClosestHit::<true>(self), rays, out);
    }

    /// Occlusion of a few rays, ignoring primitive `except` (`u32::MAX`:
    /// none): `out[i]` is exactly `self.occluded_except(&rays[i], except)`;
    /// the rays walk as for [`Geometry::intersect_few`].
    pub fn occluded_few(&self, rays: &[Ray], except: u32, out: &mut [bool]) {
        self.few(self.occlusion(except), rays, out);
    }

    fn occlusion(&self, except: u32) -> Occlusion<'_, true> {
        Occlusion {
            geometry: self,
            except,
        }
    }

    /// `best`, or a plane hit nearer than it (or, without one, in
    /// `(ray.tmin, ray.tmax)`). From [`LANES_FROM`] planes on they are
    /// tested eight at a time
    /// ([`PlaneLanes`](crate::shape::plane_lanes::PlaneLanes)), with the
    /// scalar loop's answer; fewer one by one.
    #[inline]
    fn closest_plane(&self, ray: &Ray, mut best: Option<PrimHit>) -> Option<PrimHit> {
        let plane_hit = |t, i: usize| PrimHit {
            t,
            prim: u32::MAX - i as u32,
            u: 0.0,
            v: 0.0,
            part: 0,
        };
        let mut tmax = best.map_or(ray.tmax, |h| h.t);
        if self.planes.len() >= LANES_FROM {
            return match self.plane_lanes.closest(&Ray { tmax, ..*ray }) {
                Some((t, i)) => Some(plane_hit(t, i)),
                None => best,
            };
        }
        for (i, plane) in self.planes.iter().enumerate() {
            let r = Ray { tmax, ..*ray };
            if let Some(t) = plane.intersect(&r) {
                tmax = t;
                best = Some(plane_hit(t, i));
            }
        }
        best
    }

    /// One ray: the planes, the BVH's walk unless they settle it, the
    /// planes again.
    #[inline(always)]
    fn one<'g, Q: SceneQuery<'g>>(&'g self, query: Q, ray: &Ray) -> Q::Answer {
        let first = query.planes_first(ray);
        if Q::done(&first) {
            return first;
        }
        let answer = self.walk_closed(query, ray);
        query.planes_last(ray, answer)
    }

    /// The BVH's answer for one ray, its end closed once before the walk
    /// ([`SceneQuery::Open`]). Bit for bit the walk of `query` itself:
    /// each leaf is tested with the same interval, and a box is culled one
    /// step later, which no hit in `(tmin, tmax]` can tell.
    #[inline(always)]
    fn walk_closed<'g, Q: SceneQuery<'g>>(&'g self, query: Q, ray: &Ray) -> Q::Answer {
        self.bvh.walk_to(
            ray,
            closed_end(ray).tmax,
            &self.leaf_blocks,
            &mut query.open(),
        )
    }

    /// Up to [`PACKET_SIZE`] rays a caller chose to trace together.
    fn packet<'g, Q: SceneQuery<'g>>(&'g self, query: Q, rays: &[Ray], out: &mut [Q::Answer]) {
        let n = rays.len();
        assert!(
            n <= PACKET_SIZE,
            "a packet holds at most {PACKET_SIZE} rays"
        );
        let out = &mut out[..n];
        self.planes_before(query, rays, out);
        self.travel(query, rays, out, self.travel_packet(rays));
        self.planes_after(query, rays, out);
    }

    /// Any number of rays, travelling as [`Geometry::travel_stream`] says.
    fn stream<'g, Q: SceneQuery<'g>>(&'g self, query: Q, rays: &[Ray], out: &mut [Q::Answer]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        self.planes_before(query, rays, out);
        self.travel_stream(rays, |how| self.travel(query, rays, out, how));
        self.planes_after(query, rays, out);
    }

    /// Rays walked one after another ([`Geometry::intersect_few`]).
    fn few<'g, Q: SceneQuery<'g>>(&'g self, query: Q, rays: &[Ray], out: &mut [Q::Answer]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        self.planes_before(query, rays, out);
        self.alone(query, rays, out, false);
        self.planes_after(query, rays, out);
    }

    /// Walks the rays `how` names as it says. `out` holds the planes'
    /// first answers; a ray they settle keeps its answer.
    #[inline(always)]
    fn travel<'g, Q: SceneQuery<'g>>(
        &'g self,
        query: Q,
        rays: &[Ray],
        out: &mut [Q::Answer],
        how: Travel,
    ) {
        match how {
            Travel::Packet(r, packet) => self.walk_packet_unless_done(query, &packet, &mut out[r]),
            // Nothing in the tree can answer them.
            Travel::Outside(_) => {}
            Travel::Alone(r) => self.alone(query, &rays[r.clone()], &mut out[r], false),
            Travel::InFlight(r) => self.alone(query, &rays[r.clone()], &mut out[r], true),
            Travel::Bundle(r) => self.bundle(query, &rays[r.clone()], &mut out[r]),
            Travel::Gathered(ids) => on_gathered(rays, ids, out, |r, o| self.bundle(query, r, o)),
        }
    }

    /// `out[i]`: what the planes answer for ray `i` before the BVH is
    /// walked (the query's default where there are none).
    #[inline(always)]
    fn planes_before<'g, Q: SceneQuery<'g>>(
        &'g self,
        query: Q,
        rays: &[Ray],
        out: &mut [Q::Answer],
    ) {
        if self.planes.is_empty() {
            out.fill(Q::Answer::default());
        } else {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = query.planes_first(r);
            }
        }
    }

    /// `out[i]` once the planes have been asked after the BVH.
    #[inline(always)]
    fn planes_after<'g, Q: SceneQuery<'g>>(
        &'g self,
        query: Q,
        rays: &[Ray],
        out: &mut [Q::Answer],
    ) {
        if !self.planes.is_empty() {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = query.planes_last(r, *o);
            }
        }
    }

    /// `packet`'s walk, its answers written where `out` holds no final
    /// answer yet (a ray a plane blocks keeps its answer).
    #[inline(always)]
    fn walk_packet_unless_done<'g, Q: SceneQuery<'g>>(
        &'g self,
        query: Q,
        packet: &Packet,
        out: &mut [Q::Answer],
    ) {
        let mut answers = [Q::Answer::default(); PACKET_SIZE];
        let mut lanes = query.packet(packet);
        self.bvh
            .walk_packet(packet, &mut answers, &self.leaf_blocks, &mut lanes);
        for (o, a) in out.iter_mut().zip(answers) {
            if !Q::done(o) {
                *o = a;
            }
        }
    }

    /// Rays walked alone, several `in_flight` at once or one at a time,
    /// those `out` already answers skipped. Not inlined into the stream's
    /// loop: next to the packet code it compiled to slower code
    /// (docs/embree.md, "Rays in flight").
    #[inline(never)]
    fn alone<'g, Q: SceneQuery<'g>>(
        &'g self,
        mut query: Q,
        rays: &[Ray],
        out: &mut [Q::Answer],
        in_flight: bool,
    ) {
        // The build's code alone: run through `accel::kernel` (one
        // kernel's function per way, or both in one) the loop one at a
        // time took 5–6% more instructions per random bunny ray
        // (docs/performance.md, "AVX-512 by runtime dispatch").
        if in_flight {
            self.bvh
                .walk_in_flight(rays, &self.leaf_blocks, &mut query, out, Q::done);
            return;
        }
        for (o, r) in out.iter_mut().zip(rays) {
            if !Q::done(o) {
                *o = self.walk_closed(query, r);
            }
        }
    }

    /// Up to [`BUNDLE_SIZE`] alike rays walked as bundles.
    fn bundle<'g, Q: SceneQuery<'g>>(&'g self, mut query: Q, rays: &[Ray], out: &mut [Q::Answer]) {
        self.bvh
            .walk_bundle(rays, &self.leaf_blocks, &mut query, out, Q::done);
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
    let gathered: [Ray; BUNDLE_SIZE] =
        std::array::from_fn(|k| ids.get(k).map_or(filler, |&i| rays[i as usize]));
    let mut answers: [T; BUNDLE_SIZE] =
        std::array::from_fn(|k| ids.get(k).map_or(T::default(), |&i| out[i as usize]));
    walk(&gathered[..n], &mut answers[..n]);
    for (&i, a) in ids.iter().zip(answers) {
        out[i as usize] = a;
    }
}
