//! Watertight ray–triangle intersection: Woop, Benthin and Wald 2013,
//! "Watertight Ray/Triangle Intersection" (JCGT 2(1)).
//!
//! The ray is sheared so that it runs along +z from the origin; the hit test
//! then reduces to signs of 2D edge functions. Edges shared by two triangles
//! are evaluated identically for both, so a ray through an edge or vertex
//! hits at least one of them: no cracks. Edge functions that come out
//! exactly zero are recomputed in f64, as the paper recommends.

use crate::math::Ray;
use glam::Vec3;

/// Per-ray precomputation of the shear (done once per traversal).
#[derive(Debug, Clone, Copy)]
pub struct ShearedRay {
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
}

impl ShearedRay {
    pub fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        let kz = d.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Swap to keep the winding, so the sign of det tells the facing.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        Self {
            kx,
            ky,
            kz,
            sx: d[kx] * sz,
            sy: d[ky] * sz,
            sz,
        }
    }
}

/// Intersect one triangle. Returns `(t, u, v)` with `u`, `v` the barycentric
/// weights of `v1` and `v2`, for `t` strictly inside `(tmin, tmax)`.
#[inline(always)]
pub fn intersect(ray: &Ray, s: &ShearedRay, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    // Vertices relative to the ray origin.
    let a = v[0] - ray.origin;
    let b = v[1] - ray.origin;
    let c = v[2] - ray.origin;
    // Shear and scale into ray space.
    let ax = a[s.kx] - s.sx * a[s.kz];
    let ay = a[s.ky] - s.sy * a[s.kz];
    let bx = b[s.kx] - s.sx * b[s.kz];
    let by = b[s.ky] - s.sy * b[s.kz];
    let cx = c[s.kx] - s.sx * c[s.kz];
    let cy = c[s.ky] - s.sy * c[s.kz];
    // Scaled barycentric edge functions.
    let mut e0 = cx * by - cy * bx;
    let mut e1 = ax * cy - ay * cx;
    let mut e2 = bx * ay - by * ax;
    // Fall back to double precision on exact zeros (on an edge).
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        e0 = (cx * by - cy * bx) as f32;
        e1 = (ax * cy - ay * cx) as f32;
        e2 = (bx * ay - by * ax) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    // Scaled hit distance.
    let az = s.sz * a[s.kz];
    let bz = s.sz * b[s.kz];
    let cz = s.sz * c[s.kz];
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t > ray.tmin && t < ray.tmax) {
        return None;
    }
    // A hit within the rounding error of t = 0 is the ray's own origin
    // surface: reject it, with the bound of pbrt-v4 (section 6.8.4,
    // "Conservative Ray–Triangle t Values"). Without it, a ray spawned
    // from a point exactly on the triangle's plane (zero error bound) can
    // re-hit the plane at t = 1e-9.
    let world_z = [a[s.kz], b[s.kz], c[s.kz]];
    if t <= origin_error_bound(
        ax,
        ay,
        bx,
        by,
        cx,
        cy,
        world_z,
        [az, bz, cz],
        [e0, e1, e2],
        inv_det,
    ) {
        return None;
    }
    Some((t, e1 * inv_det, e2 * inv_det))
}

/// δt: the error bound of the computed t, from the bounds on the sheared
/// coordinates and edge functions.
///
/// pbrt adds the largest |z| to the largest |x| and |y| in δx and δy, for
/// the shear `x − sx·z`; that z is in world units (`world_z`, before the
/// scaling by `sz = 1/d_z`), while the z of t (`z`) is in units of t. pbrt
/// uses the scaled z for both, which is the same only for unit-length
/// directions: a ray whose direction is 1e-6 long (a mesh at scale 1e-6)
/// would get a bound a million times too large and lose every hit.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn origin_error_bound(
    ax: f32,
    ay: f32,
    bx: f32,
    by: f32,
    cx: f32,
    cy: f32,
    world_z: [f32; 3],
    z: [f32; 3],
    e: [f32; 3],
    inv_det: f32,
) -> f32 {
    use crate::math::offset::gamma;
    let max_z = z[0].abs().max(z[1].abs()).max(z[2].abs());
    let delta_z = gamma(3) * max_z;
    let max_world_z = world_z[0].abs().max(world_z[1].abs()).max(world_z[2].abs());
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    let delta_x = gamma(5) * (max_x + max_world_z);
    let delta_y = gamma(5) * (max_y + max_world_z);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = e[0].abs().max(e[1].abs()).max(e[2].abs());
    3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs()
}

