//! PLOC, parallel locally-ordered clustering (Meister and Bittner 2018,
//! "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy
//! Construction"), every pass of it in parallel and the same tree on any
//! thread count.
//!
//! The leaves are sorted along a Morton curve (`cluster::morton_order`).
//! Each pass, every cluster finds its nearest neighbour within `radius`
//! places of the sorted order, by the surface area of their union; the
//! pairs that are each other's nearest merge into a new cluster, which
//! takes the place of the first of the two, and the others stay. obvhs's
//! builder finds the neighbours in parallel but merges in one sequential
//! loop, which bends the build's scaling over threads (docs/performance.md).
//! Here the merge is parallel too: each block of the clusters counts what
//! it keeps and how many pairs it merges, and a prefix sum over the
//! blocks says where each block writes its clusters of the next pass and
//! its children into the tree, in the order one sequential walk would.
//! Ties between neighbours go to the nearer index, so every choice is a
//! function of the boxes alone and the tree is the same for any thread
//! count and any blocking.

use crate::math::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use rayon::prelude::*;

/// A cluster of a pass: its box and what it is in the tree, a leaf (its
/// primitive with [`LEAF`] set) or an inner node (its first child's index).
#[derive(Clone, Copy)]
struct Cluster {
    bounds: Aabb,
    node: u32,
}

const LEAF: u32 = 1 << 31;

impl Cluster {
    fn tree_node(self) -> Bvh2Node {
        let aabb = obvhs::aabb::Aabb {
            min: self.bounds.min.into(),
            max: self.bounds.max.into(),
        };
        match self.node & LEAF {
            0 => Bvh2Node::new(aabb, 0, self.node),
            _ => Bvh2Node::new(aabb, 1, self.node & !LEAF),
        }
    }
}

/// Clusters a task takes in a pass: enough that its work dwarfs its
/// hand-off. The blocks never change the tree.
const BLOCK: usize = 1 << 14;

/// The binary tree over `boxes`, whose ids `order` lists along the Morton
/// curve: leaf `i` holds primitive `i` (as obvhs writes it: the leaf's
/// `first_index` is `i`, and `primitive_indices` is the identity). Each
/// cluster looks `radius` places each way, but only one for the first
/// `near_passes` passes (obvhs's `search_depth_threshold`), when clusters
/// are many and their neighbours on the curve already near. Children come
/// after their parents.
pub(super) fn ploc(boxes: &[Aabb], order: &[u32], radius: usize, near_passes: usize) -> Bvh2 {
    let n = order.len();
    assert!(n > 0 && n < LEAF as usize && radius >= 1);
    let mut current: Vec<Cluster> = order
        .par_iter()
        .with_min_len(BLOCK)
        .map(|&i| Cluster {
            bounds: boxes[i as usize],
            node: i | LEAF,
        })
        .collect();
    let mut next = current.clone();
    let mut nearest = vec![0u32; n];
    // The nodes, made in parallel (the first write to a fresh page costs
    // the kernel a clear, which one thread would do for all of them).
    let mut nodes: Vec<Bvh2Node> = (0..2 * n - 1)
        .into_par_iter()
        .with_min_len(BLOCK)
        .map(|_| Bvh2Node::default())
        .collect();
    // Pairs are written down from the end, so children follow parents.
    let mut insert = nodes.len();
    let (mut count, mut passes) = (n, 0);
    while count > 1 {
        let r = if passes < near_passes { 1 } else { radius };
        find_nearest(&current[..count], &mut nearest[..count], r);
        let (kept, merged) = merge(
            &current[..count],
            &nearest[..count],
            &mut next,
            &mut nodes[..insert],
        );
        debug_assert!(merged > 0, "a pass merges the closest pair at least");
        std::mem::swap(&mut current, &mut next);
        count = kept;
        insert -= 2 * merged;
        passes += 1;
    }
    debug_assert_eq!(insert, 1);
    nodes[0] = current[0].tree_node();
    Bvh2 {
        nodes,
        primitive_indices: (0..n as u32).collect(),
        max_depth: DEFAULT_MAX_STACK_DEPTH.max(passes + 1),
        children_are_ordered_after_parents: true,
        ..Bvh2::default()
    }
}

