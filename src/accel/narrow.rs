//! Which eight consecutive rays of a stream are narrow enough to walk as
//! a packet.
//!
//! A packet's node test serves its eight rays at once, which pays while
//! they enter mostly the same nodes: the lens samples of one pixel, or
//! neighbouring pixels' primary rays, run about twice as fast as packets
//! as one ray at a time (`strata bench`). Where the rays part ways, each
//! node that any of them enters costs the packet its lane tests, and
//! unrelated rays run slower as a packet than as single rays in flight
//! ([`super::in_flight`]). Embree's stream API hands every eight consecutive
//! rays to its packet kernel, which drops to single-ray traversal once
//! few of a packet's rays remain active, so it makes the choice during
//! the walk (Benthin, Wald, Woop, Ernst and Mark 2012, "Combining Single
//! and Packet-Ray Tracing for Arbitrary Ray Distributions on the Intel MIC
//! Architecture", TVCG 18(9)); here it is made once per eight
//! consecutive rays, before the walk, from their geometry.
//!
//! The measure is how wide the rays spread inside the tree's box.
//! Where every ray's direction lies within angle θ of the first ray's and
//! its line passes within w of the packet's apex F (the point the rays
//! pass near, [`Packet`]'s module docs), two rays are at most about
//! 2w + θ·L apart inside a box of diagonal L. Eight rays walk as a packet
//! where sin θ ≤ [`NARROW`] and 2w ≤ `NARROW`·L for every ray, a beam at
//! most about 2·`NARROW`·L wide. Both tests compare squares of cross
//! products, so they need neither a square root nor a division.

use super::packet::{misses_box, reciprocals, Packet, PACKET_SIZE};
use super::prefetch::prefetch;
use crate::math::ray::ray_lanes;
use crate::math::{Aabb, Ray};
use std::ops::Range;
use wide::f32x8;

/// The largest sine of the angle between two rays' directions, and the
/// largest distance of a ray's line from the apex as a fraction of half
/// the tree's diagonal, of eight rays that walk as a packet: drawn below
/// the spread where packets stopped paying (docs/embree.md, "Narrow
/// packets").
pub const NARROW: f32 = 0.01;

/// `a × b`, in glam's order of operations (see [`ends_narrow`]).
fn cross(a: [f32x8; 3], b: [f32x8; 3]) -> [f32x8; 3] {
    [
        a[1] * b[2] - b[1] * a[2],
        a[2] * b[0] - b[2] * a[0],
        a[0] * b[1] - b[0] * a[1],
    ]
}

fn dot(a: [f32x8; 3], b: [f32x8; 3]) -> f32x8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Packet<'_> {
    /// Whether the rays are narrow enough to travel together in a tree of
    /// diagonal `extent` (module docs). False for a non-finite extent.
    pub fn is_narrow(&self, extent: f32) -> bool {
        if !extent.is_finite() {
            return false;
        }
        let soa = self.lanes();
        let dir = [soa[3], soa[4], soa[5]];
        let first = dir.map(|d| f32x8::splat(d.to_array()[0]));
        let len2 = dot(dir, dir);
        // sin²θ = |d₀ × d|² / (|d₀|² |d|²) ≤ NARROW², on the same side.
        let sin = dot(cross(first, dir), cross(first, dir));
        let square = f32x8::splat(NARROW * NARROW);
        let angle =
            sin.simd_le(square * dot(first, first) * len2) & dot(first, dir).simd_gt(f32x8::ZERO);
        // w² = |(F − o) × d|² / |d|² ≤ (NARROW · extent / 2)².
        let to_apex: [f32x8; 3] = std::array::from_fn(|a| f32x8::splat(self.apex()[a]) - soa[a]);
        let off = dot(cross(to_apex, dir), cross(to_apex, dir));
        let half = 0.5 * NARROW * extent;
        let near = off.simd_le(f32x8::splat(half * half) * len2);
        // NaN anywhere (a zero direction) fails the comparisons.
        (angle & near).to_bitmask() == (1 << PACKET_SIZE) - 1
    }
}

/// [`Packet::is_narrow`]'s angle test on the first and last of eight rays,
/// in the same operations: a necessary condition in a few multiplications,
/// which turns unrelated rays away before their packet is built.
#[inline(always)]
fn ends_narrow(eight: &[Ray]) -> bool {
    let (a, b) = (eight[0].direction, eight[eight.len() - 1].direction);
    let sin = a.cross(b).length_squared();
    sin <= NARROW * NARROW * a.length_squared() * b.length_squared() && a.dot(b) > 0.0
}

