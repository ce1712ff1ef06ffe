//! The local geometry at a hit, computed once per closest hit.

use super::{Geometry, NO_TRANSFORM};
use crate::accel::PrimHit;
use crate::math::offset::{barycentric_error, transformed_error};
use crate::math::Ray;
use crate::shape::triangle;
use glam::{Vec2, Vec3};

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
            let mut ng = triangle::geometric_normal(&v).normalize_or(Vec3::Z);
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