/// `nearest[i]`: the index of the cluster within `r` places of `i` whose
/// union with `i` has the least surface area, the nearer index on a tie.
/// Each block weighs every pair that touches it once, from the left end
/// of each pair.
fn find_nearest(clusters: &[Cluster], nearest: &mut [u32], r: usize) {
    let count = clusters.len();
    nearest
        .par_chunks_mut(BLOCK)
        .enumerate()
        .for_each(|(b, nearest)| {
            let lo = b * BLOCK;
            let hi = lo + nearest.len();
            let mut best = vec![(f32::INFINITY, u32::MAX); hi - lo];
            let better = |(c, j): (f32, u32), (bc, bj): (f32, u32)| c < bc || (c == bc && j < bj);
            for i in lo.saturating_sub(r)..hi {
                let own = clusters[i].bounds;
                for j in i + 1..(i + r + 1).min(count) {
                    if j < lo {
                        continue;
                    }
                    let cost = own.union(clusters[j].bounds).half_area();
                    if i >= lo && better((cost, j as u32), best[i - lo]) {
                        best[i - lo] = (cost, j as u32);
                    }
                    if j < hi && better((cost, i as u32), best[j - lo]) {
                        best[j - lo] = (cost, i as u32);
                    }
                }
            }
            for (out, (_, j)) in nearest.iter_mut().zip(best) {
                *out = j;
            }
        });
}

