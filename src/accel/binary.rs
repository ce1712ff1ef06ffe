//! The binary tree a build collapses: PLOC ([`super::ploc`]) over
//! primitives sorted along a Morton curve, then obvhs's reinsertion
//! (Meister and Bittner 2018; Bittner, Hapala and Havran 2013); or, for
//! the fastest preset, PLOC over [`super::cluster`]s into strata's own
//! compact tree ([`BinaryTree`]), which nothing reinserts.

use super::binary_tree::BinaryTree;
use super::build::BuildQuality;
pub(super) use super::cluster::Boxes;
use super::cluster::{morton_order, Clusters};
use super::node::MAX_PRIMS;
use crate::math::Aabb;
use crate::system::steps::Steps;
use glam::Vec3A;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::PlocSearchDistance;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

impl obvhs::Boundable for Aabb {
    #[inline]
    fn aabb(&self) -> obvhs::aabb::Aabb {
        obvhs::aabb::Aabb {
            min: Vec3A::from(self.min),
            max: Vec3A::from(self.max),
        }
    }
}

/// A binary tree in one of the two layouts the collapse reads
/// ([`super::binary_tree::Binary`]).
#[derive(Clone)]
pub(super) enum Tree {
    /// obvhs's, which its reinsertion has optimised (fast, medium, high).
    Obvhs(Bvh2),
    /// strata's own, over clusters (fastest).
    Own(BinaryTree),
}

impl Tree {
    /// How many primitives the tree holds.
    pub(super) fn prim_count(&self) -> usize {
        match self {
            Tree::Obvhs(bvh2) => bvh2.primitive_indices.len(),
            Tree::Own(tree) => tree.ids.len(),
        }
    }
}

/// The binary tree over `boxes` and their union; `None` if there are no
/// boxes.
pub(super) fn binary_tree_and_bounds(
    boxes: Boxes,
    quality: BuildQuality,
    steps: &mut Steps,
) -> Option<(Tree, Aabb)> {
    if boxes.is_empty() {
        return None;
    }
    assert!(
        boxes.len() <= MAX_PRIMS,
        "too many primitives for one BVH: {}",
        boxes.len()
    );
    // A union is exact, so any grouping gives the same box.
    let bounds = steps.time("bounds", || {
        boxes
            .par_iter()
            .with_min_len(1 << 14)
            .copied()
            .reduce(|| Aabb::EMPTY, Aabb::union)
    });
    Some((binary_tree(boxes, bounds, quality, steps), bounds))
}

/// The binary tree over `boxes` (not empty, inside `bounds`): obvhs's,
/// one primitive a leaf, or for the fastest preset strata's own, one
/// cluster of up to [`LEAF_PRIMS`](super::collapse::LEAF_PRIMS)
/// primitives a leaf ([`super::cluster`]).
pub(super) fn binary_tree(
    boxes: Boxes,
    bounds: Aabb,
    quality: BuildQuality,
    steps: &mut Steps,
) -> Tree {
    let preset = quality.preset(boxes.len());
    let params = quality.params(boxes.len());
    if preset == BuildQuality::Fastest {
        // The clusters free the boxes once their first round has read them.
        let clusters = steps.time("clusters", || Clusters::new(boxes, bounds));
        let Clusters {
            order,
            starts,
            boxes,
            spare,
        } = clusters;
        // The clusters lie along the curve already: cluster c is leaf c,
        // and its primitives are `order`'s ids from starts[c] to
        // starts[c + 1]. PLOC takes the clusters' boxes and the rounds'
        // other buffer as its own clusters.
        let (radius, near) = (radius(&params), params.search_depth_threshold);
        debug_assert_eq!(params.reinsertion_batch_ratio, 0.0);
        return Tree::Own(steps.time("ploc", || {
            super::ploc::ploc_tree(boxes, spare, starts, order, radius, near)
        }));
    }
    let order = steps.time("morton", || morton_order(&boxes, bounds));
    // PLOC frees the boxes and the order before its passes.
    let mut bvh2 = steps.time("ploc", || ploc(boxes, order, &params));
    if params.reinsertion_batch_ratio > 0.0 {
        steps.time("reinsertion", || {
            ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None)
        });
    }
    // The collapse reads nodes and primitive indices only: free the maps
    // reinsertion kept (parents: 8 bytes a primitive) before it.
    bvh2.parents = Vec::new();
    bvh2.primitives_to_nodes = Vec::new();
    Tree::Obvhs(bvh2)
}

/// PLOC's tree over `boxes` sorted along the curve as `order` lists them
/// ([`super::ploc`]: parallel, the same tree on any thread count), one
/// leaf each, leaf `i` holding id `i`, with the preset's search radius.
fn ploc(boxes: Boxes, order: Vec<u32>, params: &BvhBuildParams) -> Bvh2 {
    super::ploc::ploc(boxes, order, radius(params), params.search_depth_threshold)
}

