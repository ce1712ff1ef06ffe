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
//! | [`Mesh::first_hits`], [`Mesh::first_hits_into`] | [`FirstHit`]: t, face, barycentrics, normal, point (or the columns asked for) | ray |
//! | [`Mesh::occluded`] | whether anything blocks it | ray |
//! | [`Mesh::all_hits`] | every crossing of the surface ([`Crossings`]: t, face, barycentrics), nearest first, and their count | ray |
//! | [`Mesh::count_hits`] | how many crossings | ray |
//! | [`Mesh::contains`] | inside or not (parity of crossings) | point |
//! | [`Mesh::closest_point`] | [`ClosestPoint`]: point, distance, face | point |
//!
//! **Far from the origin.** A mesh made from arrays ([`Mesh::new_exact`]),
//! or loaded from a file that writes float64 ([`Mesh::load`]), whose box
//! lies farther from the origin than its size is held relative
//! to a centre near its box's middle ([`Mesh::centre`]): the tree and the
//! walk are float32 numbers of the mesh's own size, not of its distance
//! from the origin, so UTM coordinates or a mesh moved by 1e6 are traced as
//! accurately as at the origin. A binding makes rays and points relative
//! to it (in float64, then rounded). The centre is the box's middle
//! rounded to a multiple of the power of two at least the box's size (0
//! on an axis where the middle is no farther out than that size), so a
//! mesh near the origin keeps centre 0 (and every bit of its answers), and
//! a mesh moved by a multiple of that power answers bit for bit as it did
//! unmoved. Hit points and closest points are computed in float64 on the
//! triangle the walk found, as given ([`exact`]).

mod answers;
pub mod exact;
#[cfg(test)]
mod tests;

pub use crate::accel::BuildQuality;
use crate::error::{InputError, InputResult};
use crate::geometry::instance::placed;
use crate::geometry::travel::SPAN;
use crate::geometry::{Found, Geometry};
pub use crate::math::Ray;
use crate::scene::loaders::{check_extension, load_mesh_file_with, used_vertices, Reading};
pub use crate::scene::MeshArraysError;
use crate::scene::{check_extent, load_mesh_scene, mesh_geometry};
pub use answers::{ClosestPoint, Crossings, FirstHit, FirstHitColumns};
use glam::{Affine3A, DVec3, Vec3};
use rayon::prelude::*;
use std::path::Path;

/// A mesh's float64 vertices and its faces, as [`Mesh::new_exact`] takes
/// them, and what the file's loader read leniently.
type Arrays = (Vec<DVec3>, Vec<[u32; 3]>, Vec<InputError>);

/// A mesh file's vertices as the file writes them, in float64, and its
/// faces in file order: each mesh's vertices that its faces use, in the
/// loader's order (tobj's for an OBJ: an object's own, by first use), the
/// meshes one after another, as a scene compiles them. `None`
/// for a format whose coordinates are float32 (glTF, binary STL) or a file whose
/// extension names none (the scene's compile words that error), which are
/// loaded as a scene's meshes are.
fn file_arrays(path: &Path) -> InputResult<Option<Arrays>> {
    if !check_extension(path).is_ok_and(|e| matches!(e.as_str(), "obj" | "ply" | "off" | "stl")) {
        return Ok(None);
    }
    let mut asset = load_mesh_file_with(path, Reading::EXACT_FACES)?;
    if !asset.shared.is_empty() {
        return Ok(None);
    }
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for mesh in std::mem::take(&mut asset.meshes) {
        let Some(exact) = mesh.exact_positions else {
            return Ok(None);
        };
        let used = used_vertices(&mesh.indices, exact.len());
        let base = vertices.len() as u32;
        if used.iter().all(|&u| u) {
            // Every vertex used (a PLY's, most often): the arrays as read.
            if base == 0 && faces.is_empty() {
                (vertices, faces) = (exact, mesh.indices);
            } else {
                vertices.extend(exact);
                faces.extend(mesh.indices.iter().map(|t| t.map(|k| k + base)));
            }
            continue;
        }
        // A vertex no face uses is never traced; a file may leave it NaN.
        let mut index = vec![u32::MAX; exact.len()];
        for ((k, p), used) in exact.into_iter().enumerate().zip(used) {
            if used {
                index[k] = vertices.len() as u32;
                vertices.push(p);
            }
        }
        faces.extend(mesh.indices.iter().map(|t| t.map(|k| index[k as usize])));
    }
    Ok(Some((vertices, faces, asset.warnings)))
}

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
    /// What the tree's coordinates are relative to (module docs): zero
    /// but for a mesh from arrays far from the origin.
    centre: DVec3,
    /// The vertices and faces as given, where the tree's float32 corners
    /// (plus the centre) are not them exactly: what float64 answers are
    /// computed on.
    given: Option<Given>,
    /// A placed mesh's prototype's centre: its tree's coordinates are
    /// relative to it (the maps it was built with are composed with it).
    prototype_centre: DVec3,
}

