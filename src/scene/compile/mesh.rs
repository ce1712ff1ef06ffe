//! Triangles: mesh files (read once each, their materials registered once)
//! and single triangles, kept indexed until the BVH is built and then
//! written once, in leaf order, into the scene's leaf blocks.

use super::arrays::EXTENT;
use super::Compiler;
use crate::accel::prefetch::prefetch;
use crate::accel::prefetch::Prefetch;
use crate::accel::{BuildChoice, Bvh8};
use crate::error::io_message;
use crate::error::{InputError, InputResult};
use crate::geometry::{Geometry, GeometryParts, TriangleVertices};
use crate::geometry::{MeshAttribute, MeshNormals, MeshRange, MeshTangents, MeshUvs};
use crate::material::Material;
use crate::math::Aabb;
use crate::math::Transform;
use crate::scene::asset::{place_tangents, LoadedAsset, LoadedMesh};
use crate::scene::loaders::{self, load_mesh_file_with, Reading};
use glam::{Affine3A, Vec3};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The triangles of one [`MeshRange`] until the BVH is built. A mesh file's
/// meshes stay indexed (world-space positions and the file's indices, about
/// 18 bytes per triangle instead of 36), so the build runs beside half the
/// memory and the triangles are expanded once, in leaf order, afterwards.
pub(super) enum TriangleSource {
    Soup(Vec<[Vec3; 3]>),
    Indexed {
        positions: Vec<Vec3>,
        /// Checked against `positions` when made.
        indices: Vec<[u32; 3]>,
    },
    /// Mesh `mesh` of a mesh file: its positions moved into world space,
    /// its indices read where the loaded file holds them (checked against
    /// the positions when made), not copied: 12 bytes a triangle less
    /// while loading, and no copy to wait for.
    File {
        positions: Vec<Vec3>,
        asset: Arc<LoadedAsset>,
        mesh: usize,
    },
    /// Mesh `mesh` of a mesh file as the file has it (a prototype's, in
    /// its own object space): positions and indices read where the loaded
    /// file holds them, nothing copied.
    FileSpace {
        asset: Arc<LoadedAsset>,
        mesh: usize,
    },
    /// Part `part` of shared mesh `shared` of a mesh file, in the mesh's
    /// own space (its prototype's), read where the loaded file holds it.
    Shared {
        asset: Arc<LoadedAsset>,
        shared: usize,
        part: usize,
    },
}

/// A [`TriangleSource`]'s triangles, borrowed where they are held.
#[derive(Clone, Copy)]
pub(super) enum Triangles<'a> {
    Soup(&'a [[Vec3; 3]]),
    /// Indices checked against the positions when made.
    Indexed {
        positions: &'a [Vec3],
        indices: &'a [[u32; 3]],
    },
}

impl Triangles<'_> {
    #[inline]
    pub(super) fn get(self, i: usize) -> [Vec3; 3] {
        match self {
            Self::Soup(t) => t[i],
            Self::Indexed { positions, indices } => indices[i].map(|k| positions[k as usize]),
        }
    }

    /// Asks, without waiting, for the first memory triangle `i`'s read
    /// touches: its indices, or a soup's vertices.
    #[inline(always)]
    fn prefetch_first(self, i: usize) {
        match self {
            Self::Soup(t) => prefetch(&t[i]),
            Self::Indexed { indices, .. } => prefetch(&indices[i]),
        }
    }

    /// Asks, without waiting, for an indexed triangle `i`'s vertices
    /// (a soup's are its first memory).
    #[inline(always)]
    fn prefetch_vertices(self, i: usize) {
        if let Self::Indexed { positions, indices } = self {
            for k in indices[i] {
                prefetch(&positions[k as usize]);
            }
        }
    }
}

impl TriangleSource {
    pub(super) fn len(&self) -> usize {
        match self.triangles() {
            Triangles::Soup(t) => t.len(),
            Triangles::Indexed { indices, .. } => indices.len(),
        }
    }

