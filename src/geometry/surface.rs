//! The local geometry at a hit, computed once per closest hit.

use super::{Geometry, NO_TRANSFORM};
use crate::accel::PrimHit;
use crate::math::offset::{barycentric_error, transformed_error};
use crate::math::Ray;
use crate::shape::triangle;
use glam::{Vec2, Vec3, Vec4};

/// The local geometry at a hit, in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub p: Vec3,
    /// Conservative per-axis bound on the rounding error of `p`.
    pub p_error: Vec3,
    /// Unit geometric normal, pointing out of the solid (or along the
    /// triangle's winding for open surfaces).
    pub geometric_normal: Vec3,
    /// Unit shading normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    pub material: u32,
    /// Texture coordinates, on meshes that keep them (those whose material
    /// has a texture); `None` everywhere else.
    pub uv: Option<Vec2>,
}

impl Surface {
    /// Whether `wo` (unit, towards the viewer) leaves the outside, and the
    /// geometric and shading normals turned towards it: the side both
    /// integrators shade.
    #[inline(always)]
    pub fn facing(&self, wo: Vec3) -> (bool, Vec3, Vec3) {
        let entering = self.geometric_normal.dot(wo) >= 0.0;
        if entering {
            (true, self.geometric_normal, self.shading_normal)
        } else {
            (false, -self.geometric_normal, -self.shading_normal)
        }
    }
}

impl Geometry {
    /// Full geometry of a hit, computed once per closest hit.
    pub fn surface(&self, ray: &Ray, hit: &PrimHit) -> Surface {
        let n_tris = self.triangle_count;
        if let Some(i) = self.plane_index(hit.prim) {
            let plane = &self.planes[i];
            let (p, p_error) = plane.surface_at(ray.at(hit.t));
            return Surface {
                p,
                p_error,
                geometric_normal: plane.normal,
                shading_normal: plane.normal,
                material: plane.material,
                uv: None,
            };
        }
        if hit.prim < n_tris {
            let v = self.triangle(hit);
            let b = [1.0 - hit.u - hit.v, hit.u, hit.v];
            let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
            let mesh = self.mesh_of(hit.prim);
            let mut ng = triangle::unit_normal(&v).unwrap_or(Vec3::Z);
            if mesh.mirrored {
                ng = -ng;
            }
            let tri = (hit.prim - mesh.first) as usize;
            let mut ns = ng;
            if let Some(normals) = &mesh.normals {
                if let Some(n) = normals.interpolate(tri, b).try_normalize() {
                    // Keep the shading normal on the geometric side.
                    ns = if n.dot(ng) < 0.0 { -n } else { n };
                }
            }
            return Surface {
                p,
                p_error: barycentric_error(b, v),
                geometric_normal: ng,
                shading_normal: ns,
                material: mesh.material,
                uv: mesh.uvs.as_ref().map(|uvs| uvs.interpolate(tri, b)),
            };
        }
        if hit.prim >= self.first_instance() {
            let (instance, prototype) = self.instance(hit.prim);
            return instance.surface(prototype, ray, hit);
        }
        let prim = &self.shapes[(hit.prim - n_tris) as usize];
        let local = self.object_ray(prim, ray);
        let (p, err, n, material) = prim.shape.surface_at(&local, hit, &self.csg);
        let (p, p_error, n) = if prim.transform == NO_TRANSFORM {
            (p, err, n)
        } else {
            let tr = &self.transforms[prim.transform as usize];
            (
                tr.point(p),
                transformed_error(&tr.to_world, p, err),
                tr.normal(n),
            )
        };
        Surface {
            p,
            p_error,
            geometric_normal: n,
            shading_normal: n,
            material: material.unwrap_or(prim.material),
            uv: None,
        }
    }
}