/// One pass's merge: clusters that are each other's nearest become one
/// in `next`, where the first of them was, their two nodes written at the
/// end of `nodes` (the first pair last); the rest are copied. Returns the
/// clusters in `next` and the pairs merged.
fn merge(
    clusters: &[Cluster],
    nearest: &[u32],
    next: &mut [Cluster],
    nodes: &mut [Bvh2Node],
) -> (usize, usize) {
    let count = clusters.len();
    // What cluster i becomes: 0 merged into an earlier one, 1 kept, 2 the
    // first of a pair.
    let fate = |i: usize| {
        let j = nearest[i] as usize;
        match (nearest[j] as usize == i, j > i) {
            (true, false) => 0u8,
            (false, _) => 1,
            (true, true) => 2,
        }
    };
    let blocks = count.div_ceil(BLOCK);
    let tallies: Vec<(usize, usize)> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            (b * BLOCK..((b + 1) * BLOCK).min(count)).fold((0, 0), |(kept, pairs), i| match fate(i) {
                0 => (kept, pairs),
                1 => (kept + 1, pairs),
                _ => (kept + 1, pairs + 1),
            })
        })
        .collect();
    let (kept, pairs) = tallies
        .iter()
        .fold((0, 0), |(k, p), &(bk, bp)| (k + bk, p + bp));
    // Each block's share of `next` (in order) and of `nodes` (from the
    // end down: the first block's pairs last).
    let mut parts = Vec::with_capacity(blocks);
    let mut node_start = nodes.len();
    let first_pair = node_start - 2 * pairs;
    let mut next_rest = &mut next[..kept];
    let mut nodes_rest = &mut nodes[first_pair..];
    for &(bk, bp) in &tallies {
        let (out, rest) = std::mem::take(&mut next_rest).split_at_mut(bk);
        let below = nodes_rest.len() - 2 * bp;
        let (rest_nodes, mine) = std::mem::take(&mut nodes_rest).split_at_mut(below);
        node_start -= 2 * bp;
        parts.push((out, mine, node_start));
        (next_rest, nodes_rest) = (rest, rest_nodes);
    }
    parts
        .into_par_iter()
        .enumerate()
        .for_each(|(b, (out, mine, start))| {
            let mut out = out.iter_mut();
            // This block's pairs fill `mine` from its end down.
            let mut slot = mine.len();
            for i in b * BLOCK..((b + 1) * BLOCK).min(count) {
                let c = clusters[i];
                match fate(i) {
                    0 => {}
                    1 => *out.next().unwrap() = c,
                    _ => {
                        let other = clusters[nearest[i] as usize];
                        slot -= 2;
                        mine[slot] = c.tree_node();
                        mine[slot + 1] = other.tree_node();
                        *out.next().unwrap() = Cluster {
                            bounds: c.bounds.union(other.bounds),
                            node: (start + slot) as u32,
                        };
                    }
                }
            }
        });
    (kept, pairs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

    fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(work)
    }

    /// Boxes of small triangles on a bumpy sphere, in a shuffled order: a
    /// surface, as meshes are, with many equal areas on its regular grid.
    fn surface_boxes(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = seeded(seed);
        (0..n)
            .map(|_| {
                let d = rng.cube(1.0).normalize_or(Vec3::X);
                let c = d * (10.0 + (5.0 * d.x).sin());
                let c = (c * 64.0).round() / 64.0;
                Aabb::new(c, c + Vec3::splat(0.05))
            })
            .collect()
    }

    fn node_bits(bvh: &Bvh2) -> Vec<[u32; 8]> {
        bvh.nodes
            .iter()
            .map(|n| {
                let (a, b) = (n.aabb.min, n.aabb.max);
                [a.x, a.y, a.z, b.x, b.y, b.z]
                    .map(f32::to_bits)
                    .iter()
                    .copied()
                    .chain([n.prim_count, n.first_index])
                    .collect::<Vec<u32>>()
                    .try_into()
                    .unwrap()
            })
            .collect()
    }

    /// The same tree, node for node and bit for bit, on 1, 2 and 3
    /// threads, for the near-only radius and wide ones, over several
    /// blocks of clusters.
    #[test]
    fn the_tree_is_the_same_on_any_thread_count() {
        let boxes = surface_boxes(5 * BLOCK + 123, 7);
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let order = super::super::cluster::morton_order(&boxes, bounds);
        for (radius, near) in [(1, 0), (6, 2), (14, 3)] {
            let trees: Vec<_> = [1, 2, 3]
                .map(|t| on_threads(t, || node_bits(&ploc(&boxes, &order, radius, near))))
                .into();
            assert_eq!(trees[0], trees[1], "radius {radius}: 1 and 2 threads");
            assert_eq!(trees[0], trees[2], "radius {radius}: 1 and 3 threads");
        }
    }

    /// Every node's box is its children's union, children follow their
    /// parents, every node but the root is a child once, and every
    /// primitive is in one leaf.
    #[test]
    fn the_tree_is_well_formed() {
        for n in [1usize, 2, 3, 17, 40_000] {
            let boxes = surface_boxes(n, 3);
            let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            let order = super::super::cluster::morton_order(&boxes, bounds);
            let bvh = ploc(&boxes, &order, 6, 2);
            assert_eq!(bvh.nodes.len(), 2 * n - 1);
            let as_box = |k: usize| {
                let a = bvh.nodes[k].aabb;
                Aabb::new(a.min.into(), a.max.into())
            };
            assert_eq!(as_box(0), bounds, "{n}: the root is the union");
            let mut parents = vec![0u32; bvh.nodes.len()];
            let mut leaves = vec![0u32; n];
            for (k, node) in bvh.nodes.iter().enumerate() {
                if node.prim_count > 0 {
                    assert_eq!(node.prim_count, 1);
                    leaves[node.first_index as usize] += 1;
                    assert_eq!(as_box(k), boxes[node.first_index as usize]);
                    continue;
                }
                let c = node.first_index as usize;
                assert!(c > k, "{n}: children after their parent");
                parents[c] += 1;
                parents[c + 1] += 1;
                assert_eq!(as_box(k), as_box(c).union(as_box(c + 1)));
            }
            assert_eq!(parents[0], 0);
            assert!(parents[1..].iter().all(|&p| p == 1), "{n}");
            assert!(leaves.iter().all(|&l| l == 1), "{n}");
        }
    }

    /// Each cluster's nearest is the brute-force least union area within
    /// the radius, the nearer index on a tie, across block edges.
    #[test]
    fn nearest_neighbours_match_brute_force() {
        let boxes = surface_boxes(2 * BLOCK + 50, 11);
        let clusters: Vec<Cluster> = boxes
            .iter()
            .map(|&bounds| Cluster { bounds, node: 0 })
            .collect();
        for r in [1, 6, 14] {
            let mut nearest = vec![0; clusters.len()];
            find_nearest(&clusters, &mut nearest, r);
            for (i, &got) in nearest.iter().enumerate() {
                let lo = i.saturating_sub(r);
                let hi = (i + r + 1).min(clusters.len());
                let want = (lo..hi)
                    .filter(|&j| j != i)
                    .map(|j| (boxes[i].union(boxes[j]).half_area(), j))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                    .unwrap()
                    .1;
                assert_eq!(got as usize, want, "radius {r}, cluster {i}");
            }
        }
    }
}
