//! How rays travel through the tree: alone, as a packet, as bundles, or
//! several in flight. Every way returns the single-ray answers bit for
//! bit ([`super::query`]), so this decides speed, never an answer or an
//! image; every choice of it, and every threshold behind one, is made
//! here, and [`super::query`] only runs what it is told.
//!
//! | rays | how they travel | decided by |
//! |---|---|---|
//! | up to eight a caller traces together | a packet, or alone if [`Packet::new`] refuses them | [`Geometry::travel_packet`] |
//! | a stream | bundles, narrow packets, alone or in flight | [`Geometry::travel_stream`] |
//! | a render's batch | a packet or one by one | [`PacketMode`] and [`BatchRays`] |
//! | a bundle's or a packet's rays that may meet one instance | into its prototype together as a bundle, or one by one | `Geometry::enter_together` |
//!
//! **Bundles.** A stream is read in spans of [`SPAN`] rays. A span whose
//! rays are alike, all from close origins (a camera's rays,
//! [`CLOSE_ORIGINS`]) or all in close directions (the shadow rays of
//! neighbouring pixels' hits towards one light, [`CLOSE_DIRECTIONS`]),
//! walks as bundles of up to [`BUNDLE_SIZE`] rays. Alike rays share much
//! of their walks, and in a bundle each node on the shared part is read
//! once for all of them. A bundle walks the rays of each direction octant
//! on their own, so a span from many origins is first sorted by octant,
//! as Embree's stream API sorts its rays (its `rtcOccluded1M`; Tsakok
//! 2009, "Faster Incoherent Rays: Multi-BVH Ray Stream Tracing"): its
//! shadow rays change octant from one pixel to the next. A span from one
//! origin keeps its order, since a camera's rays change octant only where
//! the image crosses an axis. Rays that are not alike part too soon for a
//! bundle to pay, and sorting a camera's rays by octant costs more than it
//! saves (docs/embree.md, "Bundles"); neither pays on a tree past
//! [`BUNDLE_MAX_BYTES`].
//!
//! **Narrow packets.** The spans whose rays are not alike stay in order,
//! and consecutive ones go on together: each eight consecutive rays of
//! them within a spread of [`NARROW`] ([`crate::accel::narrow`]) walk as
//! a packet, eight that all miss the tree's box do not walk at all.
//!
//! **Alone or in flight.** The rest walk alone: several in flight at once
//! where the tree prefetches (one that outgrows the caches,
//! [`crate::accel::prefetch`]; [`crate::accel::in_flight`]), else one at
//! a time, since on a tree that fits the caches there is no wait to
//! overlap.
//!
//! **A render's batches.** The renderer traces a batch's camera rays as a
//! packet from [`CAMERA_PACKET_MIN`] rays, and its shadow rays towards one
//! light sample never as one, under `--packets auto` ([`PacketMode`]).

use super::Geometry;
use crate::accel::bundle::{octant, BUNDLE_MAX_BYTES, BUNDLE_SIZE};
use crate::accel::narrow::ends_narrow;
use crate::accel::packet::{misses_box, reciprocals};
use crate::accel::prefetch::prefetch;
use crate::accel::{Packet, PACKET_SIZE};
use crate::math::ray::ray_lanes;
use crate::math::{Aabb, Ray};
use glam::{Vec3, Vec3A};
use std::ops::Range;

/// Rays a span sorts into bundles: Embree's stream API takes its rays in
/// chunks of this size in `tools/embree`, and so does `strata trace`.
pub const SPAN: usize = 256;

/// A span's origins are close together when the diagonal of their box
/// is at most this fraction of the diagonal of the tree's box: a pinhole
/// camera's rays (one point) and a thin lens's (a lens much smaller than
/// the scene) are; random rays, whose origins span the scene's box and
/// more, are not.
pub const CLOSE_ORIGINS: f32 = 1.0 / 8.0;

