//! Parallelogram (the surface of a `rect` area light): `corner + a·edge_u +
//! b·edge_v` for a, b in [0, 1], facing `edge_u × edge_v`.

use crate::math::offset::gamma;
use crate::math::{unit_cross, unit_scale, Aabb, Ray};
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Unit normal, `normalize(edge_u × edge_v)`.
    pub normal: Vec3,
    /// Dual vectors: `a = dual_u · (p − corner)`, `b = dual_v · (p − corner)`.
    dual_u: Vec3,
    dual_v: Vec3,
}

impl Rect {
    /// `None` if the edges are parallel or zero.
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Option<Self> {
        // At any scale: `normalize` of the cross product overflows for
        // edges past 4e9 and underflows below 1e-10.
        let normal = unit_cross(edge_u, edge_v)?;
        let vn = edge_v.cross(normal);
        let un = edge_u.cross(normal);
        let dual_u = vn / vn.dot(edge_u);
        let dual_v = un / un.dot(edge_v);
        (dual_u.is_finite() && dual_v.is_finite()).then_some(Self {
            corner,
            edge_u,
            edge_v,
            normal,
            dual_u,
            dual_v,
        })
    }

    /// `|edge_u × edge_v|`, from the edges brought near 1 by a power of
    /// two ([`unit_scale`]): the same bits where the product's length²
    /// stays in float32's range, and no overflow past edges of 4e9 or
    /// underflow below 1e-10 (a light that small was sampled as one of no
    /// area, so by area it lit nothing).
    pub fn area(&self) -> f32 {
        let s = unit_scale(self.edge_u.abs().max(self.edge_v.abs()).max_element());
        (self.edge_u * s).cross(self.edge_v * s).length() / (s * s)
    }

    /// True if the edges are perpendicular, so solid-angle sampling applies.
    pub fn is_rectangle(&self) -> bool {
        self.edge_u.dot(self.edge_v).abs() <= 1e-5 * self.edge_u.length() * self.edge_v.length()
    }

    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let denom = ray.direction.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.corner - ray.origin).dot(self.normal) / denom;
        if !(t > ray.tmin && t < ray.tmax) {
            return None;
        }
        let q = ray.at(t) - self.corner;
        let a = self.dual_u.dot(q);
        let b = self.dual_v.dot(q);
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some(t)
    }

    /// Project onto the plane and bound the remaining error.
    pub fn surface_at(&self, p: Vec3) -> (Vec3, Vec3, Vec3) {
        let q = p - (p - self.corner).dot(self.normal) * self.normal;
        (q, gamma(6) * (q.abs() + self.corner.abs()), self.normal)
    }

    pub fn point(&self, a: f32, b: f32) -> Vec3 {
        self.corner + a * self.edge_u + b * self.edge_v
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&[
            self.corner,
            self.point(1.0, 0.0),
            self.point(0.0, 1.0),
            self.point(1.0, 1.0),
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_and_misses_outside_a_slanted_parallelogram() {
        let r = Rect::new(
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 1.0),
        )
        .unwrap();
        assert!((r.normal - -Vec3::Y).length() < 1e-6);
        let down = |x: f32, z: f32| Ray::new(Vec3::new(x, 3.0, z), -Vec3::Y);
        assert_eq!(r.intersect(&down(2.5, 0.5)), Some(3.0));
        assert!(
            r.intersect(&down(1.2, 0.9)).is_none(),
            "left of the slanted edge"
        );
        assert!(r.intersect(&down(3.9, 0.9)).is_some());
        assert!((r.area() - 2.0).abs() < 1e-6);
        assert!(Rect::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0).is_none());
    }
}
