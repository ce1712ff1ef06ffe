//! Every crossing of a ray with a mesh's surface, for the mesh queries
//! (`all_hits`, `count_hits` and `contains` of the Python package): one
//! walk of the BVH that never ends early and never shortens the ray, as a
//! [`Query`] of [`crate::accel`]'s single-ray walk.
//!
//! Each triangle is tested with
//! [`crossing`](crate::shape::triangle::crossing), the watertight test
//! with its ties broken, so a ray through an edge or a vertex that
//! triangles share crosses one of them where it crosses the surface:
//! never none and never two. These are mesh queries: analytic shapes and
//! planes are not crossings.
//!
//! An instance's crossings are its prototype's triangles moved to world
//! space as a copy would hold them (the map applied as
//! [`Instance::affine`](super::Instance::affine)'s `transform_point3`
//! does, lane by lane) and tested with the world ray: the prototype's
//! tree is walked in object space, but each leaf's test is the one a mesh
//! of the copies would make, bit for bit, so t, the triangles crossed and
//! the ties at edges shared within a copy or between copies are the
//! copies' own. Testing in object space instead would round the ray once
//! more per copy and break ties at an edge two copies share differently
//! on each side.

mod placed;
mod stream;

use super::Geometry;
use crate::accel::node_test::RayPlanes;
use crate::accel::{AnyOrder, Query};
use crate::math::lanes::mask_lanes;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle_lanes;
use glam::Vec3;

/// One crossing of a ray with a triangle: its t along the ray and the
/// triangle's primitive id (triangle `i` of the scene's meshes, in file
/// order, is primitive `i`; a triangle of an instance is reported as the
/// instance, as a closest hit is).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    pub t: f32,
    pub prim: u32,
    /// The triangle's leaf slot, as a closest hit's `part` (see "What a
    /// hit's `part` says" in [`super`]): read it through
    /// [`Geometry::flat_prim`], [`Geometry::inner_prim`] or
    /// [`Geometry::world_triangle`].
    pub part: u32,
}

/// The direction of [`Geometry::contains`]'s ray: no axis, no diagonal and
/// no simple ratio of components, so that it does not run along the faces
/// and edges of axis-aligned meshes (√2 − 1, (√5 − 1)/2, 1/√3).
pub const CONTAINS_DIRECTION: Vec3 = Vec3::new(0.414_213_57, 0.618_034, 0.577_350_26);

/// The walk's question: every crossing of each leaf it reaches, handed to
/// `found` in the order the walk finds them. It never shortens the ray
/// (a crossing beyond another still counts) and never ends the walk.
struct EveryCrossing<'g, F> {
    geometry: &'g Geometry,
    found: F,
}

impl<F: FnMut(Crossing)> Query for EveryCrossing<'_, F> {
    type State = ShearedRay;
    type Answer = ();
    const SHORTENS: bool = false;

    #[inline(always)]
    fn start(&mut self, ray: &Ray) -> ShearedRay {
        ShearedRay::new(ray)
    }

    #[inline(always)]
    fn leaf(&mut self, s: &mut ShearedRay, start: u32, count: u32, ray: &mut Ray) -> bool {
        self.geometry
            .crossings_in_leaf(start, count, ray, s, &mut self.found);
        false
    }

    #[inline(always)]
    fn answer(&mut self, _: &ShearedRay, _: bool) {}
}

impl Geometry {
    /// Appends every crossing of the ray with the triangles in
    /// `(ray.tmin, ray.tmax]` to `out`, sorted by t, then by primitive id
    /// (an instance's by its prototype's triangle id after that: the order
    /// of [`Geometry::flat_prim`], a mesh of the copies' order).
    ///
    /// A ray through an edge or a vertex shared by triangles of a closed
    /// mesh, where it crosses the surface, is reported once (by the
    /// triangle that owns it, see
    /// [`crossing`](crate::shape::triangle::crossing)); where it only
    /// touches the surface (a silhouette edge or vertex) it is reported
    /// twice or not at all. Triangles only (the world's and the
    /// instances'): analytic shapes and planes are not counted.
    pub fn crossings(&self, ray: &Ray, out: &mut Vec<Crossing>) {
        let first = out.len();
        self.walk_crossings(ray, |c| out.push(c));
        out[first..].sort_unstable_by(|a, b| self.crossing_order(a, b));
    }

    /// The order of a ray's crossings: by t, then by primitive id, then
    /// (an instance's) by its prototype's triangle id.
    fn crossing_order(&self, a: &Crossing, b: &Crossing) -> std::cmp::Ordering {
        a.t.total_cmp(&b.t)
            .then(a.prim.cmp(&b.prim))
            .then_with(|| self.inner_prim(a).cmp(&self.inner_prim(b)))
    }

    /// How many crossings [`Geometry::crossings`] would append, without
    /// storing them. Triangles only.
    pub fn count_crossings(&self, ray: &Ray) -> u32 {
        let mut n = 0;
        self.walk_crossings(ray, |_| n += 1);
        n
    }

    /// Whether `point` is inside a closed mesh: an odd number of crossings
    /// along one ray from it, in the fixed direction [`CONTAINS_DIRECTION`].
    /// Robust on edges and vertices the ray meets (see
    /// [`Geometry::crossings`]); a point on the surface itself may go
    /// either way. Triangles only: analytic shapes and planes are ignored.
    ///
    /// On an open mesh (a hole, a missing face) the answer is the parity
    /// along that one direction, which another direction may contradict:
    /// it does not mean inside or outside. An empty mesh contains nothing.
    pub fn contains(&self, point: Vec3) -> bool {
        self.count_crossings(&Ray::new(point, CONTAINS_DIRECTION)) % 2 == 1
    }

    /// Walks the BVH for every crossing of the ray, in no order. The walk
    /// never ends early and never shortens the ray, so it reaches the same
    /// leaves in any order: children are taken as they come, unsorted
    /// ([`AnyOrder`]), which saves the nearest-first sort at every node.
    #[inline(always)]
    fn walk_crossings(&self, ray: &Ray, found: impl FnMut(Crossing)) {
        let mut query = EveryCrossing {
            geometry: self,
            found,
        };
        self.bvh.walk_by(
            ray,
            RayPlanes::new(ray),
            AnyOrder,
            &self.leaf_blocks,
            &mut query,
        );
    }

    /// The crossings of leaf `start..start + count`: its triangles in one
    /// 8-wide test ([`triangle_lanes::crossings`], bit for bit the scalar
    /// [`crossing`](crate::shape::triangle::crossing) that brute force
    /// uses; faster than that one by one on the dragon, as
    /// `cargo bench -p strata-benches --bench traversal -- mesh_queries` measures).
    #[inline(always)]
    fn crossings_in_leaf(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        s: &ShearedRay,
        found: &mut impl FnMut(Crossing),
    ) {
        let (b, lanes) = Self::leaf_lanes(start, count);
        let block = &self.leaf_blocks[b];
        // A scene of instances alone has no triangle in its own leaves.
        if self.triangle_count > 0 {
            let (hit, t) = triangle_lanes::crossings(ray, s, block, lanes);
            for lane in mask_lanes(hit) {
                let prim = block.id[lane];
                if prim < self.triangle_count {
                    found(Crossing {
                        t: t[lane],
                        prim,
                        part: Self::slot(b, lane),
                    });
                }
            }
        }
        if !self.instances.is_empty() {
            let instances = self.first_instance()..self.primitive_count() as u32;
            for lane in mask_lanes(lanes) {
                if instances.contains(&block.id[lane]) {
                    self.instance_crossings(block.id[lane], ray, s, found);
                }
            }
        }
    }
}
