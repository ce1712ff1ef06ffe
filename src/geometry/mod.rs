//! Everything a ray can hit, and the three queries the integrator asks of
//! it: the closest hit ([`Geometry::intersect`]), occlusion
//! ([`Geometry::occluded_except`]) and the local surface at a hit
//! ([`Geometry::surface`]), each also for packets of up to eight rays.
//!
//! Triangles of every mesh are baked into world space and stored once, in
//! the BVH's leaf order, eight *slots* to a block (the leaf store, private
//! to this module: [`Geometry::slot_prim`], [`Geometry::slot_triangle`]);
//! analytic shapes keep their object space ([`primitive::Shape`]); CSG
//! trees ([`csg`]) are one BVH primitive each; infinite planes stay
//! outside the BVH. A ray goes down one way: [`query`] asks the BVH
//! ([`crate::accel`]) for leaves, the [`leaf`] kernels test what they hold
//! with the leaf primitives of [`crate::shape`], and [`surface`] turns the
//! closest hit into a [`Surface`]. How a set of rays travels (alone, as a
//! packet, as bundles, several in flight) is decided in [`travel`].
//!
//! # What a hit's `part` says
//!
//! [`PrimHit::part`], [`Crossing::part`] and [`Nearest::part`] say which
//! part of primitive `prim` was found, by what `prim` is:
//!
//! | `prim` | `part` |
//! |---|---|
//! | a triangle (below [`Geometry::triangle_count`]) | its leaf slot here |
//! | an instance ([`Geometry::first_instance`] on) | the leaf slot of its prototype's triangle |
//! | a cylinder | 0 the side, 1 the bottom cap, 2 the top cap |
//! | a CSG tree | the operand's code ([`csg::Csg`]) |
//! | another shape or a plane | 0 |
//!
//! Outside this module a part is read only through [`Geometry::slot_of`],
//! [`Geometry::triangle`], [`Geometry::world_triangle`],
//! [`Geometry::object_triangle`], [`Geometry::inner_prim`] and
//! [`Geometry::flat_prim`], never decoded by hand.

pub mod crossings;
pub mod csg;
pub mod instance;
mod instance_bundle;
#[cfg(test)]
mod interval_tests;
pub mod leaf;
pub mod nearest;
mod placed_rounding;
pub mod primitive;
pub mod query;
pub mod surface;
pub mod travel;

use crate::accel::pages::{collect_on, move_to_huge_pages, Pages};
use crate::accel::{Bvh8, PrimHit};
use crate::math::lanes::LANES;
use crate::math::{Ray, Transform};
use crate::shape::plane::Plane;
use crate::shape::plane_lanes::PlaneLanes;
use crate::shape::triangle_lanes::TriangleBlock;
pub use crossings::Crossing;
use csg::Csg;
use glam::Vec3;
pub use instance::{Instance, NO_MATERIAL};
pub use nearest::Nearest;
pub use primitive::{
    AnalyticPrim, MeshAttribute, MeshNormals, MeshRange, MeshTangents, MeshUvs, Shape, NO_TRANSFORM,
};
use rayon::prelude::*;
pub use surface::Surface;

#[derive(Debug, Clone)]
pub struct Geometry {
    /// The leaf store: the BVH's leaves, eight slots to a block, slot `s`
    /// being lane `s % 8` of block `s / 8` and holding primitive
    /// `id[lane]` with, for a triangle (an id below `triangle_count`), its
    /// world-space vertices, stored once, in the order traversal reads
    /// them. The slots of analytic shapes and padding hold NaN vertices.
    /// These ids are the BVH's leaf order (its own `prim_ids` is emptied
    /// once they are here). Triangle ids stay in file order: triangle `i`
    /// of the scene's meshes is primitive `i`. Private to this module: the
    /// rest of the crate reads it through [`Geometry::slot_prim`],
    /// [`Geometry::slot_triangle`] and [`Geometry::triangle`].
    leaf_blocks: Vec<TriangleBlock>,
    /// Triangles in the scene: primitives `0..triangle_count`.
    pub(crate) triangle_count: u32,
    /// Sorted by `first`; covers every triangle.
    pub(crate) meshes: Vec<MeshRange>,
    /// Primitive `triangle_count + i`.
    pub(crate) shapes: Vec<AnalyticPrim>,
    pub(crate) transforms: Vec<Transform>,
    /// The CSG trees that [`Shape::Csg`] primitives name, with their operands.
    pub(crate) csg: Csg,
    /// Unbounded, outside the BVH.
    pub(crate) planes: Vec<Plane>,
    /// The same planes eight to a SIMD chunk, which every ray is tested
    /// against.
    pub(crate) plane_lanes: PlaneLanes,
    /// Primitives `first_instance()..`: placements of the prototypes.
    pub(crate) instances: Vec<Instance>,
    /// Meshes stored once in their own object space, each with its own
    /// tree, that instances place ([`instance`]); triangles only.
    pub(crate) prototypes: Vec<Geometry>,
    pub(crate) bvh: Bvh8,
}

