//! The nearest point through an instance, in world distances.
//!
//! The prototype's tree is walked best first, but every candidate triangle
//! is moved to world space as a copy would hold it ([`Instance::affine`]'s
//! `transform_point3`) and measured there, so under a non-uniform or
//! sheared map the distance is the world one, and the answer the copies'
//! bit for bit. The walk orders and prunes the prototype's boxes by a
//! lower bound of their world distance, the larger of two
//! ([`LowerBound`]): the distance to the world box around the box's image
//! (tight far away and under axis-aligned stretches), and the object-space
//! distance divided by ‖M⁻¹‖₂ (M⁻¹ the world-to-object map; exact under
//! rotations and uniform scales). A leaf's triangles are sifted in object
//! space by the world bound stretched by ‖M⁻¹‖₂ ([`ObjectBound`]), before
//! they are moved. Each bound carries what rounding may add
//! ([`PlacedRounding`]), so no triangle the copies would answer is culled.

use super::{boxes_within, closest_point_on_triangle, Best};
use crate::accel::{ChildBoxes, NearestQueue, NodeTest};
use crate::geometry::placed_rounding::PlacedRounding;
use crate::geometry::{Geometry, Instance};
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::Aabb;
use glam::{Affine3A, Vec3};
use wide::f32x8;

impl Geometry {
    /// Offers `best` the nearest point of instance primitive `id` to
    /// `point` (world space), if it is nearer than `best` and within the
    /// walk's squared bound `bound` (what `reach` makes of a distance).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn instance_nearest(
        &self,
        id: u32,
        point: Vec3,
        bound: f32,
        reach: &impl Fn(f32) -> f32,
        max_distance: f32,
        best: &mut Option<Best>,
        queue: &mut NearestQueue,
    ) {
        let (instance, prototype) = self.instance(id);
        if box_distance2(&instance.world_bounds, point) > bound || prototype.bvh.is_empty() {
            return;
        }
        let map = instance.affine();
        let rounding = PlacedRounding::new(instance, &map, prototype);
        let object = ObjectBound::new(instance, &rounding, point);
        let lower = LowerBound::new(&map, &rounding, &object, point);
        let p = object.point;
        let blocks = &prototype.leaf_blocks;
        prototype
            .bvh
            .nearest_by(lower, bound, blocks, queue, |start, count, bound| {
                let (b, lanes) = Geometry::leaf_lanes(start, count);
                let block = &blocks[b];
                for lane in mask_lanes(boxes_within(block, p, object.of(bound)) & lanes) {
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
                best.map_or(bound, |c| reach(c.d2.sqrt())).min(bound)
            });
    }
}

/// A lower bound of the world distance from the query point to anything in
/// each of a prototype node's eight child boxes, squared.
struct LowerBound {
    /// The query point in world space and in object space.
    world: [f32x8; 3],
    object: [f32x8; 3],
    /// The object-to-world map by rows, its absolute values, its shift.
    rows: [[f32; 3]; 3],
    abs_rows: [[f32; 3]; 3],
    shift: [f32; 3],
    /// What rounding may move a world box or a triangle by, per axis.
    world_slack: f32,
    /// The object-space slack, and 1 / ‖M⁻¹‖₂ rounded down.
    object_slack: f32,
    shrink: f32,
}

impl LowerBound {
    fn new(map: &Affine3A, rounding: &PlacedRounding, object: &ObjectBound, point: Vec3) -> Self {
        let m = map.matrix3.transpose().to_cols_array_2d();
        Self {
            world: point.to_array().map(f32x8::splat),
            object: object.point.to_array().map(f32x8::splat),
            rows: m,
            abs_rows: m.map(|row| row.map(f32::abs)),
            shift: map.translation.to_array(),
            world_slack: rounding.world,
            object_slack: object.slack,
            shrink: (1.0 / object.stretch) * (1.0 - 4.0 * f32::EPSILON),
        }
    }

    /// The larger of the distance to each child's box moved to world space
    /// (its centre moved, its half extent by |M|) and its object-space
    /// distance shrunk by ‖M⁻¹‖₂, less rounding; garbage for empty slots.
    #[inline(always)]
    fn of(&self, boxes: ChildBoxes<'_>) -> f32x8 {
        let zero = f32x8::ZERO;
        let half = f32x8::splat(0.5);
        let lo = |axis: usize| boxes.lo(axis);
        let hi = |axis: usize| boxes.hi(axis);
        let centre = [0, 1, 2].map(|j| (lo(j) + hi(j)) * half);
        let extent = [0, 1, 2].map(|j| (hi(j) - lo(j)) * half);
        let mut world = zero;
        let mut object = zero;
        for a in 0..3 {
            let row = |j: usize| f32x8::splat(self.rows[a][j]);
            let abs_row = |j: usize| f32x8::splat(self.abs_rows[a][j]);
            let c = centre[0] * row(0)
                + centre[1] * row(1)
                + centre[2] * row(2)
                + f32x8::splat(self.shift[a]);
            let h = extent[0] * abs_row(0)
                + extent[1] * abs_row(1)
                + extent[2] * abs_row(2)
                + f32x8::splat(self.world_slack);
            let d = ((self.world[a] - c).abs() - h).fast_max(zero);
            world += d * d;
            let d = (lo(a) - self.object[a])
                .fast_max(self.object[a] - hi(a))
                .fast_max(zero);
            object += d * d;
        }
        let object = ((object.sqrt() - f32x8::splat(self.object_slack)).fast_max(zero))
            * f32x8::splat(self.shrink);
        world.fast_max(object * object)
    }
}

