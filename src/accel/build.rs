//! Building: obvhs PLOC into a binary tree, then a collapse into 8-wide
//! nodes chosen by the surface area heuristic over the whole subtree
//! (Ylitie, Karras and Laine 2017), see `CollapseCosts`.

use super::node::{encode_leaf, is_leaf, leaf_range, Node8, EMPTY, MAX_LEAF_PRIMS, MAX_PRIMS};
use crate::math::Aabb;
use glam::Vec3A;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;

crate::mode::mode_enum! {
    /// Build effort. `auto` picks by primitive count: the better presets pay
    /// off on big meshes only if rays outnumber triangles.
    #[derive(Default)]
    pub enum BuildQuality("BVH quality") {
        Fastest = "fastest",
        Fast = "fast",
        #[default]
        Auto = "auto",
        Medium = "medium",
        High = "high",
    }
}

impl BuildQuality {
    fn params(self, prim_count: usize) -> BvhBuildParams {
        match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::High => BvhBuildParams::slow_build(),
            Self::Auto if prim_count > 2_000_000 => BvhBuildParams::fast_build(),
            Self::Auto => BvhBuildParams::medium_build(),
        }
    }
}

/// The 8-wide BVH. `prim_ids` lists primitive ids in leaf order, in
/// blocks of [`LEAF_BLOCK`] slots that no leaf straddles; unused slots
/// hold [`NO_PRIM`].
#[derive(Debug, Clone)]
pub struct Bvh8 {
    pub nodes: Vec<Node8>,
    pub prim_ids: Vec<u32>,
    pub bounds: Aabb,
    /// Deepest node level, for sizing traversal stacks.
    pub depth: u32,
    /// Whether traversal prefetches the children it defers (see
    /// [`super::prefetch`]). On after a build; a scene turns it off when
    /// its tree fits the caches ([`super::prefetch::Prefetch::Auto`]).
    pub prefetch: bool,
}

impl Bvh8 {
    pub fn empty() -> Self {
        Self {
            nodes: Vec::new(),
            prim_ids: Vec::new(),
            bounds: Aabb::EMPTY,
            depth: 0,
            prefetch: true,
        }
    }

    /// Build over primitive boxes; primitive `i` is reported as id `i`.
    /// Boxes must be finite (the scene compiler rejects the rest).
    pub fn build(boxes: &[Aabb], quality: BuildQuality) -> Self {
        match binary_tree_and_bounds(boxes, quality) {
            Some((bvh2, bounds)) => Self::collapse(&bvh2, bounds),
            None => Self::empty(),
        }
    }

    /// [`Bvh8::build`] that takes the boxes and frees them once the binary
    /// tree is built, before the collapse: they are not needed after it,
    /// and 24 bytes a primitive less at the collapse lowers the build's
    /// peak where the collapse is the peak (small meshes).
    pub fn build_from(boxes: Vec<Aabb>, quality: BuildQuality) -> Self {
        match binary_tree_and_bounds(&boxes, quality) {
            Some((bvh2, bounds)) => {
                drop(boxes);
                Self::collapse(&bvh2, bounds)
            }
            None => Self::empty(),
        }
    }

    /// The 8-wide tree over obvhs's binary one, whose root box is `bounds`.
    fn collapse(bvh2: &Bvh2, bounds: Aabb) -> Self {
        let mut out = Self {
            nodes: Vec::with_capacity(bvh2.nodes.len() / 4 + 1),
            prim_ids: Vec::with_capacity(bvh2.primitive_indices.len()),
            bounds,
            depth: 0,
            prefetch: true,
        };
        let mut collapse = Collapse {
            costs: CollapseCosts::new(bvh2),
            out: &mut out,
            packer: LanePacker::default(),
        };
        collapse.root();
        out
    }

    /// Bytes held by the final structure.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node8>() + self.prim_ids.len() * 4
    }

    /// Counts and the expected traversal cost of the tree, for reports.
    pub fn stats(&self) -> TreeStats {
        let mut stats = TreeStats {
            nodes: self.nodes.len(),
            ..TreeStats::default()
        };
        let root_area = self.bounds.half_area() as f64;
        let mut cost = 0.0f64;
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
                    let count = leaf_range(child).1;
                    stats.leaves += 1;
                    stats.leaf_prims += count as usize;
                    cost += LEAF_COST as f64 * area;
                } else {
                    cost += NODE_COST as f64 * area;
                }
            }
        }
        if root_area > 0.0 {
            stats.sah_cost = NODE_COST as f64 + cost / root_area;
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
}