/// How many places of the curve each way a cluster looks for its nearest
/// neighbour, for the preset `params`.
fn radius(params: &BvhBuildParams) -> usize {
    match params.ploc_search_distance {
        PlocSearchDistance::Minimum => 1,
        PlocSearchDistance::VeryLow => 2,
        PlocSearchDistance::Low => 6,
        PlocSearchDistance::Medium => 14,
        PlocSearchDistance::High => 24,
        PlocSearchDistance::VeryHigh => 32,
    }
}

/// obvhs's own PLOC tree over `boxes` (sequential merges), one leaf
/// each, leaf `i` holding id `i`: what [`ploc`] replaced, kept to hold it
/// to the same quality.
#[cfg(test)]
fn obvhs_ploc(boxes: &[Aabb], params: &BvhBuildParams) -> Bvh2 {
    let mut bvh2 = Bvh2::default();
    obvhs::ploc::PlocBuilder::with_capacity(boxes.len()).build_with_bvh(
        &mut bvh2,
        params.ploc_search_distance,
        boxes,
        (0..boxes.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    bvh2
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::random_boxes;
    use super::super::build::Bvh8;
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

    /// The fastest preset's tree in strata's own layout collapses to the
    /// same 8-wide tree, bit for bit, as the same merges written as
    /// obvhs's tree (what it built before): the layout changes the
    /// build's memory, not its tree; on one thread and on three.
    #[test]
    fn the_own_layout_collapses_to_the_tree_obvhs_layout_did() {
        use super::super::build::tests::on_threads;
        let boxes = random_boxes(200_000, 21);
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let params = BuildQuality::Fastest.params(boxes.len());
        let (radius, near) = (radius(&params), params.search_depth_threshold);
        let obvhs_layout = {
            let c = Clusters::new(Boxes::Borrowed(&boxes), bounds);
            let mut bvh2 = super::super::ploc::ploc_in_order(c.boxes, c.order, radius, near);
            for node in bvh2.nodes.iter_mut().filter(|n| n.prim_count > 0) {
                let j = node.first_index as usize;
                node.first_index = c.starts[j];
                node.prim_count = c.starts[j + 1] - c.starts[j];
            }
            Bvh8::collapse(&Tree::Obvhs(bvh2), bounds, u32::MAX)
        };
        let bits = |b: &Bvh8| -> Vec<u32> {
            b.nodes
                .iter()
                .flat_map(|n| {
                    n.child
                        .into_iter()
                        .chain(n.bounds.as_flattened().iter().map(|x| x.to_bits()))
                })
                .collect()
        };
        for threads in [1, 3] {
            let own = on_threads(threads, || {
                let tree = binary_tree(
                    Boxes::Borrowed(&boxes),
                    bounds,
                    BuildQuality::Fastest,
                    &mut Steps::default(),
                );
                let Tree::Own(own) = &tree else {
                    panic!("fastest builds strata's own tree")
                };
                assert_eq!(own.nodes.len() + 1, own.leaves.len());
                Bvh8::collapse(&tree, bounds, u32::MAX)
            });
            assert!(bits(&own) == bits(&obvhs_layout), "{threads} threads");
            assert_eq!(own.prim_ids, obvhs_layout.prim_ids);
            assert_eq!(
                (own.depth, own.bounds),
                (obvhs_layout.depth, obvhs_layout.bounds)
            );
        }
    }

    /// The parallel PLOC ([`super::ploc`]) makes trees as good as obvhs's
    /// sequential one did, through reinsertion and the collapse: SAH cost
    /// within 2% for each preset with a primitive a leaf, over boxes in a
    /// volume and boxes on a surface (the dragon's figures are in
    /// docs/performance.md).
    #[test]
    fn parallel_ploc_keeps_the_tree_quality_of_obvhs() {
        let mut rng = seeded(12);
        let surface: Vec<Aabb> = (0..150_000)
            .map(|_| {
                let d = rng.cube(1.0).normalize_or(Vec3::Y);
                let c = d * (10.0 + (4.0 * d.x).sin() * (3.0 * d.y).cos());
                Aabb::new(c - 0.03, c + 0.03)
            })
            .collect();
        for boxes in [random_boxes(150_000, 9), surface] {
            let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            for quality in [BuildQuality::Fast, BuildQuality::Medium, BuildQuality::High] {
                let params = quality.params(boxes.len());
                let Tree::Obvhs(ours) = binary_tree(
                    Boxes::Borrowed(&boxes),
                    bounds,
                    quality,
                    &mut Steps::default(),
                ) else {
                    panic!("{quality:?} reinserts in obvhs's tree");
                };
                let mut theirs = obvhs_ploc(&boxes, &params);
                ReinsertionOptimizer::default().run(
                    &mut theirs,
                    params.reinsertion_batch_ratio,
                    None,
                );
                let cost = |b: Bvh2| {
                    let tree = Tree::Obvhs(b);
                    Bvh8::collapse(&tree, bounds, u32::MAX).stats().sah_cost
                };
                let (ours, theirs) = (cost(ours), cost(theirs));
                assert!(
                    ours < 1.02 * theirs,
                    "{quality:?}: SAH cost {ours} against obvhs's {theirs}"
                );
            }
        }
    }
}
