//! One rectangle seen from up to eight points at once: the spherical
//! rectangles of [`super::spherical_rect`] (Ureña, Fajardo and King 2013)
//! in `wide::f32x8` lanes, for the hit points of one batch of camera
//! samples.
//!
//! Building and sampling a spherical rectangle is a chain of dependent
//! divisions and square roots; one lane per point runs eight chains in the
//! time of one. Every lane performs exactly the scalar code's operations in
//! its order (no fused multiply-adds, IEEE division and square roots, the
//! scalar clamps' NaN behaviour, and the same vector arc cosine, sine and
//! cosine of [`crate::math::trig`]), so each lane is bit for bit the scalar
//! [`SphericalRect`](super::spherical_rect::SphericalRect): the tests check that, and the image does not depend
//! on how samples were batched.

use crate::math::lanes::{Lanes3, LANES};
use crate::math::trig::{acos8, sin_cos8};
use crate::math::unit_scale;
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;
use wide::f32x8;

/// `f32::clamp`: NaN stays NaN (a plain min/max pair would not keep it).
fn clamp(v: f32x8, lo: f32x8, hi: f32x8) -> f32x8 {
    let v = v.simd_lt(lo).select(lo, v);
    v.simd_gt(hi).select(hi, v)
}

/// `f32::max` against a number: NaN gives `lo`, as the scalar code's does.
fn max_num(v: f32x8, lo: f32x8) -> f32x8 {
    v.simd_gt(lo).select(v, lo)
}

/// `f32::copysign`.
fn copysign(magnitude: f32x8, sign: f32x8) -> f32x8 {
    let bit = f32x8::splat(-0.0);
    (magnitude & !bit) | (sign & bit)
}

/// One rectangle seen from up to eight points, ready to sample.
#[derive(Debug, Clone, Copy)]
pub struct SphericalRects {
    origin: Lanes3,
    x: Vec3,
    y: Vec3,
    /// The frame's z axis, turned per lane so the rectangle lies at negative z.
    z: Lanes3,
    x0: f32x8,
    x1: f32x8,
    y0: f32x8,
    y1: f32x8,
    z0: f32x8,
    b0: f32x8,
    b1: f32x8,
    k: f32x8,
    solid_angle: [f32; LANES],
    /// Lanes whose rectangle [`SphericalRect::new`] would build.
    valid: u32,
}

