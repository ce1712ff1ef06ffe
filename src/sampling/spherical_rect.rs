//! Uniform sampling of the solid angle of a rectangle: Ureña, Fajardo and
//! King 2013, "An Area-Preserving Parametrization for Spherical Rectangles"
//! (EGSR). Sampling by solid angle removes the 1/r² variance blow-up of area
//! sampling when a large light is close to the shading point, and the map is
//! area preserving, so stratified (u, v) stay stratified on the sphere.

use crate::math::trig::{acos8, sin_cos};
use crate::math::unit_scale;
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;
use wide::f32x8;

/// A rectangle seen from one point, ready to sample.
#[derive(Debug, Clone, Copy)]
pub struct SphericalRect {
    origin: Vec3,
    x: Vec3,
    y: Vec3,
    z: Vec3,
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    z0: f32,
    b0: f32,
    b1: f32,
    k: f32,
    /// The solid angle subtended, in steradians.
    pub solid_angle: f32,
}

impl SphericalRect {
    /// `corner` and perpendicular edges `edge_u`, `edge_v`, seen from `origin`.
    /// `None` if the point lies in the rectangle's plane or the angle is too
    /// small to sample in f32 (the caller falls back to area sampling).
    pub fn new(origin: Vec3, corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Option<Self> {
        let (lu, lv) = (edge_u.length(), edge_v.length());
        let x = edge_u / lu;
        let y = edge_v / lv;
        let mut z = x.cross(y);
        let d = corner - origin;
        let mut z0 = d.dot(z);
        // Orient the local frame so the rectangle lies at negative z.
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0 == 0.0 {
            return None;
        }
        let x0 = d.dot(x);
        let y0 = d.dot(y);
        let (x1, y1) = (x0 + lu, y0 + lv);
        // The spherical quad's corners and the normals of its great-circle
        // edges. The normals are scale-free, so they are made from the
        // corners brought near 1 by a power of two ([`unit_scale`]): the
        // same bits wherever the unscaled products stay in float32's range,
        // and a light 1e9 or 1e-11 across (whose corners' fourth powers
        // overflow or underflow) sampled as one 1 across.
        let s = unit_scale(
            x0.abs()
                .max(x1.abs())
                .max(y0.abs())
                .max(y1.abs())
                .max(z0.abs()),
        );
        let v00 = Vec3::new(x0, y0, z0) * s;
        let v01 = Vec3::new(x0, y1, z0) * s;
        let v10 = Vec3::new(x1, y0, z0) * s;
        let v11 = Vec3::new(x1, y1, z0) * s;
        let n0 = v00.cross(v10).try_normalize()?;
        let n1 = v10.cross(v11).try_normalize()?;
        let n2 = v11.cross(v01).try_normalize()?;
        let n3 = v01.cross(v00).try_normalize()?;
        // Interior angles; their excess over 2π is the solid angle. The four
        // arc cosines in one vector call, the one the lanes make.
        let cosines = [n0.dot(n1), n1.dot(n2), n2.dot(n3), n3.dot(n0)];
        let cosines: [f32; 8] = std::array::from_fn(|i| (-cosines[i % 4]).clamp(-1.0, 1.0));
        let [g0, g1, g2, g3, ..] = acos8(f32x8::from(cosines)).to_array();
        let k = TAU - g2 - g3;
        let solid_angle = g0 + g1 - k;
        if !(solid_angle > 1e-6) {
            return None;
        }
        Some(Self {
            origin,
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0.z,
            b1: n2.z,
            k,
            solid_angle,
        })
    }

    /// The point on the rectangle for a uniform sample `u` of [0,1)²; the
    /// direction from the origin to it has density 1 / `solid_angle`.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        // Choose the x coordinate by the area to its left.
        let au = u.x * self.solid_angle + self.k;
        let (sin_au, cos_au) = sin_cos(au);
        let fu = (cos_au * self.b0 - self.b1) / sin_au;
        let cu = ((fu * fu + self.b0 * self.b0).sqrt().recip().copysign(fu)).clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(1e-12).sqrt()).clamp(self.x0, self.x1);
        // Then y, uniformly in the projected height of that column.
        let d = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + u.y * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-6 {
            (hv * d) / (1.0 - hv2).sqrt()
        } else {
            self.y1
        };
        self.origin + xu * self.x + yv.clamp(self.y0, self.y1) * self.y + self.z0 * self.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solid angle of a rectangle by brute-force quadrature of cosθ/r² dA.
    fn quadrature(origin: Vec3, corner: Vec3, eu: Vec3, ev: Vec3) -> f64 {
        let n = eu.cross(ev).normalize();
        let area = eu.cross(ev).length() as f64;
        let steps = 400;
        let mut sum = 0.0;
        for i in 0..steps {
            for j in 0..steps {
                let p = corner
                    + eu * ((i as f32 + 0.5) / steps as f32)
                    + ev * ((j as f32 + 0.5) / steps as f32);
                let d = p - origin;
                let r2 = d.length_squared() as f64;
                sum += (n.dot(d).abs() as f64 / r2.sqrt()) / r2;
            }
        }
        sum * area / (steps * steps) as f64
    }

    #[test]
    fn solid_angle_matches_quadrature_and_samples_land_on_the_rectangle() {
        let cases = [
            (
                Vec3::new(0.2, -1.0, 0.3),
                Vec3::new(-0.5, 0.0, -0.5),
                Vec3::X,
                Vec3::Z,
            ),
            (
                Vec3::new(3.0, -0.1, 0.0),
                Vec3::new(-0.5, 0.0, -0.5),
                Vec3::X * 2.0,
                Vec3::Z * 0.5,
            ),
            (
                Vec3::new(0.0, 5.0, 0.0),
                Vec3::new(-0.5, 0.0, -0.5),
                Vec3::X,
                Vec3::Z,
            ),
        ];
        for (o, c, eu, ev) in cases {
            let s = SphericalRect::new(o, c, eu, ev).unwrap();
            let q = quadrature(o, c, eu, ev);
            assert!(
                ((s.solid_angle as f64) - q).abs() / q < 2e-3,
                "{} vs {q}",
                s.solid_angle
            );
            let n = eu.cross(ev).normalize();
            for i in 0..16 {
                for j in 0..16 {
                    let p = s.sample(Vec2::new((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0));
                    let local = p - c;
                    assert!(local.dot(n).abs() < 1e-4, "on the plane");
                    let a = local.dot(eu) / eu.length_squared();
                    let b = local.dot(ev) / ev.length_squared();
                    assert!(
                        (-1e-4..=1.0001).contains(&a) && (-1e-4..=1.0001).contains(&b),
                        "inside: {a} {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_map_is_area_preserving() {
        // Equal areas of the unit square map to equal solid angles: the
        // quadrant u < 0.5 covers half the solid angle. Check by projecting
        // back: the solid angle of the sub-rectangle left of the sampled
        // x at u = 0.5 must be half the total.
        let (o, c, eu, ev) = (
            Vec3::new(0.3, -0.7, 0.1),
            Vec3::new(-1.0, 0.0, -0.5),
            Vec3::X * 2.0,
            Vec3::Z,
        );
        let s = SphericalRect::new(o, c, eu, ev).unwrap();
        let p = s.sample(Vec2::new(0.5, 0.5));
        let split = (p - c).dot(eu) / eu.length_squared();
        let left = SphericalRect::new(o, c, eu * split, ev).unwrap();
        assert!((left.solid_angle / s.solid_angle - 0.5).abs() < 1e-3);
    }
}