    /// The triangles as arrays, wherever they are held: resolved once for
    /// a loop over many of them, rather than once a triangle.
    pub(super) fn triangles(&self) -> Triangles<'_> {
        let (positions, indices) = match self {
            Self::Soup(t) => return Triangles::Soup(t),
            Self::Indexed { positions, indices } => (positions, indices),
            Self::File {
                positions,
                asset,
                mesh,
            } => (positions, &asset.meshes[*mesh].indices),
            Self::FileSpace { asset, mesh } => {
                let m = &asset.meshes[*mesh];
                (&m.positions, &m.indices)
            }
            Self::Shared {
                asset,
                shared,
                part,
            } => {
                let m = &asset.shared[*shared].parts[*part];
                (&m.positions, &m.indices)
            }
        };
        Triangles::Indexed { positions, indices }
    }

    /// Frees what the file's asset holds beside the indices (its file-space
    /// positions) once this source is its only holder: the scene keeps
    /// nothing else of it, and the build runs beside less.
    pub(super) fn release_file_positions(&mut self) {
        if let Self::File { asset, .. } = self {
            if let Some(asset) = Arc::get_mut(asset) {
                for m in &mut asset.meshes {
                    m.positions = Vec::new();
                }
            }
        }
    }
}

/// Triangle `id`'s vertices, read from its mesh's (indexed) source: what
/// [`Geometry::new`] stores in the leaf slot that holds it.
pub(super) fn triangle_at<'a>(
    meshes: &[MeshRange],
    sources: &'a [TriangleSource],
) -> TrianglesById<'a> {
    TrianglesById {
        firsts: meshes.iter().map(|m| m.first).collect(),
        triangles: sources.iter().map(TriangleSource::triangles).collect(),
    }
}

/// Every mesh's triangles by primitive id (see [`triangle_at`]).
pub(super) struct TrianglesById<'a> {
    /// Each mesh's first triangle, so the meshes themselves can move on.
    firsts: Vec<u32>,
    triangles: Vec<Triangles<'a>>,
}

impl TrianglesById<'_> {
    #[inline(always)]
    fn find(&self, id: u32) -> (Triangles<'_>, usize) {
        let k = self.firsts.partition_point(|&first| first <= id) - 1;
        (self.triangles[k], (id - self.firsts[k]) as usize)
    }
}

impl TriangleVertices for TrianglesById<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> [Vec3; 3] {
        let (triangles, i) = self.find(id);
        triangles.get(i)
    }

    #[inline(always)]
    fn prefetch_indices(&self, id: u32) {
        let (triangles, i) = self.find(id);
        triangles.prefetch_first(i);
    }

    #[inline(always)]
    fn prefetch_vertices(&self, id: u32) {
        let (triangles, i) = self.find(id);
        triangles.prefetch_vertices(i);
    }
}

/// Where a mesh of the scene was written, for errors about its triangles:
/// the key of its object, and for a mesh file's mesh the file (as found
/// and as the scene writes it) and the mesh's name there (an OBJ
/// object's, a glTF mesh's; empty where it has none).
pub(super) struct MeshOrigin {
    pub key: String,
    pub file: Option<(PathBuf, String, String)>,
}

