//! What a mesh loader hands to the scene compiler: plain arrays in file
//! order, with optional data present only where the file has it. A mesh
//! the file places more than once (a glTF mesh that several nodes use) is
//! kept once, in its own space, with its placements ([`SharedMesh`]);
//! [`LoadedAsset::baked_meshes`] gives the file as copies in file order.

use super::description::{CameraDesc, CameraType, LightDesc, LightType};
use crate::error::InputError;
use crate::geometry::{MeshNormals, MeshTangents, MeshUvs};
use crate::material::Material;
use crate::math::{Aabb, Transform};
use crate::texture::Textures;
use glam::{Affine3A, DVec3, Mat3, Vec3};
use rayon::prelude::*;
use std::borrow::Cow;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

/// One triangle mesh read from a file. Triangles keep the file's order, so a
/// triangle's index in `indices` is the primitive id that `strata trace`
/// reports and that Embree sees.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// The file's own coordinates in float64, one per position (`positions`
    /// are their rounding to float32), kept only where the load asked for
    /// them ([`Coordinates::Float64`]), by the loaders of the formats that
    /// can write more than float32 holds: OBJ, OFF and ASCII STL text, PLY
    /// `double` properties (a PLY's `float` ones widened). A query mesh is held to
    /// them (`raycast::Mesh::load`); a scene traces `positions`.
    ///
    /// [`Coordinates::Float64`]: crate::scene::loaders::Coordinates::Float64
    pub exact_positions: Option<Vec<DVec3>>,
    pub indices: Vec<[u32; 3]>,
    /// Shading normals, only if the file has them.
    pub normals: Option<MeshNormals>,
    /// Texture coordinates (in [`crate::texture`]'s space), only if the file
    /// has them for every triangle and the mesh's material has a texture.
    pub uvs: Option<MeshUvs>,
    /// Tangents (glTF `TANGENT`), only if the file has them and the mesh's
    /// material has a normal map.
    pub tangents: Option<MeshTangents>,
    /// Index into [`LoadedAsset::materials`], if the file assigns one.
    pub material: Option<usize>,
    /// The file's placement of the mesh mirrors it (a glTF node whose
    /// world transform has a negative determinant), so its triangles face
    /// the other way from their stored winding (glTF 2.0, "Meshes": the
    /// determinant sets the winding).
    pub mirrored: bool,
}

impl LoadedMesh {
    /// The mesh moved by `m`: positions as points, normals by the inverse
    /// transpose (renormalised), its winding's sense flipped if `m`
    /// mirrors. Indices and texture coordinates stay as they are.
    pub fn placed(mut self, m: &Affine3A) -> Self {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if let Some(normals) = &mut self.normals {
            let normal_matrix = normal_matrix(m);
            for n in &mut normals.values {
                *n = (normal_matrix * *n).normalize_or_zero();
            }
        }
        if let Some(tangents) = &mut self.tangents {
            *tangents = place_tangents(tangents, m);
        }
        self.mirrored ^= m.matrix3.determinant() < 0.0;
        self
    }

    /// Every vertex a triangle uses, once each.
    fn used_vertices(&self) -> impl Iterator<Item = Vec3> + '_ {
        let mut used = vec![false; self.positions.len()];
        for &i in self.indices.iter().flatten() {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
        self.positions
            .iter()
            .zip(used)
            .filter_map(|(&p, u)| u.then_some(p))
    }
}

/// A matrix proportional to the inverse transpose of `m`'s linear part
/// (its cofactor matrix, sign-corrected), so normals stay on the side they
/// were on. Defined even for singular maps.
fn normal_matrix(m: &Affine3A) -> Mat3 {
    let m = Mat3::from(m.matrix3);
    let cofactor = Mat3::from_cols(
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    );
    if m.determinant() < 0.0 {
        -cofactor
    } else {
        cofactor
    }
}

