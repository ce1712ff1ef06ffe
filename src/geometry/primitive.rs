//! What the BVH's leaves hold besides triangles: analytic shapes in their
//! own object space (a closed enum, matched in the hot loop), and the runs
//! of triangles that came from one mesh with their material and normals.

use super::csg::Csg;
use crate::accel::PrimHit;
use crate::math::{Aabb, Ray};
use crate::shape::cylinder::Cylinder;
use crate::shape::disk::Disk;
use crate::shape::rect::Rect;
use crate::shape::sphere::Sphere;
use glam::{Vec2, Vec3};
use std::ops::{Add, Mul};

/// An analytic shape in its own object space. Closed set: the hot loop matches on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    Sphere(Sphere),
    Cylinder(Cylinder),
    /// The visible surface of a `rect` area light.
    Rect(Rect),
    /// The visible surface of a `disk` area light.
    Disk(Disk),
    /// The root node of a tree in [`super::Geometry::csg`].
    Csg(u32),
}

impl Shape {
    /// The first hit in `(tmin, tmax)`; the caller fills in `prim`.
    #[inline]
    pub(super) fn intersect(&self, ray: &Ray, csg: &Csg) -> Option<PrimHit> {
        let (t, part) = match self {
            Shape::Sphere(s) => (s.intersect(ray)?, 0),
            Shape::Cylinder(c) => c.intersect(ray)?,
            Shape::Rect(r) => (r.intersect(ray)?, 0),
            Shape::Disk(d) => (d.intersect(ray)?, 0),
            Shape::Csg(root) => return csg.intersect(*root, ray),
        };
        Some(PrimHit {
            t,
            prim: 0,
            u: 0.0,
            v: 0.0,
            part,
        })
    }

    /// Object-space point, error bound and outward normal, and the material
    /// if the shape chooses it per part.
    pub(super) fn surface_at(
        &self,
        ray: &Ray,
        hit: &PrimHit,
        csg: &Csg,
    ) -> (Vec3, Vec3, Vec3, Option<u32>) {
        let (p, err, n) = match self {
            Shape::Sphere(s) => s.surface_at(ray.at(hit.t)),
            Shape::Cylinder(c) => c.surface_at(ray.at(hit.t), hit.part),
            Shape::Rect(r) => r.surface_at(ray.at(hit.t)),
            Shape::Disk(d) => d.surface_at(ray.at(hit.t)),
            Shape::Csg(_) => {
                let (p, err, n, material) = csg.surface_at(ray, hit);
                return (p, err, n, Some(material));
            }
        };
        (p, err, n, None)
    }

    /// What the shape is, in a word or two.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere(_) => "sphere",
            Shape::Cylinder(_) => "cylinder",
            Shape::Rect(_) => "rect light",
            Shape::Disk(_) => "disk light",
            Shape::Csg(_) => "CSG solid",
        }
    }

    pub fn bounds(&self, csg: &Csg) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Cylinder(c) => c.bounds(),
            Shape::Rect(r) => r.bounds(),
            Shape::Disk(d) => d.bounds(),
            Shape::Csg(root) => csg.bounds(*root),
        }
    }
}

pub const NO_TRANSFORM: u32 = u32::MAX;

/// A bounded analytic primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticPrim {
    pub shape: Shape,
    /// Index into [`super::Geometry::transforms`], or [`NO_TRANSFORM`].
    pub transform: u32,
    pub material: u32,
}

/// A run of triangles from one mesh, sharing one material. The default
/// is empty, of material 0, with no attributes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshRange {
    pub name: String,
    pub first: u32,
    pub count: u32,
    pub material: u32,
    /// Baked under a map that reverses orientation (a mirror): the world
    /// winding turns the other way than the file's, so the geometric
    /// normal, taken from the winding, is flipped back to keep pointing
    /// out of the solid (pbrt-v4's `transformSwapsHandedness`).
    pub mirrored: bool,
    /// Shading normals, only when the file had them.
    pub normals: Option<MeshNormals>,
    /// Texture coordinates, only when the file had them and the mesh's
    /// material has a texture to look up with them.
    pub uvs: Option<MeshUvs>,
    /// Tangents (xyz, and w the handedness ±1), only when the file had
    /// them (glTF `TANGENT`) and the mesh's material has a normal map.
    pub tangents: Option<MeshTangents>,
}

/// A per-corner attribute with its own per-triangle indexing (an OBJ may
/// index normals and texture coordinates apart from positions; glTF
/// repeats the position indices).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshAttribute<T> {
    pub values: Vec<T>,
    /// One entry per triangle, parallel to the mesh's vertex indices.
    pub indices: Vec<[u32; 3]>,
}

/// Shading normals of a mesh's corners.
pub type MeshNormals = MeshAttribute<Vec3>;

/// Texture coordinates of a mesh's corners, in the texture space of
/// [`crate::texture`] (`(0, 0)` the top-left of the image).
pub type MeshUvs = MeshAttribute<Vec2>;

/// Tangents of a mesh's corners: xyz along ∂p/∂u, w = ±1 the sign of the
/// bitangent `w (n × t)` (glTF 2.0, `TANGENT`).
pub type MeshTangents = MeshAttribute<glam::Vec4>;

impl<T: Copy + Add<Output = T>> MeshAttribute<T>
where
    f32: Mul<T, Output = T>,
{
    /// The attribute at barycentric weights `b` in triangle `tri` (counted
    /// from the mesh's first).
    #[inline]
    pub fn interpolate(&self, tri: usize, b: [f32; 3]) -> T {
        let idx = self.indices[tri];
        b[0] * self.values[idx[0] as usize]
            + b[1] * self.values[idx[1] as usize]
            + b[2] * self.values[idx[2] as usize]
    }
}
