//! The 8-wide BVH and its build: the binary tree ([`super::binary`]:
//! PLOC and reinsertion), then a collapse into 8-wide nodes chosen
//! by the surface area heuristic over the whole subtree (Ylitie, Karras
//! and Laine 2017), see [`super::collapse`].

use super::binary::{binary_tree, give_back_if_large, Boxes, Recipe};
use super::collapse::{LEAF_COST, NODE_COST, OTHER_COST};
use super::node::{encode_leaf, is_leaf, leaf_range, Node8, EMPTY};
use super::simd::pages::{move_to_huge_pages, Pages};
use crate::math::Aabb;
use crate::system::steps::Steps;
use glam::Vec3;
#[cfg(test)]
use obvhs::bvh2::Bvh2;

crate::mode::mode_enum! {
    /// Build effort. `auto` picks by primitive count, and for a render by
    /// the estimated build and trace time of each preset
    /// ([`BuildQuality::choose`], [`super::choice`]).
    #[derive(Default)]
    pub enum BuildQuality("BVH quality") {
        Preview = "preview",
        Fastest = "fastest",
        Fast = "fast",
        #[default]
        Auto = "auto",
        Medium = "medium",
        High = "high",
    }
}

impl BuildQuality {
    /// The preset a build over `prim_count` primitives uses when no render
    /// says how many rays it will trace: `auto` is `medium`.
    pub fn preset(self, prim_count: usize) -> Self {
        self.choose(prim_count, None).quality
    }
}

/// The 8-wide BVH. `prim_ids` lists primitive ids in leaf order, in
/// blocks of [`LANES`](crate::math::lanes::LANES) slots that no leaf straddles; unused slots
/// hold [`NO_PRIM`](super::NO_PRIM).
#[derive(Debug, Clone)]
pub struct Bvh8 {
    /// The nodes, the root first; their layout is accel's own
    /// ([`Bvh8::node_count`], [`Bvh8::root_boxes`] and the walks read them).
    pub(super) nodes: Vec<Node8>,
    pub prim_ids: Vec<u32>,
    pub bounds: Aabb,
    /// Deepest node level, for sizing traversal stacks.
    pub depth: u32,
    /// Whether traversal prefetches the children it defers (see
    /// [`super::prefetch`]). On after a build; a scene turns it off when
    /// its tree fits the caches ([`super::prefetch::Prefetch::Auto`]).
    pub prefetch: bool,
    /// The pages the nodes are on, and the leaf store built from this
    /// tree goes on ([`Bvh8::set_pages`]); small after a build.
    pub(crate) pages: Pages,
}

impl Bvh8 {
    pub fn empty() -> Self {
        Self {
            nodes: Vec::new(),
            prim_ids: Vec::new(),
            bounds: Aabb::EMPTY,
            depth: 0,
            prefetch: true,
            pages: Pages::Small,
        }
    }

    /// Build over primitive boxes; primitive `i` is reported as id `i`.
    /// Boxes must be finite (the scene compiler rejects the rest).
    pub fn build(boxes: &[Aabb], quality: BuildQuality) -> Self {
        Self::build_boxes(
            Boxes::Borrowed(boxes),
            quality,
            u32::MAX,
            &mut Steps::default(),
        )
    }

    /// [`Bvh8::build`] that takes the boxes and frees them as soon as the
    /// build is done with them: before PLOC for the fastest preset (which
    /// builds over clusters, and whose peak is PLOC's: 24 bytes a
    /// primitive less there), else once the binary tree is built, before
    /// the collapse.
    pub fn build_from(boxes: Vec<Aabb>, quality: BuildQuality) -> Self {
        Self::build_from_with_others(boxes, quality, u32::MAX)
    }