/// A mesh the file places more than once (a glTF mesh that several nodes
/// use), kept once in its own space: the scene compiler makes it one
/// prototype and each placement an instance of it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SharedMesh {
    /// Its parts (a glTF mesh's primitives), in the mesh's own space.
    pub parts: Vec<LoadedMesh>,
    /// Its placements, in file (node traversal) order.
    pub placements: Vec<SharedPlacement>,
}

/// One placement of a [`SharedMesh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharedPlacement {
    /// Mesh space to file space: finite and invertible.
    pub to_file: Affine3A,
    /// Where its first part falls among [`LoadedAsset::baked_meshes`]: its
    /// parts follow one another from there.
    pub at: usize,
}

/// Tangents moved by `m`: xyz as directions (they lie along ∂p/∂u, which
/// moves with the points), w turned where `m` mirrors, since the normal's
/// cross product with the tangent turns then too.
pub fn place_tangents(tangents: &MeshTangents, m: &Affine3A) -> MeshTangents {
    let sign = m.matrix3.determinant().signum();
    MeshTangents {
        values: tangents
            .values
            .iter()
            .map(|t| {
                let xyz = (m.matrix3 * glam::Vec3A::from(t.truncate())).normalize_or_zero();
                Vec3::from(xyz).extend(t.w * sign)
            })
            .collect(),
        indices: tangents.indices.clone(),
    }
}

/// A camera found in a glTF file, already placed in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCamera {
    pub position: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees for a perspective camera.
    pub yfov_degrees: Option<f32>,
    /// World-space view height for an orthographic camera.
    pub ortho_height: Option<f32>,
    /// Width over height of the view, where the file gives it (a
    /// perspective camera's `aspectRatio`, an orthographic one's
    /// `xmag / ymag`).
    pub aspect_ratio: Option<f32>,
}

/// A punctual light (glTF `KHR_lights_punctual`), in world space, its
/// photometric units already turned into radiometric ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadedLight {
    Point {
        position: Vec3,
        /// Radiant intensity in W/sr per channel.
        intensity: Vec3,
    },
    Spot {
        position: Vec3,
        /// Unit axis of the cone, the way the light shines.
        direction: Vec3,
        /// Radiant intensity on the axis in W/sr per channel.
        intensity: Vec3,
        /// Half-angles from the axis in radians, 0 ≤ inner ≤ outer ≤ π/2.
        inner_angle: f32,
        outer_angle: f32,
    },
    Directional {
        /// Unit direction the light travels.
        direction: Vec3,
        /// Irradiance in W/m² on a surface facing the light.
        irradiance: Vec3,
    },
}

impl LoadedLight {
    /// The light moved by an object's transform: positions as points,
    /// directions as vectors (renormalised).
    pub fn transformed(&self, t: &Transform) -> Self {
        match *self {
            Self::Point {
                position,
                intensity,
            } => Self::Point {
                position: t.point(position),
                intensity,
            },
            Self::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => Self::Spot {
                position: t.point(position),
                direction: t.vector(direction).normalize_or_zero(),
                intensity,
                inner_angle,
                outer_angle,
            },
            Self::Directional {
                direction,
                irradiance,
            } => Self::Directional {
                direction: t.vector(direction).normalize_or_zero(),
                irradiance,
            },
        }
    }

    /// The `[[lights]]` entry that makes this light: a scene file's own
    /// words for it, so a file's lights and a hand-written scene's are
    /// compiled (and checked) by the same code.
    pub fn to_desc(&self) -> LightDesc {
        match *self {
            Self::Point {
                position,
                intensity,
            } => LightDesc {
                kind: LightType::Point,
                position: Some(position.into()),
                intensity: Some(intensity.into()),
                ..LightDesc::default()
            },
            Self::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => LightDesc {
                kind: LightType::Spot,
                position: Some(position.into()),
                direction: Some(direction.into()),
                intensity: Some(intensity.into()),
                inner_angle: Some(inner_angle.to_degrees()),
                outer_angle: Some(outer_angle.to_degrees()),
                ..LightDesc::default()
            },
            Self::Directional {
                direction,
                irradiance,
            } => LightDesc {
                kind: LightType::Directional,
                direction: Some(direction.into()),
                irradiance: Some(irradiance.into()),
                ..LightDesc::default()
            },
        }
    }
}

