//! `inside`: rays from points inside the mesh, in uniform directions. Every
//! one of them must hit a closed mesh.
//!
//! Candidate origins are uniform in the bounding box. A point counts as
//! inside when the winding number of the surface around it, counted along
//! three random directions and their opposites (+1 for each crossing out
//! through the front, −1 through the back), is the same non-zero number
//! along all six. Signed counting keeps duplicated faces and degenerate
//! triangles from flipping the answer; needing six agreeing probes keeps
//! rays through edges from doing so. Points on the surface (within a few
//! f32 spacings of it along a probe or along the ray itself) are rejected:
//! whether a crossing at t = 0 counts differs between intersectors.

use super::{Generator, MeshInfo, Stream};
use crate::accel::{BuildQuality, Bvh8, EveryLeaf};
use crate::math::{Aabb, Ray};
use crate::shape::triangle::{geometric_normal, intersect, ShearedRay};
use glam::{DVec3, Vec3};

pub struct Inside<'a> {
    triangles: &'a [[Vec3; 3]],
    bvh: Bvh8,
    lo: DVec3,
    size: DVec3,
}

impl<'a> Inside<'a> {
    pub fn new(mesh: &MeshInfo<'a>) -> Result<Self, String> {
        let size = (mesh.bounds.max - mesh.bounds.min).as_dvec3();
        if size.min_element() <= 0.0 {
            return Err("the mesh is flat, so it has no inside".to_string());
        }
        let boxes: Vec<Aabb> = mesh
            .triangles
            .iter()
            .map(|t| Aabb::from_points(t))
            .collect();
        Ok(Self {
            triangles: mesh.triangles,
            bvh: Bvh8::build(&boxes, BuildQuality::Fast),
            lo: mesh.bounds.min.as_dvec3(),
            size,
        })
    }

    /// Signed crossings of the ray with the surface.
    fn winding(&self, ray: &Ray) -> i32 {
        let sheared = ShearedRay::new(ray);
        let mut winding = 0;
        // Triangles are read by id, not in leaf blocks: nodes are prefetched only.
        let mut every = EveryLeaf(|start, count| {
            for (_, id) in self.bvh.leaf_prims(start, count) {
                let tri = &self.triangles[id as usize];
                if intersect(ray, &sheared, tri).is_some() {
                    winding += if geometric_normal(tri).dot(ray.direction) > 0.0 {
                        1
                    } else {
                        -1
                    };
                }
            }
        });
        self.bvh.walk(ray, &[] as &[()], &mut every);
        winding
    }

    /// Whether the surface passes within about two f32 spacings of `origin`
    /// along the line through it in unit direction `d`. Such a point is on
    /// the surface as far as rounding can tell (common when the mesh is far
    /// from the origin and every coordinate is coarsely rounded): a ray
    /// from it may see its first crossing at t = 0, which counts as a hit
    /// for some intersectors and not for others.
    fn touches_surface(&self, origin: Vec3, d: Vec3) -> bool {
        let reach = 2.0 * f32::EPSILON * origin.abs().max_element().max(f32::MIN_POSITIVE);
        // From a little behind the point to a little beyond it: the triangle
        // test ignores crossings within rounding of t = 0, which is exactly
        // where this one would be if it started at the point.
        let segment = Ray::segment(origin - reach * d, d, 2.0 * reach);
        self.winding_crossings(&segment) > 0
    }

    /// How many triangles the ray crosses in its interval.
    fn winding_crossings(&self, ray: &Ray) -> u32 {
        let sheared = ShearedRay::new(ray);
        let mut crossings = 0;
        let mut every = EveryLeaf(|start, count| {
            for (_, id) in self.bvh.leaf_prims(start, count) {
                if intersect(ray, &sheared, &self.triangles[id as usize]).is_some() {
                    crossings += 1;
                }
            }
        });
        self.bvh.walk(ray, &[] as &[()], &mut every);
        crossings
    }
}

impl Generator for Inside<'_> {
    fn ray(&self, _index: u32, rng: &mut Stream) -> Option<Ray> {
        let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let origin = (self.lo + u * self.size).as_vec3();
        for _ in 0..3 {
            let d = rng.unit_vector().as_vec3();
            let w = self.winding(&Ray::new(origin, d));
            // Opposite probes agree unless a crossing sits at t = 0, that
            // is, unless the point lies on the surface.
            if w == 0 || self.winding(&Ray::new(origin, -d)) != w || self.touches_surface(origin, d)
            {
                return None;
            }
        }
        let d = rng.unit_vector().as_vec3();
        (!self.touches_surface(origin, d)).then(|| Ray::new(origin, d))
    }
}

#[cfg(test)]
mod tests {
    use crate::rays::tests::octahedron;
    use crate::rays::{generate, RayKind};
    use glam::Vec3;

    #[test]
    fn origins_are_inside_the_octahedron() {
        let tris = octahedron(2.0, Vec3::new(1.0, -3.0, 0.5));
        for ray in generate(RayKind::Inside, &tris, 500, 1).unwrap() {
            let p = (ray.origin - Vec3::new(1.0, -3.0, 0.5)) / 2.0;
            assert!(p.abs().element_sum() <= 1.0 + 1e-5, "{p} is outside");
        }
    }

    /// Far from the origin, f32 coordinates are coarse next to a small
    /// mesh, and many candidate origins land on its faces, edges and
    /// vertices; none of those may become an inside ray.
    #[test]
    fn origins_on_the_surface_are_rejected() {
        let offset = Vec3::splat(1e5);
        let tris = octahedron(0.2, offset);
        let info = crate::rays::MeshInfo::new(&tris).unwrap();
        let inside = super::Inside::new(&info).unwrap();
        let vertex = offset + Vec3::new(0.2, 0.0, 0.0);
        assert!(inside.touches_surface(vertex, Vec3::new(0.6, 0.8, 0.0)));
        assert!(!inside.touches_surface(offset, Vec3::X));
        // The vertices as f32 holds them: 0.2 rounds to a multiple of 2⁻⁷.
        let r = tris[0][0].x - offset.x;
        for ray in generate(RayKind::Inside, &tris, 2000, 3).unwrap() {
            let p = ray.origin - offset;
            // On this grid, points of the faces have |x| + |y| + |z| = r exactly.
            assert!(
                p.abs().element_sum() < r,
                "{p} is on or outside the surface"
            );
        }
    }

    #[test]
    fn a_flat_mesh_has_no_inside() {
        let tris = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
        assert!(generate(RayKind::Inside, &tris, 1, 0).is_err());
    }
}