impl NodeTest for LowerBound {
    /// The squared lower bounds, and the children within `reach`, a
    /// squared world distance.
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        let d2 = self.of(boxes);
        (d2, d2.simd_le(f32x8::splat(reach)).to_bitmask())
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
    fn new(instance: &Instance, rounding: &PlacedRounding, point: Vec3) -> Self {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::node_test::tests::{brute_nearest, walk_nearest};
    use crate::accel::{BuildQuality, Bvh8};
    use crate::geometry::instance::NO_MATERIAL;
    use crate::geometry::placed_rounding::spectral_norm;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Mat3;

    /// The best-first walk of a tree of object-space points, ordered and
    /// pruned by [`LowerBound`], finds the point nearest in world space
    /// (each point moved as a copy holds it) that brute force finds, under
    /// non-uniform scales, shears and mirrors, with and without a bound;
    /// and it prunes. A bound that overestimated a box's world distance
    /// (a map's rows for its columns, ‖M⁻¹‖ left out) would cull the
    /// nearest point.
    #[test]
    fn the_lower_bound_walk_finds_the_nearest_world_point_of_brute_force() {
        let mut rng = seeded(77);
        let points: Vec<Vec3> = (0..2000).map(|_| rng.cube(4.0)).collect();
        let boxes: Vec<Aabb> = points.iter().map(|&p| Aabb::new(p, p)).collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        let mut queue = NearestQueue::new();
        let (mut opened_all, mut walks) = (0, 0);
        for i in 0..300 {
            let scale = Vec3::new(
                rng.range(0.2, 3.0),
                rng.range(0.2, 3.0),
                rng.range(0.2, 3.0),
            );
            let mirror = if i % 2 == 0 { -1.0 } else { 1.0 };
            let shear = Mat3::from_cols(
                Vec3::X,
                Vec3::new(rng.range(-0.5, 0.5), 1.0, 0.0),
                Vec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), mirror),
            );
            let m = Mat3::from_diagonal(scale) * shear;
            let to_world = Affine3A::from_mat3_translation(m, rng.cube(20.0));
            let instance = Instance::new(to_world, 0, NO_MATERIAL, 0).expect("invertible");
            let map = instance.affine();
            // The rounding as `PlacedRounding::new` sizes it for this box.
            let extent = Vec3::splat(2.0);
            let to_world = Mat3::from(map.matrix3);
            let abs = Mat3::from_cols(
                to_world.x_axis.abs(),
                to_world.y_axis.abs(),
                to_world.z_axis.abs(),
            );
            let world = (abs * extent + Vec3::from(map.translation).abs()).length();
            let stretch = spectral_norm(instance.to_object);
            let wide = 16.0 * f32::EPSILON;
            let cond = stretch
                * (abs.x_axis.length_squared()
                    + abs.y_axis.length_squared()
                    + abs.z_axis.length_squared())
                .sqrt();
            let rounding = PlacedRounding {
                stretch,
                vertex: wide * (stretch * world + (cond + 1.0) * extent.length()),
                world: 2.0 * wide * world,
            };
            let q = rng.cube(60.0);
            let limit = if i % 3 == 0 {
                rng.range(1.0, 100.0)
            } else {
                f32::INFINITY
            };
            let moved: Vec<Vec3> = points.iter().map(|&p| map.transform_point3(p)).collect();
            let brute = brute_nearest(&moved, q, limit);
            let object = ObjectBound::new(&instance, &rounding, q);
            let lower = LowerBound::new(&map, &rounding, &object, q);
            let (best, opened) = walk_nearest(&bvh, lower, limit, &mut queue, &moved, q);
            assert_eq!(best, brute, "map {i}: {m}, limit {limit}");
            opened_all += opened;
            walks += 1;
        }
        let leaves = bvh.prim_ids.len() / 4;
        assert!(
            opened_all < walks * leaves / 10,
            "{opened_all} leaves in {walks} walks: the bound prunes"
        );
    }
}
