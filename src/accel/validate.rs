//! Invariant checks of a built tree, as obvhs's `validate` checks its own:
//! what traversal and the scene's leaf blocks take for granted. A debug
//! build checks every tree it builds ([`Bvh8::debug_validated`]); in
//! release builds the tests check the trees of every scene they load
//! (`tests/suite/common/checked.rs`), and the tests here every preset's trees
//! over degenerate inputs (see docs/validation.md, "The BVH's invariants").
//!
//! A valid tree over primitives `0..n`:
//! - every node but the root is the child of exactly one slot (no node is
//!   unreachable, none is shared, there are no cycles), and every node has
//!   a child;
//! - every occupied slot's box is a box (min ≤ max, no NaN) inside its
//!   node's own box, the root's inside the tree's `bounds`; every empty
//!   slot has the inverted infinite box that every slab test rejects;
//! - every leaf holds 1 to [`MAX_LEAF_PRIMS`] slots, inside `prim_ids` and
//!   inside one block of [`LANES`] slots, no slot in two leaves;
//! - every primitive is in exactly one leaf, and inside its leaf's box when
//!   its box is known;
//! - `prim_ids` is whole blocks, each starting with its leaves' slots and
//!   padded to the end with [`NO_PRIM`], no block all padding;
//! - `depth` is the level of the deepest node (the root's is 1).

use super::build::Bvh8;
use super::node::{decode, ChildRef, Node8, EMPTY, MAX_LEAF_PRIMS};
use super::NO_PRIM;
use crate::math::lanes::LANES;
use crate::math::Aabb;
use glam::Vec3;

impl Bvh8 {
    /// Checks the tree over primitives `0..prim_count` (see the module
    /// docs); the error names the first broken invariant and the node, slot
    /// or primitive where it broke.
    pub fn validate(&self, prim_count: usize) -> Result<(), String> {
        self.validate_leaves(&self.prim_ids, prim_count, |_| None)
    }

    /// [`Bvh8::validate`] over primitives `0..boxes.len()`, and every
    /// primitive's box (`boxes[id]`) inside the box of its leaf.
    pub fn validate_boxes(&self, boxes: &[Aabb]) -> Result<(), String> {
        self.validate_leaves(&self.prim_ids, boxes.len(), |id| {
            boxes.get(id as usize).copied()
        })
    }

    /// [`Bvh8::validate`] with the leaf slots `slots` in place of
    /// `prim_ids` (a compiled scene moves them into its leaf blocks), and
    /// every primitive whose box `prim_box` knows inside its leaf's box.
    pub fn validate_leaves(
        &self,
        slots: &[u32],
        prim_count: usize,
        prim_box: impl Fn(u32) -> Option<Aabb>,
    ) -> Result<(), String> {
        if self.nodes.is_empty() {
            return match (slots.len(), prim_count, self.depth) {
                (0, 0, 0) => Ok(()),
                (0, 0, depth) => Err(format!("an empty tree of depth {depth}")),
                (0, n, _) => Err(format!("an empty tree over {n} primitives")),
                (s, _, _) => Err(format!("an empty tree with {s} leaf slots")),
            };
        }
        if !is_box(&self.bounds) {
            return Err(format!("the tree's bounds {:?} are not a box", self.bounds));
        }
        if !slots.len().is_multiple_of(LANES) {
            return Err(format!(
                "{} leaf slots are not whole blocks of {LANES}",
                slots.len()
            ));
        }
        let mut check = Walk {
            slots,
            prim_box,
            reached: vec![false; self.nodes.len()],
            in_leaf: vec![false; slots.len()],
            held: vec![false; prim_count],
        };
        let deepest = check.walk(self)?;
        if let Some(i) = check.reached.iter().position(|&r| !r) {
            return Err(format!("node {i} is unreachable from the root"));
        }
        if deepest != self.depth {
            return Err(format!(
                "depth is {} but the deepest node is at level {deepest}",
                self.depth
            ));
        }
        if let Some(id) = check.held.iter().position(|&h| !h) {
            return Err(format!("primitive {id} is in no leaf"));
        }
        check_padding(slots, &check.in_leaf)
    }

    /// The tree itself, after checking it in a debug build: every build
    /// checks the tree it made over `prim_count` primitives.
    #[inline]
    pub(super) fn debug_validated(self, prim_count: usize) -> Self {
        if cfg!(debug_assertions) {
            if let Err(e) = self.validate(prim_count) {
                panic!("the build made an invalid BVH: {e}");
            }
        }
        self
    }
}

