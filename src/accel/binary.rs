//! The binary tree a build collapses: PLOC ([`super::ploc`]) over
//! primitives sorted along a Morton curve, or over [`super::cluster`]s of
//! them, then reinsertion ([`super::reinsert`]: Meister and Bittner
//! 2018; Bittner, Hapala and Havran 2013), as each preset's [`Recipe`]
//! says.

use super::build::BuildQuality;
use super::choice::MODEL_MIN_PRIMS;
pub(super) use super::cluster::Boxes;
use super::cluster::{morton_order, Clusters};
use super::node::MAX_PRIMS;
use super::simd::pages::give_back_freed_memory;
use crate::math::Aabb;
use crate::system::steps::Steps;
use glam::Vec3A;
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;

/// How a preset builds its binary tree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Recipe {
    /// Rounds of pairing into [`Clusters`] before PLOC, each cluster a
    /// leaf of up to 2^rounds primitives; 0: one primitive a leaf.
    pub cluster_rounds: u32,
    /// How many places of the curve each way a cluster looks for its
    /// nearest neighbour: 1, 2, 6, 14, 24 or 32 (obvhs's distances, for
    /// each of which `super::ploc` compiles a search).
    pub radius: usize,
    /// PLOC's first passes that look one place each way only (obvhs's
    /// `search_depth_threshold`), while clusters are many and their
    /// neighbours on the curve near.
    pub near_passes: usize,
    /// The share of nodes reinsertion's first batch tries to move (obvhs's
    /// `reinsertion_batch_ratio`); 0: none.
    pub reinsertion: f32,
}

impl Recipe {
    /// The recipe of `preset` (not `auto`) for `prims` primitives, of
    /// which `others` are tested one by one in a leaf (instances or
    /// analytic shapes).
    ///
    /// From [`MODEL_MIN_PRIMS`] triangles on, every preset builds over
    /// clusters: two rounds, then PLOC with a window of two and
    /// reinsertion of 2%, is `medium`, the full-quality tree, within 1.3%
    /// of the SAH cost of PLOC over single primitives with a window of 14
    /// and reinsertion of 5% (the recipe below that size) in less than
    /// half its time (docs/performance.md, "The full-quality build from
    /// clusters"). `high` pairs primitives once, then runs PLOC with a
    /// window of 24 and no near passes and reinserts 30%: a tree that
    /// costs less than obvhs's slow recipe over single primitives (17.28
    /// against 17.38 on the dragon) in the same time, over a binary tree
    /// a third smaller ("The high tree over pairs"). Below that size
    /// every build takes milliseconds; and a leaf of clustered instances
    /// or shapes would test them one by one where a node tests their
    /// boxes together, so a tree of which they are more than 1% keeps one
    /// primitive a leaf (a mesh's scene with a sphere or two does not);
    /// `fastest` clusters whatever it holds, as asked.
    pub(super) fn of(preset: BuildQuality, prims: usize, others: usize) -> Self {
        let large = prims - others.min(prims) >= MODEL_MIN_PRIMS && others * 100 <= prims;
        let recipe = |cluster_rounds, radius, near_passes, reinsertion| Self {
            cluster_rounds,
            radius,
            near_passes,
            reinsertion,
        };
        match preset {
            // The preview tree is cut from the curve, not built: unread.
            BuildQuality::Preview | BuildQuality::Fastest => recipe(3, 1, 0, 0.0),
            BuildQuality::Fast if large => recipe(3, 2, 0, 0.01),
            BuildQuality::Medium | BuildQuality::Auto if large => recipe(2, 2, 0, 0.02),
            BuildQuality::High if large => recipe(1, 24, 0, 0.3),
            BuildQuality::Fast | BuildQuality::Medium | BuildQuality::Auto | BuildQuality::High => {
                Self::one_a_leaf(preset)
            }
        }
    }

    /// The recipe of `preset` over one primitive a leaf: obvhs's
    /// parameters of the same name (`fast_build`, `medium_build`,
    /// `slow_build` for `high`; `fastest_build` otherwise).
    pub(super) fn one_a_leaf(preset: BuildQuality) -> Self {
        let (radius, near_passes, reinsertion) = match preset {
            BuildQuality::Fast => (6, 2, 0.02),
            BuildQuality::Medium | BuildQuality::Auto => (14, 3, 0.05),
            BuildQuality::High => (24, 2, 0.2),
            BuildQuality::Preview | BuildQuality::Fastest => (1, 0, 0.0),
        };
        Self {
            cluster_rounds: 0,
            radius,
            near_passes,
            reinsertion,
        }
    }
}

