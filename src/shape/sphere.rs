//! Sphere.
//!
//! ```toml
//! [[objects]]
//! sphere = { center = [0.0, 1.0, 0.0], radius = 1.0 }
//! ```
//!
//! The quadratic is solved in the numerically careful form of Haines,
//! Günther and Akenine-Möller 2019, "Precision Improvements for Ray/Sphere
//! Intersection" (Ray Tracing Gems, chapter 7): the discriminant comes from
//! the distance of the line to the centre, and the two roots from the stable
//! pair q/a and c/q, so far-away and grazing rays stay accurate.

use crate::math::offset::gamma;
use crate::math::Ray;
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// Both roots along the whole line, ordered, or `None` if the line misses.
    pub fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        let f = ray.origin - self.center;
        let d = ray.direction;
        let a = d.length_squared();
        let b = -f.dot(d);
        let c = f.length_squared() - self.radius * self.radius;
        // Vector from the centre to the line's closest point.
        let l = f + (b / a) * d;
        let disc = a * (self.radius * self.radius - l.length_squared());
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = b + b.signum() * disc.sqrt();
        let (t0, t1) = if q == 0.0 {
            // Ray origin at the centre's plane and tangent: c = 0.
            let h = (-c / a).max(0.0).sqrt();
            (-h, h)
        } else {
            (c / q, q / a)
        };
        Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
    }

    /// The first hit in `(tmin, tmax)`.
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let (t0, t1) = self.roots(ray)?;
        if t0 > ray.tmin && t0 < ray.tmax {
            Some(t0)
        } else if t1 > ray.tmin && t1 < ray.tmax {
            Some(t1)
        } else {
            None
        }
    }

    /// Point on the surface (re-projected, so its error is small) with its
    /// error bound and outward unit normal.
    pub fn surface_at(&self, p: Vec3) -> (Vec3, Vec3, Vec3) {
        let mut n = (p - self.center).normalize();
        if !n.is_finite() {
            n = Vec3::Z;
        }
        let p = self.center + self.radius * n;
        let err = gamma(5) * (self.center.abs() + (self.radius * n).abs());
        (p, err, n)
    }

    pub fn contains(&self, p: Vec3) -> bool {
        (p - self.center).length_squared() < self.radius * self.radius
    }

    pub fn bounds(&self) -> crate::math::Aabb {
        crate::math::Aabb::new(
            self.center - Vec3::splat(self.radius),
            self.center + Vec3::splat(self.radius),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Sphere = Sphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 2.0,
    };

    #[test]
    fn hits_from_outside_and_inside_with_analytic_t() {
        let ray = Ray::new(Vec3::new(1.0, 2.0, 10.0), -Vec3::Z);
        assert!((S.intersect(&ray).unwrap() - 5.0).abs() < 1e-5);
        let inside = Ray::new(S.center, Vec3::X * 0.5);
        assert!(
            (S.intersect(&inside).unwrap() - 4.0).abs() < 1e-5,
            "unnormalised direction keeps t parametric"
        );
    }

    #[test]
    fn tangent_and_near_miss() {
        let tangent = Ray::new(Vec3::new(3.0, 2.0, 10.0), -Vec3::Z);
        let t = S.intersect(&tangent).expect("a tangent ray touches");
        assert!((t - 7.0).abs() < 1e-2);
        let miss = Ray::new(Vec3::new(3.0001, 2.0, 10.0), -Vec3::Z);
        assert!(S.intersect(&miss).is_none());
    }

    #[test]
    fn far_away_rays_stay_accurate() {
        let far = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let ray = Ray::new(Vec3::new(0.0, 0.5, 1e5), -Vec3::Z);
        let t = far.intersect(&ray).unwrap();
        let expected = 1e5 - (1.0f32 - 0.25).sqrt();
        assert!((t - expected).abs() / expected < 1e-6);
        // The re-projected surface point lies on the sphere to float accuracy.
        let (p, _, _) = far.surface_at(ray.at(t));
        assert!((p.length() - 1.0).abs() < 1e-6);
    }
}