impl std::fmt::Display for TreeStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let per = |a: usize, b: usize| a as f64 / b.max(1) as f64;
        write!(
            f,
            "{} nodes ({:.2} children each), {} leaves ({:.2} primitives each), SAH cost {:.1}",
            self.nodes,
            per(self.children, self.nodes),
            self.leaves,
            per(self.leaf_prims, self.leaves),
            self.sah_cost
        )
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

/// obvhs's binary tree over `boxes` and their union; `None` if there are
/// no boxes.
fn binary_tree_and_bounds(boxes: &[Aabb], quality: BuildQuality) -> Option<(Bvh2, Aabb)> {
    if boxes.is_empty() {
        return None;
    }
    assert!(
        boxes.len() <= MAX_PRIMS,
        "too many primitives for one BVH: {}",
        boxes.len()
    );
    let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    Some((binary_tree(boxes, quality), bounds))
}

/// obvhs's binary tree over `boxes` (not empty), one primitive a leaf.
fn binary_tree(boxes: &[Aabb], quality: BuildQuality) -> Bvh2 {
    let params = quality.params(boxes.len());
    // obvhs reads our boxes through `Boundable`: no converted copy
    // (32 bytes a primitive) at the build's memory peak.
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        boxes,
        (0..boxes.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    if params.reinsertion_batch_ratio > 0.0 {
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    }
    // The collapse reads nodes and primitive indices only: free the maps
    // reinsertion kept (parents: 8 bytes a primitive) before it.
    bvh2.parents = Vec::new();
    bvh2.primitives_to_nodes = Vec::new();
    bvh2
}

/// The relative costs the collapse weighs, per unit of surface area (the
/// chance a ray enters a box): an 8-wide node test, and a leaf test, which
/// is one 8-wide triangle test whatever the leaf's size (up to
/// [`LEAF_PRIMS`]). On this code a node test with its share of child
/// ordering and stack work is about 70 instructions and four cache lines,
/// a leaf test about 110 and five. Instructions per dragon ray hardly move
/// for LEAF_COST from 1 to 2.5; a cost per triangle in the leaf (0.05 or
/// 0.15 of a node test) only added some (callgrind, random, grazing and
/// camera rays).
const NODE_COST: f32 = 1.0;
const LEAF_COST: f32 = 1.5;

/// Post-order of the BVH2 (children before parents), by an explicit stack:
/// trees can be deep.
fn post_order(bvh2: &Bvh2) -> Vec<u32> {
    let n = bvh2.nodes.len();
    let mut order = Vec::with_capacity(n);
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        order.push(i);
        let node = &bvh2.nodes[i as usize];
        if node.prim_count == 0 {
            stack.push(node.first_index);
            stack.push(node.first_index + 1);
        }
    }
    order.reverse();
    order
}

/// The SAH cost tables of the collapse (Ylitie, Karras and Laine 2017,
/// "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
/// BVHs", §3.1), computed bottom-up over the binary tree. `cost[n][i - 1]`
/// is the least cost of representing BVH2 node `n`'s subtree as at most
/// `i` children of one 8-wide node:
///
/// - one child (`i = 1`): `n` as a leaf (if it holds at most
///   [`LEAF_PRIMS`] primitives) or as an 8-wide node of its own, whose
///   cost is its test plus the best distribution of its two children over
///   eight slots;
/// - more (`i > 1`): the better of using one slot fewer, and splitting the
///   `i` slots between `n`'s two children.
///
/// Costs are areas times the constants above, all relative to one tree, so
/// no division by the root's area is needed. The greedy collapse this
/// replaces (open the largest child until there are eight) filled every
/// node and made leaves of 2.3 (dragon) to 2.5 (bunny) triangles, paying an 8-wide
/// leaf test for each; the tables instead weigh a bigger leaf's larger box
/// against the node tests it saves.
struct CollapseCosts<'a> {
    bvh2: &'a Bvh2,
    /// Areas are measured in units of the largest coordinate, so they
    /// neither overflow (coordinates near 1e20 have areas past f32::MAX)
    /// nor flush to zero (near 1e-20), and the choices do not depend on
    /// the scene's scale.
    unit: f32,
    /// Per inner node, at [`CollapseCosts::slot`]: only inner nodes have
    /// tables (a leaf's is its leaf cost in every entry), which halves
    /// their memory (36 bytes a primitive at the build's peak, not 72).
    cost: Vec<[f32; 8]>,
    counts: Vec<u32>,
}