impl Compiler<'_> {
    pub(super) fn push_mesh(
        &mut self,
        (name, origin): (String, MeshOrigin),
        tris: TriangleSource,
        material: u32,
        normals: Option<MeshNormals>,
        (uvs, tangents): (Option<MeshUvs>, Option<MeshTangents>),
        mirrored: bool,
    ) {
        if tris.len() == 0 {
            return;
        }
        let first = self.meshes.last().map_or(0, |m| m.first + m.count);
        let count = tris.len() as u32;
        self.sources.push(tris);
        self.mesh_origins.push(origin);
        self.meshes.push(MeshRange {
            name,
            first,
            count,
            material,
            mirrored,
            normals,
            uvs,
            tangents,
        });
    }

    /// A mesh file's contents and the scene index of its first material,
    /// read (and its materials registered) once per file. `at` is the key
    /// path that names the file, for errors.
    pub(super) fn asset(
        &mut self,
        file: &str,
        at: &str,
    ) -> InputResult<(Arc<LoadedAsset>, u32, PathBuf)> {
        let path = self.base_dir.join(file);
        if !self.assets.contains_key(&path) {
            // A file that cannot be opened, or of a kind we do not read, is a
            // mistake in the scene file: say where. A problem inside the mesh
            // file is reported at its own line there.
            if let Err(e) = std::fs::File::open(&path) {
                let message = format!("cannot read '{}': {}", path.display(), io_message(&e));
                return Err(self.err(at, message));
            }
            if let Err(message) = loaders::check_extension(&path) {
                return Err(self.err(at, message));
            }
            let reading = match self.traced_file {
                true => Reading::FACES,
                false => Reading::RENDER,
            };
            let mut asset = match self.preloaded.take_if(|(p, _)| *p == path) {
                Some((_, asset)) => asset,
                None => load_mesh_file_with(&path, reading)?,
            };
            if self.traced_file {
                asset = asset.into_baked();
            }
            self.warnings.append(&mut asset.warnings);
            // The file's images move into the scene's (no copy); its
            // materials' texture indices move with them.
            let first_texture = self.textures.append(std::mem::take(&mut asset.textures));
            let first_material = self.materials.len() as u32;
            for (name, mat) in &asset.materials {
                self.materials.push(Material {
                    diffuse_texture: mat.diffuse_texture.map(|t| t + first_texture),
                    maps: mat.maps.offset(first_texture),
                    ..*mat
                });
                self.material_ids
                    .entry(format!("{file}:{name}"))
                    .or_insert(self.materials.len() as u32 - 1);
            }
            self.assets
                .insert(path.clone(), (Arc::new(asset), first_material));
        }
        let (asset, first_material) = self.assets.get(&path).expect("inserted above").clone();
        Ok((asset, first_material, path))
    }

    pub(super) fn mesh_file(
        &mut self,
        file: &str,
        key: &str,
        m: Affine3A,
        explicit_material: Option<u32>,
        inherited: u32,
    ) -> InputResult<()> {
        let (asset, first_material, path) = self.asset(file, &format!("{key}.mesh"))?;
        let t = Transform::new(m).expect("checked by the caller");
        let instanced = self.mesh_uses.get(&path).is_some_and(|&n| n > 1);
        let written = file.to_string();
        let file = (asset.clone(), first_material, path.clone());
        // The meshes the file itself places more than once are instances
        // wherever the file is placed; the rest is one prototype if the
        // file is placed more than once, else baked.
        self.shared_instances(&file, (key, &written), m, explicit_material, inherited)?;
        if instanced && asset.meshes.iter().any(|mesh| !mesh.indices.is_empty()) {
            self.mesh_instance(&file, (key, &written), m, explicit_material, inherited)?;
        }
        for (k, mesh) in asset.meshes.iter().enumerate().filter(|_| !instanced) {
            check_indices(mesh, &path)?;
            if let Some(normals) = &mesh.normals {
                check_attribute(normals, mesh, &path, "normals")?;
            }
            if let Some(uvs) = &mesh.uvs {
                check_attribute(uvs, mesh, &path, "texture coordinates")?;
            }
            if let Some(tangents) = &mesh.tangents {
                check_attribute(tangents, mesh, &path, "tangents")?;
            }
            let tris = TriangleSource::File {
                positions: mesh.positions.par_iter().map(|&p| t.point(p)).collect(),
                asset: asset.clone(),
                mesh: k,
            };
            let normals = mesh.normals.as_ref().map(|n| MeshNormals {
                values: n.values.iter().map(|&v| t.normal_to_world * v).collect(),
                indices: n.indices.clone(),
            });
            let material = explicit_material
                .or(mesh.material.map(|i| first_material + i as u32))
                .unwrap_or(inherited);
            // UVs only where a texture will be looked up with them: a
            // scene-file material put on a textured mesh has none.
            let textured = self.materials[material as usize].is_textured();
            let uvs = mesh.uvs.clone().filter(|_| textured);
            let mapped = self.materials[material as usize].maps.normal.is_some();
            let tangents = mesh
                .tangents
                .as_ref()
                .filter(|_| mapped)
                .map(|tangents| place_tangents(tangents, &m));
            let name = if mesh.name.is_empty() {
                key.to_string()
            } else {
                mesh.name.clone()
            };
            let mirrored = (m.matrix3.determinant() < 0.0) != mesh.mirrored;
            let origin = MeshOrigin {
                key: format!("{key}.mesh"),
                file: Some((path.clone(), written.clone(), mesh.name.clone())),
            };
            self.push_mesh(
                (name, origin),
                tris,
                material,
                normals,
                (uvs, tangents),
                mirrored,
            );
        }
        Ok(())
    }
}

