//! Reinsertion (Meister and Bittner, "Parallel Reinsertion for Bounding
//! Volume Hierarchy Optimization", 2018): in batches, the largest nodes
//! of a binary tree each look for the place where moving them lowers the
//! tree's surface area most, then the moves that do not touch one another
//! are made, best first.
//!
//! obvhs's `ReinsertionOptimizer` makes the same batches (a share of the
//! nodes, then that share over 3, 5, … 31) with the same search and the
//! same move (obvhs's `find_reinsertion` and `reinsert_node`, called
//! here), but runs on one thread what lies between its parallel searches:
//! it grows the parents' array, clears a mark for every node before each
//! batch and radix-sorts each batch's candidates. On 16 threads those
//! were most of the step's time (docs/performance.md, "Reinsertion
//! between its searches"). Here the arrays come zeroed from the allocator
//! and their pages are first written by the parallel passes, a mark is
//! the batch's number (nothing to clear), and the candidates are chosen
//! by a selection over keys made in parallel.
//!
//! Every order is total (area, then node id), so the tree is the same
//! for any number of threads. Ties among equal areas may be broken
//! otherwise than obvhs's radix sort breaks them, so the tree can differ
//! from obvhs's where two nodes have the same area; it is no worse (the
//! tests below hold it to obvhs's SAH cost).

use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::{find_reinsertion, reinsert_node, Reinsertion};
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;

/// How many batches: batch b (from 0) is the first's size over 2b + 1,
/// down to 1/31 (obvhs's sequence, which spends the later batches on the
/// largest nodes only).
const BATCHES: u32 = 16;
const _: () = assert!(BATCHES < u8::MAX as u32, "a batch's mark is a byte");

/// Reinserts nodes of `bvh2` in batches, the first of `share` of its nodes
/// (obvhs's `reinsertion_batch_ratio`); none if `share` is 0. Leaves
/// `bvh2.parents` filled.
pub(super) fn reinsert(bvh2: &mut Bvh2, share: f32) {
    let nodes = bvh2.nodes.len();
    if nodes < 3 || share <= 0.0 {
        return;
    }
    // Zeroed by the allocator, not on this thread: obvhs's
    // `compute_parents` leaves the length as it is and stores every
    // parent in parallel, the pages faulted in there.
    let mut parents = vec![0u32; nodes];
    Bvh2::compute_parents(&bvh2.nodes, &mut parents);
    bvh2.parents = parents;
    bvh2.children_are_ordered_after_parents = false;
    // marks[i] == b: node i is moved or moved into in batch b (from 1); a
    // byte a node, as obvhs's flags (the `high` build peaks here).
    let mut marks = vec![0u8; nodes];
    for batch in 0..BATCHES {
        // obvhs's sizes to the bit: the share of the nodes in f32, over
        // 1, 3, 5, …; `+ 1`: the root is never a candidate.
        let divisor = (2 * batch + 1) as f32;
        let size = ((nodes as f32 * share * (1.0 / divisor)) as usize).max(1);
        let count = nodes.min(size + 1) - 1;
        let candidates = largest_nodes(&bvh2.nodes, count);
        let tree = &*bvh2;
        let mut moves: Vec<Reinsertion> = candidates
            .par_iter()
            .with_min_len(256)
            .map(|&node| find_reinsertion(tree, node as usize))
            .filter(|found| found.area_diff > 0.0)
            .collect();
        moves.par_sort_unstable_by(|a, b| {
            b.area_diff
                .total_cmp(&a.area_diff)
                .then(a.from.cmp(&b.from))
        });
        let mark = batch as u8 + 1;
        for found in &moves {
            let (from, to) = (found.from as usize, found.to as usize);
            // The nodes a move rewrites or reads the parent of; a move
            // touching one that an earlier move of the batch touched is
            // dropped (its search saw the tree before that move), and its
            // node may be a candidate again in a later batch.
            let touched = [
                to,
                from,
                Bvh2Node::get_sibling_id(from),
                bvh2.parents[to] as usize,
                bvh2.parents[from] as usize,
            ];
            if touched.iter().any(|&node| marks[node] == mark) {
                continue;
            }
            for node in touched {
                marks[node] = mark;
            }
            reinsert_node(bvh2, from, to);
        }
    }
}