impl<'a> CollapseCosts<'a> {
    fn new(bvh2: &'a Bvh2) -> Self {
        let inner = bvh2.nodes.len() / 2;
        let root = &bvh2.nodes[0].aabb;
        let largest = root.min.abs().max(root.max.abs()).max_element();
        let mut costs = Self {
            bvh2,
            unit: if largest > 0.0 { 1.0 / largest } else { 1.0 },
            cost: vec![[0.0f32; 8]; inner],
            counts: vec![0u32; inner],
        };
        for i in post_order(bvh2) {
            let node = &bvh2.nodes[i as usize];
            if node.prim_count > 0 {
                continue;
            }
            let (l, r) = children(node);
            let count = costs.count(l) + costs.count(r);
            let area = costs.area(i as usize);
            let (left, right) = (costs.table(l), costs.table(r));
            let split = |j: usize| split_cost(&left, &right, j).0;
            let as_node = NODE_COST * area + split(8);
            let mut c = [0.0f32; 8];
            c[0] = if count <= LEAF_PRIMS {
                as_node.min(leaf_cost(area))
            } else {
                as_node
            };
            for j in 2..=8 {
                c[j - 1] = c[j - 2].min(split(j));
            }
            let slot = Self::slot(node);
            costs.cost[slot] = c;
            costs.counts[slot] = count;
        }
        costs
    }

    /// Where an inner node's table is kept: obvhs stores the two children
    /// of a node side by side with the left one at an odd index, so half
    /// of it numbers the inner nodes from 0.
    #[inline]
    fn slot(node: &Bvh2Node) -> usize {
        node.first_index as usize / 2
    }

    /// Half the surface area of BVH2 node `i`'s box, in [`CollapseCosts::unit`]s.
    fn area(&self, i: usize) -> f32 {
        let b = &self.bvh2.nodes[i].aabb;
        let d = b.max * self.unit - b.min * self.unit;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn count(&self, i: usize) -> u32 {
        let node = &self.bvh2.nodes[i];
        if node.prim_count > 0 {
            node.prim_count
        } else {
            self.counts[Self::slot(node)]
        }
    }

    fn table(&self, i: usize) -> [f32; 8] {
        let node = &self.bvh2.nodes[i];
        if node.prim_count > 0 {
            [leaf_cost(self.area(i)); 8]
        } else {
            self.cost[Self::slot(node)]
        }
    }

    /// The least cost of sharing `slots` children between inner node
    /// `i`'s two children, and the left one's share.
    fn split(&self, i: usize, slots: usize) -> (f32, usize) {
        let (l, r) = children(&self.bvh2.nodes[i]);
        split_cost(&self.table(l), &self.table(r), slots)
    }

    /// True if BVH2 node `i`, as one child slot, is best a leaf: its
    /// one-slot cost is the leaf's (`min` returns one of its operands, so
    /// the equality is exact, and a tie goes to the leaf as in the table).
    fn is_leaf(&self, i: usize) -> bool {
        let node = &self.bvh2.nodes[i];
        node.prim_count > 0
            || self.count(i) <= LEAF_PRIMS && self.table(i)[0] == leaf_cost(self.area(i))
    }

    /// The children of BVH2 node `i` made an 8-wide node: its two children
    /// share eight slots as the tables chose. Only the root can instead be
    /// its own only child, a leaf, when that is cheaper (a tree of a few
    /// primitives); any other node made a node is one the tables found
    /// cheaper opened.
    fn node_children(&self, i: usize, out: &mut Vec<usize>) {
        let node = &self.bvh2.nodes[i];
        if node.prim_count > 0 {
            out.push(i);
            return;
        }
        let (split, k) = self.split(i, 8);
        if self.count(i) <= LEAF_PRIMS && leaf_cost(self.area(i)) <= split {
            out.push(i);
            return;
        }
        let (l, r) = children(node);
        self.distribute(l, k, out);
        self.distribute(r, 8 - k, out);
    }

    /// The BVH2 nodes that fill at most `slots` children of one 8-wide
    /// node for `i`'s subtree, following the choices the tables made.
    fn distribute(&self, i: usize, slots: usize, out: &mut Vec<usize>) {
        let mut work = vec![(i, slots)];
        while let Some((i, slots)) = work.pop() {
            let node = &self.bvh2.nodes[i];
            if slots == 1 || node.prim_count > 0 {
                out.push(i);
                continue;
            }
            let (split, k) = self.split(i, slots);
            if self.table(i)[slots - 2] <= split {
                work.push((i, slots - 1));
            } else {
                let (l, r) = children(node);
                work.push((r, slots - k));
                work.push((l, k));
            }
        }
    }
}

/// An inner BVH2 node's two children.
#[inline]
fn children(node: &Bvh2Node) -> (usize, usize) {
    (node.first_index as usize, node.first_index as usize + 1)
}

#[inline]
fn leaf_cost(area: f32) -> f32 {
    area * LEAF_COST
}

/// The least cost of sharing `slots` children between two subtrees, and
/// the left one's share.
#[inline]
fn split_cost(left: &[f32; 8], right: &[f32; 8], slots: usize) -> (f32, usize) {
    (1..slots)
        .map(|k| (left[k - 1] + right[slots - k - 1], k))
        .fold(
            (f32::INFINITY, 1),
            |best, c| if c.0 < best.0 { c } else { best },
        )
}

struct Collapse<'a> {
    costs: CollapseCosts<'a>,
    out: &'a mut Bvh8,
    packer: LanePacker,
}