impl SphericalRects {
    /// The rectangle (`corner`, perpendicular edges `edge_u`, `edge_v`) seen
    /// from `origins[i]` in lane `i`, for the lanes of `active` (others are
    /// left invalid). Lane `i` is valid exactly where
    /// `SphericalRect::new(origins[i], ..)` is `Some`.
    pub fn new(
        origins: &[Vec3; LANES],
        active: u32,
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
    ) -> Self {
        let (lu, lv) = (edge_u.length(), edge_v.length());
        let x = edge_u / lu;
        let y = edge_v / lv;
        let z_up = x.cross(y);
        let origin = Lanes3 {
            x: f32x8::from(origins.map(|o| o.x)),
            y: f32x8::from(origins.map(|o| o.y)),
            z: f32x8::from(origins.map(|o| o.z)),
        };
        let c = Lanes3::splat(corner);
        let d = Lanes3 {
            x: c.x - origin.x,
            y: c.y - origin.y,
            z: c.z - origin.z,
        };
        let z0_up = d.dot(Lanes3::splat(z_up));
        let flip = z0_up.simd_gt(f32x8::ZERO);
        let z0 = flip.select(-z0_up, z0_up);
        let z_down = Lanes3::splat(-z_up);
        let z = Lanes3 {
            x: flip.select(z_down.x, f32x8::splat(z_up.x)),
            y: flip.select(z_down.y, f32x8::splat(z_up.y)),
            z: flip.select(z_down.z, f32x8::splat(z_up.z)),
        };
        let x0 = d.dot(Lanes3::splat(x));
        let y0 = d.dot(Lanes3::splat(y));
        let (x1, y1) = (x0 + f32x8::splat(lu), y0 + f32x8::splat(lv));
        // Brought near 1 for the normals, as the scalar code does.
        let largest = x0
            .abs()
            .max(x1.abs())
            .max(y0.abs())
            .max(y1.abs())
            .max(z0.abs());
        let s = f32x8::from(largest.to_array().map(unit_scale));
        let corner_at = |cx: f32x8, cy: f32x8| Lanes3 {
            x: cx * s,
            y: cy * s,
            z: z0 * s,
        };
        let (v00, v01) = (corner_at(x0, y0), corner_at(x0, y1));
        let (v10, v11) = (corner_at(x1, y0), corner_at(x1, y1));
        let (n0, ok0) = v00.cross(v10).try_normalize();
        let (n1, ok1) = v10.cross(v11).try_normalize();
        let (n2, ok2) = v11.cross(v01).try_normalize();
        let (n3, ok3) = v01.cross(v00).try_normalize();
        let in_plane = z0.simd_eq(f32x8::ZERO);
        let formed = (ok0 & ok1 & ok2 & ok3 & !in_plane).to_bitmask() & active;
        // Interior angles; their excess over 2π is the solid angle.
        let angle = |c: f32x8| acos8(clamp(-c, -f32x8::ONE, f32x8::ONE));
        let [g0, g1, g2, g3] = [n0.dot(n1), n1.dot(n2), n2.dot(n3), n3.dot(n0)].map(angle);
        let k = f32x8::splat(TAU) - g2 - g3;
        let solid_angle = g0 + g1 - k;
        let valid = solid_angle.simd_gt(f32x8::splat(1e-6)).to_bitmask() & formed;
        Self {
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
            solid_angle: solid_angle.to_array(),
            valid,
        }
    }

    /// Lanes whose rectangle was built (bit `i` for lane `i`).
    pub fn valid(&self) -> u32 {
        self.valid
    }

    /// The solid angle subtended at lane `i`'s point (valid lanes only).
    pub fn solid_angle(&self, lane: usize) -> f32 {
        self.solid_angle[lane]
    }