    /// [`Bvh8::build_from`] over triangles `..first_other` and, from
    /// `first_other` on, primitives a leaf tests one by one (analytic
    /// shapes, instances): the collapse charges a leaf for each of those,
    /// so that it prefers to test their boxes in 8-wide nodes.
    pub fn build_from_with_others(
        boxes: Vec<Aabb>,
        quality: BuildQuality,
        first_other: u32,
    ) -> Self {
        Self::build_timed(boxes, quality, first_other, &mut Steps::default())
    }

    /// [`Bvh8::build_from_with_others`] that adds the wall time of each of
    /// its steps to `steps` (bounds, clusters or Morton order, PLOC,
    /// reinsertion, collapse; for the preview preset morton, cut and
    /// assemble; then, for a large tree, give back), for `--stats`.
    pub fn build_timed(
        boxes: Vec<Aabb>,
        quality: BuildQuality,
        first_other: u32,
        steps: &mut Steps,
    ) -> Self {
        Self::build_boxes(Boxes::Owned(boxes), quality, first_other, steps)
    }

    /// Every build: the preview tree cut from the boxes' Morton order
    /// ([`super::lbvh`]), or the binary tree collapsed into 8-wide nodes.
    fn build_boxes(
        boxes: Boxes,
        quality: BuildQuality,
        first_other: u32,
        steps: &mut Steps,
    ) -> Self {
        let prims = boxes.len();
        let Some(bounds) = super::binary::bounds(&boxes, steps) else {
            return Self::empty();
        };
        let preset = quality.preset(prims);
        let tree = if preset == BuildQuality::Preview {
            super::lbvh::build(boxes, bounds, steps).debug_validated(prims)
        } else {
            let others = prims.saturating_sub(first_other as usize);
            let recipe = Recipe::of(preset, prims, others);
            let bvh2 = binary_tree(boxes, bounds, recipe, steps);
            steps.time("collapse", || {
                super::collapse::collapse_owned(bvh2, bounds, first_other).debug_validated(prims)
            })
        };
        give_back_if_large(prims, steps);
        tree
    }

    /// The 8-wide tree over obvhs's binary one, whose root box is `bounds`,
    /// the binary tree kept: for tests (a build frees it as it collapses).
    #[cfg(test)]
    pub(super) fn collapse(bvh2: &Bvh2, bounds: Aabb, first_other: u32) -> Self {
        super::collapse::collapse(bvh2, bounds, first_other)
            .debug_validated(bvh2.primitive_indices.len())
    }

    /// True for a tree of no node (built over no primitive), which every
    /// walk answers without a step.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// How many 8-wide nodes the tree has.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Frees the nodes' spare capacity, for a tree kept for the rest of a
    /// run.
    pub fn shrink_to_fit(&mut self) {
        self.nodes.shrink_to_fit();
    }

    /// Puts the nodes on `pages` (in place, after the build), and with
    /// them the leaf store a scene builds from this tree next
    /// (`Geometry::new`): huge pages spare a walk through a large tree a
    /// TLB miss at most nodes, where the rays pay for faulting them in
    /// ([`super::choice`]).
    pub fn set_pages(&mut self, pages: Pages) {
        if pages == Pages::Huge {
            move_to_huge_pages(&self.nodes);
        }
        self.pages = pages;
    }