impl Collapse<'_> {
    fn root(&mut self) {
        self.out.nodes.push(Node8::EMPTY);
        // Work list of (BVH2 node, Node8 slot to fill, depth): iterative, so
        // degenerate deep trees cannot overflow the call stack.
        let mut work = vec![(0usize, 0usize, 1u32)];
        let mut children = Vec::with_capacity(8);
        while let Some((src, dst, depth)) = work.pop() {
            self.out.depth = self.out.depth.max(depth);
            children.clear();
            self.costs.node_children(src, &mut children);
            for (slot, &c) in children.iter().enumerate() {
                let b = self.costs.bvh2.nodes[c].aabb;
                let node = &mut self.out.nodes[dst];
                for axis in 0..3 {
                    node.bounds[2 * axis][slot] = b.min[axis];
                    node.bounds[2 * axis + 1][slot] = b.max[axis];
                }
                if self.costs.is_leaf(c) {
                    let prims = self.gather_prims(c);
                    let start = self.packer.place(&prims, &mut self.out.prim_ids);
                    self.out.nodes[dst].child[slot] = encode_leaf(start, prims.len() as u32);
                } else {
                    let new = self.out.nodes.len();
                    self.out.nodes.push(Node8::EMPTY);
                    self.out.nodes[dst].child[slot] = new as u32;
                    work.push((c, new, depth + 1));
                }
            }
            debug_assert!(self.out.nodes[dst].child.iter().any(|&c| c != EMPTY));
        }
    }

    fn gather_prims(&self, i: usize) -> Vec<u32> {
        let mut prims = Vec::with_capacity(LEAF_PRIMS as usize);
        let mut stack = vec![i];
        while let Some(i) = stack.pop() {
            let node = &self.costs.bvh2.nodes[i];
            if node.prim_count > 0 {
                let s = node.first_index as usize;
                prims.extend_from_slice(
                    &self.costs.bvh2.primitive_indices[s..s + node.prim_count as usize],
                );
            } else {
                stack.push(node.first_index as usize + 1);
                stack.push(node.first_index as usize);
            }
        }
        prims
    }
}