impl LoadedCamera {
    /// The camera moved by an object's transform.
    pub fn transformed(&self, t: &Transform) -> Self {
        Self {
            position: t.point(self.position),
            forward: t.vector(self.forward),
            up: t.vector(self.up),
            ..self.clone()
        }
    }

    /// The `[camera]` table that makes this camera. `look_at` lies along
    /// the view direction as far off as the camera is from the origin (at
    /// least 1), so that `look_at − position` keeps the direction to f32
    /// precision however far from the origin the camera stands.
    pub fn to_desc(&self) -> CameraDesc {
        let reach = self.position.length().max(1.0);
        let look_at = self.position + self.forward.normalize_or_zero() * reach;
        CameraDesc {
            kind: if self.ortho_height.is_some() {
                CameraType::Orthographic
            } else {
                CameraType::Perspective
            },
            position: self.position.into(),
            look_at: look_at.into(),
            up: self.up.into(),
            fov: self
                .ortho_height
                .is_none()
                .then_some(self.yfov_degrees)
                .flatten(),
            height: self.ortho_height,
            aperture: None,
            focus_distance: None,
        }
    }
}

/// Everything one mesh file contributes to a scene.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedAsset {
    /// The meshes placed once, in file space, in file order.
    pub meshes: Vec<LoadedMesh>,
    /// The meshes placed more than once, each kept once in its own space.
    pub shared: Vec<SharedMesh>,
    pub materials: Vec<(String, Material)>,
    /// The images and textures the materials' `diffuse_texture` indices name.
    pub textures: Textures,
    pub cameras: Vec<LoadedCamera>,
    pub lights: Vec<LoadedLight>,
    /// What the loader read leniently, as other tools do (a material no
    /// library defines, a stray header line, no triangles at all), each
    /// naming the file and, where one applies, the line.
    pub warnings: Vec<InputError>,
}

impl LoadedAsset {
    /// Triangles the file places: a shared mesh's once per placement.
    pub fn triangle_count(&self) -> usize {
        let shared: usize = self
            .shared
            .iter()
            .map(|s| s.parts.iter().map(|m| m.indices.len()).sum::<usize>() * s.placements.len())
            .sum();
        self.meshes.iter().map(|m| m.indices.len()).sum::<usize>() + shared
    }