/// Unnormalised geometric normal along the winding (v0, v1, v2).
pub fn geometric_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3; 3] {
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn hits_with_analytic_t_and_barycentrics_from_both_sides() {
        for (o, d) in [
            (Vec3::new(0.25, 0.5, 2.0), -Vec3::Z),
            (Vec3::new(0.25, 0.5, -3.0), Vec3::Z * 2.0),
        ] {
            let ray = Ray::new(o, d);
            let (t, u, v) = intersect(&ray, &ShearedRay::new(&ray), &tri()).unwrap();
            let expected_t = o.z.abs() / d.length();
            assert!((t - expected_t).abs() < 1e-6, "t {t}");
            assert!((u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        }
    }

    #[test]
    fn misses_outside_and_respects_the_interval() {
        let ray = Ray::new(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z);
        assert!(intersect(&ray, &ShearedRay::new(&ray), &tri()).is_none());
        let mut ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        ray.tmax = 0.5;
        assert!(intersect(&ray, &ShearedRay::new(&ray), &tri()).is_none());
        ray.tmax = f32::INFINITY;
        ray.tmin = 1.5;
        assert!(intersect(&ray, &ShearedRay::new(&ray), &tri()).is_none());
    }

    #[test]
    fn a_ray_through_a_shared_edge_or_vertex_hits_a_triangle() {
        // A unit square split along its diagonal, plus a fan around a vertex.
        let a = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        let b = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        for i in 0..=1000 {
            let x = i as f32 / 1000.0 * 0.999 + 0.0005;
            let dir = Vec3::new(0.1, -0.2, -1.0) * (1.0 + i as f32 * 1e-3);
            // Aim exactly at the diagonal point (x, x, 0) from above.
            let target = Vec3::new(x, x, 0.0);
            let ray = Ray::new(target - 3.0 * dir, dir);
            let s = ShearedRay::new(&ray);
            assert!(
                intersect(&ray, &s, &a).is_some() || intersect(&ray, &s, &b).is_some(),
                "leak at {x}"
            );
        }
    }

    #[test]
    fn a_ray_leaving_the_triangle_plane_does_not_rehit_it() {
        let v = [
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
        ];
        for i in 0..1000 {
            let x = -9.0 + (i as f32) * 0.017;
            // Starts exactly on the plane, leaves at a grazing angle.
            let ray = Ray::new(
                Vec3::new(-x * 0.3, 0.0, x),
                Vec3::new(-0.99996, 0.0087265, 0.0),
            );
            assert!(
                intersect(&ray, &ShearedRay::new(&ray), &v).is_none(),
                "re-hit at {x}"
            );
        }
    }

    #[test]
    fn the_answer_does_not_depend_on_the_direction_length_or_the_scale() {
        // The same rays with directions scaled by powers of two hit at t
        // scaled exactly inversely, for triangles at 1, 1e-6 and 1e5.
        for (scale, offset) in [(1.0, 0.0), (1e-6, 0.0), (1.0, 1e5)] {
            let v = tri().map(|p| p * scale + Vec3::splat(offset));
            let target = (v[0] + v[1] + v[2]) / 3.0;
            let origin = target + Vec3::new(0.3, -0.2, 2.0) * scale;
            for k in [-24, -10, 0, 10] {
                let f = 2f32.powi(k);
                let ray = Ray::new(origin, (target - origin) * f);
                let hit = intersect(&ray, &ShearedRay::new(&ray), &v);
                let (t, _, _) = hit.unwrap_or_else(|| panic!("miss at scale {scale}, 2^{k}"));
                assert!(
                    (t * f - 1.0).abs() < 1e-5,
                    "t = {t} at scale {scale}, 2^{k}"
                );
            }
        }
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let point = [Vec3::ONE; 3];
        for tri in [line, point] {
            let ray = Ray::new(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z);
            assert!(intersect(&ray, &ShearedRay::new(&ray), &tri).is_none());
        }
    }
}