/// Places leaves into blocks of [`LEAF_BLOCK`] slots so that no leaf
/// straddles two blocks: a leaf is then one 8-wide triangle test over one
/// contiguous block (see `shape::triangle8`). First fit among the last few
/// blocks that still have room keeps the padding small (a fraction of a
/// percent on scanned meshes) and keeps leaves that are near in the tree
/// near in memory.
#[derive(Default)]
struct LanePacker {
    /// Blocks with free slots: (first free slot, end of block).
    open: Vec<(u32, u32)>,
}

impl LanePacker {
    /// Blocks kept open for first fit.
    const OPEN_BLOCKS: usize = 8;

    /// Writes `prims` into free slots of `prim_ids` (growing it by whole
    /// blocks padded with [`NO_PRIM`]) and returns the first slot.
    fn place(&mut self, prims: &[u32], prim_ids: &mut Vec<u32>) -> u32 {
        let n = prims.len() as u32;
        let i = match self.open.iter().position(|&(free, end)| end - free >= n) {
            Some(i) => i,
            None => {
                let start = prim_ids.len() as u32;
                prim_ids.resize(prim_ids.len() + LEAF_BLOCK, NO_PRIM);
                if self.open.len() == Self::OPEN_BLOCKS {
                    self.open.remove(0);
                }
                self.open.push((start, start + LEAF_BLOCK as u32));
                self.open.len() - 1
            }
        };
        let start = self.open[i].0;
        prim_ids[start as usize..(start + n) as usize].copy_from_slice(prims);
        self.open[i].0 += n;
        if self.open[i].0 == self.open[i].1 {
            self.open.remove(i);
        }
        start
    }
}

/// Slots per leaf block. A leaf is a run of slots inside one block, so the
/// scene can store each block as one 8-lane triangle block
/// ([`crate::shape::triangle8`]) and test a whole leaf at once.
pub const LEAF_BLOCK: usize = 8;

/// The id of a slot that holds no primitive (padding at the end of a block).
pub const NO_PRIM: u32 = u32::MAX;

/// Subtrees with at most this many primitives become one leaf.
const LEAF_PRIMS: u32 = 8;
const _: () = assert!(LEAF_PRIMS <= MAX_LEAF_PRIMS && LEAF_PRIMS as usize <= LEAF_BLOCK);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

    fn random_boxes(n: usize, seed: u32) -> Vec<Aabb> {
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
    /// dynamic programme made, for every preset.
    #[test]
    fn collapse_builds_the_tree_its_cost_tables_chose() {
        for (quality, seed) in [
            (BuildQuality::Fastest, 1),
            (BuildQuality::Medium, 2),
            (BuildQuality::High, 3),
        ] {
            let boxes = random_boxes(3000, seed);
            let bvh2 = binary_tree(&boxes, quality);
            let costs = CollapseCosts::new(&bvh2);
            let promised = NODE_COST as f64 + costs.split(0, 8).0 as f64 / costs.area(0) as f64;
            let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            let stats = Bvh8::collapse(&bvh2, bounds).stats();
            assert!(
                (stats.sah_cost - promised).abs() < 1e-4 * promised,
                "{quality:?}: built {} promised {promised}",
                stats.sah_cost
            );
            assert_eq!(stats.leaf_prims, 3000);
        }
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
    }

    /// The collapse makes the same choices at any scale: the same binary
    /// tree scaled by 2^±60 (exactly, a power of two) collapses to the same
    /// shape, where raw areas would overflow to infinity or flush to zero.
    #[test]
    fn collapse_does_not_depend_on_the_scale_of_the_scene() {
        let boxes = random_boxes(2000, 4);
        let bvh2 = binary_tree(&boxes, BuildQuality::Medium);
        let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let shape = |s: &TreeStats| (s.nodes, s.children, s.leaves, s.leaf_prims);
        let reference = Bvh8::collapse(&bvh2, bounds).stats();
        for scale in [2f32.powi(60), 2f32.powi(-60)] {
            let mut scaled = bvh2.clone();
            for node in &mut scaled.nodes {
                node.aabb.min *= scale;
                node.aabb.max *= scale;
            }
            let bounds = Aabb::new(bounds.min * scale, bounds.max * scale);
            let stats = Bvh8::collapse(&scaled, bounds).stats();
            assert_eq!(shape(&stats), shape(&reference), "scale {scale}");
        }
    }
}
