//! Spot lights: a point light whose intensity falls off across a cone.
//!
//! The falloff is the one glTF's `KHR_lights_punctual` recommends, so a
//! spot light read from a glTF file lights as its exporter meant: full
//! intensity inside the inner cone, none outside the outer cone, and
//! between them the square of a linear ramp in the cosine of the angle
//! from the axis, `t² with t = (cosθ − cos θ_outer) / (cos θ_inner − cos θ_outer)`.
//! Equal angles give a hard edge.

use super::LightSample;
use glam::Vec3;
use std::f32::consts::PI;

/// The fraction of a spot light's axial intensity that leaves at angle θ
/// from its axis, given `cos_theta` and the cosines of its inner and outer
/// half-angles (`cos_inner ≥ cos_outer`).
#[inline]
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        1.0
    } else if cos_theta <= cos_outer {
        0.0
    } else {
        let t = (cos_theta - cos_outer) / (cos_inner - cos_outer);
        t * t
    }
}

/// Total power of a spot light of axial intensity `intensity`:
/// 2π I ∫ falloff d(cosθ) = 2π I ((1 − cos_inner) + (cos_inner − cos_outer) / 3),
/// the ramp's t² integrating to a third of its width.
pub fn spot_power(intensity: Vec3, cos_inner: f32, cos_outer: f32) -> Vec3 {
    2.0 * PI * intensity * ((1.0 - cos_inner) + (cos_inner - cos_outer) / 3.0)
}

/// The one sample of a spot light at `position` shining along unit
/// `direction`, seen from `p`: none outside the outer cone (no shadow ray
/// to spend), else the point light's `I / d²` times the falloff.
#[inline]
pub(super) fn sample(
    p: Vec3,
    position: Vec3,
    direction: Vec3,
    intensity: Vec3,
    (cos_inner, cos_outer): (f32, f32),
) -> Option<LightSample> {
    let to = position - p;
    let d2 = to.length_squared();
    if d2.is_nan() || d2 <= 0.0 {
        return None;
    }
    let distance = d2.sqrt();
    let wi = to / distance;
    let falloff = spot_falloff(-wi.dot(direction), cos_inner, cos_outer);
    if falloff <= 0.0 {
        return None;
    }
    Some(LightSample {
        wi,
        distance,
        weight: intensity * (falloff / d2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{Light, LightSampling};
    use glam::Vec2;

    fn spot(inner_deg: f32, outer_deg: f32) -> Light {
        Light::Spot {
            position: Vec3::new(0.0, 2.0, 0.0),
            direction: -Vec3::Y,
            intensity: Vec3::new(4.0, 2.0, 1.0),
            cos_inner: inner_deg.to_radians().cos(),
            cos_outer: outer_deg.to_radians().cos(),
        }
    }

    /// On the floor under a spot light 2 high, irradiance at distance x
    /// from the foot is I · falloff · cosθ / d² with cosθ = 2/d: full
    /// inside the inner cone, zero outside the outer one, glTF's ramp
    /// squared between, and continuous at both edges.
    #[test]
    fn a_spot_lights_the_floor_as_its_analytic_falloff_says() {
        let light = spot(20.0, 40.0);
        let (ci, co) = (20f32.to_radians().cos(), 40f32.to_radians().cos());
        for i in 0..200 {
            let x = i as f32 * 0.01;
            let p = Vec3::new(x, 0.0, 0.0);
            let d2 = x * x + 4.0;
            let cos = 2.0 / d2.sqrt();
            let expected = if cos >= ci {
                1.0
            } else if cos <= co {
                0.0
            } else {
                ((cos - co) / (ci - co)).powi(2)
            };
            let got = light.sample(p, Vec2::splat(0.5), LightSampling::SolidAngle);
            match got {
                Some(s) => {
                    assert!((s.wi.dot(Vec3::Y) - cos).abs() < 1e-5);
                    let falloff = s.weight.x * d2 / 4.0;
                    assert!(
                        (falloff - expected).abs() < 1e-4,
                        "x {x}: {falloff} vs {expected}"
                    );
                    assert!((s.weight.y * 2.0 - s.weight.x).abs() < 1e-6, "colour kept");
                }
                None => assert_eq!(expected, 0.0, "x {x}"),
            }
        }
        // The edges meet: 1 at the inner cone, 0 at the outer one.
        assert_eq!(spot_falloff(ci, ci, co), 1.0);
        assert!(spot_falloff(ci - 1e-6, ci, co) > 0.999);
        assert!(spot_falloff(co + 1e-6, ci, co) < 1e-6);
        // Equal angles: a hard edge, no division by zero.
        assert_eq!(spot_falloff(0.5, 0.5, 0.5), 1.0);
        assert_eq!(spot_falloff(0.4999, 0.5, 0.5), 0.0);
    }

    /// The power in closed form equals the intensity integrated over the
    /// sphere of directions (a midpoint sum in cosθ).
    #[test]
    fn the_power_is_the_falloff_integrated_over_the_sphere() {
        for (inner, outer) in [(0.0, 45.0), (20.0, 40.0), (30.0, 30.0), (10.0, 150.0)] {
            let (ci, co) = (f32::to_radians(inner).cos(), f32::to_radians(outer).cos());
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|k| {
                    let c = -1.0 + 2.0 * (k as f64 + 0.5) / n as f64;
                    spot_falloff(c as f32, ci, co) as f64
                })
                .sum();
            let numeric = 2.0 * std::f64::consts::PI * sum * 2.0 / n as f64;
            let closed = spot_power(Vec3::ONE, ci, co).x as f64;
            assert!(
                (numeric - closed).abs() < 1e-4 * closed.max(1e-3),
                "{inner}..{outer}: {numeric} vs {closed}"
            );
        }
    }
}
