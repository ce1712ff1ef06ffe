//! One light's samples from up to eight shading points at once, one per
//! SIMD lane: each lane samples exactly what [`Light::seen_from`] samples
//! from its point alone.

use super::sample::{by_solid_angle_from, towards};
use super::{Light, LightFrom, LightSample, LightSampling};
use crate::math::lanes::{mask_lanes, LANES};
use crate::sampling::spherical_rect_lanes::SphericalRects;
use glam::{Vec2, Vec3};

impl Light {
    /// The light as seen from up to eight points at once, `points[i]` for
    /// the lanes `i` of `active` (the hit points of one batch of camera
    /// samples): [`Light::seen_from`] per lane, with a rect light's
    /// spherical rectangles built in SIMD lanes. Lane `i`'s samples are
    /// exactly those of `self.seen_from(points[i], method)`.
    pub fn seen_from_lanes(
        &self,
        points: &[Vec3; LANES],
        active: u32,
        method: LightSampling,
    ) -> LightLanes<'_> {
        if active.count_ones() == 1 {
            // One point (a reflected ray's hit, a lone pixel's one sample): the
            // scalar code, which each lane equals, without the lanes' cost.
            let lane = active.trailing_zeros() as usize;
            return LightLanes::One {
                lane,
                seen: self.seen_from(points[lane], method),
            };
        }
        if let Some((rect, radiance)) = self.rect_by_solid_angle_somewhere(method) {
            // The lanes whose points sample it by its spherical rectangle
            // (the scalar code's decision, `by_solid_angle_from`); the
            // others (and the lanes where it cannot be built) by area.
            let mut wanted = active;
            for i in mask_lanes(active) {
                if !by_solid_angle_from(rect, points[i], method) {
                    wanted &= !(1 << i);
                }
            }
            if wanted == 0 {
                return LightLanes::Each {
                    light: self,
                    points: *points,
                    method: LightSampling::Area,
                };
            }
            let rects = SphericalRects::new(points, wanted, rect.corner, rect.edge_u, rect.edge_v);
            return LightLanes::Rects {
                light: self,
                points: *points,
                weight: std::array::from_fn(|i| radiance * rects.solid_angle(i)),
                normal: rect.normal,
                rects,
            };
        }
        LightLanes::Each {
            light: self,
            points: *points,
            method,
        }
    }
}

/// A light seen from up to eight shading points (see
/// [`Light::seen_from_lanes`]).
// One lives on the stack per light and batch; boxing the large variant
// would allocate there instead.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub enum LightLanes<'l> {
    /// A single point, seen as [`Light::seen_from`] sees it.
    One { lane: usize, seen: LightFrom<'l> },
    /// A rect light sampled by solid angle: its spherical rectangles, its
    /// normal, and radiance times each lane's solid angle.
    Rects {
        light: &'l Light,
        points: [Vec3; LANES],
        rects: SphericalRects,
        normal: Vec3,
        weight: [Vec3; LANES],
    },
    /// Any other light or method: each sample does all its work.
    Each {
        light: &'l Light,
        points: [Vec3; LANES],
        method: LightSampling,
    },
}