/// How rays travel through the tree.
#[allow(clippy::large_enum_variant)]
pub enum Travel<'r> {
    /// Eight rays or fewer, as one packet. Made and matched on the stack,
    /// so the packet stays unboxed.
    Packet(Packet<'r>),
    /// Rays that all miss the tree's box ([`misses_box`]): nothing to
    /// walk, no hit in the tree.
    Outside,
    /// Rays that walk alone.
    Alone,
}

impl<'r> Travel<'r> {
    /// How up to [`PACKET_SIZE`] rays a caller chose to trace together
    /// travel in a tree whose box is `bounds`: not at all where they all
    /// miss it, else as a packet where [`Packet::from_parts`] can make one,
    /// else alone.
    #[inline(always)]
    pub fn of_packet(rays: &'r [Ray], bounds: &Aabb) -> Self {
        if rays.is_empty() || rays.len() > PACKET_SIZE {
            return Travel::Alone;
        }
        let lanes = ray_lanes(rays);
        let inv = reciprocals(&lanes);
        if misses_box(&lanes, &inv, bounds) {
            return Travel::Outside;
        }
        match Packet::from_parts(rays, &lanes, &inv) {
            Some(packet) => Travel::Packet(packet),
            None => Travel::Alone,
        }
    }
}

/// Splits `rays` into the [`PACKET_SIZE`] consecutive rays that walk as
/// packets (narrow in a tree whose box is `bounds`) or miss that box
/// altogether, and the stretches of rays between them, and calls `visit`
/// on each in order: `visit(range, Travel::Packet(..))` or
/// `visit(range, Travel::Outside)` for the former, `visit(range,
/// Travel::Alone)` for each non-empty one of the latter. A last few rays
/// fewer than a packet holds walk alone.
pub fn split_narrow<'r>(
    rays: &'r [Ray],
    bounds: &Aabb,
    mut visit: impl FnMut(Range<usize>, Travel<'r>),
) {
    let extent = bounds.diagonal().length();
    let mut alone_from = 0;
    for (g, eight) in rays.chunks_exact(PACKET_SIZE).enumerate() {
        // The rays sixteen on, asked for now: the walks in between push
        // the stream's own lines out of the hardware prefetcher's reach.
        let ahead = (g + 2) * PACKET_SIZE;
        if let Some(next) = rays.get(ahead..ahead + PACKET_SIZE) {
            prefetch(<&[Ray; PACKET_SIZE]>::try_from(next).unwrap());
        }
        if !ends_narrow(eight) {
            continue;
        }
        let lanes = ray_lanes(eight);
        let inv = reciprocals(&lanes);
        let start = g * PACKET_SIZE;
        let range = start..start + PACKET_SIZE;
        if misses_box(&lanes, &inv, bounds) {
            if alone_from < start {
                visit(alone_from..start, Travel::Alone);
            }
            visit(range, Travel::Outside);
            alone_from = start + PACKET_SIZE;
            continue;
        }
        let Some(p) = Packet::from_parts(eight, &lanes, &inv) else {
            continue;
        };
        if !p.is_narrow(extent) {
            continue;
        }
        if alone_from < start {
            visit(alone_from..start, Travel::Alone);
        }
        visit(range, Travel::Packet(p));
        alone_from = start + PACKET_SIZE;
    }
    if alone_from < rays.len() {
        visit(alone_from..rays.len(), Travel::Alone);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Xorshift numbers in [−0.5, 0.5].
    fn uniform(seed: u32) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32 - 0.5
        }
    }

    fn narrow(rays: &[Ray], extent: f32) -> bool {
        Packet::new(rays).is_some_and(|p| p.is_narrow(extent))
    }

    /// Eight rays from `eye` through a row of points `spacing` apart,
    /// `distance` ahead.
    fn fan(eye: Vec3, distance: f32, spacing: f32) -> Vec<Ray> {
        (0..8)
            .map(|i| {
                let target = eye + Vec3::new(i as f32 * spacing, 0.3, distance);
                Ray::new(eye, target - eye)
            })
            .collect()
    }

    #[test]
    fn a_fan_from_one_eye_is_narrow_up_to_its_spread() {
        // Directions 1e-3 apart per ray: the beam spans 7e-3 of a unit box.
        assert!(narrow(&fan(Vec3::ZERO, 1.0, 1e-3), 1.0));
        assert!(!narrow(&fan(Vec3::ZERO, 1.0, 2e-3), 1.0));
        // From one point, only the angles count: not the tree's size, the
        // eye's position or the directions' lengths.
        assert!(narrow(&fan(Vec3::ZERO, 1.0, 1e-3), 1e-3));
        assert!(!narrow(&fan(Vec3::ZERO, 1.0, 2e-3), 1e3));
        assert!(narrow(&fan(Vec3::splat(1e5), 50.0, 50e-3), 1.0));
    }

    #[test]
    fn rays_through_one_focus_point_are_narrow_only_for_a_small_lens() {
        let focus = Vec3::new(0.0, 0.0, 10.0);
        let lens = |radius: f32| -> Vec<Ray> {
            (0..8)
                .map(|i| {
                    let phi = i as f32 * std::f32::consts::TAU / 8.0;
                    let origin = radius * Vec3::new(phi.cos(), phi.sin(), 0.0);
                    Ray::new(origin, focus - origin)
                })
                .collect()
        };
        // Opposite rays' directions are about 2·radius / 10 apart.
        assert!(narrow(&lens(1e-3), 20.0));
        assert!(!narrow(&lens(0.1), 20.0));
    }

    #[test]
    fn parallel_rays_are_as_wide_as_their_spread_of_origins() {
        let rays = |spread: f32| -> Vec<Ray> {
            (0..8)
                .map(|i| {
                    Ray::new(
                        Vec3::new(i as f32 * spread, 0.0, 0.0),
                        Vec3::new(0.2, 0.3, 1.0),
                    )
                })
                .collect()
        };
        // The lines are parallel, so the apex is ray 0's origin; the last
        // line passes 7·spread·sin(x, d) ≈ 6.9·spread from it, against
        // half of 0.01 of a unit box.
        assert!(narrow(&rays(5e-4), 1.0));
        assert!(!narrow(&rays(1e-3), 1.0));
    }

    #[test]
    fn unrelated_or_unbounded_rays_are_not_narrow() {
        let mut next = uniform(7);
        let random: Vec<Ray> = (0..8)
            .map(|_| {
                Ray::new(
                    Vec3::new(next(), next(), next()),
                    Vec3::new(next(), next(), 1.0),
                )
            })
            .collect();
        assert!(!narrow(&random, 1.0));
        let fan = fan(Vec3::ZERO, 1.0, 1e-4);
        assert!(!narrow(&fan, f32::INFINITY));
        assert!(!narrow(&fan, f32::NAN));
    }

    /// The cheap test turns away no eight rays the full test would accept:
    /// fans and lens samples of every width around the line, in every
    /// direction, with and without spread origins.
    #[test]
    fn the_first_and_last_rays_never_turn_away_a_narrow_packet() {
        let mut next = uniform(99);
        let (mut accepted, mut rejected) = (0, 0);
        for k in 0..4000 {
            let axis = Vec3::new(next(), next(), next()).normalize() * (1.0 + 10.0 * next().abs());
            let side = axis.any_orthonormal_vector();
            let spread = NARROW * (next() + 0.5) * 0.3;
            let lens = if k % 2 == 0 { 0.0 } else { 1e-3 * next() };
            let eye = Vec3::new(next(), next(), next()) * 10.0;
            let eight: Vec<Ray> = (0..8)
                .map(|i| {
                    let d = axis + side * (axis.length() * spread * (i as f32 + next()));
                    let o = eye + side * lens * i as f32;
                    Ray::new(o, d)
                })
                .collect();
            if narrow(&eight, 1.0) {
                accepted += 1;
                assert!(ends_narrow(&eight), "{eight:?}");
            } else {
                rejected += 1;
            }
        }
        assert!(accepted > 500 && rejected > 500, "{accepted} {rejected}");
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
        split_narrow(&rays, &bounds, |range, travel| {
            let how = match travel {
                Travel::Packet(_) => "packet",
                Travel::Outside => "outside",
                Travel::Alone => "rest",
            };
            seen.push((how, range))
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
        split_narrow(&[], &bounds, |_, _| none += 1);
        assert_eq!(none, 0);
    }
}