/// Where [`Geometry::new`] reads each triangle's vertices, by primitive
/// id: a closure, or a store that can also be asked ahead for the memory
/// a triangle's read will touch, in two steps (its indices, then, once
/// those are near, its vertices).
pub trait TriangleVertices: Sync {
    fn vertices(&self, id: u32) -> [Vec3; 3];
    /// Asks for the first memory triangle `id`'s read touches (its
    /// indices, or a soup's vertices) without waiting.
    #[inline(always)]
    fn prefetch_indices(&self, _id: u32) {}
    /// Asks for triangle `id`'s vertices without waiting.
    #[inline(always)]
    fn prefetch_vertices(&self, _id: u32) {}
}

impl<F: Fn(u32) -> [Vec3; 3] + Sync> TriangleVertices for F {
    #[inline(always)]
    fn vertices(&self, id: u32) -> [Vec3; 3] {
        self(id)
    }
}

/// What a [`Geometry`] holds besides its tree and its leaf store, as the
/// scene's compiler gathers it ([`Geometry::new`]).
#[derive(Debug, Default)]
pub struct GeometryParts {
    /// Sorted by `first`, covering triangles `0..n` without a gap.
    pub meshes: Vec<MeshRange>,
    pub shapes: Vec<AnalyticPrim>,
    pub transforms: Vec<Transform>,
    pub csg: Csg,
    pub planes: Vec<Plane>,
    pub instances: Vec<Instance>,
    pub prototypes: Vec<Geometry>,
}

/// Something found on a primitive: a closest hit ([`PrimHit`]), a
/// [`Crossing`] or a [`Nearest`] point, named by its primitive and the
/// part of it (module docs, "What a hit's `part` says").
pub trait Found {
    fn prim(&self) -> u32;
    fn part(&self) -> u32;
}

/// Each record keeps its primitive and part in fields of those names.
macro_rules! found_by_fields {
    ($($record:ty),*) => {$(
        impl Found for $record {
            #[inline(always)]
            fn prim(&self) -> u32 {
                self.prim
            }
            #[inline(always)]
            fn part(&self) -> u32 {
                self.part
            }
        }
    )*};
}

found_by_fields!(PrimHit, Crossing, Nearest);

impl Geometry {
    /// A geometry over `bvh`, whose leaf order (`prim_ids`) becomes the
    /// leaf store: a slot holding triangle `id` (below the meshes' count)
    /// stores `vertices(id)`, read straight from the caller's sources, so
    /// the triangles are never held twice; other slots keep their id alone.
    /// The tree's own `prim_ids` is emptied.
    pub fn new(parts: GeometryParts, mut bvh: Bvh8, vertices: impl TriangleVertices) -> Self {
        let triangle_count = parts.meshes.last().map_or(0, |m| m.first + m.count);
        // Slots in leaf order are triangles in no order of their sources,
        // so each read would wait for memory: a block asks ahead for the
        // indices of the triangles four blocks on (where they are indexed)
        // and for the vertices of those two blocks on, whose indices the
        // blocks before asked for.
        let prim_ids = &bvh.prim_ids;
        let ahead = |b: usize| {
            let slots = prim_ids.get(b * LANES..(b + 1) * LANES).unwrap_or(&[]);
            slots.iter().copied().filter(|&id| id < triangle_count)
        };
        // On the nodes' pages (`Bvh8::set_pages`).
        let leaf_blocks = collect_on(
            bvh.pages,
            prim_ids.par_chunks(LANES).enumerate().map(|(b, ids)| {
                ahead(b + 4).for_each(|id| vertices.prefetch_indices(id));
                ahead(b + 2).for_each(|id| vertices.prefetch_vertices(id));
                let mut block = TriangleBlock::EMPTY;
                for (lane, &id) in ids.iter().enumerate() {
                    if id < triangle_count {
                        block.set(lane, &vertices.vertices(id), id);
                    } else {
                        block.id[lane] = id;
                    }
                }
                block
            }),
        );
        bvh.prim_ids = Vec::new();
        let GeometryParts {
            meshes,
            shapes,
            transforms,
            csg,
            planes,
            instances,
            prototypes,
        } = parts;
        Self {
            leaf_blocks,
            triangle_count,
            meshes,
            shapes,
            transforms,
            csg,
            plane_lanes: PlaneLanes::new(&planes),
            planes,
            instances,
            prototypes,
            bvh,
        }
    }

