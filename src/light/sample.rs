//! One light's samples from one shading point: by area or by solid angle
//! ([`LightSampling`]), with what a point's samples share worked out once
//! ([`Light::seen_from`]).

use super::Light;
use crate::math::Frame;
use crate::sampling::spherical_rect::SphericalRect;
use crate::sampling::warp::{concentric_disk, uniform_cone, uniform_sphere};
use crate::shape::rect::Rect;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

crate::mode::mode_enum! {
    /// How area lights are sampled.
    #[derive(Default)]
    pub enum LightSampling("light sampling") {
        /// Uniform over the light's surface: pdf 1/A, converted by cosθ_l / r².
        Area = "area",
        /// Uniform over the solid angle the light subtends, where we can.
        #[default]
        SolidAngle = "solid_angle" | "solid-angle",
        /// As `solid_angle`, but a rect light that subtends less than
        /// `SMALL_SOLID_ANGLE` at the shading point by area, where the
        /// two densities nearly agree and area's samples cost less (the
        /// path integrator's default).
        Auto = "auto",
    }
}

/// The solid angle (sr) below which `auto` samples a rect light by area,
/// as seen from a shading point: there area sampling's density in solid
/// angle, r²/(A cosθ), varies by about Ω/2 across the light, so its
/// samples' weights are nearly as even as the spherical rectangle's, which
/// costs a dozen dependent divisions, roots and arc cosines to build and
/// to sample (Ureña, Fajardo and King 2013). Measured in docs/mitsuba.md,
/// "Rect lights by area where they look small".
pub const SMALL_SOLID_ANGLE: f32 = 0.1;

impl LightSampling {
    /// Whether lights with a cheap solid-angle density of their own
    /// (spheres' cones, environment maps) are sampled by it.
    #[inline]
    pub fn by_solid_angle(self) -> bool {
        self != LightSampling::Area
    }
}

/// Whether `method`, which samples the rectangle `rect` by solid angle
/// from some points ([`Light::rect_by_solid_angle_somewhere`]), does from
/// `p`: everywhere but under `auto`, which asks [`subtends_much`]. The
/// per-point part of [`Light::solid_angle_rect`], which the lanes ask per
/// lane.
#[inline]
pub(super) fn by_solid_angle_from(rect: &Rect, p: Vec3, method: LightSampling) -> bool {
    method != LightSampling::Auto || subtends_much(rect, p)
}

/// Whether `auto` samples `rect` by solid angle from `p`: its solid angle
/// there, estimated as A·cosθ/d² from the light's centre (d) and normal,
/// is at least [`SMALL_SOLID_ANGLE`]. A point behind the one-sided light
/// (which sees none of it) answers no.
#[inline]
pub(super) fn subtends_much(rect: &Rect, p: Vec3) -> bool {
    let to = p - rect.point(0.5, 0.5);
    let d2 = to.length_squared();
    let facing = rect.normal.dot(to);
    // A·cosθ/d² = A·(n·to)/d³ ≥ Ω₀, without a division.
    rect.area() * facing >= SMALL_SOLID_ANGLE * d2 * d2.sqrt()
}

/// One light sample seen from a shading point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub wi: Vec3,
    /// Distance to the sampled point on the light (∞ for directional light).
    pub distance: f32,
    /// Radiance over pdf (or irradiance for delta lights): the direct
    /// light estimate is `f · weight · cosθ_i`.
    pub weight: Vec3,
}

impl Light {
    /// Sample the light as seen from `p`, with `u` uniform in [0,1)².
    pub fn sample(&self, p: Vec3, u: Vec2, method: LightSampling) -> Option<LightSample> {
        self.seen_from(p, method).sample(u)
    }

    /// True only if no sample of this light can light `p` from the side its
    /// geometric normal `n` faces: every point of a rect light lies below
    /// the tangent plane of `p`, or `p` is behind the one-sided light. Then
    /// every sample would be rejected, so the caller skips the light
    /// without building or drawing anything (the draws are counter-based,
    /// so no other number changes). The margin, a thousandth of the
    /// distance to the light (or more), lies far outside the rounding of a sample's
    /// position and direction, so the answer never differs from what the
    /// samples would have found. Other lights answer false. Inlined into
    /// the per-lane loop that asks it: the call cost the dragon-rect render
    /// 2% (see docs/mitsuba.md, "What was tried for the render").
    #[inline]
    pub fn hidden_from(&self, p: Vec3, n: Vec3) -> bool {
        let Light::Rect { rect, .. } = self else {
            return false;
        };
        let corners = [
            rect.corner,
            rect.corner + rect.edge_u,
            rect.corner + rect.edge_v,
            rect.corner + rect.edge_u + rect.edge_v,
        ];
        // The L1 norm bounds the distance from above (no square roots).
        let reach = corners
            .iter()
            .map(|c| (*c - p).abs().element_sum())
            .fold(0.0, f32::max);
        let margin = 1e-3 * reach;
        // A sample's direction is a positive combination of the corners'
        // directions (the rectangle is convex), so if n·(c − p) < 0 for
        // every corner c, then n·wi < 0 for every sample.
        let below = corners.iter().all(|c| n.dot(*c - p) < -margin);
        // The light emits towards `rect.normal`: from behind, cosθ_l ≤ 0.
        let behind = rect.normal.dot(p - rect.corner) < -margin;
        (below || behind) && margin.is_finite()
    }

