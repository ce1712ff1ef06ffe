//! The density with which a light's sampling ([`Light::sample`]) draws a
//! given direction: what multiple importance sampling weighs a BSDF ray
//! that hits the light's surface by (the path integrator).

use super::{Light, LightSampling};
use crate::sampling::spherical_rect::SphericalRect;
use glam::Vec3;
use std::f32::consts::PI;

impl Light {
    /// The density (per steradian) with which [`Light::sample`] from `p`
    /// by `method` draws the direction towards `q`, a point of the light's
    /// surface with normal `n` there; 0 for lights without a surface.
    pub fn pdf(&self, p: Vec3, q: Vec3, n: Vec3, method: LightSampling) -> f32 {
        let to = q - p;
        let d2 = to.length_squared();
        if !(d2 > 0.0) {
            return 0.0;
        }
        let wi = to / d2.sqrt();
        let by_area = |area: f32, one_sided: bool| {
            let cos_l = if one_sided {
                -n.dot(wi)
            } else {
                n.dot(wi).abs()
            };
            if cos_l > 0.0 {
                d2 / (cos_l * area)
            } else {
                0.0
            }
        };
        let pdf = match *self {
            Light::Rect { rect, .. } => {
                let solid_angle = self
                    .solid_angle_rect(p, method)
                    .and_then(|_| SphericalRect::new(p, rect.corner, rect.edge_u, rect.edge_v));
                match solid_angle {
                    Some(s) if -rect.normal.dot(wi) > 0.0 => 1.0 / s.solid_angle,
                    Some(_) => 0.0,
                    None => by_area(rect.area(), true),
                }
            }
            Light::Disk { disk, .. } => by_area(disk.area(), true),
            Light::Sphere { center, radius, .. } => {
                let cone = super::sphere_cone(p, center, radius);
                if let (true, Some((_, solid_angle))) = (method.by_solid_angle(), cone) {
                    1.0 / solid_angle
                } else {
                    // Sampled over the sphere's area, whose samples see only
                    // its outside (none from within: there BSDF rays alone
                    // find it, with weight 1).
                    by_area(4.0 * PI * radius * radius, true)
                }
            }
            _ => 0.0,
        };
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// The radiance a light with a surface emits (zero for the others).
    pub fn surface_radiance(&self) -> Vec3 {
        match *self {
            Light::Rect { radiance, .. }
            | Light::Disk { radiance, .. }
            | Light::Sphere { radiance, .. } => radiance,
            _ => Vec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::disk::Disk;
    use crate::shape::rect::Rect;
    use glam::Vec2;

    /// Each sample's radiance over its weight is the density `pdf` gives
    /// for its direction, by either method, for every light with a surface.
    #[test]
    fn the_density_is_the_one_samples_are_drawn_with() {
        let lights = [
            Light::Rect {
                rect: Rect::new(Vec3::new(-1.0, 2.0, -0.5), Vec3::X * 2.0, Vec3::Z).unwrap(),
                radiance: Vec3::new(2.0, 1.0, 1.0),
                prim: 0,
            },
            Light::Disk {
                disk: Disk::new(Vec3::new(0.5, 2.0, 0.0), -Vec3::Y, 0.7),
                radiance: Vec3::ONE,
                prim: 0,
            },
            Light::Sphere {
                center: Vec3::new(1.0, 3.0, 0.0),
                radius: 0.5,
                radiance: Vec3::splat(3.0),
                prim: 0,
            },
        ];
        // The rect light subtends about 0.5 sr from the first point and
        // 0.014 from the second: `auto` samples it by solid angle from
        // the one and by area from the other.
        let points = [Vec3::new(0.1, 0.0, 0.2), Vec3::new(0.1, -10.0, 0.2)];
        assert!(lights[0]
            .solid_angle_rect(points[0], LightSampling::Auto)
            .is_some());
        assert!(lights[0]
            .solid_angle_rect(points[1], LightSampling::Auto)
            .is_none());
        for (light, p) in lights.iter().flat_map(|l| points.map(|p| (l, p))) {
            for method in [
                LightSampling::Area,
                LightSampling::SolidAngle,
                LightSampling::Auto,
            ] {
                let mut drawn = 0;
                for i in 0..16 {
                    let u = Vec2::new((i as f32 + 0.5) / 16.0, (i as f32 * 7.0 + 0.5) / 16.0 % 1.0);
                    let Some(s) = light.sample(p, u, method) else {
                        continue;
                    };
                    drawn += 1;
                    let q = p + s.wi * s.distance;
                    let n = match light {
                        Light::Rect { rect, .. } => rect.normal,
                        Light::Disk { disk, .. } => disk.normal(),
                        Light::Sphere { center, .. } => (q - *center).normalize(),
                        _ => unreachable!(),
                    };
                    let want = light.surface_radiance().max_element() / s.weight.max_element();
                    let got = light.pdf(p, q, n, method);
                    assert!(
                        (got - want).abs() <= 2e-3 * want,
                        "{light:?} {method:?} from {p}: {got} vs {want}"
                    );
                }
                // (A sphere drawn by area shows its far half from behind.)
                assert!(
                    drawn >= 5,
                    "{light:?} {method:?} from {p}: {drawn} samples of 16"
                );
            }
        }
    }
}
