//! The GGX microfacet distribution (Walter, Marschner, Li and Torrance
//! 2007, "Microfacet Models for Refraction through Rough Surfaces") with
//! Smith's height-correlated masking-shadowing (Heitz 2014,
//! "Understanding the Masking-Shadowing Function in Microfacet-Based
//! BRDFs"), its visible normals drawn as Heitz 2018 ("Sampling the GGX
//! Distribution of Visible Normals", JCGT 7(4)) does, and Schlick's
//! Fresnel with a coloured F0. Directions are in the local frame: the
//! shading normal is +z.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The smallest α: below it the lobe is narrower than f32 directions
/// resolve, and D overflows.
pub const MIN_ALPHA: f32 = 1e-3;

/// GGX's D(h) for roughness α (isotropic).
#[inline]
pub fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith's Λ(w) for GGX.
#[inline]
pub fn ggx_lambda(w: Vec3, alpha: f32) -> f32 {
    let z2 = w.z * w.z;
    if z2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = (w.x * w.x + w.y * w.y) / z2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// Smith's masking G1(w) = 1/(1 + Λ(w)).
#[inline]
pub fn ggx_g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(w, alpha))
}

/// Height-correlated masking-shadowing G2(wo, wi) = 1/(1 + Λ(wo) + Λ(wi)):
/// symmetric, so the BRDF is reciprocal.
#[inline]
pub fn ggx_g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha))
}

/// A microfacet normal drawn from the normals visible from `wo` (above
/// the surface), with density D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo.z
/// (Heitz 2018, listing 1: stretch, sample a projected hemisphere,
/// unstretch).
pub fn sample_visible_normal(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    // The view in the hemisphere configuration (α = 1).
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    // A point on the disk, squeezed towards the half the view sees.
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let mut p2 = r * phi.sin();
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// The density of `wi = reflect(wo, h)` when `h` is drawn by
/// [`sample_visible_normal`]: D_wo(h) / (4 wo·h) = G1(wo) D(h) / (4 wo.z).
#[inline]
pub fn reflected_pdf(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z)
}

/// Schlick 1994: F = F0 + (1 − F0)(1 − cosθ)⁵, per channel.
#[inline]
pub fn schlick_rgb(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The projected area of the microfacets is the macro surface's:
    /// ∫ D(h) h.z dω = 1, for narrow and wide lobes.
    #[test]
    fn ggx_normals_project_to_the_unit_disk() {
        for alpha in [0.05f32, 0.3, 1.0] {
            let n = 1 << 18;
            let mut sum = 0.0f64;
            // Midpoint rule in (cos²θ, φ): dω = dcosθ dφ, and D depends on θ alone.
            for i in 0..n {
                let c = (i as f64 + 0.5) / n as f64;
                let h = Vec3::new((1.0 - c * c).sqrt() as f32, 0.0, c as f32);
                sum += (ggx_d(h, alpha) as f64) * c * 2.0 * std::f64::consts::PI / n as f64;
            }
            assert!((sum - 1.0).abs() < 2e-2, "α {alpha}: {sum}");
        }
    }

    /// Visible normals face the view, and the mean of wi·z over their
    /// reflections weighted by 1/pdf estimates the hemisphere's projected
    /// solid angle where the reflection stays above (≤ π).
    #[test]
    fn visible_normals_face_the_view() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        for alpha in [0.1f32, 0.5, 1.0] {
            for i in 0..32 {
                for j in 0..32 {
                    let u = Vec2::new((i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0);
                    let h = sample_visible_normal(wo, alpha, u);
                    assert!(h.z > 0.0 && wo.dot(h) > -1e-4, "α {alpha}: {h}");
                    assert!((h.length() - 1.0).abs() < 1e-4);
                }
            }
        }
    }
}
