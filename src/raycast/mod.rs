//! Ray and point queries on a triangle mesh, answered in numbers a binding
//! copies straight into arrays: the library half of the Python package's
//! `strata_rt.Mesh` (`python/src/mesh.rs` parses arguments, converts
//! arrays, releases the GIL and raises errors around it; nothing of the
//! geometry is there).
//!
//! A [`Mesh`] holds a [`Geometry`] made from arrays ([`Mesh::new`]), from a
//! mesh file ([`Mesh::load`]) or by placing another mesh any number of
//! times ([`Mesh::place`], instances of one stored prototype). A placed
//! mesh answers every query as a mesh of its copies would: face
//! `k · T + j` is face `j` of copy `k` (T faces each), the hit triangle,
//! its normal and point are the copy's in world space, and its bounds are
//! the copies' vertices' box ([`Geometry::flat_prim`],
//! [`Geometry::world_triangle`]).
//!
//! Every ray query answers for `(tmin, tmax]`, as every query of
//! [`Geometry`] does ([`crate::geometry::query`]): the rays a binding
//! makes for `(0, t_max]` go in as they are.
//!
//! | query | answers | per |
//! |---|---|---|
//! | [`Mesh::first_hits`] | [`FirstHit`]: t, face, barycentrics, normal, point | ray |
//! | [`Mesh::occluded`] | whether anything blocks it | ray |
//! | [`Mesh::all_hits`] | every [`Crossing`] of the surface, nearest first, and their count | ray |
//! | [`Mesh::count_hits`] | how many crossings | ray |
//! | [`Mesh::contains`] | inside or not (parity of crossings) | point |
//! | [`Mesh::closest_point`] | [`ClosestPoint`]: point, distance, face | point |

#[cfg(test)]
mod tests;

pub use crate::accel::BuildQuality;
use crate::error::InputResult;
use crate::geometry::instance::placed;
use crate::geometry::travel::SPAN;
use crate::geometry::Geometry;
pub use crate::math::Ray;
pub use crate::scene::MeshArraysError;
use crate::scene::{load_mesh_scene, mesh_geometry};
use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use std::path::Path;

/// A triangle mesh and its tree, built once and asked any number of
/// queries (module docs).
#[derive(Debug, Clone)]
pub struct Mesh {
    geometry: Geometry,
    /// Where each instance's faces start among the copies' face ids
    /// ([`Geometry::flat_offsets`]); the last entry is the face count.
    flat: Vec<u64>,
    /// The [min, max] corners of the faces' box: every vertex's (of every
    /// copy), tighter than the tree's box.
    bounds: [Vec3; 2],
    /// The maps a placed mesh was placed by, as given (the instances keep
    /// their inverses); empty for a mesh that is not placed.
    maps: Vec<Affine3A>,
}

/// One ray's first hit, or [`FirstHit::MISS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstHit {
    /// Along the ray, in its direction's lengths; infinite on a miss.
    pub t: f32,
    /// The face hit (in the copies' numbering for a placed mesh); -1 on a miss.
    pub face: i64,
    /// Barycentric coordinates of the face's second and third vertices.
    pub u: f32,
    pub v: f32,
    /// The unit geometric normal of the face in world space, by the
    /// right-hand rule over its vertex order (trimesh's face normal).
    pub normal: Vec3,
    /// `(1 − u − v)·v0 + u·v1 + v·v2` of the face in world space.
    pub point: Vec3,
}

impl FirstHit {
    /// What a ray that hits nothing answers: t infinite, face -1, NaN else.
    pub const MISS: FirstHit = FirstHit {
        t: f32::INFINITY,
        face: -1,
        u: f32::NAN,
        v: f32::NAN,
        normal: Vec3::NAN,
        point: Vec3::NAN,
    };
}

/// Where a ray crosses the surface: its t and the face crossed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub t: f32,
    pub face: i64,
}

/// The nearest surface point to a query point, or [`ClosestPoint::MISS`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    pub point: Vec3,
    /// Its distance; negative inside where a signed distance was asked.
    pub distance: f32,
    /// The face it lies on; -1 where none lies within reach.
    pub face: i64,
}

