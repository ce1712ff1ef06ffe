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

use super::cluster::Boxes;
use glam::Vec3A;
use obvhs::aabb::Aabb as Box3A;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use rayon::prelude::*;

/// The clusters of a pass, in curve order: their boxes (in SIMD lanes,
/// where the neighbour search spends its time) and what each is in the
/// tree, a leaf (its primitive with [`LEAF`] set) or an inner node (its
/// first child's index).
struct Clusters {
    bounds: Vec<Box3A>,
    node: Vec<u32>,
}

const LEAF: u32 = 1 << 31;

impl Clusters {
    /// Keeps the first `count` clusters and frees the room for the rest.
    fn shrink_to(&mut self, count: usize) {
        self.bounds.truncate(count);
        self.bounds.shrink_to_fit();
        self.node.truncate(count);
        self.node.shrink_to_fit();
    }
}

/// The tree's node for a cluster of box `aabb` and `node`.
fn tree_node(aabb: Box3A, node: u32) -> Bvh2Node {
    match node & LEAF {
        0 => Bvh2Node::new(aabb, 0, node),
        _ => Bvh2Node::new(aabb, 1, node & !LEAF),
    }
}

/// Half the surface area of the union of two boxes, its sides measured
/// in `scale`s (the root box's sides, so that no area overflows to
/// infinity or flushes to zero, whatever the scene's size): PLOC's distance.
#[inline(always)]
fn union_area(a: &Box3A, b: &Box3A, scale: Vec3A) -> f32 {
    let d = (a.max.max(b.max) - a.min.min(b.min)) * scale;
    (d.x + d.y) * d.z + d.x * d.y
}

