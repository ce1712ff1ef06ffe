//! `edges`: rays aimed exactly at the edges and vertices that triangles
//! share, the rays a non-watertight intersector lets through.
//!
//! Two rays in three aim at a point `a + s (b − a)` of a shared edge (with
//! `s` uniform in [0.01, 0.99], exact in f64), one in three at a shared
//! vertex. The direction comes from a cone around the inward mean normal and
//! is kept only if it meets every triangle around the target from the same
//! side (`d · n < 0` with a margin), so the triangles' projections along the
//! ray tile a neighbourhood of the target and a watertight intersector must
//! hit one of them. Edges and vertices next to degenerate triangles or
//! slivers are left out. The origin is 0.1 to 1 bounding radii back, and the ray
//! reaches its target at `t = 1`: a ray whose first hit is beyond `t = 1`
//! has passed through the surface.

use super::topology::{normal, Shared, Topology};
use super::{aimed_ray, Generator, MeshInfo, Stream};
use crate::math::Ray;
use glam::{DVec3, Vec3};

/// Triangles with an inradius below this fraction of the bounding radius
/// are slivers that float32 cannot resolve: edges next to them are not
/// aimed at (such a sliver closing a T-junction leaves a crack that no
/// float32 intersector closes).
const THIN: f64 = 1e-5;

/// The least `−d̂ · n̂` for every triangle around the target.
const FACING_MARGIN: f64 = 0.02;

pub struct Edges<'a> {
    triangles: &'a [[Vec3; 3]],
    topology: Topology,
    radius: f64,
}

impl<'a> Edges<'a> {
    pub fn new(mesh: &MeshInfo<'a>) -> Result<Self, String> {
        let topology = Topology::new(mesh.triangles, THIN * mesh.radius);
        if topology.edges.is_empty() {
            return Err(
                "the mesh has no shared edges (no two consistently wound triangles meet)"
                    .to_string(),
            );
        }
        Ok(Self {
            triangles: mesh.triangles,
            topology,
            radius: mesh.radius,
        })
    }

    /// Whether the mesh is closed, for the ray file's description.
    pub fn closed(&self) -> bool {
        self.topology.closed
    }
}

impl Generator for Edges<'_> {
    fn ray(&self, _index: u32, rng: &mut Stream) -> Option<Ray> {
        let vertices = &self.topology.vertices;
        let at_vertex = !vertices.is_empty() && rng.uniform() < 1.0 / 3.0;
        let (target, tris): (DVec3, &[u32]) = if at_vertex {
            match &vertices[rng.below(vertices.len())] {
                Shared::Vertex { p, tris } => (p.as_dvec3(), tris),
                Shared::Edge { .. } => unreachable!("vertices hold vertices"),
            }
        } else {
            let edges = &self.topology.edges;
            match &edges[rng.below(edges.len())] {
                Shared::Edge { a, b, tris } => {
                    let s = 0.01 + 0.98 * rng.next_f64();
                    let (a, b) = (a.as_dvec3(), b.as_dvec3());
                    (a + s * (b - a), &tris[..])
                }
                Shared::Vertex { .. } => unreachable!("edges hold edges"),
            }
        };
        let normals: Vec<DVec3> = tris
            .iter()
            .map(|&t| normal(&self.triangles[t as usize]).normalize())
            .collect();
        let inward = -normals.iter().sum::<DVec3>().try_normalize()?;
        // A direction within about 45° of the inward normal, facing every triangle.
        let d = (inward + 0.8 * rng.unit_vector()).try_normalize()?;
        if normals.iter().any(|n| d.dot(*n) > -FACING_MARGIN) {
            return None;
        }
        let back = self.radius * (0.1 + 0.9 * rng.next_f64());
        aimed_ray(target - back * d, target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rays::tests::octahedron;
    use crate::rays::{generate, RayKind};
    use crate::shape::triangle::{intersect, ShearedRay};

    /// Brute force: the first hit's t, if any.
    fn first_hit(tris: &[[Vec3; 3]], ray: &Ray) -> Option<f32> {
        let s = ShearedRay::new(ray);
        tris.iter()
            .filter_map(|t| intersect(ray, &s, t).map(|h| h.0))
            .min_by(f32::total_cmp)
    }

    #[test]
    fn edge_rays_hit_their_target_on_closed_meshes_at_every_scale() {
        for (scale, offset) in [
            (1.0, Vec3::ZERO),
            (1e-6, Vec3::ZERO),
            (1.0, Vec3::splat(1e5)),
        ] {
            let tris = octahedron(scale, offset);
            for ray in generate(RayKind::Edges, &tris, 2000, 3).unwrap() {
                let t = first_hit(&tris, &ray).expect("watertight: the ray must hit");
                assert!((t - 1.0).abs() < 1e-3, "hit at t = {t}, not at the target");
            }
        }
    }
}