impl Geometry {
    /// dP/du and dP/dv in world space at a triangle hit whose mesh keeps
    /// texture coordinates: the tangent frame a normal or bump map is read
    /// in (pbrt-v4 §6.5.3's per-triangle partial derivatives). Computed on
    /// request, so surfaces without such maps pay nothing. `None` off
    /// meshes, without coordinates, or where the UV triangle has no area
    /// (the frame would be degenerate).
    pub fn uv_derivatives(&self, hit: &PrimHit) -> Option<(Vec3, Vec3)> {
        if hit.prim < self.triangle_count {
            let mesh = self.mesh_of(hit.prim);
            let uvs = mesh.uvs.as_ref()?;
            let tri = (hit.prim - mesh.first) as usize;
            let t = uvs.indices[tri].map(|i| uvs.values[i as usize]);
            return triangle_uv_derivatives(self.triangle(hit), t);
        }
        if hit.prim >= self.first_instance() {
            let (instance, prototype) = self.instance(hit.prim);
            let inner = PrimHit {
                prim: prototype.slot_prim(hit.part),
                ..*hit
            };
            let (du, dv) = prototype.uv_derivatives(&inner)?;
            let m = instance.affine().matrix3;
            return Some((m * du, m * dv));
        }
        None
    }
}

impl Geometry {
    /// The file's tangent (glTF `TANGENT`: xyz, w the handedness) at a
    /// triangle hit, in world space; `None` where the mesh has none.
    pub fn vertex_tangent(&self, hit: &PrimHit) -> Option<Vec4> {
        if hit.prim < self.triangle_count {
            let mesh = self.mesh_of(hit.prim);
            let tangents = mesh.tangents.as_ref()?;
            let tri = (hit.prim - mesh.first) as usize;
            return Some(tangents.interpolate(tri, [1.0 - hit.u - hit.v, hit.u, hit.v]));
        }
        if hit.prim >= self.first_instance() {
            let (instance, prototype) = self.instance(hit.prim);
            let inner = PrimHit {
                prim: prototype.slot_prim(hit.part),
                ..*hit
            };
            let t = prototype.vertex_tangent(&inner)?;
            let m = instance.affine().matrix3;
            let xyz = Vec3::from(m * glam::Vec3A::from(t.truncate()));
            return Some(xyz.extend(t.w * m.determinant().signum()));
        }
        None
    }
}

/// The partial derivatives of position by texture coordinates over a
/// triangle with corners `p` and coordinates `t`: the solution of
/// `p₁ − p₀ = Δu₁ ∂p/∂u + Δv₁ ∂p/∂v` and its twin for `p₂`. `None` where
/// the UV triangle has no area or the answer is not finite.
pub fn triangle_uv_derivatives(p: [Vec3; 3], t: [Vec2; 3]) -> Option<(Vec3, Vec3)> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    if !(det.abs() > 1e-12) {
        return None;
    }
    let inv = 1.0 / det;
    let dpdu = (d2.y * e1 - d1.y * e2) * inv;
    let dpdv = (d1.x * e2 - d2.x * e1) * inv;
    (dpdu.is_finite() && dpdv.is_finite()).then_some((dpdu, dpdv))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_derivatives_solve_the_edges() {
        let p = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(3.0, 2.5, 3.0),
            Vec3::new(0.5, 4.0, 2.0),
        ];
        let t = [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.7, 0.1),
            Vec2::new(0.3, 0.9),
        ];
        let (du, dv) = triangle_uv_derivatives(p, t).unwrap();
        for k in 1..3 {
            let d = t[k] - t[0];
            let edge = d.x * du + d.y * dv;
            assert!(
                edge.abs_diff_eq(p[k] - p[0], 1e-5),
                "{edge} vs {}",
                p[k] - p[0]
            );
        }
        // A UV triangle with no area has no frame.
        let flat = [Vec2::ZERO, Vec2::new(0.5, 0.5), Vec2::ONE];
        assert_eq!(triangle_uv_derivatives(p, flat), None);
        assert_eq!(triangle_uv_derivatives(p, [Vec2::NAN; 3]), None);
    }
}
