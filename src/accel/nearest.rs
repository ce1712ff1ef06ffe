//! The nearest-point walk: leaves in the order of their boxes' distance
//! from a point, best first, as far as a bound that the leaf test lowers
//! as it finds nearer candidates (what a point query on the tree asks,
//! whatever the leaves hold).
//!
//! Best first (a binary heap keyed by squared box distance) rather than
//! depth first: a leaf is tested only once every nearer box has been
//! opened, so a walk tests no leaf whose box is farther than the answer.
//! Squared distances of the eight children of a node come from one
//! 8-wide computation over the node's boxes.

use super::build::Bvh8;
use super::node::{is_leaf, leaf_range, Node8, EMPTY};
use glam::Vec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use wide::f32x8;

impl Bvh8 {
    /// Visits the leaves whose boxes lie within squared distance `bound`
    /// of `point`, nearest box first (equal distances in child order).
    /// `leaf(start, count, bound)` tests the leaf holding slots
    /// `start..start + count` and returns the bound for the rest of the
    /// walk: `bound` itself, or less once it has found something nearer.
    /// The walk ends when the nearest box left is beyond the bound.
    ///
    /// Box distances are computed in f32 and compared with `bound` as
    /// they are: a caller whose leaf distances carry rounding error of
    /// their own widens the bound it returns by that error.
    pub fn nearest<F>(&self, point: Vec3, mut bound: f32, mut leaf: F)
    where
        F: FnMut(u32, u32, f32) -> f32,
    {
        if self.nodes.is_empty() {
            return;
        }
        let p = point.to_array().map(f32x8::splat);
        // Entries are (squared distance bits << 32) | child reference:
        // distances are never negative, so their bits order as they do.
        let mut heap: BinaryHeap<Reverse<u64>> = BinaryHeap::with_capacity(64);
        heap.push(Reverse(0));
        while let Some(Reverse(entry)) = heap.pop() {
            if f32::from_bits((entry >> 32) as u32) > bound {
                break;
            }
            let child = entry as u32;
            if is_leaf(child) {
                let (start, count) = leaf_range(child);
                bound = leaf(start, count, bound);
                continue;
            }
            let node = &self.nodes[child as usize];
            let d2 = box_distances(node, &p).to_array();
            for (slot, &d2) in d2.iter().enumerate() {
                let c = node.child[slot];
                if c != EMPTY && d2 <= bound {
                    heap.push(Reverse((d2.to_bits() as u64) << 32 | c as u64));
                }
            }
        }
    }
}

/// The squared distance from `p` to each of the node's eight boxes (0
/// inside; +∞ for an empty slot, whose box is inverted and infinite).
#[inline(always)]
fn box_distances(node: &Node8, p: &[f32x8; 3]) -> f32x8 {
    let mut d2 = f32x8::ZERO;
    for (axis, &p) in p.iter().enumerate() {
        let below = f32x8::from(node.bounds[2 * axis]) - p;
        let above = p - f32x8::from(node.bounds[2 * axis + 1]);
        let d = below.max(above).max(f32x8::ZERO);
        d2 += d * d;
    }
    d2
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::*;
    use crate::accel::NO_PRIM;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};

    /// Random points as point boxes; the nearest of them to random query
    /// points, with and without a bound, against brute force, for every
    /// build quality.
    #[test]
    fn the_walk_finds_the_nearest_point_of_brute_force() {
        let mut rng = seeded(11);
        let points: Vec<Vec3> = (0..3000).map(|_| rng.cube(20.0)).collect();
        let boxes: Vec<Aabb> = points.iter().map(|&p| Aabb::new(p, p)).collect();
        for quality in [
            BuildQuality::Fastest,
            BuildQuality::Medium,
            BuildQuality::High,
        ] {
            let bvh = Bvh8::build(&boxes, quality);
            for i in 0..500 {
                let q = rng.cube(30.0);
                let limit = if i % 2 == 0 {
                    f32::INFINITY
                } else {
                    rng.unit() * 3.0
                };
                let brute = (0..points.len())
                    .map(|k| ((points[k] - q).length_squared(), k as u32))
                    .filter(|&(d2, _)| d2 <= limit)
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let mut best: Option<(f32, u32)> = None;
                let mut leaves = 0;
                bvh.nearest(q, limit, |start, count, bound| {
                    leaves += 1;
                    for slot in start..start + count {
                        let id = bvh.prim_ids[slot as usize];
                        if id == NO_PRIM {
                            continue;
                        }
                        let d2 = (points[id as usize] - q).length_squared();
                        let nearer = best.is_none_or(|b| (d2, id) < b);
                        if d2 <= bound && nearer {
                            best = Some((d2, id));
                        }
                    }
                    best.map_or(bound, |b| b.0)
                });
                assert_eq!(best, brute, "{quality:?}, limit {limit}");
                assert!(leaves < 100, "{leaves} leaves: the walk is not pruned");
            }
        }
    }

    #[test]
    fn an_empty_tree_visits_nothing() {
        let bvh = Bvh8::build(&[], BuildQuality::Auto);
        bvh.nearest(Vec3::ZERO, f32::INFINITY, |_, _, _| panic!("no leaves"));
    }
}