/// Each axis's multiplier to the root box's side (0 for a flat axis).
fn unit_scale(bounds: &[Box3A]) -> Vec3A {
    let root = bounds
        .par_iter()
        .with_min_len(BLOCK)
        .copied()
        .reduce(Box3A::empty, |a, b| a.union(&b));
    let side = root.max - root.min;
    Vec3A::select(side.cmpgt(Vec3A::ZERO), Vec3A::ONE / side, Vec3A::ZERO)
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
///
/// Takes the boxes and the order and frees them once its first clusters
/// are made of them: before its passes, where a build of a primitive a
/// leaf peaks (28 bytes a primitive less there).
pub(super) fn ploc(boxes: Boxes, order: Vec<u32>, radius: usize, near_passes: usize) -> Bvh2 {
    let bounds: Vec<Box3A> = order
        .par_iter()
        .with_min_len(BLOCK)
        .map(|&i| {
            let b = boxes[i as usize];
            Box3A {
                min: b.min.into(),
                max: b.max.into(),
            }
        })
        .collect();
    drop(boxes);
    let node = order
        .par_iter()
        .with_min_len(BLOCK)
        .map(|&i| i | LEAF)
        .collect();
    drop(order);
    let ids = (0..bounds.len() as u32).into_par_iter().collect();
    ploc_over(bounds, Vec::new(), node, ids, radius, near_passes)
}

/// [`ploc`]'s tree over boxes already in curve order, leaf `i` holding
/// `bounds[i]` and `first_index` `i`, and `primitive_indices` those the
/// caller gives: the fastest preset's clusters ([`super::cluster`]).
/// `spare` is a buffer the clusters of the next pass may take (its
/// pages, touched already, rather than fresh ones; its contents are not
/// read).
pub(super) fn ploc_in_order(
    bounds: Vec<Box3A>,
    spare: Vec<Box3A>,
    primitive_indices: Vec<u32>,
    radius: usize,
    near_passes: usize,
) -> Bvh2 {
    let node = (0..bounds.len() as u32)
        .into_par_iter()
        .with_min_len(BLOCK)
        .map(|i| i | LEAF)
        .collect();
    ploc_over(bounds, spare, node, primitive_indices, radius, near_passes)
}

/// PLOC over clusters `bounds` in curve order, cluster `i` the tree's
/// `node[i]` (a leaf: its primitive with [`LEAF`] set).
fn ploc_over(
    bounds: Vec<Box3A>,
    mut spare: Vec<Box3A>,
    node: Vec<u32>,
    primitive_indices: Vec<u32>,
    radius: usize,
    near_passes: usize,
) -> Bvh2 {
    let n = bounds.len();
    assert!(n > 0 && n < LEAF as usize && radius >= 1);
    // The next pass's clusters are made as long as the first merge keeps
    // (a third fewer), not a copy of the first pass's: `merge` grows them.
    spare.clear();
    let mut next = Clusters {
        bounds: spare,
        node: Vec::new(),
    };
    let mut current = Clusters { bounds, node };
    let mut nearest = vec![0u32; n];
    let scale = unit_scale(&current.bounds);
    // The nodes, zeroed by the allocator: fresh pages, which the kernel
    // maps (and clears) only when a merge first writes them, in parallel.
    // So the tree's memory grows as the clusters' shrinks, and the two
    // are never both whole (64 and 72 bytes a primitive).
    let mut nodes: Vec<Bvh2Node> = wide::bytemuck::zeroed_vec(2 * n - 1);
    // Pairs are written down from the end, so children follow parents.
    let mut insert = nodes.len();
    let (mut count, mut passes, mut held) = (n, 0, n);
    while count > 1 {
        let r = if passes < near_passes { 1 } else { radius };
        find_nearest(&current.bounds[..count], &mut nearest[..count], r, scale);
        let (kept, merged) = merge(&current, count, &nearest, &mut next, &mut nodes[..insert]);
        debug_assert!(merged > 0, "a pass merges the closest pair at least");
        std::mem::swap(&mut current, &mut next);
        count = kept;
        insert -= 2 * merged;
        passes += 1;
        // Hand back the clusters' buffers past what the passes to come
        // can use whenever an eighth of them is spare (a shrink in place,
        // by whole pages: no copy), so that they shrink as the tree grows:
        // the first passes merge a third of the clusters each.
        if count <= held - held / 8 {
            held = count;
            current.shrink_to(count);
            next.shrink_to(count);
            nearest.truncate(count);
            nearest.shrink_to_fit();
        }
    }
    debug_assert_eq!(insert, 1);
    nodes[0] = tree_node(current.bounds[0], current.node[0]);
    Bvh2 {
        nodes,
        primitive_indices,
        max_depth: DEFAULT_MAX_STACK_DEPTH.max(passes + 1),
        children_are_ordered_after_parents: true,
        ..Bvh2::default()
    }
}

/// `nearest[i]`: the index of the cluster within `r` places of `i` whose
/// union with `i` has the least surface area ([`closer`] on a tie). Each
/// block weighs every pair that touches it once, from the left end of
/// each pair. A cluster's candidates arrive in increasing index (its left
/// neighbours as the left ends of their pairs, then its right ones). The
/// radius is a constant of each instance, so the inner loop unrolls, and
/// the bests are kept by selects: which neighbour is nearer is a coin toss
/// a branch would mispredict.
fn find_nearest(bounds: &[Box3A], nearest: &mut [u32], r: usize, scale: Vec3A) {
    match r {
        1 => nearest_within::<1>(bounds, nearest, scale),
        2 => nearest_within::<2>(bounds, nearest, scale),
        6 => nearest_within::<6>(bounds, nearest, scale),
        14 => nearest_within::<14>(bounds, nearest, scale),
        24 => nearest_within::<24>(bounds, nearest, scale),
        32 => nearest_within::<32>(bounds, nearest, scale),
        _ => unreachable!("obvhs's search distances are 1, 2, 6, 14, 24 and 32"),
    }
}

/// Among neighbours of cluster `i` whose unions with it have equal areas,
/// whether `j` is to be preferred to `best`: the nearer index, and of two
/// as near (one each side) the right one for an even `i`, the left one
/// for an odd `i`. Boxes in a regular row (instances placed on a grid, a
/// lattice of equal parts) tie with both neighbours; were the left always
/// taken, every cluster would choose its left neighbour and only the first
/// pair would be each other's nearest, one merge a pass and a build
/// quadratic in their number (20,000 placements took 4.7 s). By parity,
/// clusters 2k and 2k + 1 choose each other and a row halves every pass.
/// A function of the indices alone, so the tree is still the same for any
/// thread count and blocking.
#[inline(always)]
fn closer(i: usize, j: usize, best: usize) -> bool {
    let (dj, db) = (j.abs_diff(i), best.abs_diff(i));
    dj < db || (dj == db && (j > i) == i.is_multiple_of(2))
}

fn nearest_within<const R: usize>(bounds: &[Box3A], nearest: &mut [u32], scale: Vec3A) {
    let count = bounds.len();
    nearest
        .par_chunks_mut(BLOCK)
        .enumerate()
        .for_each(|(b, nearest)| {
            let lo = b * BLOCK;
            let hi = lo + nearest.len();
            // The best of each cluster from lo to hi + R (those past hi
            // are weighed but not kept), from its left neighbours so far.
            let mut best = vec![(f32::INFINITY, 0u32); hi - lo + R];
            // `j` sees `i` as its nearest left candidate so far (`<=`: the
            // later of equal left candidates is the nearer); `i` sees `j`
            // as its next right one, after its left ones ([`closer`]).
            let pair = |best: &mut [(f32, u32)], i: usize, j: usize, (bi, ni): (f32, u32)| {
                let cost = union_area(&bounds[i], &bounds[j], scale);
                let other = &mut best[j - lo];
                *other = if cost <= other.0 {
                    (cost, i as u32)
                } else {
                    *other
                };
                if cost < bi || (cost == bi && closer(i, j, ni as usize)) {
                    (cost, j as u32)
                } else {
                    (bi, ni)
                }
            };
            // Left neighbours of the block's first clusters.
            for i in lo.saturating_sub(R)..lo {
                for j in lo..(i + R + 1).min(count) {
                    pair(&mut best, i, j, (f32::INFINITY, 0));
                }
            }
            for i in lo..hi {
                let mut own = best[i - lo];
                if i + R < count {
                    let right = &bounds[i + 1..=i + R];
                    let theirs = &mut best[i + 1 - lo..=i + R - lo];
                    own = weigh_right::<R>(i, &bounds[i], right, theirs, own, scale);
                } else {
                    for j in i + 1..count {
                        own = pair(&mut best, i, j, own);
                    }
                }
                nearest[i - lo] = own.1;
            }
        });
}

/// Cluster `i` (box `own_box`, its best so far `own`) weighed against
/// its `R` right neighbours (boxes `right`, bests `theirs`): the same
/// comparisons in the same order as one pair at a time, in a loop of a
/// constant length over arrays, so that it unrolls with no bounds checks
/// and no call (the pair closure it replaces was not inlined: 14% of a
/// medium build's samples on the dragon went to its calls).
#[inline(always)]
fn weigh_right<const R: usize>(
    i: usize,
    own_box: &Box3A,
    right: &[Box3A],
    theirs: &mut [(f32, u32)],
    mut own: (f32, u32),
    scale: Vec3A,
) -> (f32, u32) {
    let right: &[Box3A; R] = right.try_into().unwrap();
    let theirs: &mut [(f32, u32); R] = theirs.try_into().unwrap();
    for k in 0..R {
        let cost = union_area(own_box, &right[k], scale);
        let other = &mut theirs[k];
        *other = if cost <= other.0 {
            (cost, i as u32)
        } else {
            *other
        };
        let j = i + 1 + k;
        own = if cost < own.0 || (cost == own.0 && closer(i, j, own.1 as usize)) {
            (cost, j as u32)
        } else {
            own
        };
    }
    own
}

/// One pass's merge of the first `count` clusters of `current`: clusters
/// that are each other's nearest become one in `next`, where the first of
/// them was, their two nodes written at the end of `nodes` (the first pair
/// last); the rest are copied. Returns the clusters in `next` and the
/// pairs merged.
fn merge(
    current: &Clusters,
    count: usize,
    nearest: &[u32],
    next: &mut Clusters,
    nodes: &mut [Bvh2Node],
) -> (usize, usize) {
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
    let block = |b: usize| b * BLOCK..((b + 1) * BLOCK).min(count);
    let tallies: Vec<(usize, usize)> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            block(b).fold((0, 0), |(kept, pairs), i| match fate(i) {
                0 => (kept, pairs),
                1 => (kept + 1, pairs),
                _ => (kept + 1, pairs + 1),
            })
        })
        .collect();
    let (kept, pairs) = tallies
        .iter()
        .fold((0, 0), |(k, p), &(bk, bp)| (k + bk, p + bp));
    grow_to(&mut next.bounds, kept);
    grow_to(&mut next.node, kept);
    // Each block's share of `next` (in order) and of `nodes` (from the
    // end down: the first block's pairs last), and where its nodes start.
    let mut parts = Vec::with_capacity(blocks);
    let mut node_start = nodes.len();
    let first_pair = node_start - 2 * pairs;
    let mut bounds_rest = &mut next.bounds[..kept];
    let mut node_rest = &mut next.node[..kept];
    let mut nodes_rest = &mut nodes[first_pair..];
    for &(bk, bp) in &tallies {
        let (bounds_out, b_rest) = std::mem::take(&mut bounds_rest).split_at_mut(bk);
        let (node_out, n_rest) = std::mem::take(&mut node_rest).split_at_mut(bk);
        let below = nodes_rest.len() - 2 * bp;
        let (rest_nodes, mine) = std::mem::take(&mut nodes_rest).split_at_mut(below);
        node_start -= 2 * bp;
        parts.push((bounds_out, node_out, mine, node_start));
        (bounds_rest, node_rest, nodes_rest) = (b_rest, n_rest, rest_nodes);
    }
    parts
        .into_par_iter()
        .enumerate()
        .for_each(|(b, (bounds_out, node_out, mine, start))| {
            let mut out = bounds_out.iter_mut().zip(node_out.iter_mut());
            // This block's pairs fill `mine` from its end down.
            let mut slot = mine.len();
            for i in block(b) {
                let (own, node) = (current.bounds[i], current.node[i]);
                match fate(i) {
                    0 => {}
                    1 => {
                        let (b, n) = out.next().unwrap();
                        (*b, *n) = (own, node);
                    }
                    _ => {
                        let j = nearest[i] as usize;
                        let other = current.bounds[j];
                        slot -= 2;
                        mine[slot] = tree_node(own, node);
                        mine[slot + 1] = tree_node(other, current.node[j]);
                        let (b, n) = out.next().unwrap();
                        (*b, *n) = (own.union(&other), (start + slot) as u32);
                    }
                }
            }
        });
    (kept, pairs)
}

