//! Everything a ray can hit, and the three queries the integrator asks of
//! it: the closest hit ([`Geometry::intersect`]), occlusion
//! ([`Geometry::occluded_except`]) and the local surface at a hit
//! ([`Geometry::surface`]), each also for packets of up to eight rays.
//!
//! Triangles of every mesh are baked into world space and stored once, in
//! the BVH's leaf order ([`Geometry::leaf_blocks`]); analytic shapes keep
//! their object space ([`primitive::Shape`]); CSG trees ([`csg`]) are one
//! BVH primitive each; infinite planes stay outside the BVH. A ray goes
//! down one way: [`query`] asks the BVH ([`crate::accel`]) for leaves, the
//! [`leaf`] kernels test what they hold with the leaf primitives of
//! [`crate::shape`], and [`surface`] turns the closest hit into a
//! [`Surface`].

pub mod bundles;
pub mod crossings;
pub mod csg;
pub mod instance;
pub mod leaf;
pub mod nearest;
mod placed_rounding;
pub mod primitive;
pub mod query;
pub mod surface;

use crate::accel::{Bvh8, PrimHit};
use crate::math::lanes::LANES;
use crate::math::{Ray, Transform};
use crate::shape::plane::Plane;
use crate::shape::triangle_lanes::TriangleBlock;
pub use crossings::Crossing;
use csg::Csg;
use glam::Vec3;
pub use instance::{Instance, NO_MATERIAL};
pub use nearest::Nearest;
pub use primitive::{
    AnalyticPrim, MeshAttribute, MeshNormals, MeshRange, MeshUvs, Shape, NO_TRANSFORM,
};
pub use surface::Surface;

#[derive(Debug, Clone)]
pub struct Geometry {
    /// The BVH's leaves, eight slots to a block: slot `s` is lane `s % 8`
    /// of block `s / 8` and holds primitive `id[lane]` with, for a
    /// triangle (an id below `triangle_count`), its world-space vertices,
    /// stored once, in the order traversal reads them. The slots of
    /// analytic shapes and padding hold NaN vertices. These ids are the
    /// BVH's leaf order (its own `prim_ids` is emptied once they are
    /// here). Triangle ids stay in file order: triangle `i` of the scene's
    /// meshes is primitive `i`. Use [`Geometry::triangle`] for a hit's
    /// vertices and [`Geometry::file_order_triangles`] for a copy in file
    /// order.
    pub leaf_blocks: Vec<TriangleBlock>,
    /// Triangles in the scene: primitives `0..triangle_count`.
    pub triangle_count: u32,
    /// Sorted by `first`; covers every triangle.
    pub meshes: Vec<MeshRange>,
    /// Primitive `triangles.len() + i`.
    pub shapes: Vec<AnalyticPrim>,
    pub transforms: Vec<Transform>,
    /// The CSG trees that [`Shape::Csg`] primitives name, with their operands.
    pub csg: Csg,
    /// Unbounded, outside the BVH.
    pub planes: Vec<Plane>,
    /// Primitives `first_instance()..`: placements of the prototypes.
    pub instances: Vec<Instance>,
    /// Meshes stored once in their own object space, each with its own
    /// tree, that instances place ([`instance`]); triangles only.
    pub prototypes: Vec<Geometry>,
    pub bvh: Bvh8,
}

impl Geometry {
    pub fn primitive_count(&self) -> usize {
        self.triangle_count as usize + self.shapes.len() + self.instances.len()
    }

    /// Whether leaves may hold anything but world triangles.
    #[inline(always)]
    pub(crate) fn has_others(&self) -> bool {
        !self.shapes.is_empty() || !self.instances.is_empty()
    }

    /// The vertices of a triangle hit (its `part` is the leaf slot).
    #[inline]
    pub fn triangle(&self, hit: &PrimHit) -> [Vec3; 3] {
        let block = &self.leaf_blocks[hit.part as usize / LANES];
        debug_assert_eq!(block.id[hit.part as usize % LANES], hit.prim);
        block.triangle(hit.part as usize % LANES)
    }