/// A mesh's vertices in float64 and its faces, as a binding gave them.
#[derive(Debug, Clone)]
struct Given {
    vertices: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
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
        let vertices = vertices.iter().map(|v| v.as_dvec3()).collect();
        Self::new_exact(vertices, faces, quality)
    }

    /// [`Mesh::new`] of float64 vertices: traced relative to a centre where
    /// the mesh lies far from the origin, its hit and closest points
    /// computed on these vertices (module docs).
    pub fn new_exact(
        vertices: Vec<DVec3>,
        faces: Vec<[u32; 3]>,
        quality: BuildQuality,
    ) -> Result<Self, MeshArraysError> {
        // Vertices no face uses are never traced (`mesh_geometry`): they
        // neither move the centre nor need to be held exactly.
        let used = used_vertices(&faces, vertices.len());
        let centre = centre_of(
            vertices
                .iter()
                .zip(&used)
                .filter(|(_, &u)| u)
                .map(|(v, _)| v),
        );
        let near: Vec<Vec3> = vertices.iter().map(|&v| (v - centre).as_vec3()).collect();
        let held_exactly = (near.iter().zip(&vertices).zip(&used))
            .all(|((n, &v), &u)| !u || n.as_dvec3() + centre == v);
        let given_faces = (!held_exactly).then(|| faces.clone());
        // `mesh_geometry` refuses a vertex that is not finite as traced;
        // it is quoted as given (relative to the centre a NaN would be
        // quoted moved), and one finite as given is beyond float32 there.
        let geometry = mesh_geometry(near, faces, quality).map_err(|e| match e {
            MeshArraysError::NotFinite { vertex, face, .. } => {
                let value = vertices[vertex].to_array();
                match vertices[vertex].is_finite() {
                    true => MeshArraysError::BeyondFloat32 {
                        vertex,
                        value,
                        face,
                    },
                    false => MeshArraysError::NotFinite {
                        vertex,
                        value,
                        face,
                    },
                }
            }
            e => e,
        })?;
        let given = given_faces.map(|faces| Given { vertices, faces });
        let mesh = Self::from_geometry(geometry);
        let bounds = mesh.bounds.map(|b| (b.as_dvec3() + centre).as_vec3());
        Ok(Self {
            centre,
            given,
            bounds,
            ..mesh
        })
    }

    /// What rays and points are made relative to before they are traced
    /// (module docs): zero for a mesh near the origin, a loaded or a
    /// placed mesh.
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// The vertices and faces as given to [`Mesh::new_exact`] where the
    /// tree does not hold them exactly (a binding's pickling keeps them).
    pub fn given(&self) -> Option<(&[DVec3], &[[u32; 3]])> {
        self.given
            .as_ref()
            .map(|g| (g.vertices.as_slice(), g.faces.as_slice()))
    }

    /// The world corners, in float64, of the face `found` lies on: as
    /// given, or the tree's (exact, then) moved back by the centre.
    fn corners(&self, found: &impl Found, face: i64) -> [DVec3; 3] {
        match &self.given {
            Some(g) => g.faces[face as usize].map(|k| g.vertices[k as usize]),
            None => self
                .geometry
                .world_triangle(found)
                .map(|p| p.as_dvec3() + self.centre),
        }
    }

    /// A mesh file (OBJ, PLY, OFF, STL, glTF or GLB) read with strata's
    /// loaders and used as it is: triangle `i` of the file is face `i`.
    /// Where the format can write more than float32 holds (OBJ, OFF and
    /// ASCII STL text, PLY `double` properties), the file's own float64
    /// coordinates are held as a mesh from arrays is ([`Mesh::new_exact`]):
    /// centred where far from the origin, hit and closest points on the
    /// faces the file writes ([`file_arrays`]). Only the faces are read
    /// (`Reading::EXACT_FACES`, or `FACES` for the scene's path): no
    /// materials or textures. With it, what the loader read leniently (a
    /// file without faces), each a warning naming the file and the line.
    pub fn load(path: &Path, quality: BuildQuality) -> InputResult<(Self, Vec<InputError>)> {
        if let Some((vertices, faces, warnings)) = file_arrays(path)? {
            let mesh = Self::new_exact(vertices, faces, quality)
                .map_err(|e| InputError::file(path, e.to_string()))?;
            return Ok((mesh, warnings));
        }
        let (scene, _) = load_mesh_scene(path, quality)?;
        let warnings = scene.warnings;
        let mesh = Self::from_geometry(scene.geometry);
        // Traced as the file places it (its centre is the origin).
        let extent = match mesh.triangle_count() {
            0 => 0.0,
            _ => mesh.bounds[0].abs().max(mesh.bounds[1].abs()).max_element(),
        };
        check_extent(f64::from(extent)).map_err(|e| InputError::file(path, e.to_string()))?;
        Ok((mesh, warnings))
    }

    /// This mesh placed once by each of `maps` (object to world): stored
    /// once, each placement an instance of it (module docs).
    pub fn place(&self, maps: &[Affine3A], quality: BuildQuality) -> Result<Self, PlaceError> {
        if self.is_placed() {
            return Err(PlaceError::AlreadyPlaced);
        }
        // The tree is relative to the centre: each map takes it there first.
        let shift = Affine3A::from_translation(self.centre.as_vec3());
        let built: Vec<Affine3A> = maps.iter().map(|&m| m * shift).collect();
        let mut prototype = self.geometry.clone();
        prototype.restore_pages();
        let geometry = placed(prototype, &built, quality).map_err(PlaceError::Map)?;
        Ok(Self {
            maps: maps.to_vec(),
            prototype_centre: self.centre,
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
        let c = self.prototype_centre;
        let back = |p: Vec3| (p.as_dvec3() + c).as_vec3();
        let tris = prototype.file_order_triangles();
        Some((tris.into_iter().map(|t| t.map(back)).collect(), &self.maps))
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
            centre: DVec3::ZERO,
            given: None,
            prototype_centre: DVec3::ZERO,
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
        if let Some(own) = self.own_corners() {
            return own.iter().map(|t| t.map(DVec3::as_vec3)).collect();
        }
        let g = &self.geometry;
        let mut tris = g.file_order_triangles();
        for instance in g.instances() {
            let m = instance.affine();
            let own = g.prototypes()[instance.prototype as usize].file_order_triangles();
            tris.extend(own.iter().map(|t| t.map(|p| m.transform_point3(p))));
        }
        tris
    }

    /// Every face's world corners in float64, in face order: those of
    /// a mesh held as given or relative to a centre ([`Mesh::own_corners`]),
    /// else (near the origin, or placed) [`Mesh::triangles`] widened.
    /// [`Mesh::triangles`] rounds these to float32, which a far mesh's
    /// corners do not survive (an integer grid at 2e12 merges).
    pub fn corner_positions(&self) -> Vec<[DVec3; 3]> {
        match self.own_corners() {
            Some(own) => own,
            None => (self.triangles().iter())
                .map(|t| t.map(Vec3::as_dvec3))
                .collect(),
        }
    }

    /// The float64 world corners of a mesh that is not simply its trees'
    /// float32 triangles: as given, or as traced moved back by the centre
    /// (exactly: without its vertices as given, a mesh is held relative to
    /// a centre only where float32 holds them so there). `None` for a mesh
    /// traced as it lies (centre 0, a placed mesh among them).
    fn own_corners(&self) -> Option<Vec<[DVec3; 3]>> {
        if let Some(g) = &self.given {
            let corner = |k: u32| g.vertices[k as usize];
            return Some(g.faces.iter().map(|f| f.map(corner)).collect());
        }
        if self.centre == DVec3::ZERO {
            return None;
        }
        let c = self.centre;
        let tris = self.geometry.file_order_triangles();
        Some(tris.iter().map(|t| t.map(|p| p.as_dvec3() + c)).collect())
    }

    /// `out[i]`: the first hit of `rays[i]` in `(tmin, tmax]`. Watertight:
    /// a ray through a shared edge or vertex of a closed mesh hits one of
    /// the faces there, never none.
    ///
    /// `surface`: whether to find the face's normal and the hit point (a
    /// second look at the face's corners); without it they stay NaN.
    ///
    /// Never inlined, as the binding's other walks
    /// ([`Geometry::count_crossings_stream`]): compiled in the library,
    /// not again in the crate that calls it.
    #[inline(never)]
    pub fn first_hits(&self, rays: &[Ray], out: &mut [FirstHit], surface: bool) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        self.each_first_hit(rays, surface, |i, ray, hit| {
            out[i] = match hit {
                None => FirstHit::MISS,
                Some(hit) if surface => self.first_hit(ray, hit, true),
                Some(hit) => FirstHit {
                    t: hit.t,
                    face: self.geometry.flat_prim(hit, &self.flat) as i64,
                    u: hit.u,
                    v: hit.v,
                    ..FirstHit::MISS
                },
            }
        });
    }

    /// [`Mesh::first_hits`] written straight into the columns asked for
    /// (an empty column is not written; the normal is found only where
    /// it or the point is asked for, the point only where it is): a
    /// binding's arrays,
    /// without a row of every quantity staged for each ray and copied
    /// again (3% of the Python package's first hits on the dragon's
    /// random rays, docs/python.md). Where no normal is asked for, a hit's
    /// t, face, u and v go into their columns as they are: a whole
    /// [`FirstHit`] made for each ray and read back was written in pieces
    /// and read whole, and the read waited on the writes, most of the
    /// columns' cost (docs/python.md, "Reading the rays and writing the
    /// answers").
    #[inline(never)]
    pub fn first_hits_into(&self, rays: &[Ray], mut out: FirstHitColumns<'_>) {
        let n = rays.len();
        for (len, width) in out.lens() {
            assert!(
                len == 0 || len == width * n,
                "a column of {len} for {n} rays"
            );
        }
        let point = !out.point.is_empty();
        let surface = point || !out.normal.is_empty();
        let miss = out.miss;
        self.each_first_hit(rays, surface, |i, ray, hit| match hit {
            None => out.put(i, &miss),
            Some(hit) if surface => out.put(i, &self.first_hit(ray, hit, point)),
            Some(hit) => {
                let face = self.geometry.flat_prim(hit, &self.flat) as i64;
                out.put_plain(i, hit.t, face, hit.u, hit.v)
            }
        });
    }

    /// Each ray's first hit (`None`: a miss), handed to `put` with the
    /// ray's index and the ray; with `surface` the hit triangles are
    /// prefetched first, for `put` to read their corners.
    #[inline(always)]
    fn each_first_hit(
        &self,
        rays: &[Ray],
        surface: bool,
        mut put: impl FnMut(usize, &Ray, Option<&crate::accel::PrimHit>),
    ) {
        for (k, rays) in rays.chunks(SPAN).enumerate() {
            let mut found = [None; SPAN];
            let found = &mut found[..rays.len()];
            self.geometry.intersect_stream(rays, found);
            if surface && self.given.is_none() {
                // The hit triangles' corners, read below, have mostly left
                // the caches since the walk tested them: fetch them all at
                // once rather than wait for each in turn.
                for hit in found.iter().flatten() {
                    self.geometry.prefetch_triangle(hit);
                }
            }
            for (j, (hit, ray)) in found.iter().zip(rays).enumerate() {
                put(k * SPAN + j, ray, hit.as_ref());
            }
        }
    }

    /// What [`Mesh::first_hits`] answers for `ray`'s hit `hit`: the face
    /// and its normal, and with `point` the point in float64 where the ray
    /// (as traced, relative to the centre) meets the face's plane (NaN
    /// without: a binding that asks for normals alone does not pay for
    /// the point's exact solve).
    fn first_hit(&self, ray: &Ray, hit: &crate::accel::PrimHit, point: bool) -> FirstHit {
        let face = self.geometry.flat_prim(hit, &self.flat) as i64;
        let [a, b, c] = self.corners(hit, face);
        let point = if point {
            let origin = ray.origin.as_dvec3() + self.centre;
            let direction = ray.direction.as_dvec3();
            match exact::plane_hit(origin - a, direction, [DVec3::ZERO, b - a, c - a]) {
                Some((t, ..)) => origin + t * direction,
                // Parallel in float64 where float32 found a hit: the f32 barycentrics.
                None => {
                    (1.0 - f64::from(hit.u) - f64::from(hit.v)) * a
                        + f64::from(hit.u) * b
                        + f64::from(hit.v) * c
                }
            }
        } else {
            DVec3::NAN
        };
        FirstHit {
            t: hit.t,
            face,
            u: hit.u,
            v: hit.v,
            normal: (b - a).cross(c - a).normalize().as_vec3(),
            point,
        }
    }

    /// `out[i]`: whether anything blocks `rays[i]` in `(tmin, tmax]`.
    /// Never inlined, as [`Mesh::first_hits`].
    #[inline(never)]
    pub fn occluded(&self, rays: &[Ray], out: &mut [bool]) {
        self.geometry.occluded_stream(rays, u32::MAX, out);
    }

    /// Appends every crossing of the surface along each ray of `rays` in
    /// `(tmin, tmax]` to `out`'s columns, nearest first (then by face),
    /// ray after ray, and each ray's number of them to its counts. One walk per ray,
    /// not a re-cast from each hit: a ray through a shared edge or vertex
    /// of a closed mesh, where it crosses the surface, is reported once
    /// ([`Geometry::crossings`]).
    ///
    /// `uv`: whether to find each crossing's barycentrics (a second look at
    /// the face's corners); without it their columns stay as they are.
    pub fn all_hits(&self, rays: &[Ray], out: &mut Crossings, uv: bool) {
        // Several rays in flight ([`Geometry::crossings_stream`]), each
        // ray's list then copied out in ray order.
        let mut found = Vec::new();
        let mut spans = vec![(0, 0); rays.len()];
        self.geometry.crossings_stream(rays, &mut found, &mut spans);
        out.counts.extend(spans.iter().map(|&(_, n)| n));
        out.t.reserve(found.len());
        out.face.reserve(found.len());
        for (ray, &(first, n)) in rays.iter().zip(&spans) {
            for c in &found[first..first + n as usize] {
                let face = self.geometry.flat_prim(c, &self.flat) as i64;
                out.t.push(c.t);
                out.face.push(face);
                if uv {
                    let (u, v) = self.plane_uv(ray, c, face);
                    out.u.push(u);
                    out.v.push(v);
                }
            }
        }
    }

    /// Where `ray` (relative to the centre) meets the plane of the face
    /// `found` lies on, as barycentric weights, in float64.
    fn plane_uv(&self, ray: &Ray, found: &impl Found, face: i64) -> (f64, f64) {
        let [a, b, c] = self.corners(found, face);
        let origin = ray.origin.as_dvec3() + self.centre - a;
        let hit = exact::plane_hit(
            origin,
            ray.direction.as_dvec3(),
            [DVec3::ZERO, b - a, c - a],
        );
        hit.map_or((f64::NAN, f64::NAN), |(_, u, v)| (u, v))
    }

    /// `out[i]`: how many crossings [`Mesh::all_hits`] would list for
    /// `rays[i]` (several in flight, [`Geometry::count_crossings_stream`]).
    pub fn count_hits(&self, rays: &[Ray], out: &mut [u32]) {
        self.geometry.count_crossings_stream(rays, out);
    }

    /// `out[i]`: whether `points[i]` (relative to [`Mesh::centre`]) is
    /// inside: the parity of the crossings along one ray from it
    /// ([`Geometry::contains`]; meant for closed meshes).
    pub fn contains(&self, points: &[Vec3], out: &mut [bool]) {
        self.geometry.contains_stream(points, out);
    }

    /// The surface point nearest to `point` within `max_distance`
    /// (infinite: no limit), its distance (negative inside where `signed`,
    /// by [`Mesh::contains`]) and its face; [`ClosestPoint::MISS`] where
    /// none lies that near.
    ///
    /// `point` is as given (float64, world) and `near` as traced (relative
    /// to [`Mesh::centre`], float32): the walk finds the face from `near`,
    /// and the point on it and its distance are computed from `point` on
    /// the face as given, in float64 ([`exact::closest_on_triangle`]).
    pub fn closest_point(
        &self,
        point: DVec3,
        near: Vec3,
        max_distance: f32,
        signed: bool,
    ) -> ClosestPoint {
        let Some(n) = self.geometry.nearest(near, max_distance) else {
            return ClosestPoint::MISS;
        };
        let face = self.geometry.flat_prim(&n, &self.flat) as i64;
        let [a, b, c] = self.corners(&n, face);
        // Relative to the first corner, where the numbers are small.
        let (q, u, v) = exact::closest_on_triangle(point - a, [DVec3::ZERO, b - a, c - a]);
        let distance = (point - a - q).length();
        let inside = signed && self.geometry.contains(near);
        ClosestPoint {
            point: a + q,
            distance: if inside { -distance } else { distance },
            u,
            v,
            face,
        }
    }
}

