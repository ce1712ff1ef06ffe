//! Scattering formulas: the radiometric Phong BRDF, Snell's law and
//! Schlick's Fresnel approximation.

use crate::material::Material;
use glam::Vec3;
use std::f32::consts::PI;

/// ρ/π + k_s (n+2)/(2π) cosⁿα, α between the mirror of `wi` and `wo`;
/// `albedo` is ρ at the hit (the material's diffuse, perhaps textured).
#[inline]
pub fn phong_brdf(
    m: &Material,
    albedo: Vec3,
    wo: Vec3,
    wi: Vec3,
    n: Vec3,
    diffuse: bool,
    specular: bool,
) -> Vec3 {
    let mut f = if diffuse { albedo / PI } else { Vec3::ZERO };
    if specular {
        let r = 2.0 * n.dot(wi) * n - wi;
        let cos_a = r.dot(wo);
        if cos_a > 0.0 {
            f += m.specular * ((m.shininess + 2.0) / (2.0 * PI) * cos_a.powf(m.shininess));
        }
    }
    f
}

/// Snell's law: the refracted direction of `wo` (pointing away from the
/// surface, on the side of `n`) for relative index `eta` = n_outside/n_inside,
/// or `None` on total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wo);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-eta * wo + (eta * cos_i - cos_t) * n).normalize())
}

/// Schlick 1994, "An Inexpensive BRDF Model for Physically-based
/// Rendering": F = F0 + (1 − F0)(1 − cosθ)⁵, for relative index `ior`.
pub fn schlick(cos_i: f32, ior: f32) -> f32 {
    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
    f0 + (1.0 - f0) * (1.0 - cos_i.clamp(0.0, 1.0)).powi(5)
}

/// The mirror and glass weights of `m` seen along `wo` (shading normal
/// `ns`, on the side `entering` says), after Fresnel and total internal
/// reflection move transmitted energy to the mirror, with the refracted
/// direction where there is one: how both integrators split a surface's
/// `reflectivity` and `transparency`.
pub fn mirror_and_glass(
    m: &Material,
    wo: Vec3,
    ns: Vec3,
    entering: bool,
) -> (f32, f32, Option<Vec3>) {
    let mut kr = m.reflectivity;
    let mut kt = m.transparency;
    let mut refracted = None;
    if kt > 0.0 {
        let eta = if entering { 1.0 / m.ior } else { m.ior };
        match refract(wo, ns, eta) {
            Some(t) => {
                if m.fresnel {
                    let f = schlick(wo.dot(ns), if entering { m.ior } else { 1.0 / m.ior });
                    kr += kt * f;
                    kt *= 1.0 - f;
                }
                refracted = Some(t);
            }
            None => {
                // Total internal reflection: all transmitted energy reflects.
                kr += kt;
                kt = 0.0;
            }
        }
    }
    (kr, kt, refracted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snell_bends_towards_the_normal_and_reflects_totally_past_the_critical_angle() {
        let n = Vec3::Y;
        let theta = 30f32.to_radians();
        let wo = Vec3::new(theta.sin(), theta.cos(), 0.0);
        let t = refract(wo, n, 1.0 / 1.5).unwrap();
        let sin_t = t.x.abs();
        assert!((sin_t - theta.sin() / 1.5).abs() < 1e-6);
        assert!(
            t.y < 0.0 && t.x < 0.0,
            "goes through, on the other side of the normal"
        );
        // From inside glass at 60° (> critical 41.8°).
        let theta = 60f32.to_radians();
        let wo = Vec3::new(theta.sin(), theta.cos(), 0.0);
        assert!(refract(wo, n, 1.5).is_none());
    }

    #[test]
    fn schlick_matches_normal_incidence_and_grazing_limits() {
        assert!((schlick(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((schlick(0.0, 1.5) - 1.0).abs() < 1e-6);
    }
}