/// Or a span's directions are close together when the diagonal of the
/// box of their unit vectors is at most this: rays of every direction
/// spread over 3.4 (the diagonal of the cube around the unit sphere), the
/// renderer's shadow rays over 0.62 (median span; docs/embree.md,
/// "Bundles", has the sweep that chose the bound).
pub const CLOSE_DIRECTIONS: f32 = 2.0;

/// The largest sine of the angle between two rays' directions, and the
/// largest distance of a ray's line from the apex as a fraction of half
/// the tree's diagonal, of eight rays of a stream that walk as a packet
/// ([`Packet::is_narrow`]): drawn below the spread where packets stopped
/// paying (docs/embree.md, "Narrow packets").
pub const NARROW: f32 = 0.01;

/// The rays of a bundle that may meet one instance enter its prototype
/// together, as a bundle of their own, from this many on
/// (`Geometry::enter_together`); fewer walk it one at a time.
pub const ENTER_TOGETHER: usize = 2;

/// How a run of rays travels, as [`Geometry::travel_packet`] and
/// [`Geometry::travel_stream`] decide. The ranges index the rays the
/// decision was asked about.
#[allow(clippy::large_enum_variant)]
pub enum Travel<'r> {
    /// Up to [`PACKET_SIZE`] consecutive rays as one packet. Made and
    /// matched on the stack, so the packet stays unboxed.
    Packet(Range<usize>, Packet<'r>),
    /// Rays that all miss the tree's box ([`misses_box`]): nothing to
    /// walk, no hit in the tree.
    Outside(Range<usize>),
    /// Consecutive rays walked one at a time.
    Alone(Range<usize>),
    /// Consecutive rays walked alone, several in flight at once.
    InFlight(Range<usize>),
    /// Up to [`BUNDLE_SIZE`] consecutive alike rays as one bundle.
    Bundle(Range<usize>),
    /// The indices of up to [`BUNDLE_SIZE`] rays of one span, sorted by
    /// direction octant and in stream order within one, as one bundle.
    Gathered(&'r [u32]),
}

/// Calls `visit` with each [`PACKET_SIZE`] consecutive rays of `rays`
/// that walk as a packet (narrow within [`NARROW`] in a tree whose box is
/// `bounds`) or miss that box altogether, and with the stretches of rays
/// between them ([`Travel::Alone`]), in order; every ray in exactly one.
/// A last few rays fewer than a packet holds walk alone.
pub fn split_narrow<'r>(rays: &'r [Ray], bounds: &Aabb, mut visit: impl FnMut(Travel<'r>)) {
    let extent = bounds.diagonal().length();
    let mut alone_from = 0;
    for (g, eight) in rays.chunks_exact(PACKET_SIZE).enumerate() {
        // The rays sixteen on, asked for now: the walks in between push
        // the stream's own lines out of the hardware prefetcher's reach.
        let ahead = (g + 2) * PACKET_SIZE;
        if let Some(next) = rays.get(ahead..ahead + PACKET_SIZE) {
            prefetch(<&[Ray; PACKET_SIZE]>::try_from(next).unwrap());
        }
        if !ends_narrow(eight, NARROW) {
            continue;
        }
        let lanes = ray_lanes(eight);
        let inv = reciprocals(&lanes);
        let start = g * PACKET_SIZE;
        let range = start..start + PACKET_SIZE;
        if misses_box(&lanes, &inv, bounds) {
            if alone_from < start {
                visit(Travel::Alone(alone_from..start));
            }
            visit(Travel::Outside(range));
            alone_from = start + PACKET_SIZE;
            continue;
        }
        let Some(p) = Packet::from_parts(eight, &lanes, &inv) else {
            continue;
        };
        if !p.is_narrow(extent, NARROW) {
            continue;
        }
        if alone_from < start {
            visit(Travel::Alone(alone_from..start));
        }
        visit(Travel::Packet(range, p));
        alone_from = start + PACKET_SIZE;
    }
    if alone_from < rays.len() {
        visit(Travel::Alone(alone_from..rays.len()));
    }
}

/// True where the `count` points `point(k)` lie within `reach` of each
/// other: the diagonal of their box. (The box ignores NaN coordinates; so does this test,
/// which only chooses how rays travel, never their answers.) Four boxes
/// grow side by side, so that the minima and maxima are four chains, not
/// one, and the test stops after the first sixteen points whose box
/// reaches too far (the first sixteen random rays almost always do).
fn within(count: usize, point: impl Fn(usize) -> Vec3, reach: f32) -> bool {
    let mut lo = [Vec3A::INFINITY; 4];
    let mut hi = [Vec3A::NEG_INFINITY; 4];
    for first in (0..count).step_by(16) {
        for k in first..(first + 16).min(count) {
            let p = Vec3A::from(point(k));
            lo[k % 4] = lo[k % 4].min(p);
            hi[k % 4] = hi[k % 4].max(p);
        }
        let low = lo[0].min(lo[1]).min(lo[2].min(lo[3]));
        let high = hi[0].max(hi[1]).max(hi[2].max(hi[3]));
        if (high - low).length() > reach {
            return false;
        }
    }
    true
}

/// True where the rays of a span are alike enough to walk as bundles:
/// their origins lie within `reach` of each other, or their directions
/// within [`CLOSE_DIRECTIONS`]. A direction is made a unit vector only
/// when the test reaches it.
fn alike(rays: &[Ray], reach: f32) -> bool {
    within(rays.len(), |k| rays[k].origin, reach)
        || within(
            rays.len(),
            |k| rays[k].direction.normalize_or_zero(),
            CLOSE_DIRECTIONS,
        )
}

impl Geometry {
    /// How up to [`PACKET_SIZE`] rays a caller chose to trace together
    /// travel: not at all where they all miss the tree's box, else as a
    /// packet where [`Packet::from_parts`] can make one (not for
    /// directions differing in sign on every axis), else alone.
    #[inline(always)]
    pub fn travel_packet<'r>(&self, rays: &'r [Ray]) -> Travel<'r> {
        let all = 0..rays.len();
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return Travel::Alone(all);
        }
        let lanes = ray_lanes(rays);
        let inv = reciprocals(&lanes);
        if misses_box(&lanes, &inv, &self.bvh.bounds) {
            return Travel::Outside(all);
        }
        match Packet::from_parts(rays, &lanes, &inv) {
            Some(packet) => Travel::Packet(all, packet),
            None => Travel::Alone(all),
        }
    }

    /// Calls `visit` with how each part of a stream travels (module docs):
    /// every ray in exactly one part, the parts in stream order, a span's
    /// sorted bundles ([`Travel::Gathered`]) in its place.
    pub fn travel_stream(&self, rays: &[Ray], mut visit: impl FnMut(Travel<'_>)) {
        self.split_spans(rays, |part| match part {
            Span::Unlike(range) => {
                let first = range.start;
                split_narrow(&rays[range], &self.bvh.bounds, |travel| {
                    let at = |r: Range<usize>| first + r.start..first + r.end;
                    visit(match travel {
                        Travel::Packet(r, packet) => Travel::Packet(at(r), packet),
                        Travel::Outside(r) => Travel::Outside(at(r)),
                        Travel::Alone(r) if self.bvh.prefetch => Travel::InFlight(at(r)),
                        Travel::Alone(r) => Travel::Alone(at(r)),
                        other => other,
                    })
                });
            }
            Span::Bundle(range) => visit(Travel::Bundle(range)),
            Span::Sorted(ids) => visit(Travel::Gathered(ids)),
        });
    }

    /// Whether `rays` rays of a bundle that may meet one instance of this
    /// prototype walk it together, as a bundle (`super::instance_bundle`):
    /// from [`ENTER_TOGETHER`] on, on a tree small enough for bundles to
    /// pay ([`BUNDLE_MAX_BYTES`]).
    pub(super) fn enter_together(&self, rays: usize) -> bool {
        rays >= ENTER_TOGETHER && self.traversal_bytes() <= BUNDLE_MAX_BYTES
    }

    /// Calls `visit` with the parts of a stream of rays: every ray in
    /// exactly one part, unlike rays in stream order, and each span of
    /// alike rays as bundles (module docs) where the tree is small enough
    /// for them to pay ([`BUNDLE_MAX_BYTES`]).
    fn split_spans(&self, rays: &[Ray], mut visit: impl FnMut(Span)) {
        if self.traversal_bytes() > BUNDLE_MAX_BYTES || self.bvh.is_empty() {
            visit(Span::Unlike(0..rays.len()));
            return;
        }
        let bounds = &self.bvh.bounds;
        let reach = (bounds.max - bounds.min).length() * CLOSE_ORIGINS;
        let mut unlike_from = 0;
        let mut octants = [0u8; SPAN];
        let mut sorted = [0u32; SPAN];
        for start in (0..rays.len()).step_by(SPAN) {
            let end = (start + SPAN).min(rays.len());
            let span = &rays[start..end];
            // Without branches, so that the rays' first loads (misses, in
            // a long stream) overlap.
            let first_origin = span[0].origin;
            let one_origin = span.iter().fold(true, |same, r| {
                let p = r.origin;
                same & (p.x == first_origin.x) & (p.y == first_origin.y) & (p.z == first_origin.z)
            });
            if !one_origin && !alike(span, reach) {
                continue;
            }
            if unlike_from < start {
                visit(Span::Unlike(unlike_from..start));
            }
            unlike_from = end;
            if one_origin {
                // In stream order (module docs).
                for first in (start..end).step_by(BUNDLE_SIZE) {
                    visit(Span::Bundle(first..(first + BUNDLE_SIZE).min(end)));
                }
                continue;
            }
            // A counting sort by octant keeps each octant's rays in order.
            let mut first = [0usize; 9];
            for (o, r) in octants.iter_mut().zip(span) {
                *o = octant(r) as u8;
                first[*o as usize + 1] += 1;
            }
            for o in 0..8 {
                first[o + 1] += first[o];
            }
            let mut next = first;
            for (k, &o) in octants[..span.len()].iter().enumerate() {
                sorted[next[o as usize]] = (start + k) as u32;
                next[o as usize] += 1;
            }
            // A bundle may hold the end of one octant's rays and the start
            // of the next: a span then makes as few bundles as it can.
            for ids in sorted[..span.len()].chunks(BUNDLE_SIZE) {
                visit(Span::Sorted(ids));
            }
        }
        if unlike_from < rays.len() {
            visit(Span::Unlike(unlike_from..rays.len()));
        }
    }
}