/// What a mesh of `vertices` is traced relative to (module docs): the
/// middle of their box rounded to a multiple of the power of two at least
/// its largest side; zero on each axis where the middle lies no farther
/// from the origin than that side (a mesh near the origin, whose answers
/// keep every bit: rounding alone took the box [0, 1] to 1).
fn centre_of<'a>(vertices: impl Iterator<Item = &'a DVec3>) -> DVec3 {
    let (lo, hi) = vertices
        .filter(|v| v.is_finite())
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return DVec3::ZERO;
    }
    let size = (hi - lo).max_element().max(f64::MIN_POSITIVE);
    let step = 2f64.powi(size.log2().ceil() as i32);
    let middle = (lo + hi) * 0.5;
    let centre = (middle / step).round() * step;
    let near = middle.abs().cmple(DVec3::splat(size));
    // -0.0 is 0.0 (a centre of zero keeps every bit).
    DVec3::select(near, DVec3::ZERO, centre) + DVec3::ZERO
}

/// The [min, max] corners of the box of `tris`'s vertices moved by `map`.
fn corners(tris: impl Iterator<Item = [Vec3; 3]>, map: impl Fn(Vec3) -> Vec3) -> [Vec3; 2] {
    tris.flatten()
        .fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], p| {
            let q = map(p);
            [lo.min(q), hi.max(q)]
        })
}