/// The state of one check: what the walk from the root has met so far.
struct Walk<'a, F> {
    slots: &'a [u32],
    prim_box: F,
    /// Per node: reached from the root.
    reached: Vec<bool>,
    /// Per slot of `slots`: inside some leaf.
    in_leaf: Vec<bool>,
    /// Per primitive: in some leaf.
    held: Vec<bool>,
}

impl<F: Fn(u32) -> Option<Aabb>> Walk<'_, F> {
    /// Walks the tree from the root, depth first (an explicit stack: trees
    /// can be deep), checking every slot of every node it reaches; returns
    /// the level of the deepest node.
    fn walk(&mut self, bvh: &Bvh8) -> Result<u32, String> {
        let mut deepest = 0;
        self.reached[0] = true;
        // (node, its level, its box, the slot that holds it: none for the root).
        let mut stack = vec![(0usize, 1u32, bvh.bounds, None)];
        while let Some((n, level, outer, parent)) = stack.pop() {
            deepest = deepest.max(level);
            let node = &bvh.nodes[n];
            if node.child.iter().all(|&c| c == EMPTY) {
                return Err(format!("node {n} has no children"));
            }
            for slot in 0..8 {
                let b = slot_box(node, slot);
                let at = || format!("node {n}, slot {slot}");
                let child = match decode(node.child[slot]) {
                    ChildRef::Empty if is_inverted_infinite(&b) => continue,
                    ChildRef::Empty => {
                        return Err(format!(
                            "{}: an empty slot whose box {b:?} is not the inverted infinite one",
                            at()
                        ))
                    }
                    child => child,
                };
                if !is_box(&b) {
                    return Err(format!("{}: the box {b:?} is not a box", at()));
                }
                if !contains(&outer, &b) {
                    let what = match parent {
                        None => "the tree's bounds".to_string(),
                        Some((p, s)) => format!("its box in node {p}, slot {s}"),
                    };
                    return Err(format!(
                        "{}: the box {b:?} is not inside {what} {outer:?}",
                        at()
                    ));
                }
                match child {
                    ChildRef::Node(c) => {
                        let c = c as usize;
                        if c >= bvh.nodes.len() {
                            return Err(format!(
                                "{}: child node {c} is past the last node ({})",
                                at(),
                                bvh.nodes.len() - 1
                            ));
                        }
                        if self.reached[c] {
                            return Err(format!("{}: child node {c} was reached before", at()));
                        }
                        self.reached[c] = true;
                        stack.push((c, level + 1, b, Some((n, slot))));
                    }
                    ChildRef::Leaf { start, count } => self.leaf(start, count, &b, &at())?,
                    ChildRef::Empty => unreachable!(),
                }
            }
        }
        Ok(deepest)
    }

    /// Checks the leaf of slots `start..start + count`, whose box is `b`, at
    /// `at` (a node and slot).
    fn leaf(&mut self, start: u32, count: u32, b: &Aabb, at: &str) -> Result<(), String> {
        let (first, end) = (start as usize, start as usize + count as usize);
        if count > MAX_LEAF_PRIMS {
            return Err(format!(
                "{at}: a leaf of {count} primitives, more than {MAX_LEAF_PRIMS}"
            ));
        }
        if end > self.slots.len() {
            return Err(format!(
                "{at}: the leaf's slots {first}..{end} pass the last slot ({})",
                self.slots.len()
            ));
        }
        if first / LANES != (end - 1) / LANES {
            return Err(format!(
                "{at}: the leaf's slots {first}..{end} straddle two blocks of {LANES}"
            ));
        }
        for s in first..end {
            if std::mem::replace(&mut self.in_leaf[s], true) {
                return Err(format!("{at}: slot {s} is in another leaf too"));
            }
            let id = self.slots[s];
            if id == NO_PRIM {
                return Err(format!("{at}: the leaf's slot {s} is padding"));
            }
            if id as usize >= self.held.len() {
                return Err(format!(
                    "{at}: slot {s} holds primitive {id}, past the last ({})",
                    self.held.len() as i64 - 1
                ));
            }
            if std::mem::replace(&mut self.held[id as usize], true) {
                return Err(format!(
                    "{at}: primitive {id} (slot {s}) is in another leaf too"
                ));
            }
            if let Some(p) = (self.prim_box)(id) {
                if !contains(b, &p) {
                    return Err(format!(
                        "{at}: primitive {id}'s box {p:?} is not inside its leaf's box {b:?}"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Checks that every slot outside the leaves is padding, and that every
/// block starts with a leaf's slots and is padded after its last one.
fn check_padding(slots: &[u32], in_leaf: &[bool]) -> Result<(), String> {
    for (block, (ids, used)) in slots.chunks(LANES).zip(in_leaf.chunks(LANES)).enumerate() {
        let slot = |lane: usize| block * LANES + lane;
        for (lane, (&id, &used)) in ids.iter().zip(used).enumerate() {
            if !used && id != NO_PRIM {
                return Err(format!(
                    "slot {} holds primitive {id} but is in no leaf (padding is {NO_PRIM:#x})",
                    slot(lane)
                ));
            }
        }
        if !used.contains(&true) {
            return Err(format!(
                "block {block} (slots {}..{}) holds no leaf",
                slot(0),
                slot(LANES)
            ));
        }
        let leading = used.iter().take_while(|&&u| u).count();
        if let Some(lane) = used[leading..].iter().position(|&u| u) {
            return Err(format!(
                "block {block}: slot {} is in a leaf after the padding at slot {}",
                slot(leading + lane),
                slot(leading)
            ));
        }
    }
    Ok(())
}

/// The box of `slot` in `node`.
fn slot_box(node: &Node8, slot: usize) -> Aabb {
    let b = |row: usize| node.bounds[row][slot];
    Aabb::new(Vec3::new(b(0), b(2), b(4)), Vec3::new(b(1), b(3), b(5)))
}

/// min ≤ max on every axis (false for NaN).
fn is_box(b: &Aabb) -> bool {
    b.min.cmple(b.max).all()
}

/// `inner` inside `outer` (false for NaN).
fn contains(outer: &Aabb, inner: &Aabb) -> bool {
    outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all()
}

/// The box of an empty slot ([`Node8::EMPTY`]'s).
fn is_inverted_infinite(b: &Aabb) -> bool {
    *b == Aabb::EMPTY
}

/// The tree over `boxes`, checked with them (a release build does not
/// check its trees by itself): for the accel tests' trees.
#[cfg(test)]
pub(super) fn built(boxes: &[Aabb], quality: super::BuildQuality) -> Bvh8 {
    let bvh = Bvh8::build(boxes, quality);
    if let Err(e) = bvh.validate_boxes(boxes) {
        panic!("{quality:?}, {} boxes: {e}", boxes.len());
    }
    bvh
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::super::node::{encode_leaf, is_leaf, leaf_range};
    use super::super::simd::pages::Pages;
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    fn random_boxes(n: usize, seed: u64, scale: f32) -> Vec<Aabb> {
        let mut rng = seeded(seed);
        (0..n)
            .map(|_| {
                let c = rng.cube(50.0 * scale);
                let h = (rng.cube(2.0).abs() + 0.01) * scale;
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// Every preset builds a valid tree over ordinary and degenerate
    /// inputs: none, one, many alike, points, a plane, a line, and
    /// coordinates near 1e30 and 1e-30; and over enough boxes that the
    /// collapse emits the top of the tree in parallel.
    #[test]
    fn every_preset_builds_a_valid_tree_over_any_input() {
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let points: Vec<Aabb> = random_boxes(500, 3, 1.0)
            .iter()
            .map(|b| Aabb::new(b.min, b.min))
            .collect();
        let plane: Vec<Aabb> = random_boxes(500, 4, 1.0)
            .iter()
            .map(|b| Aabb::new(b.min.with_z(0.0), b.max.with_z(0.0)))
            .collect();
        let line: Vec<Aabb> = (0..500)
            .map(|i| Aabb::new(Vec3::X * i as f32, Vec3::X * (i + 1) as f32))
            .collect();
        let inputs: Vec<(&str, Vec<Aabb>)> = vec![
            ("empty", Vec::new()),
            ("one box", vec![unit]),
            ("two alike", vec![unit; 2]),
            ("1000 alike", vec![unit; 1000]),
            ("points", points),
            ("a plane", plane),
            ("a line", line),
            ("near 1e30", random_boxes(2000, 5, 1e28)),
            ("near 1e-30", random_boxes(2000, 6, 1e-32)),
            ("random", random_boxes(3000, 7, 1.0)),
            ("parallel", random_boxes(100_000, 8, 1.0)),
        ];
        for quality in BuildQuality::ALL {
            for (name, boxes) in &inputs {
                let bvh = built(boxes, quality);
                assert_eq!(bvh.stats().leaf_prims, boxes.len(), "{quality:?}, {name}");
            }
        }
    }

    /// A valid tree to break, of several levels.
    fn tree() -> (Bvh8, Vec<Aabb>) {
        let boxes = random_boxes(3000, 9, 1.0);
        let bvh = built(&boxes, BuildQuality::Medium);
        (bvh, boxes)
    }

    /// (node, slot, child) of every occupied slot, leaves or inner nodes.
    fn slots_of(bvh: &Bvh8, leaves: bool) -> Vec<(usize, usize, u32)> {
        let mut out = Vec::new();
        for (n, node) in bvh.nodes.iter().enumerate() {
            for (slot, &c) in node.child.iter().enumerate() {
                if c != EMPTY && is_leaf(c) == leaves {
                    out.push((n, slot, c));
                }
            }
        }
        out
    }

    /// The error of the tree after `corrupt`, checked with the boxes.
    fn broken(corrupt: impl FnOnce(&mut Bvh8)) -> String {
        let (mut bvh, boxes) = tree();
        corrupt(&mut bvh);
        bvh.validate_boxes(&boxes)
            .expect_err("a broken tree passed")
    }

    fn assert_says(error: &str, want: &str) {
        assert!(error.contains(want), "{error:?} does not say {want:?}");
    }

    #[test]
    fn a_child_box_outside_its_parent_box_is_caught() {
        let (bvh, _) = tree();
        let (n, slot, c) = slots_of(&bvh, false)[0];
        let error = broken(|bvh| {
            let min_x = bvh.nodes[n].bounds[0][slot];
            bvh.nodes[n].bounds[1][slot] = min_x;
        });
        assert_says(&error, &format!("node {c}, slot"));
        let error = broken(|bvh| bvh.nodes[n].bounds[1][slot] = f32::NAN);
        assert_says(&error, &format!("node {n}, slot {slot}: the box"));
        let error = broken(|bvh| bvh.bounds.max.y -= 1.0);
        assert_says(&error, "node 0, slot");
        assert_says(&error, "is not inside the tree's bounds");
    }

    #[test]
    fn a_primitive_outside_its_leaf_box_is_caught() {
        let (bvh, boxes) = tree();
        let (n, slot, _) = slots_of(&bvh, true)[0];
        let mut shrunk = bvh.clone();
        let min_z = shrunk.nodes[n].bounds[4][slot];
        shrunk.nodes[n].bounds[5][slot] = min_z;
        let error = shrunk.validate_boxes(&boxes).unwrap_err();
        assert_says(&error, &format!("node {n}, slot {slot}: primitive"));
        // Without the boxes, a leaf box is only checked against its parent.
        assert_eq!(shrunk.validate(boxes.len()), Ok(()));
    }

    #[test]
    fn a_primitive_in_two_leaves_or_none_is_caught() {
        let (bvh, boxes) = tree();
        let leaves = slots_of(&bvh, true);
        let (a, _) = leaf_range(leaves[0].2);
        let (b, _) = leaf_range(leaves[1].2);
        let twice = bvh.prim_ids[a as usize];
        // Without the boxes: the copy may lie outside its new leaf's box.
        let mut copied = bvh.clone();
        copied.prim_ids[b as usize] = twice;
        let error = copied.validate(boxes.len()).unwrap_err();
        assert_says(&error, &format!("primitive {twice} (slot"));
        assert_says(&error, "is in another leaf too");
        assert_says(
            &bvh.validate(boxes.len() + 1).unwrap_err(),
            &format!("primitive {} is in no leaf", boxes.len()),
        );
        let error = bvh.validate(boxes.len() - 1).unwrap_err();
        assert_says(
            &error,
            &format!("holds primitive {}, past the last", boxes.len() - 1),
        );
    }

    #[test]
    fn broken_padding_is_caught() {
        let mut stray = one_leaf(0, 1);
        stray.prim_ids[3] = 0;
        assert_says(
            &stray.validate(1).unwrap_err(),
            "slot 3 holds primitive 0 but is in no leaf",
        );
        let (bvh, _) = tree();
        // A leaf's slot made padding.
        let (n, slot, c) = slots_of(&bvh, true)[0];
        let error = broken(|bvh| bvh.prim_ids[leaf_range(c).0 as usize] = NO_PRIM);
        assert_says(&error, &format!("node {n}, slot {slot}: the leaf's slot"));
        assert_says(&error, "is padding");
        // A block of padding only.
        let blocks = bvh.prim_ids.len() / LANES;
        let error = broken(|bvh| bvh.prim_ids.extend([NO_PRIM; LANES]));
        assert_says(&error, &format!("block {blocks} (slots"));
        let error = broken(|bvh| bvh.prim_ids.push(NO_PRIM));
        assert_says(&error, "are not whole blocks");
    }

    /// One node over primitive 0 in a leaf at slot `start`, in one block.
    fn one_leaf(start: u32, count: u32) -> Bvh8 {
        let mut node = Node8::EMPTY;
        for row in 0..6 {
            node.bounds[row][0] = (row % 2) as f32;
        }
        node.child[0] = encode_leaf(start, count);
        let mut prim_ids = vec![NO_PRIM; LANES];
        prim_ids[start as usize] = 0;
        Bvh8 {
            nodes: vec![node],
            prim_ids,
            bounds: Aabb::new(Vec3::ZERO, Vec3::ONE),
            depth: 1,
            prefetch: true,
            pages: Pages::Small,
        }
    }

    #[test]
    fn leaves_out_of_place_are_caught() {
        assert_eq!(one_leaf(0, 1).validate(1), Ok(()));
        assert_says(
            &one_leaf(1, 1).validate(1).unwrap_err(),
            "block 0: slot 1 is in a leaf after the padding at slot 0",
        );
        let mut straddling = one_leaf(0, 1);
        straddling.prim_ids.extend([NO_PRIM; LANES]);
        straddling.nodes[0].child[0] = encode_leaf(6, 4);
        assert_says(&straddling.validate(1).unwrap_err(), "straddle two blocks");
        let (bvh, _) = tree();
        let (n, slot, _) = slots_of(&bvh, true)[0];
        let last = bvh.prim_ids.len() as u32 - 2;
        let error = broken(|bvh| bvh.nodes[n].child[slot] = encode_leaf(last, 4));
        assert_says(&error, &format!("node {n}, slot {slot}: the leaf's slots"));
        assert_says(&error, "pass the last slot");
    }

    #[test]
    fn unreachable_shared_and_missing_nodes_are_caught() {
        let (bvh, _) = tree();
        let last = bvh.nodes.len();
        let error = broken(|bvh| bvh.nodes.push(bvh.nodes[1]));
        assert_says(&error, &format!("node {last} is unreachable"));
        let inner = slots_of(&bvh, false);
        let ((n, slot, _), (_, _, c)) = (inner[1], inner[0]);
        let error = broken(|bvh| bvh.nodes[n].child[slot] = c);
        assert_says(&error, &format!("child node {c} was reached before"));
        let error = broken(|bvh| bvh.nodes[n].child[slot] = 0);
        assert_says(&error, "child node 0 was reached before");
        let error = broken(|bvh| bvh.nodes[n].child[slot] = last as u32);
        assert_says(&error, &format!("child node {last} is past the last node"));
        let error = broken(|bvh| bvh.nodes[c as usize].child = [EMPTY; 8]);
        assert_says(&error, &format!("node {c} has no children"));
    }

    #[test]
    fn an_empty_slot_with_a_box_or_a_wrong_depth_is_caught() {
        let (bvh, _) = tree();
        let (n, slot) = bvh
            .nodes
            .iter()
            .enumerate()
            .find_map(|(n, node)| node.child.iter().position(|&c| c == EMPTY).map(|s| (n, s)))
            .expect("a node with an empty slot");
        let error = broken(|bvh| bvh.nodes[n].bounds[0][slot] = 0.0);
        assert_says(&error, &format!("node {n}, slot {slot}: an empty slot"));
        let error = broken(|bvh| bvh.depth += 1);
        assert_says(&error, &format!("depth is {}", bvh.depth + 1));
        let empty = Bvh8::empty();
        assert_eq!(empty.validate(0), Ok(()));
        assert_says(
            &empty.validate(3).unwrap_err(),
            "an empty tree over 3 primitives",
        );
    }
}
