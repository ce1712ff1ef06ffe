//! Whether eight rays are narrow enough to walk as a packet: the test
//! itself, on the rays in lanes. How narrow is narrow enough, and which
//! rays of a stream are asked, is [`crate::geometry::travel`]'s choice.
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
//! 2w + θ·L apart inside a box of diagonal L. Eight rays are narrow for a
//! spread `narrow` where sin θ ≤ `narrow` and 2w ≤ `narrow`·L for every
//! ray, a beam at most about 2·`narrow`·L wide. Both tests compare squares
//! of cross products, so they need neither a square root nor a division.

use super::packet::{Packet, PACKET_SIZE};
use crate::math::Ray;
use wide::f32x8;

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
    /// Whether the rays are within spread `narrow` of each other in a tree
    /// of diagonal `extent` (module docs). False for a non-finite extent.
    pub fn is_narrow(&self, extent: f32, narrow: f32) -> bool {
        if !extent.is_finite() {
            return false;
        }
        let soa = self.lanes();
        let dir = [soa[3], soa[4], soa[5]];
        let first = dir.map(|d| f32x8::splat(d.to_array()[0]));
        let len2 = dot(dir, dir);
        // sin²θ = |d₀ × d|² / (|d₀|² |d|²) ≤ narrow², on the same side.
        let sin = dot(cross(first, dir), cross(first, dir));
        let square = f32x8::splat(narrow * narrow);
        let angle =
            sin.simd_le(square * dot(first, first) * len2) & dot(first, dir).simd_gt(f32x8::ZERO);
        // w² = |(F − o) × d|² / |d|² ≤ (narrow · extent / 2)².
        let to_apex: [f32x8; 3] = std::array::from_fn(|a| f32x8::splat(self.apex()[a]) - soa[a]);
        let off = dot(cross(to_apex, dir), cross(to_apex, dir));
        let half = 0.5 * narrow * extent;
        let near = off.simd_le(f32x8::splat(half * half) * len2);
        // NaN anywhere (a zero direction) fails the comparisons.
        (angle & near).to_bitmask() == (1 << PACKET_SIZE) - 1
    }
}

/// [`Packet::is_narrow`]'s angle test on the first and last of eight rays,
/// in the same operations: a necessary condition in a few multiplications,
/// which turns unrelated rays away before their packet is built.
#[inline(always)]
pub fn ends_narrow(eight: &[Ray], narrow: f32) -> bool {
    let (a, b) = (eight[0].direction, eight[eight.len() - 1].direction);
    let sin = a.cross(b).length_squared();
    sin <= narrow * narrow * a.length_squared() * b.length_squared() && a.dot(b) > 0.0
}

#[cfg(test)]
pub(crate) mod tests {
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

    /// The spread the cases below are drawn around (the renderer's own is
    /// `geometry::travel::NARROW`).
    const SPREAD: f32 = 0.01;

    fn narrow(rays: &[Ray], extent: f32) -> bool {
        Packet::new(rays).is_some_and(|p| p.is_narrow(extent, SPREAD))
    }

    /// Eight rays from `eye` through a row of points `spacing` apart,
    /// `distance` ahead.
    pub(crate) fn fan(eye: Vec3, distance: f32, spacing: f32) -> Vec<Ray> {
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
            let spread = SPREAD * (next() + 0.5) * 0.3;
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
                assert!(ends_narrow(&eight, SPREAD), "{eight:?}");
            } else {
                rejected += 1;
            }
        }
        assert!(accepted > 500 && rejected > 500, "{accepted} {rejected}");
    }
}