    /// Every vertex a triangle uses, in file space (a mesh's placed once
    /// once per use, a shared mesh's once per placement): what bounds and
    /// frames the model, leaving out points and lines that draw nothing.
    pub fn used_positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.own_positions().chain(self.shared_positions(true))
    }

    /// Points that bound every triangle: [`LoadedAsset::used_positions`]
    /// while the shared meshes' placed vertices number at most `budget`,
    /// else, for each placement of a shared mesh, the corners of its
    /// parts' boxes moved (every vertex lies inside them, so a camera that
    /// frames the corners frames the vertices): framing a file of many
    /// nodes costs a few points per node, not a mesh per node.
    pub fn framing_positions(&self, budget: usize) -> impl Iterator<Item = Vec3> + '_ {
        self.own_positions()
            .chain(self.shared_framing_positions(budget))
    }

    /// The shared meshes' part of [`LoadedAsset::framing_positions`].
    fn shared_framing_positions(&self, budget: usize) -> impl Iterator<Item = Vec3> + '_ {
        let placed: usize = self
            .shared
            .iter()
            .map(|s| s.parts.iter().map(|m| m.positions.len()).sum::<usize>() * s.placements.len())
            .sum();
        let exact = placed <= budget;
        let boxes = self.shared.iter().filter(move |_| !exact).flat_map(|s| {
            s.parts.iter().flat_map(move |part| {
                let b = part.used_vertices().fold(Aabb::EMPTY, Aabb::grow);
                let corners = b.corners();
                let placements = if b.is_finite() {
                    &s.placements[..]
                } else {
                    &[]
                };
                placements
                    .iter()
                    .flat_map(move |p| corners.map(|c| p.to_file.transform_point3(c)))
            })
        });
        self.shared_positions(exact).chain(boxes)
    }

    /// The points of [`LoadedAsset::framing_positions`] as a set: the
    /// meshes placed once give each vertex a triangle uses once (marked in
    /// parallel), not once per use, the rest as that iterator gives them.
    /// Any bound or greatest value over the points is the same, found in a
    /// sixth of the reads (a vertex of a closed mesh serves six triangles)
    /// and in parallel: a huge mesh's framing took a second on one thread.
    /// A file of one mesh whose triangles use every vertex (most files)
    /// is its own set, not a copy (84 MB of fresh pages on the
    /// 13.9M-triangle dragon).
    pub fn framing_points(&self, budget: usize) -> Cow<'_, [Vec3]> {
        let mut points: Vec<Vec3> = Vec::new();
        for m in &self.meshes {
            let used: Vec<AtomicBool> = (0..m.positions.len())
                .into_par_iter()
                .map(|_| AtomicBool::new(false))
                .collect();
            m.indices.par_iter().with_min_len(1 << 14).for_each(|t| {
                for &i in t {
                    if let Some(u) = used.get(i as usize) {
                        u.store(true, Relaxed);
                    }
                }
            });
            let own = marked(&m.positions, &used);
            let alone = self.meshes.len() == 1 && self.shared.is_empty();
            if let (true, Cow::Borrowed(_)) = (alone, &own) {
                return own;
            }
            // The first mesh's points are the list (a copy of a huge
            // mesh's would be one thread's, onto fresh pages).
            if points.is_empty() {
                points = own.into_owned();
            } else {
                points.extend_from_slice(&own);
            }
        }
        points.extend(self.shared_framing_positions(budget));
        Cow::Owned(points)
    }

    fn own_positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.meshes.iter().flat_map(|m| {
            m.indices
                .iter()
                .flatten()
                .filter_map(|&i| m.positions.get(i as usize).copied())
        })
    }

    /// Each shared mesh's used vertices under each placement (none unless
    /// `all`).
    fn shared_positions(&self, all: bool) -> impl Iterator<Item = Vec3> + '_ {
        self.shared.iter().filter(move |_| all).flat_map(|s| {
            s.parts.iter().flat_map(move |part| {
                // Found once per part, moved by each placement.
                let used: Rc<[Vec3]> = part.used_vertices().collect();
                s.placements.iter().flat_map(move |p| {
                    let used = used.clone();
                    (0..used.len()).map(move |i| p.to_file.transform_point3(used[i]))
                })
            })
        })
    }

    /// The file's meshes as copies in file space, in file order: each
    /// shared mesh's parts copied and moved by each placement (as
    /// [`LoadedMesh::placed`]), between the meshes placed once where the
    /// file places them. What a consumer of plain triangles reads (a CSG
    /// operand, `strata trace` of a model file), numbered as the file's.
    pub fn baked_meshes(&self) -> Cow<'_, [LoadedMesh]> {
        if self.shared.is_empty() {
            return Cow::Borrowed(&self.meshes);
        }
        Cow::Owned(bake(self.meshes.iter().cloned(), &self.shared))
    }

    /// The asset with every shared mesh baked ([`LoadedAsset::baked_meshes`]),
    /// the meshes placed once moved, not copied.
    pub fn into_baked(mut self) -> Self {
        if !self.shared.is_empty() {
            let shared = std::mem::take(&mut self.shared);
            self.meshes = bake(std::mem::take(&mut self.meshes).into_iter(), &shared);
        }
        self
    }
}