/// The `count` largest nodes by surface area among those numbered 1 to
/// 2·`count` + 1 (obvhs's choice: the first nodes are the top of the tree,
/// where the large ones are, and sorting all of them found no better
/// candidates; the root, 0, never moves), ties to the lower id. In no
/// particular order: each is searched for alone, and the moves found are
/// sorted.
fn largest_nodes(nodes: &[Bvh2Node], count: usize) -> Vec<u32> {
    let end = nodes.len().min(2 * (count + 1));
    // A key per node that orders by area (largest first), then id: a
    // half area is a float of at least 0, whose bits rise with it. A
    // comparison sort of (area, id) pairs took 57 ms of a build of sub2
    // on one thread, this selection 7 ms.
    let mut keys: Vec<u64> = (1..end)
        .into_par_iter()
        .with_min_len(1 << 12)
        .map(|node| {
            let area = nodes[node].aabb().half_area().max(0.0).to_bits();
            (u64::from(!area) << 32) | node as u64
        })
        .collect();
    if count < keys.len() {
        keys.select_nth_unstable(count);
        keys.truncate(count);
    }
    keys.into_iter().map(|key| key as u32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::build::tests::random_boxes;
    use crate::math::Aabb;
    use obvhs::bvh2::reinsertion::ReinsertionOptimizer;

    /// obvhs's own PLOC tree over `boxes`, a primitive a leaf.
    fn ploc_tree(boxes: &[Aabb]) -> Bvh2 {
        let mut bvh2 = Bvh2::default();
        obvhs::ploc::PlocBuilder::with_capacity(boxes.len()).build_with_bvh(
            &mut bvh2,
            obvhs::ploc::PlocSearchDistance::Minimum,
            boxes,
            (0..boxes.len() as u32).collect(),
            obvhs::ploc::SortPrecision::U64,
            0,
        );
        bvh2
    }

    /// The tree's SAH cost in obvhs's sense: each inner node's half area
    /// over the root's (the traversal cost), each leaf's times its count.
    fn sah(bvh2: &Bvh2) -> f64 {
        let root = bvh2.nodes[0].aabb().half_area() as f64;
        bvh2.nodes
            .iter()
            .map(|node| {
                let area = node.aabb().half_area() as f64 / root;
                if node.is_leaf() {
                    area * node.prim_count as f64
                } else {
                    area
                }
            })
            .sum()
    }

    /// The tree is sound, costs less than before and no more than 0.5%
    /// above obvhs's own reinsertion's with the same share (they differ
    /// only in ties), and is the same node for node on one thread and on
    /// three.
    #[test]
    fn reinsertion_lowers_the_cost_as_obvhs_does_on_any_thread_count() {
        for (seed, n) in [(3, 20_000), (4, 3), (5, 2)] {
            let boxes = random_boxes(n, seed);
            let before = ploc_tree(&boxes);
            for share in [0.05, 0.3, 1.0] {
                let mut ours = before.clone();
                reinsert(&mut ours, share);
                if n < 3 {
                    assert_eq!(ours.nodes.len(), before.nodes.len());
                    continue;
                }
                // obvhs's own check: every node reached once, every
                // parent link right, every box its children's union
                // (tight) and holding its primitives, each primitive once.
                ours.validate(&boxes, false, true);
                let mut theirs = before.clone();
                ReinsertionOptimizer::default().run(&mut theirs, share, None);
                let (cost, was, obvhs) = (sah(&ours), sah(&before), sah(&theirs));
                assert!(cost <= was, "{n} boxes, {share}: {cost} from {was}");
                assert!(
                    cost <= 1.005 * obvhs,
                    "{n} boxes, {share}: {cost} against obvhs's {obvhs}"
                );
                if n > 1000 && share > 0.1 {
                    // (5% of this tree's nodes, its top, find no move.)
                    assert!(cost < 0.995 * was, "{share}: {cost} from {was}");
                }
                for threads in [1, 3] {
                    let mut again = before.clone();
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    pool.install(|| reinsert(&mut again, share));
                    let same = again
                        .nodes
                        .iter()
                        .zip(&ours.nodes)
                        .all(|(a, b)| a.aabb() == b.aabb() && a.first_index == b.first_index);
                    assert!(same, "{share}: the tree on {threads} threads");
                }
            }
        }
    }
}