/// Every vertex index of a loaded mesh is in range.
pub(super) fn check_indices(mesh: &LoadedMesh, path: &Path) -> InputResult<()> {
    let n_vertices = mesh.positions.len();
    match loaders::first_where(&mesh.indices, |idx| {
        idx.iter().any(|&i| i as usize >= n_vertices)
    }) {
        Some(f) => Err(InputError::new(
            path,
            format!("face {f}"),
            "vertex index out of range",
        )),
        None => Ok(()),
    }
}

/// A per-corner attribute a loader handed over has one index triple per
/// triangle, each in range (the loaders make them so; this keeps a
/// mistake there from becoming a panic at a hit).
pub(super) fn check_attribute<T>(
    attribute: &MeshAttribute<T>,
    mesh: &LoadedMesh,
    path: &Path,
    what: &str,
) -> InputResult<()> {
    let bad = attribute.indices.len() != mesh.indices.len()
        || attribute
            .indices
            .iter()
            .flatten()
            .any(|&i| i as usize >= attribute.values.len());
    if bad {
        return Err(InputError::new(
            path,
            mesh.name.clone(),
            format!("the {what} do not match the mesh's triangles"),
        ));
    }
    Ok(())
}

/// A loaded mesh's triangles in file space, with every index checked.
pub(super) fn mesh_triangles(mesh: &LoadedMesh, path: &Path) -> InputResult<Vec<[Vec3; 3]>> {
    check_indices(mesh, path)?;
    Ok(mesh
        .indices
        .iter()
        .map(|idx| idx.map(|i| mesh.positions[i as usize]))
        .collect())
}

/// A tree over triangles alone (a prototype, or a mesh given as arrays):
/// the BVH over their boxes, the leaf blocks read from the sources in leaf
/// order, nothing else. `Err` names the first triangle that is not
/// finite or past [`REACH`].
pub(super) fn triangle_geometry(
    meshes: Vec<MeshRange>,
    sources: Vec<TriangleSource>,
    choice: BuildChoice,
) -> Result<Geometry, OutOfReach> {
    let boxes = triangle_boxes(&meshes, &sources, 0)?;
    let mut bvh = Bvh8::build_from(boxes, choice.quality);
    bvh.shrink_to_fit();
    bvh.set_pages(choice.pages);
    let vertices = triangle_at(&meshes, &sources);
    let parts = GeometryParts {
        meshes,
        ..GeometryParts::default()
    };
    let mut geometry = Geometry::new(parts, bvh, vertices);
    geometry.set_prefetch(Prefetch::Auto.enabled(geometry.traversal_bytes()));
    Ok(geometry)
}

/// How far from the origin, in any coordinate, a triangle's vertices may
/// lie: the upper end of [`EXTENT`], where the watertight test's products
/// of three coordinates (relative to a ray's origin) start to overflow
/// float32. Below it a scene renders the same at any scale (a cube scaled
/// by 2⁻⁴³ or 2³⁹, its light and camera with it, gives the unscaled image
/// bit for bit); scaled to 1e13 it rendered black.
pub const REACH: f32 = *EXTENT.end() as f32;

/// The first triangle of a mesh that the ray tests cannot trace: one with
/// a vertex that is not finite or lies past [`REACH`].
#[derive(Debug, Clone, PartialEq)]
pub struct OutOfReach {
    /// The mesh's index among the meshes checked (its origin names it).
    pub index: usize,
    /// Its index in its mesh.
    pub triangle: usize,
    /// Its vertices' largest coordinate by magnitude (inf where one is
    /// not finite).
    pub farthest: f32,
}

impl OutOfReach {
    /// What is wrong with the triangle, for an error naming its mesh.
    pub fn message(&self) -> String {
        let i = self.triangle;
        if self.farthest.is_finite() {
            format!(
                "triangle {i} lies {:.3e} from the origin, past the {REACH:e} within which float32 ray tests stay exact: scale the scene down (its camera and lights with it)",
                self.farthest
            )
        } else {
            format!("triangle {i} is not finite")
        }
    }
}