impl LightLanes<'_> {
    /// One sample per lane of `active`, lane `i` with `u[i]` uniform in
    /// [0,1)²: exactly [`LightFrom::sample`] of that lane's point.
    pub fn sample(&self, active: u32, u: &[Vec2; LANES]) -> [Option<LightSample>; LANES] {
        let mut out = [None; LANES];
        match self {
            LightLanes::One { lane, seen } => {
                if active >> lane & 1 != 0 {
                    out[*lane] = seen.sample(u[*lane]);
                }
            }
            LightLanes::Rects {
                light,
                points,
                rects,
                normal,
                weight,
            } => {
                let q = rects.sample(u);
                for i in mask_lanes(active) {
                    // Each branch writes the slot itself: one value
                    // chosen between the branches was built on the stack
                    // and copied with wide loads that waited on its narrow
                    // stores (see docs/mitsuba.md, "What was tried for the
                    // render").
                    if rects.valid() >> i & 1 != 0 {
                        out[i] = towards(points[i], q[i], *normal, weight[i], None);
                    } else {
                        // The point is (nearly) in the light's plane, or
                        // sees the light small (`auto`): sample by area.
                        out[i] = light.sample_from(points[i], u[i], LightSampling::Area);
                    }
                }
            }
            LightLanes::Each {
                light,
                points,
                method,
            } => {
                for i in mask_lanes(active) {
                    out[i] = light.sample_from(points[i], u[i], *method);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::sample::subtends_much;
    use super::*;
    use crate::shape::disk::Disk;
    use crate::shape::rect::Rect;

    /// Each lane of [`Light::seen_from_lanes`] samples exactly what
    /// [`Light::seen_from`] samples from its point alone, bit for bit, for
    /// every kind of light and method, from points around, behind, in the
    /// plane of and far from the light, with any lanes active.
    #[test]
    fn each_lane_samples_what_its_point_samples_alone() {
        use crate::sampling::stream::{seeded, Draw};
        let rect = |corner: Vec3, eu: Vec3, ev: Vec3| Light::Rect {
            rect: Rect::new(corner, eu, ev).unwrap(),
            radiance: Vec3::new(1.0, 2.0, 3.0),
            prim: 0,
        };
        let lights = [
            rect(Vec3::new(-1.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0),
            rect(
                Vec3::new(0.3, 0.5, -2.0),
                Vec3::new(0.0, 0.6, 0.8),
                Vec3::X * 0.01,
            ),
            Light::Disk {
                disk: Disk::new(Vec3::Y * 2.0, -Vec3::Y, 0.5),
                radiance: Vec3::ONE,
                prim: 0,
            },
            Light::Sphere {
                center: Vec3::Y * 3.0,
                radius: 0.7,
                radiance: Vec3::ONE,
                prim: 0,
            },
            Light::Point {
                position: Vec3::Y,
                intensity: Vec3::ONE,
            },
            Light::Spot {
                position: Vec3::Y * 2.0,
                direction: Vec3::new(0.0, -0.8, 0.6),
                intensity: Vec3::ONE,
                cos_inner: 0.9,
                cos_outer: 0.5,
            },
        ];
        let bits = |s: Option<LightSample>| {
            s.map(|s| {
                let v = [s.wi.to_array(), s.weight.to_array(), [s.distance; 3]];
                v.map(|c| c.map(f32::to_bits))
            })
        };
        let mut rng = seeded(11);
        let mut sampled = 0;
        // Under `auto`, lanes of the rect lights that look large and small.
        let (mut large, mut small) = (0, 0);
        for case in 0..3000 {
            let light = &lights[case % lights.len()];
            let points: [Vec3; LANES] = std::array::from_fn(|lane| match (case + lane) % 4 {
                // In the first light's plane, or a hair off it.
                0 => Vec3::new(rng.range(-2.0, 2.0), 1.0 + rng.range(-1e-6, 1e-6), 0.0),
                1 => Vec3::new(rng.range(-1e3, 1e3), rng.range(-1e3, 1e3), 7.0),
                _ => Vec3::new(
                    rng.range(-3.0, 3.0),
                    rng.range(-2.0, 4.0),
                    rng.range(-3.0, 3.0),
                ),
            });
            let active = 1 + (rng.unit() * 255.0) as u32;
            let u: [Vec2; LANES] = std::array::from_fn(|_| Vec2::new(rng.unit(), rng.unit()));
            if let Some((rect, _)) = light.rect_by_solid_angle_somewhere(LightSampling::Auto) {
                for i in mask_lanes(active) {
                    match subtends_much(rect, points[i]) {
                        true => large += 1,
                        false => small += 1,
                    }
                }
            }
            for method in [
                LightSampling::Area,
                LightSampling::SolidAngle,
                LightSampling::Auto,
            ] {
                let lanes = light
                    .seen_from_lanes(&points, active, method)
                    .sample(active, &u);
                for i in mask_lanes(active) {
                    let alone = light.seen_from(points[i], method).sample(u[i]);
                    sampled += alone.is_some() as u32;
                    assert_eq!(
                        bits(lanes[i]),
                        bits(alone),
                        "case {case} lane {i} {method:?}"
                    );
                }
            }
        }
        assert!(sampled > 10_000, "only {sampled} samples reached a light");
        assert!(
            large > 200 && small > 1000,
            "auto: {large} large, {small} small"
        );
    }
}