    /// The boxes of the root's children (none for an empty tree): tighter
    /// than the tree's own box once each is moved, as an instance's world
    /// box is made.
    pub fn root_boxes(&self) -> impl Iterator<Item = Aabb> + '_ {
        self.nodes.first().into_iter().flat_map(|root| {
            (0..8).filter(|&k| root.child[k] != EMPTY).map(|k| {
                let b = &root.bounds;
                Aabb::new(
                    Vec3::new(b[0][k], b[2][k], b[4][k]),
                    Vec3::new(b[1][k], b[3][k], b[5][k]),
                )
            })
        })
    }

    /// A tree of one node whose eight children are leaves of one
    /// primitive each, primitive `i` in `boxes[i]`, and that does not
    /// prefetch: the node test alone, for the kernel benches.
    pub fn one_node(boxes: &[Aabb; 8]) -> Self {
        let mut node = Node8::EMPTY;
        let mut bounds = Aabb::EMPTY;
        for (slot, b) in boxes.iter().enumerate() {
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = b.min[axis];
                node.bounds[2 * axis + 1][slot] = b.max[axis];
            }
            node.child[slot] = encode_leaf(slot as u32, 1);
            bounds = bounds.union(*b);
        }
        Self {
            nodes: vec![node],
            prim_ids: (0..8).collect(),
            bounds,
            depth: 1,
            prefetch: false,
            pages: Pages::Small,
        }
    }

    /// Bytes held by the final structure.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node8>() + self.prim_ids.len() * 4
    }

    /// Counts and the expected traversal cost of the tree, for reports.
    pub fn stats(&self) -> TreeStats {
        self.stats_charging(u32::MAX)
    }

    /// [`Bvh8::stats`] with each leaf charged as the collapse charges it
    /// for primitives `first_other..` ([`Bvh8::build_from_with_others`]).
    pub(super) fn stats_charging(&self, first_other: u32) -> TreeStats {
        let mut stats = TreeStats {
            nodes: self.nodes.len(),
            ..TreeStats::default()
        };
        let root_area = self.bounds.half_area() as f64;
        let mut cost = 0.0f64;
        // Areas of the boxes a parent keeps for its inner children and its
        // leaves; the root's own box is entered by every line through it.
        let (mut node_area, mut leaf_area) = (root_area, 0.0f64);
        let mut leaf_blocks_area = 0.0f64;
        for node in &self.nodes {
            for slot in 0..8 {
                let child = node.child[slot];
                if child == EMPTY {
                    continue;
                }
                stats.children += 1;
                let b = |row: usize| node.bounds[row][slot] as f64;
                let (dx, dy, dz) = (b(1) - b(0), b(3) - b(2), b(5) - b(4));
                let area = dx * dy + dy * dz + dz * dx;
                if is_leaf(child) {
                    let (start, count) = leaf_range(child);
                    stats.leaves += 1;
                    stats.leaf_prims += count as usize;
                    // A scene's tree has handed its ids to its leaf blocks.
                    let others = match first_other {
                        u32::MAX => 0,
                        _ => self.prim_ids[start as usize..(start + count) as usize]
                            .iter()
                            .filter(|&&id| id >= first_other)
                            .count(),
                    };
                    cost += (LEAF_COST + OTHER_COST * others as f32) as f64 * area;
                    leaf_area += area;
                    leaf_blocks_area += area * count.div_ceil(4) as f64;
                } else {
                    cost += NODE_COST as f64 * area;
                    node_area += area;
                }
            }
        }
        if root_area > 0.0 {
            stats.sah_cost = NODE_COST as f64 + cost / root_area;
            stats.node_tests = node_area / root_area;
            stats.leaf_tests = leaf_area / root_area;
            stats.embree_sah = stats.node_tests + leaf_blocks_area / root_area;
        }
        stats
    }
}

/// What [`Bvh8::stats`] reports.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TreeStats {
    pub nodes: usize,
    /// Occupied child slots over all nodes.
    pub children: usize,
    pub leaves: usize,
    /// Primitives over all leaves.
    pub leaf_prims: usize,
    /// The surface area heuristic's expected cost of one ray that enters
    /// the root, in node tests (the constants the collapse weighs).
    pub sah_cost: f64,
    /// How many nodes, and how many leaves, a random line through the
    /// root's box enters on average: the sum of their boxes' surface
    /// areas over the root's (a convex box inside another is met by that
    /// share of the lines that meet the outer one: Cauchy's formula, the
    /// surface area heuristic's premise; MacDonald and Booth 1990). The
    /// node figure is the one Embree prints as its nodes' `sah` (travCost
    /// 1); Embree charges each leaf once per block of four primitives it
    /// holds, where strata tests a leaf's up to eight in one 8-wide test.
    pub node_tests: f64,
    pub leaf_tests: f64,
    /// The total Embree prints for its `triangle4` trees (`verbose=2`):
    /// the node tests, and each leaf's area once per block of four.
    pub embree_sah: f64,
}

