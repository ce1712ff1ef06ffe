//! The crossings of an instance: its prototype's tree walked in object
//! space, each leaf's triangles moved to world space as a copy holds them
//! and tested with the world ray.
//!
//! The walk must not cull a box that holds a triangle the world test
//! crosses, though the object-space ray is the world ray rounded: a ray
//! aimed at a vertex meets it at a corner of the boxes around it, and the
//! rounded ray may pass that corner on the outside. So the walk is its
//! own: every child box grown by what rounding may move the ray and the
//! triangles in object space ([`PlacedRounding`]), and no order (a
//! crossing query needs none).

use super::Crossing;
use crate::accel::node::{decode, ChildRef};
use crate::accel::Bvh8;
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
        leaves_near(&prototype.bvh, &walk_ray, margin, |start, count| {
            query.leaf(start, count)
        });
    }
}

/// Calls `leaf(start, count)` for every leaf whose box, grown by `margin`
/// on every side, the ray may meet in `[tmin, tmax]` (both ends widened by
/// 2γ(3) of their magnitude, as the walks widen theirs: Ize 2013).
fn leaves_near(bvh: &Bvh8, ray: &Ray, margin: f32, mut leaf: impl FnMut(u32, u32)) {
    if bvh.nodes.is_empty() {
        return;
    }
    // A zero component becomes the least normal one, so that a slab the
    // ray lies in reads 0·∞ as 0, not NaN.
    let inv = ray.direction.to_array().map(|d| {
        1.0 / if d == 0.0 {
            f32::MIN_POSITIVE.copysign(d)
        } else {
            d
        }
    });
    let origin = ray.origin.to_array();
    let m = f32x8::splat(margin);
    let g = f32x8::splat(2.0 * gamma(3));
    let mut pending = Pending::default();
    pending.push(0);
    while let Some(child) = pending.pop() {
        match decode(child) {
            ChildRef::Node(n) => {
                let node = &bvh.nodes[n as usize];
                let mut near = f32x8::splat(ray.tmin);
                let mut far = f32x8::splat(ray.tmax);
                for axis in 0..3 {
                    let lo = f32x8::from(node.bounds[2 * axis]) - m;
                    let hi = f32x8::from(node.bounds[2 * axis + 1]) + m;
                    let (enter, leave) = if inv[axis] >= 0.0 { (lo, hi) } else { (hi, lo) };
                    let (o, i) = (f32x8::splat(origin[axis]), f32x8::splat(inv[axis]));
                    near = near.fast_max((enter - o) * i);
                    far = far.fast_min((leave - o) * i);
                }
                let meets = (near - g * near.abs()).simd_le(far + g * far.abs());
                for slot in mask_lanes(meets.to_bitmask()) {
                    pending.push(node.child[slot]);
                }
            }
            ChildRef::Leaf { start, count } => leaf(start, count),
            ChildRef::Empty => {}
        }
    }
}

/// The walk's stack of children still to visit: on the stack itself up to
/// a depth no tree of ours reaches, on the heap past it.
struct Pending {
    fixed: [u32; 128],
    len: usize,
    spill: Vec<u32>,
}

impl Default for Pending {
    fn default() -> Self {
        Self {
            fixed: [0; 128],
            len: 0,
            spill: Vec::new(),
        }
    }
}

impl Pending {
    #[inline(always)]
    fn push(&mut self, child: u32) {
        if self.len < self.fixed.len() {
            self.fixed[self.len] = child;
            self.len += 1;
        } else {
            self.spill.push(child);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<u32> {
        self.spill.pop().or_else(|| {
            self.len = self.len.checked_sub(1)?;
            Some(self.fixed[self.len])
        })
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
