//! The nearest point through an instance, in world distances.
//!
//! The prototype's tree is walked best first in object space, from the
//! query point moved there, but every candidate triangle is moved to world
//! space as a copy would hold it ([`Instance::affine`]'s `transform_point3`)
//! and measured there, so under a non-uniform or sheared map the distance
//! is the world one, and the answer the copies' bit for bit. The walk's
//! bound is the world bound moved to object space: a point at world
//! distance r is at object distance at most ‖M⁻¹‖₂·r (M⁻¹ the world-to-
//! object map), so a box farther than that, plus what rounding may add,
//! holds nothing within r ([`ObjectBound`]).

use super::{boxes_within, closest_point_on_triangle, Best};
use crate::geometry::placed_rounding::PlacedRounding;
use crate::geometry::{Geometry, Instance};
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::Aabb;
use glam::{Affine3A, Vec3};

impl Geometry {
    /// Offers `best` the nearest point of instance primitive `id` to
    /// `point` (world space), if it is nearer than `best` and within the
    /// walk's squared bound `bound` (what `reach` makes of a distance).
    pub(super) fn instance_nearest(
        &self,
        id: u32,
        point: Vec3,
        bound: f32,
        reach: &impl Fn(f32) -> f32,
        max_distance: f32,
        best: &mut Option<Best>,
    ) {
        let (instance, prototype) = self.instance(id);
        if box_distance2(&instance.world_bounds, point) > bound {
            return;
        }
        let map = instance.affine();
        let object = ObjectBound::new(instance, &map, prototype, point);
        let p = object.point;
        prototype.bvh.nearest(
            p,
            object.of(bound),
            &prototype.leaf_blocks,
            |start, count, object_bound| {
                let (b, lanes) = Geometry::leaf_lanes(start, count);
                let block = &prototype.leaf_blocks[b];
                for lane in mask_lanes(boxes_within(block, p, object_bound) & lanes) {
                    let within = block.id[lane];
                    if within >= prototype.triangle_count {
                        continue;
                    }
                    let world = block.triangle(lane).map(|v| map.transform_point3(v));
                    let q = closest_point_on_triangle(point, &world);
                    let candidate = Best {
                        d2: (point - q).length_squared(),
                        prim: id,
                        within,
                        part: (b * LANES + lane) as u32,
                        point: q,
                    };
                    Best::offer(best, candidate, max_distance);
                }
                best.map_or(object_bound, |c| object.of(reach(c.d2.sqrt())))
                    .min(object_bound)
            },
        );
    }
}

/// The squared distance from `p` to `b` (0 inside).
fn box_distance2(b: &Aabb, p: Vec3) -> f32 {
    let d = (b.min - p).max(p - b.max).max(Vec3::ZERO);
    d.length_squared()
}

/// A world bound turned into a bound for the walk of a prototype's tree
/// in object space, around the query point moved there.
struct ObjectBound {
    /// The query point in object space, as f32 computes it.
    point: Vec3,
    /// ‖M⁻¹‖₂ rounded up: how much the world-to-object map may stretch.
    stretch: f32,
    /// What rounding may move a triangle's object-space distance by: the
    /// query point's own rounding and the vertices' ([`PlacedRounding`]).
    slack: f32,
}

impl ObjectBound {
    fn new(instance: &Instance, map: &Affine3A, prototype: &Geometry, point: Vec3) -> Self {
        let rounding = PlacedRounding::new(instance, map, prototype);
        let moved = instance.to_object * point + instance.to_object_translation;
        let slack = rounding.vertex
            + PlacedRounding::moved(instance, point, true)
            + 16.0 * f32::EPSILON * moved.length();
        Self {
            point: moved,
            stretch: rounding.stretch,
            slack,
        }
    }

    /// The squared object-space box distance to open for a squared world
    /// bound (a triangle at world distance √bound is at object distance at
    /// most ‖M⁻¹‖·√bound, plus the rounding of it all).
    fn of(&self, bound: f32) -> f32 {
        let grow = 1.0 + 8.0 * f32::EPSILON;
        let r = bound.sqrt() * self.stretch * grow + self.slack;
        r * r * grow
    }
}