/// The meshes placed once (`own`, in order) with the copies of each
/// shared mesh's placements put where they fall.
fn bake(own: impl Iterator<Item = LoadedMesh>, shared: &[SharedMesh]) -> Vec<LoadedMesh> {
    let mut slots: Vec<Option<LoadedMesh>> = Vec::new();
    for s in shared {
        for p in &s.placements {
            for (k, part) in s.parts.iter().enumerate() {
                let at = p.at + k;
                if slots.len() <= at {
                    slots.resize(at + 1, None);
                }
                slots[at] = Some(part.clone().placed(&p.to_file));
            }
        }
    }
    let mut own = own.peekable();
    let mut out = Vec::with_capacity(slots.len());
    for slot in slots {
        match slot {
            Some(m) => out.push(m),
            None => out.extend(own.next()),
        }
    }
    out.extend(own);
    out
}

/// The positions whose mark is set, in order: all of them as they are
/// when every mark is set, else in a list of exactly their number: each
/// block of the marks counts its own, and then copies them where the
/// blocks before it end, all in parallel (a filtered collect grows
/// pieces and joins them on one thread, twice the fresh pages).
fn marked<'a>(positions: &'a [Vec3], used: &[AtomicBool]) -> Cow<'a, [Vec3]> {
    const BLOCK: usize = 1 << 16;
    let counts: Vec<usize> = used
        .par_chunks(BLOCK)
        .map(|u| u.iter().filter(|u| u.load(Relaxed)).count())
        .collect();
    let total = counts.iter().sum();
    if total == positions.len() {
        return Cow::Borrowed(positions);
    }
    let mut out: Vec<Vec3> = (0..total)
        .into_par_iter()
        .with_min_len(BLOCK)
        .map(|_| Vec3::ZERO)
        .collect();
    let mut parts = Vec::with_capacity(counts.len());
    let mut rest = &mut out[..];
    for &n in &counts {
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(n);
        parts.push(part);
        rest = tail;
    }
    let blocks = positions.par_chunks(BLOCK).zip(used.par_chunks(BLOCK));
    parts
        .into_par_iter()
        .zip(blocks)
        .for_each(|(part, (p, u))| {
            let kept = p.iter().zip(u).filter(|(_, u)| u.load(Relaxed));
            for (slot, (&p, _)) in part.iter_mut().zip(kept) {
                *slot = p;
            }
        });
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The marked positions, in order, as a filter finds them, over many
    /// blocks and with blocks that keep none or all, on 1 and 3 threads.
    #[test]
    fn marked_positions_are_the_filtered_ones_in_order() {
        let n = 5 * (1 << 16) + 77;
        let positions: Vec<Vec3> = (0..n).map(|i| Vec3::splat(i as f32)).collect();
        let keep = |i: usize| (i / (1 << 16) == 1) || (i / (1 << 16) != 2 && i % 7 == 3);
        let used: Vec<AtomicBool> = (0..n).map(|i| AtomicBool::new(keep(i))).collect();
        let want: Vec<Vec3> = (0..n).filter(|&i| keep(i)).map(|i| positions[i]).collect();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            assert_eq!(pool.install(|| marked(&positions, &used)), want);
        }
    }

    /// A mesh alone whose triangles use every vertex frames by its own
    /// positions, not a copy; one with a vertex no triangle uses, or
    /// beside another mesh, by a list of the used ones.
    #[test]
    fn a_lone_mesh_using_every_vertex_frames_by_its_own_positions() {
        let mesh = |indices: Vec<[u32; 3]>| LoadedMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::splat(9.0)],
            indices,
            ..LoadedMesh::default()
        };
        let every = LoadedAsset {
            meshes: vec![mesh(vec![[0, 1, 2], [1, 3, 2]])],
            ..LoadedAsset::default()
        };
        let points = every.framing_points(usize::MAX);
        assert!(matches!(points, Cow::Borrowed(_)));
        assert_eq!(&points[..], &every.meshes[0].positions[..]);
        let unused = LoadedAsset {
            meshes: vec![mesh(vec![[0, 1, 2]])],
            ..LoadedAsset::default()
        };
        let points = unused.framing_points(usize::MAX);
        assert_eq!(&points[..], &[Vec3::ZERO, Vec3::X, Vec3::Y]);
        let two = LoadedAsset {
            meshes: vec![mesh(vec![[0, 1, 2], [1, 3, 2]]), mesh(vec![[3, 2, 1]])],
            ..LoadedAsset::default()
        };
        let points = two.framing_points(usize::MAX);
        assert!(matches!(points, Cow::Owned(_)));
        assert_eq!(points.len(), 4 + 3);
    }

    /// A one-triangle mesh shared by three placements (one mirroring),
    /// beside a mesh placed once.
    fn asset() -> LoadedAsset {
        let tri = LoadedMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::splat(9.0)],
            indices: vec![[0, 1, 2]],
            ..LoadedMesh::default()
        };
        let placements = [
            Affine3A::from_translation(Vec3::Z),
            Affine3A::from_scale(Vec3::new(-2.0, 1.0, 1.0)),
            Affine3A::from_rotation_y(0.7) * Affine3A::from_translation(Vec3::X * 5.0),
        ];
        LoadedAsset {
            meshes: vec![tri
                .clone()
                .placed(&Affine3A::from_translation(Vec3::Y * 3.0))],
            shared: vec![SharedMesh {
                parts: vec![tri],
                placements: placements
                    .iter()
                    .enumerate()
                    .map(|(k, &to_file)| SharedPlacement {
                        to_file,
                        at: [0, 2, 3][k],
                    })
                    .collect(),
            }],
            ..LoadedAsset::default()
        }
    }

    #[test]
    fn framing_points_bound_every_placed_vertex_within_any_budget() {
        let a = asset();
        assert_eq!(a.triangle_count(), 4);
        let baked = a.baked_meshes();
        let baked_order: Vec<Vec3> = baked.iter().map(|m| m.positions[1]).collect();
        assert_eq!(baked_order[0], Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(
            baked_order[1],
            Vec3::new(1.0, 3.0, 0.0),
            "placed once, between"
        );
        assert_eq!(baked_order[2], Vec3::new(-2.0, 0.0, 0.0));
        assert!(baked[2].mirrored && !baked[0].mirrored);
        let every: Vec<Vec3> = baked
            .iter()
            .flat_map(|m| m.indices.iter().flatten().map(|&i| m.positions[i as usize]))
            .collect();
        let exact: Vec<Vec3> = a.framing_positions(usize::MAX).collect();
        assert_eq!(exact, a.used_positions().collect::<Vec<_>>());
        assert!(every
            .iter()
            .all(|p| exact.iter().any(|q| (*p - *q).length() < 1e-6)));
        assert!(
            !exact.contains(&Vec3::splat(9.0)),
            "an unused vertex frames nothing"
        );
        // The same points as a set, in any budget.
        for budget in [0, usize::MAX] {
            let key = |p: &Vec3| p.to_array().map(f32::to_bits);
            let mut all: Vec<_> = a.framing_positions(budget).map(|p| key(&p)).collect();
            let mut set: Vec<_> = a.framing_points(budget).iter().map(key).collect();
            assert!(set.len() <= all.len());
            for points in [&mut all, &mut set] {
                points.sort();
                points.dedup();
            }
            assert_eq!(set, all);
        }
        // By boxes: every vertex inside the hull of a placement's corners,
        // so inside their box.
        let boxes: Vec<Vec3> = a.framing_positions(0).collect();
        assert_eq!(boxes.len(), 3 + 3 * 8);
        let b = boxes.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p));
        assert!(every
            .iter()
            .all(|&p| p.cmpge(b.min).all() && p.cmple(b.max).all()));
    }
}
