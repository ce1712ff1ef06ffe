//! Warps from the unit square to the domains that effects sample.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Shirley and Chiu 1997, "A Low Distortion Map Between Disk and Square":
/// the concentric map keeps strata compact, so a stratified square gives a
/// stratified disk. Returns a point on the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let a = 2.0 * u - Vec2::ONE;
    // Both wedges computed and one chosen without a branch: which wedge a
    // random sample falls in is a coin toss, and as a branch it
    // mispredicted half the time (thin-lens lens samples). The quotient of
    // the wedge not chosen may be ±∞ or NaN; it is never used.
    let wide = a.x.abs() > a.y.abs();
    let x_wedge = FRAC_PI_4 * (a.y / a.x);
    let y_wedge = FRAC_PI_2 - FRAC_PI_4 * (a.x / a.y);
    let r = std::hint::select_unpredictable(wide, a.x, a.y);
    let theta = std::hint::select_unpredictable(wide, x_wedge, y_wedge);
    let d = r * Vec2::new(theta.cos(), theta.sin());
    // The centre: r is 0 there, but θ (0/0) would make the point NaN.
    std::hint::select_unpredictable(a.x == 0.0 && a.y == 0.0, Vec2::ZERO, d)
}

/// Uniform hemisphere around +z, pdf 1/(2π).
pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The normalised Phong lobe around +z: pdf (n+1)/(2π) cosⁿα.
/// cosα = u^(1/(n+1)) (Lafortune and Willems 1994, "Using the Modified Phong
/// Reflectance Model for Physically Based Rendering").
pub fn phong_lobe(u: Vec2, exponent: f32) -> Vec3 {
    // powf(u, 1/(n+1)) underflows to 0 for tiny u and huge n; ln/exp form keeps it accurate.
    let cos_a = if u.x > 0.0 {
        (u.x.ln() / (exponent + 1.0)).exp()
    } else {
        0.0
    };
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a)
}

/// Density of [`phong_lobe`] for a direction at cosine `cos_a` from the axis.
pub fn phong_lobe_pdf(cos_a: f32, exponent: f32) -> f32 {
    if cos_a <= 0.0 {
        0.0
    } else {
        (exponent + 1.0) / (2.0 * PI) * cos_a.powf(exponent)
    }
}

/// Uniform direction on the unit sphere, pdf 1/(4π).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z,
/// pdf 1/(2π(1 − cos_max)).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_stays_in_the_unit_disk_and_covers_it() {
        let mut quadrants = [0; 4];
        for i in 0..32 {
            for j in 0..32 {
                let u = Vec2::new((i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0);
                let d = concentric_disk(u);
                assert!(d.length() <= 1.0 + 1e-6);
                quadrants[(d.x > 0.0) as usize * 2 + (d.y > 0.0) as usize] += 1;
            }
        }
        assert_eq!(quadrants, [256; 4]);
    }

    #[test]
    fn phong_lobe_is_unit_length_and_concentrates_with_the_exponent() {
        for n in [1.0f32, 10.0, 1e3, 1e5] {
            let mut mean_cos = 0.0;
            for i in 0..64 {
                let u = Vec2::new((i as f32 + 0.5) / 64.0, 0.3);
                let d = phong_lobe(u, n);
                assert!((d.length() - 1.0).abs() < 1e-5);
                mean_cos += d.z / 64.0;
            }
            // E[cosα] = (n+1)/(n+2) for the pdf ∝ cosⁿα on the hemisphere.
            let expected = (n + 1.0) / (n + 2.0);
            assert!(
                (mean_cos - expected).abs() < 0.02,
                "n {n}: {mean_cos} vs {expected}"
            );
        }
    }
}
