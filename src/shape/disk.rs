//! Disk (the surface of a `disk` area light), facing `normal`.

use crate::math::offset::gamma;
use crate::math::{Aabb, Frame, Ray};
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disk {
    pub center: Vec3,
    /// Unit normal; the frame's z axis.
    pub frame: Frame,
    pub radius: f32,
}

impl Disk {
    pub fn new(center: Vec3, normal: Vec3, radius: f32) -> Self {
        Self {
            center,
            frame: Frame::from_z(normal),
            radius,
        }
    }

    pub fn normal(&self) -> Vec3 {
        self.frame.z
    }

    pub fn area(&self) -> f32 {
        std::f32::consts::PI * self.radius * self.radius
    }

    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let n = self.frame.z;
        let denom = ray.direction.dot(n);
        if denom == 0.0 {
            return None;
        }
        let t = (self.center - ray.origin).dot(n) / denom;
        if !(t > ray.tmin && t < ray.tmax) {
            return None;
        }
        ((ray.at(t) - self.center).length_squared() <= self.radius * self.radius).then_some(t)
    }

    pub fn surface_at(&self, p: Vec3) -> (Vec3, Vec3, Vec3) {
        let n = self.frame.z;
        let q = p - (p - self.center).dot(n) * n;
        (q, gamma(6) * (q.abs() + self.center.abs()), n)
    }

    pub fn bounds(&self) -> Aabb {
        // Extent along each axis: r·sqrt(1 − n_axis²).
        let n = self.frame.z;
        let e = self.radius * (Vec3::ONE - n * n).max(Vec3::ZERO).sqrt();
        Aabb::new(self.center - e, self.center + e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_within_the_radius_and_bounds_are_tight() {
        let d = Disk::new(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 1.0);
        assert_eq!(
            d.intersect(&Ray::new(Vec3::new(0.5, 0.0, 0.5), Vec3::Y)),
            Some(2.0)
        );
        assert!(d
            .intersect(&Ray::new(Vec3::new(0.8, 0.0, 0.8), Vec3::Y))
            .is_none());
        let b = d.bounds();
        assert!((b.max - Vec3::new(1.0, 2.0, 1.0)).length() < 1e-6);
    }
}