    /// Lane `i`'s point on the rectangle for its uniform sample `u[i]`:
    /// exactly the scalar `SphericalRect::sample` of that lane. Lanes outside
    /// `self.valid()` hold no meaningful point.
    pub fn sample(&self, u: &[Vec2; LANES]) -> [Vec3; LANES] {
        let ux = f32x8::from(u.map(|u| u.x));
        let uy = f32x8::from(u.map(|u| u.y));
        // Choose the x coordinate by the area to its left.
        let au = ux * f32x8::from(self.solid_angle) + self.k;
        let (sin, cos) = sin_cos8(au);
        let one = f32x8::ONE;
        let fu = (cos * self.b0 - self.b1) / sin;
        let cu = clamp(
            copysign(one / (fu * fu + self.b0 * self.b0).sqrt(), fu),
            -one,
            one,
        );
        let xu = clamp(
            -(cu * self.z0) / max_num(one - cu * cu, f32x8::splat(1e-12)).sqrt(),
            self.x0,
            self.x1,
        );
        // Then y, uniformly in the projected height of that column.
        let d = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + uy * (h1 - h0);
        let hv2 = hv * hv;
        let yv = hv2
            .simd_lt(f32x8::splat(1.0 - 1e-6))
            .select((hv * d) / (one - hv2).sqrt(), self.y1);
        let yv = clamp(yv, self.y0, self.y1);
        let (x, y) = (Lanes3::splat(self.x), Lanes3::splat(self.y));
        let point = Lanes3 {
            x: self.origin.x + xu * x.x + yv * y.x + self.z0 * self.z.x,
            y: self.origin.y + xu * x.y + yv * y.y + self.z0 * self.z.y,
            z: self.origin.z + xu * x.z + yv * y.z + self.z0 * self.z.z,
        };
        point.to_vecs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::spherical_rect::SphericalRect;
    use crate::sampling::stream::{seeded, Draw};

    /// Bits of a vector, so that -0.0 and 0.0 differ and NaN equals NaN.
    fn bits(v: Vec3) -> [u32; 3] {
        v.to_array().map(f32::to_bits)
    }

    /// Every lane against the scalar spherical rectangle, bit for bit, over
    /// points all around rectangles of many shapes and sizes: far, close,
    /// grazing, in the plane, behind, and degenerate edges.
    #[test]
    fn each_lane_is_the_scalar_rectangle_bit_for_bit() {
        let mut rng = seeded(7);
        let mut built = 0;
        for case in 0..4000 {
            let corner = Vec3::new(rng.range(-3.0, 3.0), 2.0, rng.range(-3.0, 3.0));
            let scale = [1e-4, 0.01, 1.0, 30.0][case % 4];
            // Axis-aligned (where many products are exactly zero) or turned.
            let (u_dir, v_dir) = if case % 3 == 0 {
                (Vec3::X, Vec3::Z)
            } else {
                let u_dir = rng.unit_vector();
                (u_dir, u_dir.any_orthonormal_vector())
            };
            let edge_u = u_dir * rng.range(0.0, 2.0) * scale;
            let edge_v = v_dir * rng.range(0.0, 2.0) * scale;
            let normal = u_dir.cross(v_dir);
            let origins: [Vec3; LANES] = std::array::from_fn(|lane| match (case / 4 + lane) % 5 {
                // In the rectangle's plane, or a hair off it.
                0 => corner + edge_u * 0.5 + edge_v * 0.3 + normal * rng.range(-1e-6, 1e-6),
                // Far away.
                1 => Vec3::new(rng.range(-1e4, 1e4), -1e4, rng.range(-1e4, 1e4)),
                _ => Vec3::new(
                    rng.range(-4.0, 4.0),
                    rng.range(-2.0, 6.0),
                    rng.range(-4.0, 4.0),
                ),
            });
            let active = (rng.unit() * 256.0) as u32 & 0xff;
            let rects = SphericalRects::new(&origins, active, corner, edge_u, edge_v);
            let u: [Vec2; LANES] = std::array::from_fn(|_| Vec2::new(rng.unit(), rng.unit()));
            let points = rects.sample(&u);
            for (i, o) in origins.iter().enumerate() {
                let scalar = SphericalRect::new(*o, corner, edge_u, edge_v);
                let lane_valid = rects.valid() >> i & 1 != 0;
                if active >> i & 1 == 0 {
                    assert!(!lane_valid, "an inactive lane is never valid");
                    continue;
                }
                assert_eq!(lane_valid, scalar.is_some(), "case {case} lane {i}");
                let Some(s) = scalar else { continue };
                built += 1;
                assert_eq!(s.solid_angle.to_bits(), rects.solid_angle(i).to_bits());
                assert_eq!(
                    bits(s.sample(u[i])),
                    bits(points[i]),
                    "case {case} lane {i}"
                );
            }
        }
        assert!(built > 5000, "only {built} rectangles were built");
    }

    /// Corners of the unit square, where the scalar code clamps and falls
    /// back, give the scalar points too.
    #[test]
    fn sample_square_corners_match_the_scalar_rectangle() {
        let (corner, eu, ev) = (Vec3::new(-0.5, 1.0, -0.5), Vec3::X, Vec3::Z);
        let origins: [Vec3; LANES] =
            std::array::from_fn(|i| Vec3::new(0.3 * i as f32 - 1.0, -0.2, 0.1 * i as f32));
        let rects = SphericalRects::new(&origins, 0xff, corner, eu, ev);
        assert_eq!(rects.valid(), 0xff);
        for u in [0.0, 1e-7, 0.5, 1.0 - 1e-7, 1.0] {
            for v in [0.0, 1e-7, 0.5, 1.0 - 1e-7, 1.0] {
                let points = rects.sample(&[Vec2::new(u, v); LANES]);
                for (i, o) in origins.iter().enumerate() {
                    let s = SphericalRect::new(*o, corner, eu, ev).unwrap();
                    assert_eq!(bits(s.sample(Vec2::new(u, v))), bits(points[i]));
                }
            }
        }
    }
}
