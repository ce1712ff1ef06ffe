//! Infinite plane. Unbounded, so it stays out of the BVH and is tested
//! against every ray directly (scenes have few).
//!
//! ```toml
//! [[objects]]
//! plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] }
//! ```

use crate::math::offset::gamma;
use crate::math::Ray;
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    pub material: u32,
}

impl Plane {
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let denom = ray.direction.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        (t > ray.tmin && t < ray.tmax).then_some(t)
    }

    /// Project a point onto the plane (removing the error of `o + t d`) and
    /// bound the error that remains.
    pub fn surface_at(&self, p: Vec3) -> (Vec3, Vec3) {
        let q = p - (p - self.point).dot(self.normal) * self.normal;
        let err = gamma(6) * (q.abs() + self.point.abs());
        (q, err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_rays_miss_and_others_hit_at_the_analytic_t() {
        let plane = Plane {
            point: Vec3::new(0.0, -1.0, 0.0),
            normal: Vec3::Y,
            material: 0,
        };
        assert!(plane.intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
        let t = plane
            .intersect(&Ray::new(Vec3::ZERO, Vec3::new(1.0, -1.0, 0.0)))
            .unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        assert!(
            plane.intersect(&Ray::new(Vec3::ZERO, Vec3::Y)).is_none(),
            "behind the origin"
        );
    }
}