impl obvhs::Boundable for Aabb {
    #[inline]
    fn aabb(&self) -> obvhs::aabb::Aabb {
        obvhs::aabb::Aabb {
            min: Vec3A::from(self.min),
            max: Vec3A::from(self.max),
        }
    }
}

/// The binary tree of `quality` over `boxes` (triangles' or the like:
/// none tested one by one) and their union; `None` if there are no boxes.
/// For tests, which keep the binary tree to look at; a build goes through
/// [`bounds`] and [`binary_tree`] itself.
#[cfg(test)]
pub(super) fn binary_tree_and_bounds(
    boxes: Boxes,
    quality: BuildQuality,
    steps: &mut Steps,
) -> Option<(Bvh2, Aabb)> {
    let bounds = bounds(&boxes, steps)?;
    let recipe = Recipe::of(quality.preset(boxes.len()), boxes.len(), 0);
    Some((binary_tree(boxes, bounds, recipe, steps), bounds))
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

/// From this many primitives a build hands its freed pages back before a
/// reinsertion and at its end ([`give_back_freed_memory`], 2 ms on the dragon).
const GIVE_BACK_MIN_PRIMS: usize = 100_000;

/// A build over `prims` primitives hands its freed pages back here if it
/// is large ([`GIVE_BACK_MIN_PRIMS`]), timed as its `give back` step.
pub(super) fn give_back_if_large(prims: usize, steps: &mut Steps) {
    if prims >= GIVE_BACK_MIN_PRIMS {
        steps.time("give back", give_back_freed_memory);
    }
}

/// The binary tree over `boxes` (not empty, inside `bounds`) that
/// `recipe` builds: one primitive a leaf, or one cluster of up to
/// 2^rounds primitives a leaf ([`super::cluster`]).
pub(super) fn binary_tree(boxes: Boxes, bounds: Aabb, recipe: Recipe, steps: &mut Steps) -> Bvh2 {
    let (radius, near) = (recipe.radius, recipe.near_passes);
    let mut bvh2 = if recipe.cluster_rounds > 0 {
        // The clusters free the boxes once their first round has read them.
        let rounds = recipe.cluster_rounds;
        let clusters = steps.time("clusters", || Clusters::new(boxes, bounds, rounds));
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
        steps.time("ploc", || super::ploc::ploc(boxes, order, radius, near))
    };
    if recipe.reinsertion > 0.0 {
        // The reinsertion's buffers (a third of the tree at `high`) would
        // be new pages on top of what PLOC freed and glibc still holds:
        // that is handed back first, so the reinsertion's peak is the
        // tree's and its own (docs/performance.md, "Binary nodes of 32
        // bytes": the dragon's `high` render 121 → 98 B a triangle).
        give_back_if_large(bvh2.primitive_indices.len(), steps);
        steps.time("reinsertion", || {
            super::reinsert::reinsert(&mut bvh2, recipe.reinsertion)
        });
    }
    // The collapse reads nodes and primitive indices only: free the maps
    // reinsertion kept (parents: 8 bytes a primitive) before it.
    bvh2.parents = Vec::new();
    bvh2.primitives_to_nodes = Vec::new();
    bvh2
}

/// obvhs's own PLOC tree over `boxes` (sequential merges), one leaf
/// each, leaf `i` holding id `i`: what [`ploc`] replaced, kept to hold it
/// to the same quality.
#[cfg(test)]
fn obvhs_ploc(boxes: &[Aabb], params: &obvhs::BvhBuildParams) -> Bvh2 {
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
    use obvhs::bvh2::reinsertion::ReinsertionOptimizer;

    /// Boxes of a closed, wrinkled surface (a mesh's triangles), and
    /// their union.
    fn surface_boxes(n: usize, seed: u64) -> (Vec<Aabb>, Aabb) {
        let mut rng = seeded(seed);
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| {
                let d = rng.cube(1.0).normalize_or(Vec3::Y);
                let c = d * (10.0 + (4.0 * d.x).sin() * (3.0 * d.y).cos());
                Aabb::new(c - 0.03, c + 0.03)
            })
            .collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        (boxes, bounds)
    }

    /// The SAH cost of the 8-wide tree collapsed from `bvh2`, whose root
    /// box is `bounds`.
    fn sah_cost(bvh2: &Bvh2, bounds: Aabb) -> f64 {
        Bvh8::collapse(bvh2, bounds, u32::MAX).stats().sah_cost
    }

    /// The SAH cost of the 8-wide tree `recipe` builds over `boxes`.
    fn cost_by(boxes: &[Aabb], bounds: Aabb, recipe: Recipe) -> f64 {
        let bvh2 = binary_tree(
            Boxes::Borrowed(boxes),
            bounds,
            recipe,
            &mut Steps::default(),
        );
        sah_cost(&bvh2, bounds)
    }

    /// From `MODEL_MIN_PRIMS` primitives on, `medium` builds over
    /// clusters, and its tree costs at most 2% more than the one over
    /// single primitives it replaced (the bound; 1.3% on the
    /// dragon); `fast`'s over bigger clusters costs more than
    /// `medium`'s, and `fastest`'s more again. `high`'s over pairs costs
    /// less than `medium`'s, and no more than obvhs's slow recipe over
    /// single primitives (0.6% less on the dragon). Below that size, or
    /// with more than 1% of instances or shapes, all three keep one
    /// primitive a leaf.
    #[test]
    fn trees_over_clusters_cost_little_more_than_over_primitives() {
        let (boxes, bounds) = surface_boxes(MODEL_MIN_PRIMS + 50_000, 21);
        let n = boxes.len();
        let medium = Recipe::of(BuildQuality::Medium, n, 0);
        assert!(medium.cluster_rounds > 0, "{medium:?}");
        let single = cost_by(&boxes, bounds, Recipe::one_a_leaf(BuildQuality::Medium));
        let clustered = cost_by(&boxes, bounds, medium);
        assert!(
            clustered <= 1.02 * single,
            "medium over clusters {clustered}, over primitives {single}"
        );
        let fast = cost_by(&boxes, bounds, Recipe::of(BuildQuality::Fast, n, 0));
        let fastest = cost_by(&boxes, bounds, Recipe::of(BuildQuality::Fastest, n, 0));
        assert!(
            clustered < fast && fast < fastest,
            "medium {clustered}, fast {fast}, fastest {fastest}"
        );
        let high = Recipe::of(BuildQuality::High, n, 0);
        assert!(high.cluster_rounds > 0, "{high:?}");
        let high = cost_by(&boxes, bounds, high);
        let high_single = cost_by(&boxes, bounds, Recipe::one_a_leaf(BuildQuality::High));
        assert!(
            high < clustered && high <= high_single,
            "high over pairs {high}, over primitives {high_single}, medium {clustered}"
        );
        // Small trees, and trees of which instances or shapes are more
        // than 1%, keep one a leaf; a sphere among the triangles clusters.
        for quality in [BuildQuality::Fast, BuildQuality::Medium, BuildQuality::High] {
            let single = Recipe::one_a_leaf(quality);
            assert_eq!(Recipe::of(quality, MODEL_MIN_PRIMS - 1, 0), single);
            assert_eq!(Recipe::of(quality, n, n / 100 + 1), single, "{quality:?}");
            assert_eq!(Recipe::of(quality, MODEL_MIN_PRIMS + 1, 2), single);
            assert_ne!(Recipe::of(quality, n, 1), single, "{quality:?}");
        }
    }

    /// The parallel PLOC ([`super::ploc`]) makes trees as good as obvhs's
    /// sequential one did, through reinsertion and the collapse: SAH cost
    /// within 2% for each preset with a primitive a leaf, over boxes in a
    /// volume and boxes on a surface (the dragon's figures are in
    /// docs/performance.md).
    #[test]
    fn parallel_ploc_keeps_the_tree_quality_of_obvhs() {
        let (surface, _) = surface_boxes(150_000, 12);
        for boxes in [random_boxes(150_000, 9), surface] {
            let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            for (quality, params) in [
                (BuildQuality::Fast, obvhs::BvhBuildParams::fast_build()),
                (BuildQuality::Medium, obvhs::BvhBuildParams::medium_build()),
                (BuildQuality::High, obvhs::BvhBuildParams::slow_build()),
            ] {
                let recipe = Recipe::one_a_leaf(quality);
                assert_eq!(
                    (recipe.reinsertion, recipe.near_passes),
                    (
                        params.reinsertion_batch_ratio,
                        params.search_depth_threshold
                    ),
                    "{quality:?} is obvhs's preset of its name"
                );
                let ours = binary_tree(
                    Boxes::Borrowed(&boxes),
                    bounds,
                    recipe,
                    &mut Steps::default(),
                );
                let mut theirs = obvhs_ploc(&boxes, &params);
                ReinsertionOptimizer::default().run(
                    &mut theirs,
                    params.reinsertion_batch_ratio,
                    None,
                );
                let (ours, theirs) = (sah_cost(&ours, bounds), sah_cost(&theirs, bounds));
                assert!(
                    ours < 1.02 * theirs,
                    "{quality:?}: SAH cost {ours} against obvhs's {theirs}"
                );
            }
        }
    }
}