    pub fn primitive_count(&self) -> usize {
        self.triangle_count as usize + self.shapes.len() + self.instances.len()
    }

    /// Triangles in this tree's own leaves: primitives `0..triangle_count`
    /// (a prototype's are counted in [`Geometry::unique_triangles`]).
    #[inline(always)]
    pub fn triangle_count(&self) -> u32 {
        self.triangle_count
    }

    /// The meshes, sorted by their first triangle, covering every triangle.
    pub fn meshes(&self) -> &[MeshRange] {
        &self.meshes
    }

    /// The analytic shapes: shape `i` is primitive `triangle_count() + i`.
    pub fn shapes(&self) -> &[AnalyticPrim] {
        &self.shapes
    }

    /// The CSG trees that [`Shape::Csg`] primitives name.
    pub fn csg(&self) -> &Csg {
        &self.csg
    }

    /// The infinite planes, outside the BVH.
    pub fn planes(&self) -> &[Plane] {
        &self.planes
    }

    /// The placements of prototypes: instance `k` is primitive
    /// `first_instance() + k`.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// The meshes instances place, each a geometry of triangles alone.
    pub fn prototypes(&self) -> &[Geometry] {
        &self.prototypes
    }

    /// The tree over every bounded primitive.
    pub fn bvh(&self) -> &Bvh8 {
        &self.bvh
    }

    /// Puts the tree and the leaf blocks back on the pages the tree was
    /// built for after a `clone`, which copies them into plain vectors (on
    /// small pages): a copy kept to be walked (a prototype made of a mesh)
    /// walks as fast as the original. In place; nothing for small pages.
    pub fn restore_pages(&mut self) {
        if self.bvh.pages == Pages::Huge {
            self.bvh.set_pages(Pages::Huge);
            move_to_huge_pages(&self.leaf_blocks);
        }
    }

    /// Whether walks prefetch deferred children and keep several rays in
    /// flight ([`crate::accel::prefetch`]): it changes no answer, only time.
    pub fn set_prefetch(&mut self, on: bool) {
        self.bvh.prefetch = on;
    }

    /// Whether leaves may hold anything but world triangles.
    #[inline(always)]
    pub(crate) fn has_others(&self) -> bool {
        !self.shapes.is_empty() || !self.instances.is_empty()
    }

    /// The slot of lane `lane` of leaf block `block`: what a triangle's
    /// `part` records.
    #[inline(always)]
    pub(crate) fn slot(block: usize, lane: usize) -> u32 {
        (block * LANES + lane) as u32
    }

    /// Leaf slots in this tree's leaf order: the primitive each holds
    /// ([`crate::accel::NO_PRIM`] for padding), slot `s` the `s`-th.
    pub fn leaf_slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.leaf_blocks.iter().flat_map(|b| b.id)
    }

    /// The primitive leaf slot `slot` holds.
    #[inline(always)]
    pub fn slot_prim(&self, slot: u32) -> u32 {
        let slot = slot as usize;
        self.leaf_blocks[slot / LANES].id[slot % LANES]
    }

    /// The vertices leaf slot `slot` stores (NaN where it holds no triangle).
    #[inline]
    pub fn slot_triangle(&self, slot: u32) -> [Vec3; 3] {
        let slot = slot as usize;
        self.leaf_blocks[slot / LANES].triangle(slot % LANES)
    }

    /// The leaf slot of a triangle found: in this tree's leaves for a world
    /// triangle, in its prototype's for an instance's (module docs).
    #[inline(always)]
    pub fn slot_of(found: &impl Found) -> u32 {
        found.part()
    }

    /// The vertices of a world triangle found (its `part` is the leaf slot).
    #[inline]
    pub fn triangle(&self, found: &impl Found) -> [Vec3; 3] {
        debug_assert_eq!(self.slot_prim(found.part()), found.prim());
        self.slot_triangle(found.part())
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
        // A few meshes (a scene whose every object is a mesh of its own)
        // are counted without a branch: the binary search's compares
        // mispredicted, a third of `surface`'s time on cornell.
        let i = if self.meshes.len() <= 16 {
            self.meshes
                .iter()
                .map(|m| usize::from(m.first + m.count <= tri))
                .sum()
        } else {
            self.meshes.partition_point(|m| m.first + m.count <= tri)
        };
        &self.meshes[i]
    }
}

