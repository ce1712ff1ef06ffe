//! The best-first walk: leaves in the order of their boxes' distance
//! (what the walk's node test says it is), as far as a bound that the
//! leaf test lowers as it finds nearer candidates. With the distance to
//! a point ([`PointBoxes`]) it is the nearest-point walk, whatever the
//! leaves hold; geometry walks an instance's prototype with a lower
//! bound of world distance of its own.
//!
//! Best first (a binary heap keyed by box distance) rather than depth
//! first: a leaf is tested only once every nearer box has been opened,
//! so a walk tests no leaf whose box is farther than the answer. The
//! eight children of a node are measured in one 8-wide node test.

use super::build::Bvh8;
use super::node::{is_leaf, leaf_range, EMPTY};
use super::node_test::{ChildBoxes, NodeTest, PointBoxes};
use crate::math::lanes::mask_lanes;
use glam::Vec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The queue of a best-first walk, which a caller that walks many trees
/// (an instance's prototype per instance) may keep to reuse its memory.
/// Entries are (distance bits << 32) | child reference: distances are
/// never negative, so their bits order as they do, and each key is
/// unique (child references are), so the walk's order is the same
/// whatever the heap's own order of equal keys.
#[derive(Debug, Clone, Default)]
pub struct NearestQueue(BinaryHeap<Reverse<u64>>);

impl NearestQueue {
    pub fn new() -> Self {
        Self(BinaryHeap::with_capacity(64))
    }
}

impl Bvh8 {
    /// Visits the leaves whose boxes lie within squared distance `bound`
    /// of `point`, nearest box first (equal distances in child order):
    /// [`Bvh8::nearest_by`] with the boxes' squared distance to `point`.
    /// `leaf(start, count, bound)` tests the leaf holding slots
    /// `start..start + count` and returns the bound for the rest of the
    /// walk: `bound` itself, or less once it has found something nearer.
    ///
    /// Box distances are computed in f32 and compared with `bound` as
    /// they are: a caller whose leaf distances carry rounding error of
    /// their own widens the bound it returns by that error.
    pub fn nearest<L, F>(&self, point: Vec3, bound: f32, leaf_data: &[L], leaf: F)
    where
        F: FnMut(u32, u32, f32) -> f32,
    {
        let mut queue = NearestQueue::new();
        self.nearest_by(PointBoxes::new(point), bound, leaf_data, &mut queue, leaf);
    }

    /// The best-first walk: visits the leaves whose distance by `test`
    /// is within `bound`, nearest first, calling `leaf(start, count,
    /// bound)`, which returns the bound for the rest of the walk. The
    /// walk ends when the nearest entry left is beyond the bound.
    ///
    /// `leaf_data` is as for [`Bvh8::walk`]: what the leaf test reads for
    /// the leaf at `start` is `leaf_data[start / LANES]`. Children are
    /// prefetched as they are queued (where the tree prefetches), so the
    /// misses of the nodes and leaves a walk will open overlap. `queue`
    /// is emptied first.
    pub fn nearest_by<T, L, F>(
        &self,
        test: T,
        mut bound: f32,
        leaf_data: &[L],
        queue: &mut NearestQueue,
        mut leaf: F,
    ) where
        T: NodeTest,
        F: FnMut(u32, u32, f32) -> f32,
    {
        if self.nodes.is_empty() {
            return;
        }
        let heap = &mut queue.0;
        heap.clear();
        // The entry to open next when it is known to be the nearest left
        // (a node's nearest child, if no queued entry is nearer): it skips
        // the heap, as a ray's walk enters its nearest child at once.
        let mut next = Some(0u64);
        while let Some(entry) = next.take().or_else(|| heap.pop().map(|Reverse(e)| e)) {
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
            let (d2, within) = test.test(ChildBoxes::new(&node.bounds), bound);
            let d2 = d2.to_array();
            let mut nearest = u64::MAX;
            for slot in mask_lanes(within) {
                let c = node.child[slot];
                if c != EMPTY {
                    if self.prefetch {
                        self.prefetch_child(c, leaf_data);
                    }
                    let key = (d2[slot].to_bits() as u64) << 32 | c as u64;
                    if key < nearest {
                        if nearest != u64::MAX {
                            heap.push(Reverse(nearest));
                        }
                        nearest = key;
                    } else {
                        heap.push(Reverse(key));
                    }
                }
            }
            if nearest != u64::MAX {
                match heap.peek() {
                    Some(&Reverse(top)) if top < nearest => heap.push(Reverse(nearest)),
                    _ => next = Some(nearest),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::*;
    use crate::accel::NO_PRIM;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};

    /// Leaf tests here read points by id: no block-shaped leaf data.
    const NO_DATA: &[()] = &[];

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
                bvh.nearest(q, limit, NO_DATA, |start, count, bound| {
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
        bvh.nearest(Vec3::ZERO, f32::INFINITY, NO_DATA, |_, _, _| {
            panic!("no leaves")
        });
    }
}
