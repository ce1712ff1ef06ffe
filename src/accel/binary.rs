//! The binary tree a build collapses: PLOC ([`super::ploc`]) over
//! primitives sorted along a Morton curve, or over [`super::cluster`]s
//! for the fastest preset, then obvhs's reinsertion (Meister and Bittner
//! 2018; Bittner, Hapala and Havran 2013).

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

/// obvhs's binary tree over `boxes` and their union; `None` if there are
/// no boxes. For tests, which keep the binary tree to look at; a build
/// goes through [`bounds`] and [`binary_tree`] itself.
#[cfg(test)]
pub(super) fn binary_tree_and_bounds(
    boxes: Boxes,
    quality: BuildQuality,
    steps: &mut Steps,
) -> Option<(Bvh2, Aabb)> {
    let bounds = bounds(&boxes, steps)?;
    Some((binary_tree(boxes, bounds, quality, steps), bounds))
}

/// The union of `boxes`, timed as the build's `bounds` step; `None` if
/// there are none. Every preset's build starts here.
pub(super) fn bounds(boxes: &[Aabb], steps: &mut Steps) -> Option<Aabb> {
    if boxes.is_empty() {
        return None;
    }
    assert!(
        boxes.len() <= MAX_PRIMS,
        "too many primitives for one BVH: {}",
        boxes.len()
    );
    // A union is exact, so any grouping gives the same box.
    Some(steps.time("bounds", || {
        // A plain loop over each chunk: rayon's per-item folding was
        // compiled well or not (0.01 or 0.045 s on 13.9M boxes) as the
        // inlining around it changed.
        boxes
            .par_chunks(1 << 14)
            .map(|chunk| chunk.iter().fold(Aabb::EMPTY, |a, b| a.union(*b)))
            .reduce(|| Aabb::EMPTY, Aabb::union)
    }))
}

/// obvhs's binary tree over `boxes` (not empty, inside `bounds`): one
/// primitive a leaf, or for the fastest preset one cluster of up to
/// [`LEAF_PRIMS`](super::collapse::LEAF_PRIMS) primitives a leaf
/// ([`super::cluster`]).
pub(super) fn binary_tree(
    boxes: Boxes,
    bounds: Aabb,
    quality: BuildQuality,
    steps: &mut Steps,
) -> Bvh2 {
    let preset = quality.preset(boxes.len());
    let params = quality.params(boxes.len());
    let mut bvh2 = if preset == BuildQuality::Fastest {
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
        let mut bvh2 = steps.time("ploc", || {
            super::ploc::ploc_in_order(boxes, spare, order, radius, near)
        });
        bvh2.nodes
            .par_iter_mut()
            .with_min_len(1 << 14)
            .filter(|node| node.prim_count > 0)
            .for_each(|node| {
                let c = node.first_index as usize;
                node.first_index = starts[c];
                node.prim_count = starts[c + 1] - starts[c];
            });
        bvh2
    } else {
        let order = steps.time("morton", || morton_order(&boxes, bounds));
        // PLOC frees the boxes and the order before its passes.
        steps.time("ploc", || ploc(boxes, order, &params))
    };
    if params.reinsertion_batch_ratio > 0.0 {
        steps.time("reinsertion", || {
            ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None)
        });
    }
    // The collapse reads nodes and primitive indices only: free the maps
    // reinsertion kept (parents: 8 bytes a primitive) before it.
    bvh2.parents = Vec::new();
    bvh2.primitives_to_nodes = Vec::new();
    bvh2
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
                let ours = binary_tree(
                    Boxes::Borrowed(&boxes),
                    bounds,
                    quality,
                    &mut Steps::default(),
                );
                let mut theirs = obvhs_ploc(&boxes, &params);
                ReinsertionOptimizer::default().run(
                    &mut theirs,
                    params.reinsertion_batch_ratio,
                    None,
                );
                let cost = |b: &Bvh2| Bvh8::collapse(b, bounds, u32::MAX).stats().sah_cost;
                let (ours, theirs) = (cost(&ours), cost(&theirs));
                assert!(
                    ours < 1.02 * theirs,
                    "{quality:?}: SAH cost {ours} against obvhs's {theirs}"
                );
            }
        }
    }
}