impl ClosestPoint {
    /// Nothing within reach: point NaN, distance infinite, face -1.
    pub const MISS: ClosestPoint = ClosestPoint {
        point: Vec3::NAN,
        distance: f32::INFINITY,
        face: -1,
    };
}

/// Why [`Mesh::place`] refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PlaceError {
    #[error(
        "a placed mesh cannot be placed again: place the mesh itself, with each map \
         composed with its placement"
    )]
    AlreadyPlaced,
    /// The first map that is singular or not finite, or that carries the
    /// mesh past f32's range.
    #[error("map {0} is not invertible, or places the mesh beyond float32's range")]
    Map(usize),
}

impl Mesh {
    /// A mesh of `faces` (indices into `vertices`), face `i` being
    /// triangle `i`; degenerate faces are kept (no ray hits them). The tree
    /// is built on every core of the calling rayon pool.
    pub fn new(
        vertices: Vec<Vec3>,
        faces: Vec<[u32; 3]>,
        quality: BuildQuality,
    ) -> Result<Self, MeshArraysError> {
        Ok(Self::from_geometry(mesh_geometry(
            vertices, faces, quality,
        )?))
    }

    /// A mesh file (OBJ, PLY, glTF or GLB) read with strata's loaders and
    /// used as it is: triangle `i` of the file is face `i`.
    pub fn load(path: &Path, quality: BuildQuality) -> InputResult<Self> {
        let (scene, _) = load_mesh_scene(path, quality)?;
        Ok(Self::from_geometry(scene.geometry))
    }

    /// This mesh placed once by each of `maps` (object to world): stored
    /// once, each placement an instance of it (module docs).
    pub fn place(&self, maps: &[Affine3A], quality: BuildQuality) -> Result<Self, PlaceError> {
        if self.is_placed() {
            return Err(PlaceError::AlreadyPlaced);
        }
        let geometry = placed(self.geometry.clone(), maps, quality).map_err(PlaceError::Map)?;
        Ok(Self {
            maps: maps.to_vec(),
            ..Self::from_geometry(geometry)
        })
    }

    /// What a placed mesh is made of: the mesh it places (its faces'
    /// vertices, in face order) and the maps it was placed by, as given;
    /// `None` for a mesh that is not placed. [`Mesh::new`] of those
    /// triangles, placed by those maps, answers every query bit for bit as
    /// this mesh does (a binding's pickling).
    pub fn placement(&self) -> Option<(Vec<[Vec3; 3]>, &[Affine3A])> {
        if !self.is_placed() {
            return None;
        }
        let prototype = self.geometry.prototypes().first()?;
        Some((prototype.file_order_triangles(), &self.maps))
    }

    fn from_geometry(geometry: Geometry) -> Self {
        let bounds = if geometry.instances().is_empty() {
            let own = (0..).zip(geometry.leaf_slots());
            let slots = own.filter(|&(_, id)| id < geometry.triangle_count());
            corners(slots.map(|(slot, _)| geometry.slot_triangle(slot)), |p| p)
        } else {
            // Every vertex of every copy moved (the tree's box is looser).
            let own: Vec<Vec<[Vec3; 3]>> = geometry
                .prototypes()
                .iter()
                .map(Geometry::file_order_triangles)
                .collect();
            geometry
                .instances()
                .par_iter()
                .map(|instance| {
                    let m = instance.affine();
                    let tris = own[instance.prototype as usize].iter().copied();
                    corners(tris, |p| m.transform_point3(p))
                })
                .reduce(
                    || [Vec3::INFINITY, Vec3::NEG_INFINITY],
                    |a, b| [a[0].min(b[0]), a[1].max(b[1])],
                )
        };
        Self {
            flat: geometry.flat_offsets(),
            geometry,
            bounds,
            maps: Vec::new(),
        }
    }

    /// Whether this mesh places another ([`Mesh::place`]).
    pub fn is_placed(&self) -> bool {
        !self.geometry.instances().is_empty()
    }

    /// The number of faces; of a placed mesh, every copy's.
    pub fn triangle_count(&self) -> u64 {
        self.flat.last().copied().unwrap_or(0)
    }

    /// The [min, max] corners of the faces' box (every copy's); infinite
    /// and negative infinite without faces.
    pub fn bounds(&self) -> [Vec3; 2] {
        self.bounds
    }