impl std::fmt::Display for TreeStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let per = |a: usize, b: usize| a as f64 / b.max(1) as f64;
        write!(
            f,
            "{} nodes ({:.2} children each), {} leaves ({:.2} primitives each), SAH cost {:.1}; \
             a line through the root's box enters {:.2} nodes and {:.2} leaves \
             (Embree's measure, leaves by blocks of four: {:.2})",
            self.nodes,
            per(self.children, self.nodes),
            self.leaves,
            per(self.leaf_prims, self.leaves),
            self.sah_cost,
            self.node_tests,
            self.leaf_tests,
            self.embree_sah
        )
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::binary::binary_tree_and_bounds;
    use super::super::choice::MODEL_MIN_PRIMS;
    use super::super::collapse::CollapseCosts;
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use glam::{Vec3, Vec3A};

    /// `n` boxes of random sizes scattered through a cube.
    pub(in crate::accel) fn random_boxes(n: usize, seed: u32) -> Vec<Aabb> {
        let mut rng = seeded(seed.into());
        (0..n)
            .map(|_| {
                let c = rng.cube(50.0);
                let h = rng.cube(2.0).abs() + 0.01;
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// The tree the collapse writes has exactly the cost its tables
    /// promised for the root: the reconstruction follows the choices the
    /// dynamic programme made, for every preset, and whether it charges
    /// no primitive, some or all as tested one by one.
    #[test]
    fn collapse_builds_the_tree_its_cost_tables_chose() {
        for (quality, seed) in [
            (BuildQuality::Fastest, 1),
            (BuildQuality::Medium, 2),
            (BuildQuality::High, 3),
        ] {
            let boxes = random_boxes(3000, seed);
            let (bvh2, bounds) =
                binary_tree_and_bounds(Boxes::Borrowed(&boxes), quality, &mut Steps::default())
                    .unwrap();
            for first_other in [u32::MAX, 1500, 0] {
                let costs = CollapseCosts::new(&bvh2, first_other);
                costs.assert_choices_match_tables();
                let promised = NODE_COST as f64 + costs.split(0, 8).0 as f64 / costs.area(0) as f64;
                let stats = Bvh8::collapse(&bvh2, bounds, first_other).stats_charging(first_other);
                assert!(
                    (stats.sah_cost - promised).abs() < 1e-4 * promised,
                    "{quality:?}, others from {first_other}: built {} promised {promised}",
                    stats.sah_cost
                );
                assert_eq!(stats.leaf_prims, 3000);
            }
        }
    }

    /// Charged for each primitive it tests one by one, a leaf of instances
    /// or shapes holds fewer than a leaf of triangles (which one 8-wide
    /// test covers whatever their number), on the same boxes.
    #[test]
    fn primitives_tested_one_by_one_make_smaller_leaves() {
        let boxes = random_boxes(3000, 4);
        let (bvh2, bounds) = binary_tree_and_bounds(
            Boxes::Borrowed(&boxes),
            BuildQuality::Medium,
            &mut Steps::default(),
        )
        .unwrap();
        let per_leaf = |first_other| {
            let s = Bvh8::collapse(&bvh2, bounds, first_other).stats();
            s.leaf_prims as f64 / s.leaves as f64
        };
        let (triangles, others) = (per_leaf(u32::MAX), per_leaf(0));
        assert!(
            others < 0.9 * triangles,
            "{others} others a leaf against {triangles} triangles"
        );
    }

    /// `work` on a pool of exactly `threads` threads.
    pub(in crate::accel) fn on_threads<T: Send>(
        threads: usize,
        work: impl FnOnce() -> T + Send,
    ) -> T {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(work)
    }

    /// Every leaf holds the primitives of its binary subtree: each
    /// primitive's box lies inside the box of the slot that holds it, and
    /// each is held once, for the preview tree, a tree of PLOC's over
    /// clusters (fastest), two over clusters whose nodes reinsertion has
    /// moved (fast over up to eight, high over pairs) and one with a
    /// primitive per PLOC leaf, reinserted (high under `MODEL_MIN_PRIMS`),
    /// on one thread and on three (the leaf order the tables record is
    /// joined from pieces). The tree is the same on both. And every
    /// node's boxes lie inside the tree's box.
    #[test]
    fn every_leaf_holds_the_primitives_of_its_subtree() {
        let all = random_boxes(150_000, 8);
        let small = MODEL_MIN_PRIMS - 10_000;
        for (quality, n) in [
            (BuildQuality::Preview, all.len()),
            (BuildQuality::Fastest, all.len()),
            (BuildQuality::Fast, all.len()),
            (BuildQuality::High, all.len()),
            (BuildQuality::High, small),
        ] {
            let boxes = &all[..n];
            let mut trees = Vec::new();
            for threads in [1, 3] {
                let bvh = on_threads(threads, || Bvh8::build(boxes, quality));
                let mut held = vec![0u32; boxes.len()];
                for node in &bvh.nodes {
                    for slot in 0..8 {
                        let child = node.child[slot];
                        if child == EMPTY {
                            continue;
                        }
                        let b = |row: usize| node.bounds[row][slot];
                        let leaf =
                            Aabb::new(Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5)));
                        // Every box lies inside the tree's box, which
                        // `packet::misses_box` relies on.
                        assert!(
                            bvh.bounds.min.cmple(leaf.min).all()
                                && leaf.max.cmple(bvh.bounds.max).all(),
                            "{quality:?}, {threads} threads: a box outside the tree's"
                        );
                        if !is_leaf(child) {
                            continue;
                        }
                        let (start, count) = leaf_range(child);
                        for &id in &bvh.prim_ids[start as usize..(start + count) as usize] {
                            let p = boxes[id as usize];
                            assert!(
                                leaf.min.cmple(p.min).all() && p.max.cmple(leaf.max).all(),
                                "{quality:?} over {n}, {threads} threads: primitive {id} outside its leaf"
                            );
                            held[id as usize] += 1;
                        }
                    }
                }
                assert!(
                    held.iter().all(|&h| h == 1),
                    "{quality:?}, {threads} threads"
                );
                trees.push(bvh);
            }
            assert_eq!(trees[0].prim_ids, trees[1].prim_ids, "{quality:?}");
            assert_eq!(trees[0].stats(), trees[1].stats(), "{quality:?}");
        }
    }

    /// The whole build (PLOC, reinsertion, the collapse) makes the same
    /// 8-wide tree, node array bit for bit, on 1 and 2 threads, for every
    /// preset, over enough boxes for many blocks of every parallel step.
    #[test]
    fn every_preset_builds_the_same_nodes_on_one_and_two_threads() {
        let boxes = random_boxes(120_000, 13);
        for quality in BuildQuality::ALL {
            let [one, two] = [1, 2].map(|t| on_threads(t, || Bvh8::build(&boxes, quality)));
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
            assert_eq!(one.nodes.len(), two.nodes.len(), "{quality:?}");
            assert!(bits(&one) == bits(&two), "{quality:?}: the nodes differ");
            assert_eq!(one.prim_ids, two.prim_ids, "{quality:?}");
            assert_eq!(
                (one.depth, one.bounds),
                (two.depth, two.bounds),
                "{quality:?}"
            );
        }
    }

    /// The leaves of a tree as sorted lists of primitive ids, sorted: what
    /// the tree holds, whatever its node numbering and slot order.
    fn leaf_sets(bvh: &Bvh8) -> Vec<Vec<u32>> {
        let mut leaves: Vec<Vec<u32>> = bvh
            .nodes
            .iter()
            .flat_map(|n| n.child)
            .filter(|&c| c != EMPTY && is_leaf(c))
            .map(|c| {
                let (start, count) = leaf_range(c);
                let mut ids = bvh.prim_ids[start as usize..(start + count) as usize].to_vec();
                ids.sort_unstable();
                ids
            })
            .collect();
        leaves.sort_unstable();
        leaves
    }

    /// A tree big enough to be emitted in parallel (its top subtrees hold
    /// more than `PARALLEL_PRIMS` primitives) makes the same choices as
    /// one sequential walk: the same nodes, leaves and cost, only numbered
    /// differently; and it is the same tree, bit for bit, on one thread
    /// and on three.
    #[test]
    fn parallel_collapse_matches_the_sequential_walk_on_any_thread_count() {
        let boxes = random_boxes(200_000, 6);
        let (bvh2, bounds) = binary_tree_and_bounds(
            Boxes::Borrowed(&boxes),
            BuildQuality::Fastest,
            &mut Steps::default(),
        )
        .unwrap();
        // The second half charged as primitives tested one by one.
        let others = 100_000;
        let on = |threads: usize| on_threads(threads, || Bvh8::collapse(&bvh2, bounds, others));
        let (one, three) = (on(1), on(3));
        let sequential = super::super::collapse::collapse_sequential(&bvh2, bounds, others);
        let (p, s) = (one.stats(), sequential.stats());
        assert_eq!(
            (p.nodes, p.children, p.leaves, p.leaf_prims),
            (s.nodes, s.children, s.leaves, s.leaf_prims)
        );
        assert!((p.sah_cost - s.sah_cost).abs() < 1e-9 * s.sah_cost);
        assert_eq!(one.depth, sequential.depth);
        assert_eq!(leaf_sets(&one), leaf_sets(&sequential));
        assert_eq!(leaf_sets(&one).concat().len(), boxes.len());
        // Bit for bit across thread counts.
        assert_eq!(one.prim_ids, three.prim_ids);
        assert_eq!(one.depth, three.depth);
        assert!(one
            .nodes
            .iter()
            .zip(&three.nodes)
            .all(|(a, b)| a.child == b.child
                && a.bounds.as_flattened().iter().map(|x| x.to_bits()).eq(b
                    .bounds
                    .as_flattened()
                    .iter()
                    .map(|x| x.to_bits()))));
        assert_eq!(one.nodes.len(), three.nodes.len());
        // Every node a node of the tree points to exists and is reached once.
        let mut reached = vec![0u32; one.nodes.len()];
        reached[0] = 1;
        for node in &one.nodes {
            for &c in node.child.iter().filter(|&&c| c != EMPTY && !is_leaf(c)) {
                reached[c as usize] += 1;
            }
        }
        assert!(reached.iter().all(|&r| r == 1));
    }

    /// A binary tree that is a chain 300,000 leaves deep (each inner node
    /// a leaf and the rest) collapses without overflowing the stack,
    /// holds every primitive once, and matches the sequential walk.
    #[test]
    fn a_degenerate_chain_collapses_without_deep_recursion() {
        use obvhs::bvh2::node::Bvh2Node;
        let n = 300_000u32;
        let boxed = |k: u32| obvhs::aabb::Aabb {
            min: Vec3A::ZERO,
            max: Vec3A::splat(1.0 + k as f32),
        };
        // Node 2j is the chain's inner node j, whose children are node
        // 2j + 1 (a leaf holding primitive j) and node 2j + 2 (inner node
        // j + 1, or the last leaf); the boxes nest.
        let mut nodes = Vec::with_capacity(2 * n as usize - 1);
        for j in 0..n - 1 {
            nodes.push(Bvh2Node::new(boxed(n - 1 - j), 0, 2 * j + 1));
            nodes.push(Bvh2Node::new(boxed(n - 1 - j), 1, j));
        }
        nodes.push(Bvh2Node::new(boxed(0), 1, n - 1));
        let bvh2 = Bvh2 {
            nodes,
            primitive_indices: (0..n).collect(),
            ..Default::default()
        };
        let bounds = Aabb::new(glam::Vec3::ZERO, glam::Vec3::splat(n as f32));
        let tree = std::thread::Builder::new()
            .stack_size(1 << 20)
            .spawn(move || {
                let parallel = Bvh8::collapse(&bvh2, bounds, u32::MAX);
                let sequential =
                    super::super::collapse::collapse_sequential(&bvh2, bounds, u32::MAX);
                (parallel, sequential)
            })
            .unwrap()
            .join()
            .unwrap();
        let (parallel, sequential) = tree;
        assert_eq!(leaf_sets(&parallel), leaf_sets(&sequential));
        assert_eq!(leaf_sets(&parallel).concat().len(), n as usize);
        assert_eq!(parallel.stats().nodes, sequential.stats().nodes);
    }

    /// Taking the boxes (and freeing them before the collapse) builds the
    /// same tree as borrowing them.
    #[test]
    fn build_from_owned_boxes_matches_build() {
        let boxes = random_boxes(2000, 5);
        let borrowed = Bvh8::build(&boxes, BuildQuality::Medium);
        let owned = Bvh8::build_from(boxes.clone(), BuildQuality::Medium);
        assert_eq!(owned.stats(), borrowed.stats());
        assert_eq!(owned.prim_ids, borrowed.prim_ids);
        // The build frees the binary tree as it collapses; the tests'
        // collapse keeps it, to the same tree.
        let (bvh2, bounds) = binary_tree_and_bounds(
            Boxes::Borrowed(&boxes),
            BuildQuality::Medium,
            &mut Steps::default(),
        )
        .unwrap();
        let kept = Bvh8::collapse(&bvh2, bounds, u32::MAX);
        assert_eq!(kept.stats(), borrowed.stats());
        assert_eq!(kept.prim_ids, borrowed.prim_ids);
        assert_eq!(
            (owned.bounds, owned.depth),
            (borrowed.bounds, borrowed.depth)
        );
        assert!(Bvh8::build_from(Vec::new(), BuildQuality::Auto)
            .nodes
            .is_empty());
    }

    /// Eight coincident boxes are one leaf (eight node slots would cost
    /// eight leaf tests for the same box); eight boxes far apart are eight
    /// leaves (one leaf would be entered by every ray that enters the root).
    #[test]
    fn collapse_keeps_coincident_boxes_together_and_separates_distant_ones() {
        let same = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 8];
        let bvh = Bvh8::build(&same, BuildQuality::Medium);
        let stats = bvh.stats();
        assert_eq!(
            (stats.nodes, stats.leaves, stats.leaf_prims),
            (1, 1, 8),
            "{stats}"
        );
        // Every line through the root meets the one leaf, which Embree's
        // measure charges twice (two blocks of four).
        assert_eq!(
            (stats.node_tests, stats.leaf_tests, stats.embree_sah),
            (1.0, 1.0, 3.0),
            "{stats}"
        );

        let apart: Vec<Aabb> = (0..8)
            .map(|i| {
                let c = Vec3::new(100.0 * i as f32, 0.0, 0.0);
                Aabb::new(c, c + Vec3::ONE)
            })
            .collect();
        let stats = Bvh8::build(&apart, BuildQuality::Medium).stats();
        assert_eq!(
            (stats.nodes, stats.leaves, stats.leaf_prims),
            (1, 8, 8),
            "{stats}"
        );
        // Eight unit cubes (half area 3) in a box of 701 × 1 × 1 (1403).
        let expected = 8.0 * 3.0 / 1403.0;
        assert!((stats.leaf_tests - expected).abs() < 1e-12, "{stats}");
        assert_eq!(stats.embree_sah, stats.node_tests + stats.leaf_tests);
    }

    /// The expected node and leaf tests are what random lines meet: lines
    /// uniform in direction and position among those through the root's
    /// box (each direction's lines cross a disc around the box uniformly;
    /// those that miss the box are dropped) enter on average as many of
    /// the boxes the nodes keep as `stats` says, within four standard
    /// errors. Counting a leaf once per primitive, or leaving out the
    /// root, fails it (both tried).
    #[test]
    fn expected_tests_are_the_boxes_random_lines_meet() {
        let bvh = Bvh8::build(&random_boxes(1500, 9), BuildQuality::Medium);
        let stats = bvh.stats();
        assert!(stats.nodes > 20, "{stats}");
        let meets = |o: Vec3, d: Vec3, lo: Vec3, hi: Vec3| {
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            a.min(b).max_element() <= a.max(b).min_element()
        };
        let (centre, radius) = (
            bvh.bounds.center(),
            (bvh.bounds.max - bvh.bounds.min).length() / 2.0,
        );
        let mut rng = seeded(5);
        let (mut lines, mut counts) = (0, Vec::new());
        while lines < 6000 {
            let d = rng.unit_vector();
            let (u, v) = d.any_orthonormal_pair();
            let (x, y) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            if x * x + y * y > 1.0 {
                continue;
            }
            let o = centre + radius * (x * u + y * v);
            if !meets(o, d, bvh.bounds.min, bvh.bounds.max) {
                continue;
            }
            lines += 1;
            let (mut nodes, mut leaves) = (1.0f64, 0.0f64);
            for node in &bvh.nodes {
                for slot in (0..8).filter(|&k| node.child[k] != EMPTY) {
                    let b = |row: usize| node.bounds[row][slot];
                    let (lo, hi) = (Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5)));
                    if meets(o, d, lo, hi) {
                        *if is_leaf(node.child[slot]) {
                            &mut leaves
                        } else {
                            &mut nodes
                        } += 1.0;
                    }
                }
            }
            counts.push((nodes, leaves));
        }
        // A leaf costs Embree at least one block of four.
        assert!(stats.embree_sah >= stats.node_tests + stats.leaf_tests);
        let n = counts.len() as f64;
        for (name, pick, expected) in [
            ("nodes", 0, stats.node_tests),
            ("leaves", 1, stats.leaf_tests),
        ] {
            let x: Vec<f64> = counts
                .iter()
                .map(|c| if pick == 0 { c.0 } else { c.1 })
                .collect();
            let mean = x.iter().sum::<f64>() / n;
            let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let error = sd / n.sqrt();
            assert!(
                (mean - expected).abs() < 4.0 * error,
                "{name}: lines met {mean:.3} ± {error:.3}, stats say {expected:.3} ({stats})"
            );
        }
    }

    /// The collapse makes the same choices at any scale: the same binary
    /// tree scaled by 2^±60 (exactly, a power of two) collapses to the same
    /// shape, where raw areas would overflow to infinity or flush to zero.
    #[test]
    fn collapse_does_not_depend_on_the_scale_of_the_scene() {
        let boxes = random_boxes(2000, 4);
        let (bvh2, bounds) = binary_tree_and_bounds(
            Boxes::Borrowed(&boxes),
            BuildQuality::Medium,
            &mut Steps::default(),
        )
        .unwrap();
        let shape = |s: &TreeStats| (s.nodes, s.children, s.leaves, s.leaf_prims);
        let reference = Bvh8::collapse(&bvh2, bounds, u32::MAX).stats();
        for scale in [2f32.powi(60), 2f32.powi(-60)] {
            let mut scaled = bvh2.clone();
            for node in &mut scaled.nodes {
                let mut b = *node.aabb();
                b.min *= scale;
                b.max *= scale;
                node.set_aabb(b);
            }
            let bounds = Aabb::new(bounds.min * scale, bounds.max * scale);
            let stats = Bvh8::collapse(&scaled, bounds, u32::MAX).stats();
            assert_eq!(shape(&stats), shape(&reference), "scale {scale}");
        }
    }
}
