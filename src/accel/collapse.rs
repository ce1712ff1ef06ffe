//! The collapse of obvhs's binary tree into 8-wide nodes, chosen by the
//! surface area heuristic over the whole subtree (Ylitie, Karras and Laine
//! 2017), in parts that [`super::assemble`] joins into one tree, its
//! leaves packed into blocks of [`LANES`] slots.
//!
//! Both passes run in parallel: the cost tables over the subtrees of the
//! top [`PARALLEL_DEPTH`] levels, and the emission of 8-wide nodes over
//! subtrees of at least [`PARALLEL_PRIMS`] primitives. Every
//! choice is a function of the binary tree alone, so the 8-wide tree is
//! the same for any thread count. The tables record their choices as they
//! are filled ([`Choices`]), so the emission follows them without
//! recomputing a split: the same tree, built faster.

use super::assemble::Part;
use super::build::Bvh8;
use super::node::{encode_leaf, Node8, EMPTY, MAX_LEAF_PRIMS};
use crate::math::lanes::LANES;
use crate::math::Aabb;
use glam::Vec3;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;
use std::hint::select_unpredictable;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The relative costs the collapse weighs, per unit of surface area (the
/// chance a ray enters a box): an 8-wide node test, and a leaf test, which
/// is one 8-wide triangle test whatever the leaf's size (up to
/// [`LEAF_PRIMS`]): a leaf test costs about half as much again as a node
/// test with its share of ordering and stack work (docs/embree.md, "Build
/// and collapse").
pub(super) const NODE_COST: f32 = 1.0;
pub(super) const LEAF_COST: f32 = 1.5;

/// What a leaf pays on top of [`LEAF_COST`] for each primitive it tests
/// one by one rather than in the 8-wide triangle test: an analytic shape,
/// or an instance, whose world box is tested before its prototype's walk
/// (`geometry::instance`). About a node test each (the scalar box or
/// shape test and the loop around it), so that a tree over instances
/// makes the 8-wide node test their boxes together rather than a leaf
/// test them one by one (docs/performance.md, "Instancing").
pub(super) const OTHER_COST: f32 = 1.0;

/// The id of a slot that holds no primitive (padding at the end of a block).
pub const NO_PRIM: u32 = u32::MAX;

/// Subtrees with at most this many primitives become one leaf.
pub(super) const LEAF_PRIMS: u32 = 8;
const _: () = assert!(LEAF_PRIMS <= MAX_LEAF_PRIMS && LEAF_PRIMS as usize <= LANES);

/// Subtrees of at least this many primitives are emitted in parallel, one
/// task per 8-wide child; smaller ones by one sequential walk. Large
/// enough that a task's work (milliseconds) dwarfs its hand-off, and that
/// only the top two or three levels of a large mesh's tree are split.
const PARALLEL_PRIMS: u32 = 1 << 16;

/// At most this many levels of 8-wide nodes are emitted by parallel
/// recursion; below, however large the subtree, one sequential walk (a
/// loop, not recursion) goes on. Eight children a level, so a balanced
/// tree has split into thousands of tasks long before; the bound only
/// keeps a degenerate tree (a chain) from overflowing the call stack.
const PARALLEL_LEVELS: u32 = 16;

/// The cost tables of the top this many levels of the binary tree are
/// filled by parallel recursion (at most 2^10 tasks, each a post-order
/// walk of its subtree): enough tasks to balance lopsided trees, too few
/// for their hand-offs to count.
const PARALLEL_DEPTH: u32 = 10;

/// The 8-wide tree over obvhs's binary one, whose root box is `bounds`.
/// Primitives from `first_other` on are tested one by one in a leaf
/// ([`OTHER_COST`]); those before it are triangles. The binary tree is
/// kept: for tests ([`collapse_owned`] is the build's).
#[cfg(test)]
pub(super) fn collapse(bvh2: &Bvh2, bounds: Aabb, first_other: u32) -> Bvh8 {
    parts(bvh2, first_other).into_bvh(bounds)
}

/// [`collapse`] that takes the binary tree and frees it, with the cost
/// tables' choices, before the 8-wide tree's parts are copied into one:
/// the copy is the collapse's second peak, and the binary tree (64 bytes
/// a primitive) dwarfs what it copies.
pub(super) fn collapse_owned(bvh2: Bvh2, bounds: Aabb, first_other: u32) -> Bvh8 {
    let Bvh2 {
        nodes,
        primitive_indices,
        ..
    } = bvh2;
    // The tables' walk copies the ids into leaf order; the emission reads
    // that copy and the nodes only (4 bytes a primitive less).
    let costs = CollapseCosts::over(&nodes, &primitive_indices, first_other).without_ids();
    drop(primitive_indices);
    let part = costs.emit(0, 0, 0);
    drop(costs);
    // 32 bytes a node, 400 MB on the 13.9M-triangle dragon's medium tree:
    // unmapped on a thread of its own, it costs the copy below nothing
    // (0.05 s on the build's thread).
    crate::system::memory::drop_aside(nodes);
    part.into_bvh(bounds)
}

/// The 8-wide tree over `bvh2` in parts made in parallel; the choices
/// are freed when it returns.
#[cfg(test)]
fn parts(bvh2: &Bvh2, first_other: u32) -> Part {
    CollapseCosts::new(bvh2, first_other).emit(0, 0, 0)
}

/// [`collapse`] by one sequential walk from the root, for tests of the
/// parallel emission.
#[cfg(test)]
pub(super) fn collapse_sequential(bvh2: &Bvh2, bounds: Aabb, first_other: u32) -> Bvh8 {
    CollapseCosts::new(bvh2, first_other)
        .emit_sequential(0, 0)
        .into_bvh(bounds)
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
/// no division by the root's area is needed. A node's table is read only
/// by its parent's, once: the walk that fills them keeps them on a stack
/// (children before parents), and only each node's count and choices are
/// kept for the emission, 8 bytes an inner node, not the 32 bytes of a
/// table as well, at the build's peak. The greedy collapse this
/// replaces (open the largest child until there are eight) filled every
/// node and made leaves of 2.3 (dragon) to 2.5 (bunny) triangles, paying an 8-wide
/// leaf test for each; the tables instead weigh a bigger leaf's larger box
/// against the node tests it saves.
pub(super) struct CollapseCosts<'a, 'i> {
    /// The binary tree's nodes, and its primitive ids (which only the
    /// tables' walk reads).
    nodes: &'a [Bvh2Node],
    ids: &'i [u32],
    /// Areas are measured in units of the largest coordinate, so they
    /// neither overflow (coordinates near 1e20 have areas past f32::MAX)
    /// nor flush to zero (near 1e-20), and the choices do not depend on
    /// the scene's scale.
    unit: f32,
    /// Per inner node, at [`CollapseCosts::slot`] (leaves hold theirs):
    /// how many primitives its subtree holds. In atomics (relaxed: plain
    /// loads and stores) so that parallel tasks can fill disjoint
    /// subtrees' entries; `rayon::join` orders a parent's work after its
    /// children's.
    counts: Vec<AtomicU32>,
    /// The first primitive id tested one by one ([`OTHER_COST`]).
    first_other: u32,
    /// Whether the tree holds any primitive tested one by one (a mesh's
    /// holds none, and its leaves need not look).
    any_other: bool,
    /// Per inner node, the choices its table made ([`Choices`]), so that
    /// the emission follows them without recomputing any split.
    choices: Vec<AtomicU32>,
    /// Every primitive id in the order of the tree's leaves, left to
    /// right, recorded by the walk that fills the tables: the primitives
    /// of a subtree are the run of [`CollapseCosts::count`] ids from where
    /// its leftmost leaf's are, so a leaf of the 8-wide tree copies one
    /// run instead of walking its binary subtree again (a cache miss a
    /// node: the nodes are 32 bytes, scattered by PLOC's levels).
    ordered: Vec<u32>,
}

impl<'a, 'i> CollapseCosts<'a, 'i> {
    /// The tables over `bvh2`, for tests; the build's are [`CollapseCosts::over`]
    /// its nodes and ids, which it frees apart.
    #[cfg(test)]
    pub(super) fn new(bvh2: &'a Bvh2, first_other: u32) -> CollapseCosts<'a, 'a> {
        CollapseCosts::over(&bvh2.nodes, &bvh2.primitive_indices, first_other)
    }

    /// The tables over a binary tree's `nodes` and primitive `ids`.
    fn over(nodes: &'a [Bvh2Node], ids: &'i [u32], first_other: u32) -> Self {
        let inner = nodes.len() / 2;
        let any_other = (first_other as usize) < ids.len();
        let root = nodes[0].aabb();
        let (min, max) = (Vec3::from(root.min), Vec3::from(root.max));
        let largest = min.abs().max(max.abs()).max_element();
        let mut costs = Self {
            nodes,
            ids,
            unit: if largest > 0.0 { 1.0 / largest } else { 1.0 },
            // Made in parallel: the first touch of a fresh page is the
            // cost of making a large array (see `super::build::ploc`).
            counts: (0..inner)
                .into_par_iter()
                .map(|_| AtomicU32::new(0))
                .collect(),
            first_other,
            any_other,
            choices: (0..inner)
                .into_par_iter()
                .map(|_| AtomicU32::new(0))
                .collect(),
            ordered: Vec::new(),
        };
        costs.ordered = concat(costs.fill_tables(0, 0).0);
        costs
    }

    /// Fills the tables of BVH2 node `i`'s subtree, children before
    /// parents: the top [`PARALLEL_DEPTH`] levels by parallel recursion,
    /// each subtree below in one post-order walk (which keeps a node's
    /// children's tables in cache when it reads them; filling level by
    /// level, in parallel, took three times as long on the dragon).
    /// Returns the subtree's primitive ids in leaf order, in pieces (one
    /// per walk) that the caller joins once, and the subtree's table.
    fn fill_tables(&self, i: usize, depth: u32) -> (Vec<Vec<u32>>, Table) {
        let node = &self.nodes[i];
        if node.prim_count > 0 {
            return (vec![self.leaf_prims(node).to_vec()], self.leaf_table(i));
        }
        if depth < PARALLEL_DEPTH {
            let (l, r) = children(node);
            let ((mut left, left_table), (right, right_table)) = rayon::join(
                || self.fill_tables(l, depth + 1),
                || self.fill_tables(r, depth + 1),
            );
            left.extend(right);
            return (left, self.store_table(i, &left_table, &right_table));
        }
        let (prims, table) = self.walk_tables(i);
        (vec![prims], table)
    }

    /// Fills the tables of BVH2 node `root`'s subtree in one post-order
    /// walk, each table on a stack until its parent's reads it (the left
    /// subtree's is then below the right one's); returns the subtree's
    /// primitive ids in leaf order and its table.
    fn walk_tables(&self, root: usize) -> (Vec<u32>, Table) {
        let order = post_order(self.nodes, root);
        // A tree of n leaves has 2n - 1 nodes; leaves hold one primitive
        // or more.
        let mut prims = Vec::with_capacity(order.len().div_ceil(2));
        let mut tables: Vec<Table> = Vec::new();
        for n in order {
            let node = &self.nodes[n as usize];
            let table = if node.prim_count == 0 {
                let right = tables.pop().expect("a right child's table");
                let left = tables.pop().expect("a left child's table");
                self.store_table(n as usize, &left, &right)
            } else {
                prims.extend_from_slice(self.leaf_prims(node));
                self.leaf_table(n as usize)
            };
            tables.push(table);
        }
        (prims, tables.pop().expect("the root's table"))
    }

    /// The primitive ids of BVH2 leaf `node`.
    fn leaf_prims(&self, node: &Bvh2Node) -> &[u32] {
        let first = node.first_index as usize;
        &self.ids[first..first + node.prim_count as usize]
    }

    /// The table of BVH2 leaf `i`: its leaf cost for any number of slots.
    fn leaf_table(&self, i: usize) -> Table {
        let others = self.leaf_others(&self.nodes[i]);
        ([leaf_cost(self.area(i), others); 8], others)
    }

    /// The same choices, no longer reading the primitive ids (which
    /// [`CollapseCosts::ordered`] holds in leaf order), so that they can
    /// be freed before the emission: it reads no table.
    fn without_ids(self) -> CollapseCosts<'a, 'static> {
        CollapseCosts {
            nodes: self.nodes,
            ids: &[],
            unit: self.unit,
            counts: self.counts,
            first_other: self.first_other,
            any_other: self.any_other,
            choices: self.choices,
            ordered: self.ordered,
        }
    }

    /// Computes inner node `i`'s table from its children's, stores its
    /// count and choices, and returns the table.
    fn store_table(&self, i: usize, left: &Table, right: &Table) -> Table {
        let slot = Self::slot(&self.nodes[i]);
        let others = left.1 + right.1;
        let (table, count, choices) = self.node_table(i, &left.0, &right.0, others);
        self.counts[slot].store(count, Relaxed);
        self.choices[slot].store(choices.0, Relaxed);
        (table, others)
    }

    /// The table, primitive count and choices of inner node `i`, from its
    /// children's tables; `others` of its primitives are tested one by one.
    fn node_table(
        &self,
        i: usize,
        left: &[f32; 8],
        right: &[f32; 8],
        others: u32,
    ) -> ([f32; 8], u32, Choices) {
        let (l, r) = children(&self.nodes[i]);
        let count = self.count(l) + self.count(r);
        let area = self.area(i);
        let splits = split_costs(left, right);
        let mut choices = Choices::default();
        let as_node = NODE_COST * area + splits[8].0;
        let leaf = leaf_cost(area, others);
        // As the 8-wide tree's root (its own only child, see
        // `node_children`), a leaf against the node's split alone.
        if count <= LEAF_PRIMS && leaf <= splits[8].0 {
            choices.set_root_leaf();
        }
        let mut c = [0.0f32; 8];
        // `leaf <= as_node` is what `as_node.min(leaf) == leaf` tests: a
        // tie goes to the leaf.
        c[0] = if count <= LEAF_PRIMS && leaf <= as_node {
            choices.set_leaf();
            leaf
        } else {
            as_node
        };
        choices.set_open_split(splits[8].1);
        for j in 2..=8 {
            let (split, k) = splits[j];
            // The tie goes to one slot fewer. Which wins is data: selects,
            // not the branch the compiler made of `min` and a product, which
            // mispredicted.
            let split_wins = split < c[j - 2];
            c[j - 1] = select_unpredictable(split_wins, split, c[j - 2]);
            choices.set_split(j, select_unpredictable(split_wins, k, 0));
        }
        (c, count, choices)
    }

    /// Where an inner node's table is kept: obvhs stores the two children
    /// of a node side by side with the left one at an odd index, so half
    /// of it numbers the inner nodes from 0.
    #[inline]
    fn slot(node: &Bvh2Node) -> usize {
        node.first_index as usize / 2
    }

    /// Half the surface area of BVH2 node `i`'s box, in [`CollapseCosts::unit`]s.
    pub(super) fn area(&self, i: usize) -> f32 {
        // Axis by axis, in scalars: a node's box shares its fourth lanes
        // with its counts, which read as floats are subnormal, and a
        // 4-lane multiply on them (what LLVM made of the same three
        // products on `Vec3`s) takes a microcode assist on Intel cores:
        // the collapse ran twice as long there (docs/performance.md,
        // "Binary nodes of 32 bytes"). The same operations on the same
        // three lanes, so the same bits.
        let b = self.nodes[i].aabb();
        let u = self.unit;
        let dx = b.max.x * u - b.min.x * u;
        let dy = b.max.y * u - b.min.y * u;
        let dz = b.max.z * u - b.min.z * u;
        dx * dy + dy * dz + dz * dx
    }

    fn count(&self, i: usize) -> u32 {
        let node = &self.nodes[i];
        if node.prim_count > 0 {
            node.prim_count
        } else {
            self.counts[Self::slot(node)].load(Relaxed)
        }
    }

    /// How many of BVH2 leaf `node`'s primitives are tested one by one.
    fn leaf_others(&self, node: &Bvh2Node) -> u32 {
        if !self.any_other {
            return 0;
        }
        let first = self.first_other;
        self.leaf_prims(node)
            .iter()
            .filter(|&&p| p >= first)
            .count() as u32
    }

    /// The choices of inner BVH2 node `node`'s table.
    fn choices(&self, node: &Bvh2Node) -> Choices {
        Choices(self.choices[Self::slot(node)].load(Relaxed))
    }

    /// BVH2 node `i`'s table, computed again from its subtree's leaves
    /// (the build keeps none), for tests.
    #[cfg(test)]
    fn table(&self, i: usize) -> Table {
        match self.nodes[i].prim_count {
            0 => self.walk_tables(i).1,
            _ => self.leaf_table(i),
        }
    }

    /// The least cost of sharing `slots` children between inner node
    /// `i`'s two children, and the left one's share.
    #[cfg(test)]
    pub(super) fn split(&self, i: usize, slots: usize) -> (f32, usize) {
        let (l, r) = children(&self.nodes[i]);
        split_costs(&self.table(l).0, &self.table(r).0)[slots]
    }

    /// Checks, for every inner node, that the recorded choices are the
    /// decisions its children's tables imply: a leaf when the leaf's cost
    /// is its one-slot cost, one slot fewer when that is as cheap, and
    /// otherwise the split's share.
    #[cfg(test)]
    pub(super) fn assert_choices_match_tables(&self) {
        for i in post_order(self.nodes, 0) {
            let (i, node) = (i as usize, &self.nodes[i as usize]);
            if node.prim_count > 0 {
                continue;
            }
            let ((table, others), choices) = (self.table(i), self.choices(node));
            let leaf_cost = leaf_cost(self.area(i), others);
            let small = self.count(i) <= LEAF_PRIMS;
            let leaf = small && table[0] == leaf_cost;
            assert_eq!(choices.leaf(), leaf, "node {i}");
            let root_leaf = small && leaf_cost <= self.split(i, 8).0;
            assert_eq!(choices.root_leaf(), root_leaf, "node {i}");
            assert_eq!(choices.open_split(), self.split(i, 8).1, "node {i}");
            for slots in 2..=8 {
                let (split, k) = self.split(i, slots);
                let want = (split < table[slots - 2]).then_some(k);
                assert_eq!(choices.split(slots), want, "node {i}, {slots} slots");
            }
        }
    }

    /// True if BVH2 node `i`, as one child slot, is best a leaf: its
    /// one-slot cost is the leaf's.
    fn is_leaf(&self, i: usize) -> bool {
        let node = &self.nodes[i];
        node.prim_count > 0 || self.choices(node).leaf()
    }

    /// The children of BVH2 node `i` made an 8-wide node: its two children
    /// share eight slots as the tables chose. Only the root can instead be
    /// its own only child, a leaf, when that is cheaper (a tree of a few
    /// primitives); any other node made a node is one the tables found
    /// cheaper opened. Each child comes with where its primitives start
    /// in [`CollapseCosts::ordered`], `i`'s being at `first`. `work` is
    /// scratch space.
    fn node_children(&self, i: usize, first: u32, out: &mut Vec<Child>, work: &mut Vec<Work>) {
        out.clear();
        let node = &self.nodes[i];
        if node.prim_count > 0 {
            out.push((i, first));
            return;
        }
        // Only the root can take this: any other node made a node was
        // cheaper opened, and its leaf cost exceeds its split's.
        if self.choices(node).root_leaf() {
            out.push((i, first));
            return;
        }
        let k = self.choices(node).open_split();
        let (l, r) = children(node);
        self.distribute(l, k, first, out, work);
        self.distribute(r, 8 - k, first + self.count(l), out, work);
    }

    /// The BVH2 nodes that fill at most `slots` children of one 8-wide
    /// node for `i`'s subtree (whose primitives start at `first`),
    /// following the choices the tables made.
    fn distribute(
        &self,
        i: usize,
        slots: usize,
        first: u32,
        out: &mut Vec<Child>,
        work: &mut Vec<Work>,
    ) {
        work.clear();
        work.push((i, slots, first));
        while let Some((i, slots, first)) = work.pop() {
            let node = &self.nodes[i];
            if slots == 1 || node.prim_count > 0 {
                out.push((i, first));
                continue;
            }
            match self.choices(node).split(slots) {
                None => work.push((i, slots - 1, first)),
                Some(k) => {
                    let (l, r) = children(node);
                    work.push((r, slots - k, first + self.count(l)));
                    work.push((l, k, first));
                }
            }
        }
    }

    /// The 8-wide tree for BVH2 node `src`'s subtree, whose root is at
    /// 8-wide level `level`. A large subtree near the top makes its own
    /// node here and its inner children's subtrees in parallel, appended
    /// after it in slot order; the rest is one sequential walk
    /// ([`CollapseCosts::emit_sequential`]).
    fn emit(&self, src: usize, first: u32, level: u32) -> Part {
        if self.count(src) < PARALLEL_PRIMS || level >= PARALLEL_LEVELS {
            return self.emit_sequential(src, first);
        }
        let mut part = Part::default();
        let mut scratch = Scratch::default();
        part.nodes.push(Node8::EMPTY);
        part.depth = 1;
        self.node_children(src, first, &mut scratch.children, &mut scratch.work);
        let mut inner = Vec::with_capacity(8);
        for (slot, &(c, first)) in scratch.children.iter().enumerate() {
            set_bounds(&mut part.nodes[0], slot, self.nodes[c].aabb());
            if self.is_leaf(c) {
                part.nodes[0].child[slot] = self.place_leaf(c, first, &mut part);
            } else {
                inner.push((slot, c, first));
            }
        }
        let subtrees: Vec<Part> = inner
            .par_iter()
            .map(|&(_, c, first)| self.emit(c, first, level + 1))
            .collect();
        part.subs = inner
            .iter()
            .map(|&(slot, _, _)| slot)
            .zip(subtrees)
            .collect();
        part
    }

    /// [`CollapseCosts::emit`] in one walk: nodes are numbered in the order
    /// they are made, a node's inner children side by side.
    fn emit_sequential(&self, src: usize, first: u32) -> Part {
        let mut part = Part::default();
        let mut scratch = Scratch::default();
        part.nodes.push(Node8::EMPTY);
        // Work list of (BVH2 node, Node8 to fill, depth, first primitive):
        // iterative, so degenerate deep trees cannot overflow the call stack.
        let mut work = vec![(src, 0usize, 1u32, first)];
        while let Some((src, dst, depth, first)) = work.pop() {
            part.depth = part.depth.max(depth);
            self.node_children(src, first, &mut scratch.children, &mut scratch.work);
            for (slot, &(c, first)) in scratch.children.iter().enumerate() {
                set_bounds(&mut part.nodes[dst], slot, self.nodes[c].aabb());
                part.nodes[dst].child[slot] = if self.is_leaf(c) {
                    self.place_leaf(c, first, &mut part)
                } else {
                    let new = part.nodes.len();
                    part.nodes.push(Node8::EMPTY);
                    work.push((c, new, depth + 1, first));
                    new as u32
                };
            }
            debug_assert!(part.nodes[dst].child.iter().any(|&c| c != EMPTY));
        }
        part
    }

    /// Packs the primitives under BVH2 node `c`, which start at `first`
    /// in [`CollapseCosts::ordered`], as one leaf of `part`, and returns
    /// its child reference.
    fn place_leaf(&self, c: usize, first: u32, part: &mut Part) -> u32 {
        let first = first as usize;
        let prims = &self.ordered[first..first + self.count(c) as usize];
        let start = part.packer.place(prims, &mut part.prim_ids);
        encode_leaf(start, prims.len() as u32)
    }
}

/// A child of an 8-wide node in the making: a BVH2 node, and where its
/// primitives start in [`CollapseCosts::ordered`].
type Child = (usize, u32);

/// A subtree waiting in [`CollapseCosts::distribute`]: a BVH2 node, the
/// slots it may fill, and where its primitives start.
type Work = (usize, usize, u32);

/// A subtree's table (see [`CollapseCosts`]) and how many of its
/// primitives are tested one by one.
type Table = ([f32; 8], u32);

/// Buffers the emission reuses from node to node, so that making a node
/// allocates nothing.
#[derive(Default)]
struct Scratch {
    children: Vec<Child>,
    work: Vec<Work>,
}

/// The pieces one after another, copied in parallel (`concat` is one
/// thread's copy, and its clears of a huge tree's fresh pages).
fn concat(pieces: Vec<Vec<u32>>) -> Vec<u32> {
    let mut all = vec![0u32; pieces.iter().map(Vec::len).sum()];
    let mut parts = Vec::with_capacity(pieces.len());
    let mut rest = &mut all[..];
    for piece in &pieces {
        let (part, tail) = std::mem::take(&mut rest).split_at_mut(piece.len());
        parts.push(part);
        rest = tail;
    }
    parts
        .into_par_iter()
        .zip(&pieces)
        .for_each(|(part, piece)| part.copy_from_slice(piece));
    all
}

fn set_bounds(node: &mut Node8, slot: usize, b: &obvhs::aabb::Aabb) {
    for axis in 0..3 {
        node.bounds[2 * axis][slot] = b.min[axis];
        node.bounds[2 * axis + 1][slot] = b.max[axis];
    }
}

/// Post-order of BVH2 node `root`'s subtree (children before parents),
/// by an explicit stack: trees can be deep.
fn post_order(nodes: &[Bvh2Node], root: usize) -> Vec<u32> {
    let mut order = Vec::new();
    let mut stack = vec![root as u32];
    while let Some(i) = stack.pop() {
        order.push(i);
        let node = &nodes[i as usize];
        if node.prim_count == 0 {
            stack.push(node.first_index);
            stack.push(node.first_index + 1);
        }
    }
    order.reverse();
    order
}

/// An inner BVH2 node's two children.
#[inline]
fn children(node: &Bvh2Node) -> (usize, usize) {
    (node.first_index as usize, node.first_index as usize + 1)
}

#[inline]
fn leaf_cost(area: f32, others: u32) -> f32 {
    area * (LEAF_COST + OTHER_COST * others as f32)
}

/// For each slot count `j` in 2..=8 (entry `j`; 0 and 1 unused), the
/// least cost of sharing `j` children between two subtrees, and the left
/// one's share: the smallest share among equal costs.
#[inline]
fn split_costs(left: &[f32; 8], right: &[f32; 8]) -> [(f32, usize); 9] {
    // Selects, not branches: which share wins is data.
    let mut best = [(f32::INFINITY, 1); 9];
    for (j, entry) in best.iter_mut().enumerate().skip(2) {
        let (mut cost, mut share) = (f32::INFINITY, 1);
        for k in 1..j {
            let c = left[k - 1] + right[j - k - 1];
            let better = c < cost;
            cost = if better { c } else { cost };
            share = if better { k } else { share };
        }
        *entry = (cost, share);
    }
    best
}

/// What an inner node's table chose, packed in a u32: bit 0, a leaf for
/// one slot; bit 1, a leaf rather than an 8-wide node of its own as the
/// tree's root (its leaf cost at most its split's into eight); bits 3(j − 1) to 3j − 1 for `j` in 2..=8, the left child's
/// share when `j` slots split between the children (0: one slot fewer
/// was as cheap); bits 24 to 26, the left child's share of 8 slots when
/// the node is opened as an 8-wide node of its own.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Choices(u32);

impl Choices {
    const OPEN_SHIFT: u32 = 24;

    fn set_leaf(&mut self) {
        self.0 |= 1;
    }

    fn leaf(self) -> bool {
        self.0 & 1 != 0
    }

    fn set_root_leaf(&mut self) {
        self.0 |= 2;
    }

    fn root_leaf(self) -> bool {
        self.0 & 2 != 0
    }

    /// Records the left child's share of `slots`, 0 for one slot fewer.
    fn set_split(&mut self, slots: usize, left: usize) {
        debug_assert!((2..=8).contains(&slots) && left < slots);
        self.0 |= (left as u32) << (3 * (slots - 1));
    }

    /// The left child's share of `slots` (2..=8), or `None` if the node
    /// takes one slot fewer.
    fn split(self, slots: usize) -> Option<usize> {
        match (self.0 >> (3 * (slots - 1))) & 7 {
            0 => None,
            k => Some(k as usize),
        }
    }

    fn set_open_split(&mut self, left: usize) {
        self.0 |= (left as u32) << Self::OPEN_SHIFT;
    }

    fn open_split(self) -> usize {
        ((self.0 >> Self::OPEN_SHIFT) & 7) as usize
    }
}