    /// The light as seen from `p`: what every sample taken from `p` shares,
    /// computed once (for a rect light sampled by solid angle, its
    /// spherical rectangle), so that [`LightFrom::sample`] for each of a
    /// hit's shadow samples does only the per-sample work. The samples are
    /// exactly those of [`Light::sample`].
    pub fn seen_from(&self, p: Vec3, method: LightSampling) -> LightFrom<'_> {
        if let Some((rect, radiance)) = self.solid_angle_rect(p, method) {
            if let Some(s) = SphericalRect::new(p, rect.corner, rect.edge_u, rect.edge_v) {
                return LightFrom::SphericalRect {
                    p,
                    rect: s,
                    normal: rect.normal,
                    weight: radiance * s.solid_angle,
                };
            }
            // The point is (nearly) in the light's plane: sample by area.
            return LightFrom::Light {
                light: self,
                p,
                method: LightSampling::Area,
            };
        }
        LightFrom::Light {
            light: self,
            p,
            method,
        }
    }

    /// The rect light and its radiance, where `method` samples it by the
    /// solid angle of its spherical rectangle from `p` (which needs
    /// perpendicular edges, a parallelogram being sampled by area, and
    /// under `auto` a light that looks large from `p`). One decision for
    /// [`Light::seen_from`], [`Light::seen_from_lanes`] and [`Light::pdf`].
    pub(super) fn solid_angle_rect(&self, p: Vec3, method: LightSampling) -> Option<(&Rect, Vec3)> {
        let (rect, radiance) = self.rect_by_solid_angle_somewhere(method)?;
        by_solid_angle_from(rect, p, method).then_some((rect, radiance))
    }

    /// The rect light and its radiance, where `method` samples it by solid
    /// angle from some points ([`Light::solid_angle_rect`] says which).
    pub(super) fn rect_by_solid_angle_somewhere(
        &self,
        method: LightSampling,
    ) -> Option<(&Rect, Vec3)> {
        match self {
            Light::Rect { rect, radiance, .. }
                if method.by_solid_angle() && rect.is_rectangle() =>
            {
                Some((rect, *radiance))
            }
            _ => None,
        }
    }

    /// One sample of the light from `p` by `method`, all of it per sample.
    pub(super) fn sample_from(
        &self,
        p: Vec3,
        u: Vec2,
        method: LightSampling,
    ) -> Option<LightSample> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                let to = position - p;
                let d2 = to.length_squared();
                if d2.is_nan() || d2 <= 0.0 {
                    return None;
                }
                let distance = d2.sqrt();
                Some(LightSample {
                    wi: to / distance,
                    distance,
                    weight: intensity / d2,
                })
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => super::spot::sample(p, position, direction, intensity, (cos_inner, cos_outer)),
            Light::Directional {
                direction,
                irradiance,
            } => Some(LightSample {
                wi: -direction,
                distance: f32::INFINITY,
                weight: irradiance,
            }),
            Light::Rect { rect, radiance, .. } => {
                // Solid-angle sampling of rectangles is LightFrom::SphericalRect.
                let q = rect.point(u.x, u.y);
                towards(p, q, rect.normal, radiance, Some(rect.area()))
            }
            Light::Disk { disk, radiance, .. } => {
                let d = concentric_disk(u) * disk.radius;
                let q = disk.center + d.x * disk.frame.x + d.y * disk.frame.y;
                towards(p, q, disk.normal(), radiance, Some(disk.area()))
            }
            Light::Sphere {
                center,
                radius,
                radiance,
                ..
            } => {
                let to_center = center - p;
                let cone = super::sphere_cone(p, center, radius);
                if let (true, Some((cos_max, solid_angle))) = (method.by_solid_angle(), cone) {
                    // Uniform in the cone of directions that see the sphere.
                    let dc = to_center.length_squared().sqrt();
                    let frame = Frame::from_z(to_center / dc);
                    let wi = frame.to_world(uniform_cone(u, cos_max));
                    // Distance to the near intersection along wi.
                    let b = wi.dot(to_center);
                    let disc = (radius * radius - (to_center - b * wi).length_squared()).max(0.0);
                    let distance = b - disc.sqrt();
                    return Some(LightSample {
                        wi,
                        distance,
                        weight: radiance * solid_angle,
                    });
                }
                let n = uniform_sphere(u);
                let q = center + radius * n;
                towards(p, q, n, radiance, Some(4.0 * PI * radius * radius))
            }
            // Without the surface's normal: over the whole sphere (direct
            // light passes the normal, `Environment::light_sample`).
            Light::Environment(ref env) => env.light_sample(None, u, method),
        }
    }
}