/// A part of a stream, in the order [`Geometry::split_spans`] gives them.
enum Span<'a> {
    /// Consecutive rays that are not alike, traced as packets or alone.
    Unlike(Range<usize>),
    /// Up to [`BUNDLE_SIZE`] consecutive rays walked as one bundle.
    Bundle(Range<usize>),
    /// Rays of one span sorted by octant, walked as one bundle.
    Sorted(&'a [u32]),
}

crate::mode::mode_enum! {
    /// Whether a render's batches trace their camera rays and shadow rays
    /// as packets ([`BatchRays`]).
    #[derive(Default)]
    pub enum PacketMode("packet mode") {
        /// Packets where they were measured to pay: a batch's camera rays
        /// when there are at least [`CAMERA_PACKET_MIN`], its shadow rays
        /// towards one light sample never ([`BatchRays::auto`]). Single
        /// rays otherwise.
        #[default]
        Auto = "auto",
        /// A batch's rays as a packet, however few they are.
        On = "on",
        /// Single rays only.
        Off = "off",
    }
}

/// The rays of a render's batch that the renderer may trace as a packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BatchRays {
    /// Its camera rays, one per sample: neighbouring film points, or a
    /// pixel's lens samples.
    Camera,
    /// Its shadow rays towards one light sample, one from each hit.
    Shadow,
}

