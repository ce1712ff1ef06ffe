//! The crossings of an instance: its prototype's tree walked in object
//! space, each leaf's triangles moved to world space as a copy holds them
//! and tested with the world ray.
//!
//! The walk must not cull a box that holds a triangle the world test
//! crosses, though the object-space ray is the world ray rounded: a ray
//! aimed at a vertex meets it at a corner of the boxes around it, and the
//! rounded ray may pass that corner on the outside. So the walk has a
//! node test of its own ([`GrownSlab`]): every child box grown by what
//! rounding may move the ray and the triangles in object space
//! ([`PlacedRounding`]); and it walks in any order (a crossing query
//! needs none).

use super::Crossing;
use crate::accel::{AnyOrder, ChildBoxes, EveryLeaf, NodeTest};
use crate::geometry::placed_rounding::PlacedRounding;
use crate::geometry::Geometry;
use crate::math::lanes::{mask_lanes, LANES};
use crate::math::offset::gamma;
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use crate::shape::triangle_lanes::{self, TriangleBlock};
use glam::Affine3A;
use wide::f32x8;

impl Geometry {
    /// The crossings of instance primitive `id` with the world `ray`
    /// (`s`, its shear).
    pub(super) fn instance_crossings(
        &self,
        id: u32,
        ray: &Ray,
        s: &ShearedRay,
        found: &mut impl FnMut(Crossing),
    ) {
        let (instance, prototype) = self.instance(id);
        if !instance.may_hit(ray) {
            return;
        }
        let map = instance.affine();
        let rounding = PlacedRounding::new(instance, &map, prototype);
        // Where the ray leaves the instance's box: no triangle of it lies
        // farther along, so the ray's rounding need only be bounded so far.
        let b = &instance.world_bounds;
        let inv = ray.direction.recip();
        let t0 = (b.min - ray.origin) * inv;
        let t1 = (b.max - ray.origin) * inv;
        let end = t0.max(t1).min_element().min(ray.tmax).abs();
        let end = if end.is_finite() { end } else { f32::MAX };
        let walk_ray = instance.object_ray(ray);
        let margin = rounding.vertex
            + PlacedRounding::moved(instance, ray.origin, true)
            + end * PlacedRounding::moved(instance, ray.direction, false)
            + 16.0 * f32::EPSILON * (walk_ray.origin.length() + end * walk_ray.direction.length());
        let mut query = PlacedCrossings {
            prototype,
            map,
            id,
            ray,
            sheared: s,
            found,
        };
        prototype.bvh.walk_by(
            &walk_ray,
            GrownSlab::new(&walk_ray, margin),
            AnyOrder,
            &prototype.leaf_blocks,
            &mut EveryLeaf(|start, count| query.leaf(start, count)),
        );
    }
}

/// The node test of an instance's walk: every child box grown by
/// `margin` on every side, met by the ray somewhere in `[tmin, reach]`,
/// both ends widened by 2γ(3) of their magnitude, as the walks widen
/// theirs (Ize 2013).
struct GrownSlab {
    origin: [f32; 3],
    /// The reciprocal direction, a zero component the least normal one
    /// (so that a slab the ray lies in reads 0·∞ as 0, not NaN).
    inv: [f32; 3],
    margin: f32x8,
    tmin: f32,
}

impl GrownSlab {
    fn new(ray: &Ray, margin: f32) -> Self {
        let inv = ray.direction.to_array().map(|d| {
            1.0 / if d == 0.0 {
                f32::MIN_POSITIVE.copysign(d)
            } else {
                d
            }
        });
        Self {
            origin: ray.origin.to_array(),
            inv,
            margin: f32x8::splat(margin),
            tmin: ray.tmin,
        }
    }
}

impl NodeTest for GrownSlab {
    #[inline(always)]
    fn test(&self, boxes: ChildBoxes<'_>, reach: f32) -> (f32x8, u32) {
        let g = f32x8::splat(2.0 * gamma(3));
        let mut near = f32x8::splat(self.tmin);
        let mut far = f32x8::splat(reach);
        for axis in 0..3 {
            let lo = boxes.lo(axis) - self.margin;
            let hi = boxes.hi(axis) + self.margin;
            let inv = self.inv[axis];
            let (enter, leave) = if inv >= 0.0 { (lo, hi) } else { (hi, lo) };
            let (o, i) = (f32x8::splat(self.origin[axis]), f32x8::splat(inv));
            near = near.fast_max((enter - o) * i);
            far = far.fast_min((leave - o) * i);
        }
        let meets = (near - g * near.abs()).simd_le(far + g * far.abs());
        (near, meets.to_bitmask())
    }
}

/// The leaf test of an instance's prototype for every crossing: each
/// leaf's triangles moved to world space by `map` and tested with the
/// world `ray`, reported as instance `id`.
struct PlacedCrossings<'g, 'f, F> {
    prototype: &'g Geometry,
    map: Affine3A,
    id: u32,
    ray: &'g Ray,
    sheared: &'g ShearedRay,
    found: &'f mut F,
}