/// Every triangle's box, mesh by mesh; the first triangle with a vertex
/// that is not finite or lies past [`REACH`] is an error naming its mesh
/// (by its index among `meshes`) and its index there. (Its box would not say: a box's min and max pass
/// a NaN by.) The vector has room for `room_after` more boxes.
pub(super) fn triangle_boxes(
    meshes: &[MeshRange],
    sources: &[TriangleSource],
    room_after: usize,
) -> Result<Vec<Aabb>, OutOfReach> {
    let n = meshes.last().map_or(0, |m| (m.first + m.count) as usize);
    let mut boxes = Vec::with_capacity(n + room_after);
    // NaN fails the comparison too (where `max_element` would pass it by).
    let within = |p: &Vec3| p.abs().cmple(Vec3::splat(REACH)).all();
    let out_of_reach = |t: &[Vec3; 3]| !t.iter().all(within);
    for (index, source) in sources.iter().enumerate() {
        let triangles = source.triangles();
        let first_bad = match triangles {
            Triangles::Soup(t) => {
                boxes.par_extend(t.par_iter().map(|t| Aabb::from_points(t)));
                loaders::first_where(t, out_of_reach)
            }
            Triangles::Indexed { positions, indices } => {
                let points = |t: &[u32; 3]| t.map(|k| positions[k as usize]);
                // A file's triangles reach back to vertices far from their
                // neighbours' (a subdivided mesh's new vertices come after
                // the old): each triangle's asked for a few dozen ahead.
                const AHEAD: usize = 32;
                boxes.par_extend(indices.par_iter().enumerate().map(|(i, t)| {
                    if i + AHEAD < indices.len() {
                        triangles.prefetch_vertices(i + AHEAD);
                    }
                    Aabb::from_points(&points(t))
                }));
                // The points first: about half as many as the triangles,
                // so a finite mesh's check reads a sixth of what checking
                // its triangles would.
                if positions.par_iter().all(within) {
                    None
                } else {
                    loaders::first_where(indices, |t| out_of_reach(&points(t)))
                }
            }
        };
        if let Some(i) = first_bad {
            let corners = match triangles {
                Triangles::Soup(t) => t[i],
                Triangles::Indexed { positions, indices } => {
                    indices[i].map(|k| positions[k as usize])
                }
            };
            let farthest = match corners.iter().all(|p| p.is_finite()) {
                true => corners
                    .iter()
                    .map(|p| p.abs().max_element())
                    .fold(0.0, f32::max),
                false => f32::INFINITY,
            };
            return Err(OutOfReach {
                index,
                triangle: i,
                farthest,
            });
        }
    }
    Ok(boxes)
}

#[cfg(test)]
mod tests {
    use super::super::test_support::compiled;
    use super::*;
    use crate::scene::loaders::test_files::{temp_dir, write};
    use crate::scene::{scene_from_str, RenderOverrides};

    const TWO_QUADS: &str = "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nusemtl a\nf 1 2 3 4\nusemtl b\nf 5 6 7\n";

    /// A mesh of `count` triangles from `first` with nothing but a name.
    fn range(name: &str, first: u32, count: u32) -> MeshRange {
        MeshRange {
            name: name.into(),
            first,
            count,
            ..MeshRange::default()
        }
    }

    /// An indexed mesh, whose points are checked rather than its boxes:
    /// the first triangle with a vertex that is not finite (infinite or
    /// NaN) is named, in its own mesh; a vertex no triangle uses is no
    /// error.
    #[test]
    fn an_indexed_mesh_names_its_first_triangle_with_a_vertex_not_finite() {
        let p = |x: f32| Vec3::new(x, 0.0, 1.0);
        let indexed = |bad: u32| TriangleSource::Indexed {
            positions: vec![p(0.0), p(1.0), p(2.0), p(f32::INFINITY), p(f32::NAN)],
            indices: vec![[0, 1, 2], [1, 2, 0], [2, bad, 0], [bad, 1, 2]],
        };
        let meshes = [range("a", 0, 1), range("b", 1, 4)];
        let soup = || TriangleSource::Soup(vec![[p(0.0), p(1.0), p(2.0)]]);
        for bad in [3, 4] {
            let got = triangle_boxes(&meshes, &[soup(), indexed(bad)], 0).map(|b| b.len());
            let e = got.unwrap_err();
            assert_eq!((e.index, e.triangle), (1, 2), "mesh b, vertex {bad}");
            assert_eq!(e.message(), "triangle 2 is not finite");
        }
        let unused = triangle_boxes(&meshes, &[soup(), indexed(1)], 0).map(|b| b.len());
        assert_eq!(unused, Ok(5));
    }

