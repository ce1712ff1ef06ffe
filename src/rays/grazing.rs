//! `grazing`: rays nearly parallel to a surface. Each picks a triangle with
//! probability proportional to its area and a uniform point on it, then a
//! direction in a random tangent direction tilted out of the plane by an
//! angle log-uniform in [`MIN_DEGREES`, `MAX_DEGREES`], from either side.
//! The origin is 0.05 to 1 bounding radii back along that direction, and
//! the ray reaches the point at `t = 1`.

use super::{aimed_ray, Generator, MeshInfo, Stream};
use crate::math::Ray;
use glam::{DVec3, Vec3};

/// Smallest tilt out of the triangle's plane.
pub const MIN_DEGREES: f64 = 0.01;
/// Largest tilt out of the triangle's plane.
pub const MAX_DEGREES: f64 = 1.0;

pub struct Grazing<'a> {
    triangles: &'a [[Vec3; 3]],
    /// Running sum of triangle areas, for area-weighted picking.
    cumulative_area: Vec<f64>,
    radius: f64,
}

impl<'a> Grazing<'a> {
    pub fn new(mesh: &MeshInfo<'a>) -> Result<Self, String> {
        let mut total = 0.0;
        let cumulative_area = mesh
            .triangles
            .iter()
            .map(|t| {
                total += normal(t).length();
                total
            })
            .collect();
        if !(total > 0.0) {
            return Err("every triangle of the mesh has zero area".to_string());
        }
        Ok(Self {
            triangles: mesh.triangles,
            cumulative_area,
            radius: mesh.radius,
        })
    }
}

/// Twice-area normal in f64.
fn normal(t: &[Vec3; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    (b - a).cross(c - a)
}

impl Generator for Grazing<'_> {
    fn ray(&self, _index: u32, rng: &mut Stream) -> Option<Ray> {
        let total = *self.cumulative_area.last()?;
        let pick = rng.next_f64() * total;
        let i = self
            .cumulative_area
            .partition_point(|&a| a <= pick)
            .min(self.triangles.len() - 1);
        let tri = &self.triangles[i];
        let n = normal(tri).try_normalize()?;
        // A uniform point: the square-root warp of two uniforms.
        let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
        let [a, b, c] = tri.map(|v| v.as_dvec3());
        let point = (1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c;
        // A tangent direction, tilted out of the plane.
        let r = rng.unit_vector();
        let tangent = (r - r.dot(n) * n).try_normalize()?;
        let (lo, hi) = (MIN_DEGREES.ln(), MAX_DEGREES.ln());
        let tilt = (lo + (hi - lo) * rng.next_f64()).exp().to_radians();
        let side = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
        let d = tilt.cos() * tangent + side * tilt.sin() * n;
        let back = self.radius * (0.05 + 0.95 * rng.next_f64());
        aimed_ray(point - back * d, point)
    }
}