/// Lengthens `v` to `len` items (their values are written over before
/// they are read), in parallel: the first touch of a fresh page is its
/// clear, which one thread would do for all of them.
fn grow_to<T: Copy + Default + Send>(v: &mut Vec<T>, len: usize) {
    if v.len() < len {
        let more = len - v.len();
        v.par_extend(
            (0..more)
                .into_par_iter()
                .with_min_len(BLOCK)
                .map(|_| T::default()),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::on_threads;
    use super::*;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

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
                let (a, b) = (n.aabb().min, n.aabb().max);
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
                .map(|t| {
                    on_threads(t, || {
                        node_bits(&ploc(Boxes::Borrowed(&boxes), order.clone(), radius, near))
                    })
                })
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
            let bvh = ploc(Boxes::Borrowed(&boxes), order, 6, 2);
            assert_eq!(bvh.nodes.len(), 2 * n - 1);
            let as_box = |k: usize| {
                let a = *bvh.nodes[k].aabb();
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

    /// Boxes as the neighbour search reads them.
    fn simd_boxes(boxes: &[Aabb]) -> Vec<Box3A> {
        boxes
            .iter()
            .map(|b| Box3A {
                min: b.min.into(),
                max: b.max.into(),
            })
            .collect()
    }

    /// The least union area with cluster `i` among `range`, ties to the
    /// nearer index, then to the right for an even `i` (as `closer`).
    fn brute_nearest(
        bounds: &[Box3A],
        i: usize,
        range: std::ops::Range<usize>,
        scale: Vec3A,
    ) -> usize {
        let side = |j: usize| (j > i) != i.is_multiple_of(2); // false: the side preferred
        range
            .filter(|&j| j != i)
            .map(|j| (union_area(&bounds[i], &bounds[j], scale), j))
            .min_by(|a, b| {
                let key = |(c, j): (f32, usize)| (c, j.abs_diff(i), side(j));
                let (ka, kb) = (key(*a), key(*b));
                ka.0.total_cmp(&kb.0)
                    .then(ka.1.cmp(&kb.1))
                    .then(ka.2.cmp(&kb.2))
            })
            .unwrap()
            .1
    }

    /// Boxes in a regular row, equally spaced or all in one place, tie with
    /// their neighbours on both sides; the clusters still pair off, so the
    /// passes are few and the tree balanced, not one merge a pass (which
    /// made 20,000 placements a build of seconds), and every cluster's
    /// nearest is brute force's, ties and all.
    #[test]
    fn a_regular_row_halves_every_pass() {
        for spacing in [2.0f32, 0.0] {
            let n = 20_000;
            let boxes: Vec<Aabb> = (0..n)
                .map(|k| {
                    let c = glam::Vec3::new(k as f32 * spacing, 0.0, 0.0);
                    Aabb::new(c - glam::Vec3::splat(0.5), c + glam::Vec3::splat(0.5))
                })
                .collect();
            let bounds = simd_boxes(&boxes);
            let scale = unit_scale(&bounds);
            for r in [1, 6] {
                let mut nearest = vec![0; n];
                find_nearest(&bounds, &mut nearest, r, scale);
                for i in [0, 1, 2, 3, 777, 778, n - 2, n - 1] {
                    let want =
                        brute_nearest(&bounds, i, i.saturating_sub(r)..(i + r + 1).min(n), scale);
                    assert_eq!(
                        nearest[i] as usize, want,
                        "spacing {spacing}, radius {r}, cluster {i}"
                    );
                }
            }
            let order: Vec<u32> = (0..n as u32).collect();
            let bvh = ploc(Boxes::Borrowed(&boxes), order, 6, 2);
            assert_eq!(bvh.nodes.len(), 2 * n - 1);
            // Children follow their parents: each node's depth from its
            // parent's. A balanced tree of 20,000 leaves has 15 levels.
            let mut depth = vec![0usize; bvh.nodes.len()];
            for (k, node) in bvh.nodes.iter().enumerate() {
                if node.prim_count == 0 {
                    let c = node.first_index as usize;
                    (depth[c], depth[c + 1]) = (depth[k] + 1, depth[k] + 1);
                }
            }
            let deepest = depth.iter().max().copied().unwrap_or(0);
            assert!(deepest <= 40, "spacing {spacing}: {deepest} levels");
        }
    }

    /// Each cluster's nearest is the brute-force least union area within
    /// the radius, ties to the nearer index (then by the parity of the
    /// cluster's), across block edges.
    #[test]
    fn nearest_neighbours_match_brute_force() {
        let bounds = simd_boxes(&surface_boxes(2 * BLOCK + 50, 11));
        for r in [1, 6, 14] {
            let mut nearest = vec![0; bounds.len()];
            let scale = unit_scale(&bounds);
            find_nearest(&bounds, &mut nearest, r, scale);
            for (i, &got) in nearest.iter().enumerate() {
                let lo = i.saturating_sub(r);
                let hi = (i + r + 1).min(bounds.len());
                let want = brute_nearest(&bounds, i, lo..hi, scale);
                assert_eq!(got as usize, want, "radius {r}, cluster {i}");
            }
        }
    }
}