    #[test]
    fn mesh_files_are_baked_read_once_and_stored_in_leaf_order() {
        let dir = temp_dir("compile-mesh");
        write(&dir, "two.obj", TWO_QUADS.as_bytes());
        write(&dir, "other.obj", TWO_QUADS.as_bytes());
        write(&dir, "two.mtl", b"newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 0 1\n");
        let text = r#"
[[objects]]
mesh = "two.obj"
transform = { translate = [0.0, 0.0, 5.0] }
[[objects]]
mesh = "other.obj"
"#;
        let s = scene_from_str(text, &dir.join("s.toml"), &RenderOverrides::default()).unwrap();
        let g = &s.geometry;
        assert_eq!(g.triangle_count, 6, "a quad and a triangle, in each file");
        assert!(g.instances.is_empty(), "each file placed once: baked");
        let tris = g.file_order_triangles();
        assert_eq!(tris[0][0], Vec3::new(0.0, 0.0, 5.0), "the first is moved");
        assert_eq!(tris[3][0], Vec3::ZERO, "the second is not");
        // A file placed twice is read once: its two materials registered
        // once, its triangles stored once.
        let twice = "[[objects]]\nmesh = \"two.obj\"\n[[objects]]\nmesh = \"two.obj\"\n";
        let t = scene_from_str(twice, &dir.join("t.toml"), &RenderOverrides::default()).unwrap();
        assert_eq!(t.materials.len(), 3);
        assert_eq!(
            (t.geometry.prototypes.len(), t.geometry.instances.len()),
            (1, 2)
        );
        // Every leaf slot of a triangle holds that triangle's vertices.
        for (slot, id) in (0..).zip(g.leaf_slots()) {
            if id < g.triangle_count {
                assert_eq!(g.slot_triangle(slot), tris[id as usize]);
            }
        }
        let colour = |tri: u32| s.materials[g.mesh_of(tri).material as usize].diffuse;
        assert_eq!(colour(0), Vec3::X);
        assert_eq!(colour(2), Vec3::Z);
    }

    #[test]
    fn only_textured_meshes_keep_uvs_and_texture_indices_follow_their_files() {
        use crate::scene::loaders::test_files::png;
        let dir = temp_dir("compile-uvs");
        write(&dir, "red.png", &png(1, 1, &[[255, 0, 0]]));
        write(&dir, "blue.png", &png(1, 1, &[[0, 0, 255]]));
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
        // Three files: a file placed twice would be instanced, keeping its
        // UVs for either placement.
        let files = [
            ("first", "red.png"),
            ("second", "blue.png"),
            ("third", "blue.png"),
        ];
        for (name, texture) in files {
            let mtl = format!("newmtl wood\nmap_Kd {texture}\nnewmtl paint\nKd 0.5 0.5 0.5\n");
            write(&dir, &format!("{name}.mtl"), mtl.as_bytes());
            let obj = format!(
                "mtllib {name}.mtl\n{quad}o wood\nusemtl wood\nf 1/1 2/2 3/3 4/4\n\
                 o paint\nusemtl paint\nf 1/1 2/2 3/3\n"
            );
            write(&dir, &format!("{name}.obj"), obj.as_bytes());
        }
        let text = r#"
[materials.grey]
diffuse = [0.5, 0.5, 0.5]
[[objects]]
mesh = "first.obj"
[[objects]]
mesh = "second.obj"
[[objects]]
mesh = "third.obj"
material = "grey"
"#;
        let s = scene_from_str(text, &dir.join("s.toml"), &RenderOverrides::default()).unwrap();
        let has_uvs: Vec<(&str, bool)> = s
            .geometry
            .meshes
            .iter()
            .map(|m| (m.name.as_str(), m.uvs.is_some()))
            .collect();
        assert_eq!(
            has_uvs,
            [
                ("wood", true),
                ("paint", false),
                ("wood", true),
                ("paint", false),
                ("wood", false), // a scene material without texture replaces it
                ("paint", false),
            ]
        );
        assert_eq!(
            s.textures.images.len(),
            3,
            "one image per file, each read once"
        );
        let texture_of = |mesh: usize| {
            let m = &s.materials[s.geometry.meshes[mesh].material as usize];
            m.diffuse_texture.map(|t| {
                s.textures.images[s.textures.textures[t as usize].image as usize].texels()[0]
            })
        };
        assert_eq!(texture_of(0), Some([255, 0, 0]));
        assert_eq!(texture_of(2), Some([0, 0, 255]));
        assert_eq!(texture_of(1), None);
        assert_eq!(texture_of(4), None);

        // A scene without textured meshes stores no UVs at all.
        let s = scene_from_str(
            "[[objects]]\nmesh = \"first.obj\"\nmaterial = \"grey\"\n[materials.grey]\n",
            &dir.join("t.toml"),
            &RenderOverrides::default(),
        )
        .unwrap();
        assert!(s.geometry.meshes.iter().all(|m| m.uvs.is_none()));
    }