    /// Every triangle in file order (a copy; for tools, not the hot loop).
    pub fn file_order_triangles(&self) -> Vec<[Vec3; 3]> {
        let mut out = vec![[Vec3::ZERO; 3]; self.triangle_count as usize];
        for block in &self.leaf_blocks {
            for (lane, &id) in block.id.iter().enumerate() {
                if id < self.triangle_count {
                    out[id as usize] = block.triangle(lane);
                }
            }
        }
        out
    }

    /// Bytes held by the per-triangle structures that tracing and shading
    /// read: BVH nodes, the leaf blocks (vertices and ids) and the shading
    /// normals of meshes that have them (materials are per mesh), the
    /// prototypes' included once and each instance's record.
    pub fn accel_bytes(&self) -> usize {
        self.own_accel_bytes() + self.prototype_bytes()
    }

    /// What the prototypes hold, each counted once, and the instances.
    pub fn prototype_bytes(&self) -> usize {
        self.prototypes
            .iter()
            .map(Geometry::accel_bytes)
            .sum::<usize>()
            + std::mem::size_of_val(self.instances.as_slice())
    }

    /// [`Geometry::accel_bytes`] of this tree alone, without prototypes.
    pub fn own_accel_bytes(&self) -> usize {
        let normals: usize = self
            .meshes
            .iter()
            .filter_map(|m| m.normals.as_ref())
            .map(|n| {
                n.values.len() * std::mem::size_of::<Vec3>()
                    + n.indices.len() * std::mem::size_of::<[u32; 3]>()
            })
            .sum();
        self.traversal_bytes() + normals
    }

    /// Bytes traversal reads: BVH nodes and leaf blocks (what decides
    /// whether it prefetches, see [`crate::accel::prefetch`]).
    pub fn traversal_bytes(&self) -> usize {
        self.bvh.memory_bytes() + std::mem::size_of_val(self.leaf_blocks.as_slice())
    }

    #[inline]
    pub(crate) fn object_ray(&self, prim: &AnalyticPrim, ray: &Ray) -> Ray {
        if prim.transform == NO_TRANSFORM {
            *ray
        } else {
            let m = &self.transforms[prim.transform as usize].to_object;
            // The direction is not renormalised, so t stays the world t.
            Ray {
                origin: m.transform_point3(ray.origin),
                direction: m.transform_vector3(ray.direction),
                tmin: ray.tmin,
                tmax: ray.tmax,
            }
        }
    }

    /// Test analytic primitive `id` (not a triangle).
    #[inline]
    pub(crate) fn hit_analytic(&self, id: u32, ray: &Ray) -> Option<PrimHit> {
        let prim = &self.shapes[(id - self.triangle_count) as usize];
        let local = self.object_ray(prim, ray);
        let hit = prim.shape.intersect(&local, &self.csg)?;
        Some(PrimHit { prim: id, ..hit })
    }

    /// Planes are reported with ids counting down from `u32::MAX`.
    pub fn plane_index(&self, prim: u32) -> Option<usize> {
        let i = (u32::MAX - prim) as usize;
        (i < self.planes.len()).then_some(i)
    }

    /// A primitive id as a user reads it: `plane 0`, `triangle 12 of mesh
    /// "bunny"`, `sphere (shape 3)`.
    pub fn describe_prim(&self, prim: u32) -> String {
        if let Some(i) = self.plane_index(prim) {
            return format!("plane {i}");
        }
        if prim < self.triangle_count {
            let mesh = self.mesh_of(prim);
            return format!(
                "triangle {} of mesh \"{}\" (primitive {prim})",
                prim - mesh.first,
                mesh.name
            );
        }
        if prim >= self.first_instance() && prim < self.primitive_count() as u32 {
            let k = prim - self.first_instance();
            return format!("instance {k} (primitive {prim})");
        }
        match self.shapes.get((prim - self.triangle_count) as usize) {
            Some(s) => format!("{} (primitive {prim})", s.shape.kind()),
            None => format!("primitive {prim}"),
        }
    }

    /// The mesh a triangle belongs to.
    pub fn mesh_of(&self, tri: u32) -> &MeshRange {
        let i = self.meshes.partition_point(|m| m.first + m.count <= tri);
        &self.meshes[i]
    }
}