    /// Every face's vertices in face order (every copy's, in world space):
    /// a copy of what the trees store.
    pub fn triangles(&self) -> Vec<[Vec3; 3]> {
        let g = &self.geometry;
        let mut tris = g.file_order_triangles();
        for instance in g.instances() {
            let m = instance.affine();
            let own = g.prototypes()[instance.prototype as usize].file_order_triangles();
            tris.extend(own.iter().map(|t| t.map(|p| m.transform_point3(p))));
        }
        tris
    }

    /// `out[i]`: the first hit of `rays[i]` in `(tmin, tmax]`. Watertight:
    /// a ray through a shared edge or vertex of a closed mesh hits one of
    /// the faces there, never none.
    pub fn first_hits(&self, rays: &[Ray], out: &mut [FirstHit]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        for (rays, out) in rays.chunks(SPAN).zip(out.chunks_mut(SPAN)) {
            let mut found = [None; SPAN];
            let found = &mut found[..rays.len()];
            self.geometry.intersect_stream(rays, found);
            for (o, hit) in out.iter_mut().zip(found.iter()) {
                *o = match hit {
                    None => FirstHit::MISS,
                    Some(hit) => {
                        let [a, b, c] = self.geometry.world_triangle(hit);
                        FirstHit {
                            t: hit.t,
                            face: self.geometry.flat_prim(hit, &self.flat) as i64,
                            u: hit.u,
                            v: hit.v,
                            normal: (b - a).cross(c - a).normalize(),
                            point: (1.0 - hit.u - hit.v) * a + hit.u * b + hit.v * c,
                        }
                    }
                };
            }
        }
    }

    /// `out[i]`: whether anything blocks `rays[i]` in `(tmin, tmax]`.
    pub fn occluded(&self, rays: &[Ray], out: &mut [bool]) {
        self.geometry.occluded_stream(rays, u32::MAX, out);
    }

    /// Appends every crossing of the surface along each ray of `rays` in
    /// `(tmin, tmax]` to `out`, nearest first (then by face), ray after
    /// ray, and each ray's number of them to `counts`. One walk per ray,
    /// not a re-cast from each hit: a ray through a shared edge or vertex
    /// of a closed mesh, where it crosses the surface, is reported once
    /// ([`Geometry::crossings`]).
    pub fn all_hits(&self, rays: &[Ray], out: &mut Vec<Crossing>, counts: &mut Vec<u32>) {
        let mut found = Vec::new();
        for ray in rays {
            found.clear();
            self.geometry.crossings(ray, &mut found);
            counts.push(found.len() as u32);
            out.extend(found.iter().map(|c| Crossing {
                t: c.t,
                face: self.geometry.flat_prim(c, &self.flat) as i64,
            }));
        }
    }

    /// How many crossings [`Mesh::all_hits`] would list for `ray`.
    pub fn count_hits(&self, ray: &Ray) -> u32 {
        self.geometry.count_crossings(ray)
    }

    /// Whether `point` is inside: the parity of the crossings along one ray
    /// from it ([`Geometry::contains`]; meant for closed meshes).
    pub fn contains(&self, point: Vec3) -> bool {
        self.geometry.contains(point)
    }

    /// The surface point nearest to `point` within `max_distance`
    /// (infinite: no limit), its distance (negative inside where `signed`,
    /// by [`Mesh::contains`]) and its face; [`ClosestPoint::MISS`] where
    /// none lies that near.
    pub fn closest_point(&self, point: Vec3, max_distance: f32, signed: bool) -> ClosestPoint {
        let Some(n) = self.geometry.nearest(point, max_distance) else {
            return ClosestPoint::MISS;
        };
        let inside = signed && self.geometry.contains(point);
        ClosestPoint {
            point: n.point,
            distance: if inside { -n.distance } else { n.distance },
            face: self.geometry.flat_prim(&n, &self.flat) as i64,
        }
    }
}

/// The [min, max] corners of the box of `tris`'s vertices moved by `map`.
fn corners(tris: impl Iterator<Item = [Vec3; 3]>, map: impl Fn(Vec3) -> Vec3) -> [Vec3; 2] {
    tris.flatten()
        .fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], p| {
            let q = map(p);
            [lo.min(q), hi.max(q)]
        })
}