impl<F: FnMut(Crossing)> PlacedCrossings<'_, '_, F> {
    #[inline(always)]
    fn leaf(&mut self, start: u32, count: u32) {
        let (b, lanes) = Geometry::leaf_lanes(start, count);
        let block = &self.prototype.leaf_blocks[b];
        let world = moved_block(block, &self.map);
        let (hit, t) = triangle_lanes::crossings(self.ray, self.sheared, &world, lanes);
        for lane in mask_lanes(hit) {
            if block.id[lane] < self.prototype.triangle_count {
                (self.found)(Crossing {
                    t: t[lane],
                    prim: self.id,
                    part: (b * LANES + lane) as u32,
                });
            }
        }
    }
}

/// `block`'s triangles moved by `map`, each coordinate rounded as glam's
/// `Affine3A::transform_point3` rounds it (x·m₀ + y·m₁, + z·m₂, + t, with
/// no fused step), so that they are the copies' vertices bit for bit.
#[inline(always)]
fn moved_block(block: &TriangleBlock, map: &Affine3A) -> TriangleBlock {
    let m = map.matrix3.to_cols_array_2d();
    let shift = map.translation.to_array();
    let mut out = TriangleBlock {
        v: block.v,
        id: block.id,
    };
    for k in 0..3 {
        let [x, y, z] = [0, 1, 2].map(|axis| f32x8::from(block.v[3 * k + axis]));
        for axis in 0..3 {
            let column = |c: usize| f32x8::splat(m[c][axis]);
            let moved = x * column(0) + y * column(1) + z * column(2) + f32x8::splat(shift[axis]);
            out.v[3 * k + axis] = moved.to_array();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::node_test::tests::meets_grown;
    use crate::accel::{BuildQuality, Bvh8, NO_PRIM};
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;
    use std::collections::BTreeSet;

    /// The primitives in the leaves a walk of `ray` reaches: with `grown`
    /// the instance walk's, else the ray's own ([`Bvh8::walk`]).
    fn reached(bvh: &Bvh8, ray: &Ray, grown: Option<GrownSlab>) -> BTreeSet<u32> {
        let mut prims = BTreeSet::new();
        let mut every = EveryLeaf(|start, count| {
            prims.extend(bvh.leaf_prims(start, count).map(|(_, id)| id));
        });
        match grown {
            Some(test) => bvh.walk_by(ray, test, AnyOrder, &[] as &[()], &mut every),
            None => bvh.walk(ray, &[] as &[()], &mut every),
        }
        prims.remove(&NO_PRIM);
        prims
    }

    /// The grown slab reaches every leaf the ray's own walk reaches and
    /// every leaf holding a box that the ray meets once grown by the
    /// margin (brute force in f64), rays through vertices of the boxes
    /// and along their faces included; and it still prunes.
    #[test]
    fn the_grown_slab_reaches_a_superset_of_the_ray_s_leaves_and_every_grown_box() {
        let mut rng = seeded(31);
        let boxes: Vec<Aabb> = (0..2000)
            .map(|_| {
                let c = rng.cube(20.0);
                let h = rng.cube(0.8).abs();
                Aabb::new(c - h, c + h)
            })
            .collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        let (mut extra, mut total) = (0, 0);
        for i in 0..600 {
            let target = boxes[i % boxes.len()];
            // Aimed at a corner of a box, or along one of its faces.
            let aim = if i % 2 == 0 {
                target.min
            } else {
                Vec3::new(target.min.x, target.max.y, rng.range(-10.0, 10.0))
            };
            let origin = rng.cube(50.0);
            let mut ray = Ray::new(origin, aim - origin);
            if i % 5 == 0 {
                // Parallel to a face, through the box's vertical edge (a
                // ray in a face's plane itself is entered or not by the
                // sign of its zero, in either test).
                ray.direction.z = 0.0;
                ray.origin.z = (target.min.z + target.max.z) / 2.0;
            }
            ray.tmax = if i % 3 == 0 {
                f32::INFINITY
            } else {
                rng.range(0.5, 2.0)
            };
            let margin = [0.0, 1e-4, 0.05, 0.5][i % 4];
            let own = reached(&bvh, &ray, None);
            let grown = reached(&bvh, &ray, Some(GrownSlab::new(&ray, margin)));
            assert!(grown.is_superset(&own), "ray {i}, margin {margin}");
            for (id, b) in boxes.iter().enumerate() {
                if meets_grown(&ray, b, margin) {
                    assert!(grown.contains(&(id as u32)), "ray {i}: box {id}");
                }
            }
            extra += grown.len() - own.len();
            total += grown.len();
        }
        assert!(extra > 0, "the margin reaches more boxes");
        assert!(
            total < 600 * boxes.len() / 10,
            "and the walk prunes: {total}"
        );
    }
}