/// A light seen from one shading point `p` (see [`Light::seen_from`]).
#[derive(Debug, Clone, Copy)]
pub enum LightFrom<'l> {
    /// A rect light sampled uniformly in the solid angle it subtends at `p`.
    SphericalRect {
        p: Vec3,
        rect: SphericalRect,
        normal: Vec3,
        /// Radiance times the solid angle: radiance over the pdf.
        weight: Vec3,
    },
    /// Any other light or method: each sample does all its work.
    Light {
        light: &'l Light,
        p: Vec3,
        method: LightSampling,
    },
}

impl LightFrom<'_> {
    /// A sample with `u` uniform in [0,1)².
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<LightSample> {
        match *self {
            LightFrom::SphericalRect {
                p,
                rect,
                normal,
                weight,
            } => towards(p, rect.sample(u), normal, weight, None),
            LightFrom::Light { light, p, method } => light.sample_from(p, u, method),
        }
    }
}

/// A sample towards point `q` on a one-sided surface with normal `n`.
/// `area = Some(A)` converts an area-density sample (pdf 1/A) to solid angle;
/// `None` means `weight` already is radiance over the solid-angle pdf.
pub(super) fn towards(
    p: Vec3,
    q: Vec3,
    n: Vec3,
    weight: Vec3,
    area: Option<f32>,
) -> Option<LightSample> {
    let to = q - p;
    let d2 = to.length_squared();
    if !(d2 > 0.0) {
        return None;
    }
    let distance = d2.sqrt();
    let wi = to / distance;
    let cos_l = -n.dot(wi);
    if cos_l <= 0.0 {
        // The back of a one-sided emitter.
        return None;
    }
    let weight = match area {
        Some(a) => weight * (cos_l * a / d2),
        None => weight,
    };
    weight.is_finite().then_some(LightSample {
        wi,
        distance,
        weight,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::disk::Disk;

    /// Irradiance at the origin from each light by both methods must agree
    /// with each other and with the analytic value where one exists.
    fn irradiance(light: &Light, method: LightSampling, n: Vec3) -> f64 {
        let steps = 64;
        let mut sum = 0.0;
        for i in 0..steps {
            for j in 0..steps {
                let u = Vec2::new(
                    (i as f32 + 0.5) / steps as f32,
                    (j as f32 + 0.5) / steps as f32,
                );
                if let Some(s) = light.sample(Vec3::ZERO, u, method) {
                    sum += (s.weight.x * s.wi.dot(n).max(0.0)) as f64;
                }
            }
        }
        sum / (steps * steps) as f64
    }

    #[test]
    fn area_and_solid_angle_sampling_agree_with_analytic_irradiance() {
        // A disk of radius R at height h, facing down onto the origin:
        // E = π L R² / (h² + R²).
        let disk = Light::Disk {
            disk: Disk::new(Vec3::Y * 2.0, -Vec3::Y, 1.0),
            radiance: Vec3::ONE,
            prim: 0,
        };
        let exact = PI as f64 * 1.0 / 5.0;
        assert!((irradiance(&disk, LightSampling::Area, Vec3::Y) - exact).abs() / exact < 2e-3);
        // A sphere of radius r at distance d straight above: E = π L r²/d².
        let sphere = Light::Sphere {
            center: Vec3::Y * 3.0,
            radius: 1.0,
            radiance: Vec3::ONE,
            prim: 0,
        };
        let exact = PI as f64 / 9.0;
        for m in [LightSampling::Area, LightSampling::SolidAngle] {
            let e = irradiance(&sphere, m, Vec3::Y);
            assert!((e - exact).abs() / exact < 5e-3, "{m:?}: {e} vs {exact}");
        }
        // A square light close overhead: both methods agree.
        let rect = Light::Rect {
            rect: Rect::new(Vec3::new(-1.0, 0.3, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0).unwrap(),
            radiance: Vec3::ONE,
            prim: 0,
        };
        let a = irradiance(&rect, LightSampling::Area, Vec3::Y);
        let s = irradiance(&rect, LightSampling::SolidAngle, Vec3::Y);
        assert!((a - s).abs() / s < 5e-3, "area {a} vs solid angle {s}");
    }

    /// `auto` draws a rect light's spherical rectangle where it subtends
    /// at least [`SMALL_SOLID_ANGLE`] and its area where less (or where
    /// the point is behind it), judged by A·cosθ/d² from its centre: a
    /// square of side 2 (A = 4) straight overhead at height h subtends
    /// about 4/h², so the switch is near h = √40 ≈ 6.3, and at 45° off
    /// its axis (cosθ/d² = 1/(2√2 h²)) near h = 3.8. Either way the
    /// samples give the exact irradiance of a square light overhead,
    /// E = 4L·(x/√(1+x²))·atan(x/√(1+x²)) with x = 1/h (a quarter of the
    /// square, side 1 at distance h, four times).
    #[test]
    fn auto_samples_a_rect_light_by_solid_angle_only_where_it_looks_large() {
        let at = |h: f32| Light::Rect {
            rect: Rect::new(Vec3::new(-1.0, h, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0).unwrap(),
            radiance: Vec3::ONE,
            prim: 0,
        };
        let large = |light: &Light, p: Vec3| {
            let method = LightSampling::Auto;
            let by_solid_angle = light.solid_angle_rect(p, method).is_some();
            let seen = matches!(light.seen_from(p, method), LightFrom::SphericalRect { .. });
            assert_eq!(by_solid_angle, seen, "{p}");
            by_solid_angle
        };
        for (h, want) in [(1.0, true), (6.0, true), (6.6, false), (30.0, false)] {
            assert_eq!(large(&at(h), Vec3::ZERO), want, "overhead at {h}");
        }
        for (h, want) in [(3.6, true), (4.0, false)] {
            assert_eq!(large(&at(h), Vec3::new(h, 0.0, 0.0)), want, "45° at {h}");
        }
        // Behind the light, which emits downwards: by area.
        assert!(!large(&at(-0.5), Vec3::ZERO));
        for h in [0.5f64, 2.0, 8.0] {
            let x = 1.0 / h;
            let c = x / (1.0 + x * x).sqrt();
            let exact = 4.0 * c * c.atan();
            let e = irradiance(&at(h as f32), LightSampling::Auto, Vec3::Y);
            assert!(
                (e - exact).abs() / exact < 5e-3,
                "height {h}: {e} vs {exact}"
            );
        }
    }

    #[test]
    fn a_hidden_light_has_no_sample_that_lights_the_point() {
        let rect = Light::Rect {
            rect: Rect::new(Vec3::new(-1.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0).unwrap(),
            radiance: Vec3::ONE,
            prim: 0,
        };
        let lit = |p: Vec3, n: Vec3| {
            (0..16).any(|i| {
                (0..16).any(|j| {
                    let u = Vec2::new((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                    [LightSampling::Area, LightSampling::SolidAngle]
                        .into_iter()
                        .any(|m| rect.sample(p, u, m).is_some_and(|s| n.dot(s.wi) > 0.0))
                })
            })
        };
        let cases = [
            (Vec3::ZERO, Vec3::Y, false),
            (Vec3::ZERO, -Vec3::Y, true),
            (Vec3::ZERO, Vec3::X, false),
            (Vec3::new(3.0, 0.0, 0.0), Vec3::X, true),
            (Vec3::new(3.0, 0.0, 0.0), -Vec3::X, false),
            (Vec3::Y * 2.0, Vec3::Y, true),
            (Vec3::Y * 2.0, -Vec3::Y, true),
        ];
        for (p, n, hidden) in cases {
            assert_eq!(rect.hidden_from(p, n), hidden, "{p} {n}");
            if hidden {
                assert!(!lit(p, n), "{p} {n}");
            }
        }
        let point = Light::Point {
            position: Vec3::Y,
            intensity: Vec3::ONE,
        };
        assert!(!point.hidden_from(Vec3::ZERO, -Vec3::Y));
    }

    #[test]
    fn one_sided_lights_are_dark_from_behind() {
        let rect = Light::Rect {
            rect: Rect::new(Vec3::new(-1.0, 1.0, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0).unwrap(),
            radiance: Vec3::ONE,
            prim: 0,
        };
        // edge_u × edge_v = x × z = −y: faces down, so the origin below is lit…
        assert!(rect
            .sample(Vec3::ZERO, Vec2::splat(0.5), LightSampling::Area)
            .is_some());
        // …and a point above sees its back.
        assert!(rect
            .sample(Vec3::Y * 2.0, Vec2::splat(0.5), LightSampling::Area)
            .is_none());
    }
}