#[cfg(test)]
mod tests {
    use super::{Geometry, GeometryParts, MeshRange};
    use crate::accel::pages::{marked_huge, Pages};
    use crate::accel::{BuildQuality, Bvh8};
    use crate::math::Aabb;
    use glam::Vec3;

    /// The leaf blocks go on the pages the tree was moved to, the same
    /// blocks as on small pages.
    #[test]
    fn the_leaf_blocks_go_on_the_tree_s_pages() {
        let n = 400u32;
        let corner = |i: u32| Vec3::new((i % n) as f32, (i / n) as f32, (i % 13) as f32 * 0.1);
        let tris: Vec<[Vec3; 3]> = (0..n * (n - 1))
            .map(|i| [corner(i), corner(i + 1), corner(i + n)])
            .collect();
        let geometry = |pages: Pages| {
            let boxes = tris.iter().map(|t| Aabb::from_points(t)).collect();
            let mut bvh = Bvh8::build_from(boxes, BuildQuality::Preview);
            bvh.set_pages(pages);
            let parts = GeometryParts {
                meshes: vec![MeshRange {
                    name: "grid".into(),
                    count: tris.len() as u32,
                    ..MeshRange::default()
                }],
                ..GeometryParts::default()
            };
            Geometry::new(parts, bvh, |id| tris[id as usize])
        };
        let (small, huge) = (geometry(Pages::Small), geometry(Pages::Huge));
        assert!(std::mem::size_of_val(huge.leaf_blocks.as_slice()) >= 4 << 20);
        let ids = |g: &Geometry| g.leaf_blocks.iter().flat_map(|b| b.id).collect::<Vec<_>>();
        assert_eq!(ids(&small), ids(&huge));
        // Whether memory on small pages shows as advised is the
        // allocator's to say (it may hand out a range advised before), so
        // only the huge side is checked.
        assert_ne!(marked_huge(&huge.leaf_blocks), Some(false));
        // A clone is copied into plain vectors; its pages are restored.
        let mut copy = huge.clone();
        copy.restore_pages();
        assert_ne!(marked_huge(&copy.leaf_blocks), Some(false));
        assert_eq!(ids(&copy), ids(&huge));
    }

    /// Every triangle's mesh is the one whose range holds it, counted (up
    /// to 16 meshes) or searched (more), empty meshes among them.
    #[test]
    fn every_triangle_finds_its_mesh_among_few_or_many() {
        for n in [1u32, 2, 7, 16, 17, 40] {
            // Mesh k holds k % 4 triangles (the first one at least one).
            let counts: Vec<u32> = (0..n).map(|k| if k == 0 { 1 } else { k % 4 }).collect();
            let mut meshes = Vec::new();
            let mut first = 0;
            for (k, &count) in counts.iter().enumerate() {
                meshes.push(MeshRange {
                    name: format!("m{k}"),
                    first,
                    count,
                    material: k as u32,
                    ..MeshRange::default()
                });
                first += count;
            }
            let tri = |i: u32| {
                [
                    Vec3::new(i as f32, 0.0, 0.0),
                    Vec3::new(i as f32, 1.0, 0.0),
                    Vec3::Z,
                ]
            };
            let boxes = (0..first).map(|i| Aabb::from_points(&tri(i))).collect();
            let bvh = Bvh8::build_from(boxes, BuildQuality::Preview);
            let parts = GeometryParts {
                meshes,
                ..GeometryParts::default()
            };
            let g = Geometry::new(parts, bvh, tri);
            for t in 0..first {
                let m = g.mesh_of(t);
                assert!(
                    m.first <= t && t < m.first + m.count,
                    "{n} meshes, triangle {t}: {}",
                    m.name
                );
            }
        }
    }
}