/// When `--packets auto` traces a batch's rays as a packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AutoPackets {
    /// From this many rays on.
    From(usize),
    /// Never: one by one, however many.
    Never,
}

/// Fewest camera rays a batch must have for `auto` to trace them as a
/// packet: they pay as one from 7 rays (the packet/single throughput of
/// the renderer's own batches, docs/performance.md, "Measurements behind
/// the renderer's defaults").
pub const CAMERA_PACKET_MIN: usize = 7;

impl BatchRays {
    /// `auto`'s rule for these rays: camera rays from
    /// [`CAMERA_PACKET_MIN`] on; shadow rays towards one light sample
    /// never, which never clearly paid (docs/performance.md, as above).
    pub const fn auto(self) -> AutoPackets {
        match self {
            Self::Camera => AutoPackets::From(CAMERA_PACKET_MIN),
            Self::Shadow => AutoPackets::Never,
        }
    }
}

impl PacketMode {
    /// Whether a batch traces its `live` rays of kind `rays` as a packet.
    #[inline]
    pub fn use_packet(self, rays: BatchRays, live: usize) -> bool {
        match self {
            Self::Auto => match rays.auto() {
                AutoPackets::From(min) => live >= min,
                AutoPackets::Never => false,
            },
            Self::On => live > 0,
            Self::Off => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::narrow::tests::fan;

    #[test]
    fn within_measures_the_box_diagonal() {
        let points = [Vec3::ZERO, Vec3::new(3.0, 4.0, 0.0)];
        assert!(within(2, |k| points[k], 5.0));
        assert!(!within(2, |k| points[k], 4.99));
        assert!(within(1, |k| points[k], 0.0));
        // The last of 40 points, past the first sixteen, decides.
        let mut many: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(i as f32 * 0.1, 0.0, 0.0))
            .collect();
        assert!(within(40, |k| many[k], 3.9));
        many[39].y = 5.0;
        assert!(!within(40, |k| many[k], 3.9 * 1.5));
    }

    #[test]
    fn split_covers_every_ray_once_in_order() {
        let good = fan(Vec3::ZERO, 1.0, 1e-4);
        // Narrow too, but heading away from the box.
        let away = fan(Vec3::ZERO, -1.0, 1e-4);
        let bad: Vec<Ray> = (0..8)
            .map(|i| Ray::new(Vec3::ZERO, Vec3::new(1.0, i as f32 - 3.5, 0.5)))
            .collect();
        let bounds = Aabb {
            min: Vec3::new(-0.5, -0.5, 0.5),
            max: Vec3::new(0.5, 0.5, 1.5),
        };
        // bad, good, away, good, bad, 3 left over.
        let rays: Vec<Ray> = [&bad[..], &good, &away, &good, &bad, &good[..3]].concat();
        let mut seen = Vec::new();
        split_narrow(&rays, &bounds, |travel| {
            seen.push(match travel {
                Travel::Packet(r, _) => ("packet", r),
                Travel::Outside(r) => ("outside", r),
                Travel::Alone(r) => ("rest", r),
                _ => unreachable!("split_narrow makes packets or leaves rays alone"),
            })
        });
        assert_eq!(
            seen,
            [
                ("rest", 0..8),
                ("packet", 8..16),
                ("outside", 16..24),
                ("packet", 24..32),
                ("rest", 32..43)
            ]
        );
        let mut none = 0;
        split_narrow(&[], &bounds, |_| none += 1);
        assert_eq!(none, 0);
    }

    #[test]
    fn auto_traces_camera_packets_from_their_minimum_and_shadow_packets_never() {
        let auto = PacketMode::Auto;
        assert!(!auto.use_packet(BatchRays::Camera, CAMERA_PACKET_MIN - 1));
        assert!(auto.use_packet(BatchRays::Camera, CAMERA_PACKET_MIN));
        assert!((0..=PACKET_SIZE).all(|n| !auto.use_packet(BatchRays::Shadow, n)));
        for rays in [BatchRays::Camera, BatchRays::Shadow] {
            assert!(PacketMode::On.use_packet(rays, 1));
            assert!(!PacketMode::On.use_packet(rays, 0));
            assert!(!PacketMode::Off.use_packet(rays, PACKET_SIZE));
        }
    }
}