    #[test]
    fn a_missing_mesh_names_the_file_and_out_of_range_indices_the_face() {
        let s = compiled(
            "[[objects]]\ntriangle = { v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }",
        );
        assert_eq!(s.geometry.meshes[0].name, "objects[0]");
        let e = scene_from_str(
            "[[objects]]\nmesh = \"nowhere.obj\"",
            Path::new("t.toml"),
            &RenderOverrides::default(),
        )
        .unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.location.as_str()),
            ("t.toml", "objects[0].mesh")
        );
        assert_eq!(e.line, Some(2), "the line of the mesh key");
        assert!(e.message.contains("cannot read 'nowhere.obj'"), "{e}");
        let mesh = LoadedMesh {
            positions: vec![Vec3::ZERO; 3],
            indices: vec![[0, 1, 2], [0, 1, 3]],
            ..LoadedMesh::default()
        };
        let e = check_indices(&mesh, Path::new("m.obj")).unwrap_err();
        assert_eq!(e.location, "face 1");
    }

    /// The first box that is not finite is found wherever it lies: in
    /// the first block of the parallel search, past it, in the last mesh.
    #[test]
    fn the_first_triangle_that_is_not_finite_is_named() {
        let tri = |k: usize| [Vec3::ZERO, Vec3::X, Vec3::new(0.0, k as f32, 1.0)];
        // Long enough for several of the parallel search's blocks.
        let block = 1 << 14;
        let n = 3 * block + 5;
        for bad in [None, Some(3), Some(block + 7), Some(n - 1)] {
            let mut second: Vec<[Vec3; 3]> = (0..n).map(tri).collect();
            if let Some(i) = bad {
                second[i][1].y = f32::INFINITY;
                second[n - 2][2].x = f32::NAN;
            }
            let meshes = [range("a", 0, 10), range("b", 10, n as u32)];
            let sources = [
                TriangleSource::Soup((0..10).map(tri).collect()),
                TriangleSource::Soup(second),
            ];
            match (triangle_boxes(&meshes, &sources, 0), bad) {
                (Ok(boxes), None) => assert_eq!(boxes.len(), n + 10),
                // The NaN at n - 2 comes after every other but the last.
                // Mesh 1 is b.
                (Err(e), Some(i)) => assert_eq!((e.index, e.triangle), (1, i.min(n - 2))),
                (got, want) => panic!("{:?} for {want:?}", got.map(|b| b.len())),
            }
        }
    }

    /// A triangle past [`REACH`] is refused as one that is not finite is,
    /// its distance said; one on the bound is traced. In a soup and in an
    /// indexed mesh, whose points are checked first.
    #[test]
    fn a_triangle_past_the_reach_of_float32_ray_tests_is_named() {
        let meshes = [range("far", 0, 3)];
        let at = |x: f32| [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, x)];
        for far in [REACH, 2e12, -3e15, f32::MAX] {
            let tris = vec![at(1.0), at(2.0), at(far)];
            let indexed = TriangleSource::Indexed {
                positions: tris.iter().flatten().copied().collect(),
                indices: (0..3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            };
            for source in [TriangleSource::Soup(tris), indexed] {
                let got = triangle_boxes(&meshes, &[source], 0);
                if far == REACH {
                    assert_eq!(got.map(|b| b.len()).ok(), Some(3));
                    continue;
                }
                let e = got.unwrap_err();
                assert_eq!((e.triangle, e.farthest), (2, far.abs()));
                let said = format!(
                    "triangle 2 lies {:.3e} from the origin, past the 1e12",
                    far.abs()
                );
                assert!(e.message().starts_with(&said), "{}", e.message());
            }
        }
        // A NaN coordinate beside finite ones: not finite, not "far".
        let nan = TriangleSource::Soup(vec![[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 5.0), Vec3::X]]);
        let e = triangle_boxes(&[range("nan", 0, 1)], &[nan], 0).unwrap_err();
        assert_eq!(e.message(), "triangle 0 is not finite");
    }
}
