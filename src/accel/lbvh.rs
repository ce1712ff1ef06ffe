//! The preview preset's tree: 8-wide nodes cut straight from the Morton
//! order of the primitives' centres, with no binary tree, no PLOC and no
//! surface area heuristic: a linear BVH (Lauterbach, Garland, Sengupta,
//! Luebke and Manocha 2009, "Fast BVH Construction on GPUs"), split an
//! octree level at a time.
//!
//! Sorted by their 30-bit codes, the primitives of one cell of the
//! octree over the scene's box lie side by side, and a cell's children
//! are the runs of equal three-bit digits below the highest bit the
//! cell's codes differ in (one bit an axis): up to eight, found by binary
//! search. A node starts with its range's occupied octants; while it has
//! room it opens its largest child, into that child's octants, or where
//! those do not fit, the runs of its highest two bits or one; and
//! neighbouring runs that together hold at most [`MERGE_PRIMS`]
//! primitives become one, so that nodes hold close to eight children
//! however the octants are filled. A run of up to [`LEAF_PRIMS`] is a
//! leaf: one 8-wide test. Primitives of one cell of the finest level
//! (equal codes) are split in equal runs. Large subtrees are built in
//! parallel as parts of their own ([`super::assemble`]); the tree
//! depends on the sorted keys alone, so it is the same on any thread
//! count.
//!
//! It builds in about two thirds of the fastest SAH preset's time (less
//! than half its instructions) and traces 5 to 10% slower, so `auto`
//! takes it where the build would outweigh the trace: a preview of a
//! large mesh (docs/performance.md, "The preview tree").

use super::assemble::Part;
use super::build::Bvh8;
use super::cluster::{morton_keys, Boxes};
use super::node::{encode_leaf, Node8, MAX_LEAF_PRIMS};
use super::simd::prefetch::prefetch;
use crate::math::lanes::LANES;
use crate::math::Aabb;
use crate::system::steps::Steps;
use rayon::prelude::*;
use std::ops::Range;

/// Most primitives a leaf holds: a leaf is one 8-wide test, so a run of
/// up to eight is one leaf rather than a node of small ones.
const LEAF_PRIMS: usize = MAX_LEAF_PRIMS as usize;

/// Most primitives of neighbouring runs made one leaf: runs of a few
/// primitives each (the octants of a fine cell) are merged up to four,
/// not eight, as a looser leaf is entered by more rays (on the dragon the
/// SAH cost is 20.9 with four, 21.2 with eight; docs/performance.md).
const MERGE_PRIMS: usize = 4;

/// Primitives above which a child's subtree is a part of its own, built
/// in parallel with its siblings.
const PART_PRIMS: usize = 1 << 15;

/// The preview tree over `boxes` (not empty), whose union is `bounds`;
/// owned boxes and the keys are freed before the tree's parts are joined.
/// The cut reads the boxes by id, each asked for ahead ([`AHEAD`]): a
/// copy in curve order cost a third of the step before the cut, and its
/// 24 bytes a primitive of fresh pages (docs/performance.md, "Memory asked
/// for ahead").
pub(super) fn build(boxes: Boxes, bounds: Aabb, steps: &mut Steps) -> Bvh8 {
    let keys = steps.time("morton", || morton_keys(&boxes, bounds));
    let cut = Cut {
        boxes: &boxes,
        keys: &keys,
    };
    let part = steps.time("cut", || cut.part(0..keys.len()).0);
    boxes.drop_aside();
    crate::system::memory::drop_aside(keys);
    steps.time("assemble", || part.into_bvh(bounds))
}

/// How many primitives along the curve ahead of a leaf its cut asks for
/// the boxes of.
const AHEAD: usize = 32;

/// How many keys ahead of a leaf its cut asks for (32 KB): the binary
/// searches of the nodes that follow read them, and three quarters of
/// their time went to waiting for keys (`perf annotate`); 512 took 6% off
/// the cut, 4096 13%, 16384 no more.
const KEYS_AHEAD: usize = 4096;

/// The sorted keys (`code << 32 | id`) and the primitives' boxes by id.
struct Cut<'a> {
    boxes: &'a [Aabb],
    keys: &'a [u64],
}

impl Cut<'_> {
    fn code(&self, i: usize) -> u32 {
        (self.keys[i] >> 32) as u32
    }

    /// The subtree over `range` as a part whose root is its first node,
    /// with the large children's subtrees made in parallel as parts of
    /// their own; and its box.
    fn part(&self, range: Range<usize>) -> (Part, Aabb) {
        let mut part = Part::default();
        part.nodes.push(Node8::EMPTY);
        part.depth = 1;
        if range.len() <= LEAF_PRIMS {
            // A tree of one leaf still has a root node.
            let b = self.leaf(&mut part, range, 0, 0);
            part.nodes[0].set_box(0, b);
            return (part, b);
        }
        let children = self.children(range);
        let (big, small): (Vec<Range<usize>>, Vec<Range<usize>>) = (0..children.len)
            .map(|slot| children.get(slot))
            .partition(|r| r.len() > PART_PRIMS);
        // Room for the nodes and slots of the children built here, so that
        // the arrays are not copied as they grow: a node per twelve
        // primitives (the dragon's tree has one per 17) and a slot per
        // primitive with room for padding.
        let here: usize = small.iter().map(|r| r.len()).sum();
        part.nodes.reserve(here / 12 + 1);
        part.prim_ids.reserve(here + here / 4 + LANES);
        let subs: Vec<(Part, Aabb)> = big.into_par_iter().map(|r| self.part(r)).collect();
        let bounds = self.fill(&mut part, 0, children, 1, &mut subs.into_iter());
        (part, bounds)
    }

    /// Fills node `node` of `part` (at level `level`) with `children`:
    /// its leaves, then its inner children's nodes side by side, then
    /// their subtrees in turn; a child of more than [`PART_PRIMS`] (the
    /// root's alone) is the next of `subs`, made in parallel. Returns the
    /// node's box.
    fn fill(
        &self,
        part: &mut Part,
        node: usize,
        children: Runs,
        level: u32,
        subs: &mut std::vec::IntoIter<(Part, Aabb)>,
    ) -> Aabb {
        let mut bounds = Aabb::EMPTY;
        let mut inner = [(0usize, 0usize); 8];
        let mut n_inner = 0;
        for slot in 0..children.len {
            let r = children.get(slot);
            let b = if r.len() <= LEAF_PRIMS {
                self.leaf(part, r, node, slot)
            } else if r.len() > PART_PRIMS {
                let (sub, b) = subs.next().expect("a part for each large child");
                part.subs.push((slot, sub));
                b
            } else {
                let new = part.nodes.len();
                part.nodes.push(Node8::EMPTY);
                part.nodes[node].child[slot] = new as u32;
                inner[n_inner] = (slot, new);
                n_inner += 1;
                continue;
            };
            part.nodes[node].set_box(slot, b);
            bounds = bounds.union(b);
        }
        if n_inner > 0 {
            part.depth = part.depth.max(level + 1);
        }
        for &(slot, new) in &inner[..n_inner] {
            let grandchildren = self.children(children.get(slot));
            // Below a part's root every child is smaller than a part.
            let b = self.fill(
                part,
                new,
                grandchildren,
                level + 1,
                &mut Vec::new().into_iter(),
            );
            part.nodes[node].set_box(slot, b);
            bounds = bounds.union(b);
        }
        bounds
    }

    /// Packs the primitives of `range` as one leaf of `part`, child
    /// `slot` of node `node`; returns their box.
    fn leaf(&self, part: &mut Part, range: Range<usize>, node: usize, slot: usize) -> Aabb {
        let mut ids = [0u32; LEAF_PRIMS];
        let mut bounds = Aabb::EMPTY;
        // The boxes are in the order of their ids, not the curve's: each
        // is asked for a few leaves before its leaf reads it, as leaves
        // are cut along the curve.
        for k in self
            .keys
            .get(range.start + AHEAD..range.end + AHEAD)
            .unwrap_or(&[])
        {
            prefetch(&self.boxes[*k as u32 as usize]);
        }
        if let Some(k) = self.keys.get(range.end + KEYS_AHEAD) {
            prefetch(k);
        }
        for (i, id) in range.clone().zip(&mut ids) {
            *id = self.keys[i] as u32;
            bounds = bounds.union(self.boxes[*id as usize]);
        }
        let ids = &ids[..range.len()];
        let start = part.packer.place(ids, &mut part.prim_ids);
        part.nodes[node].child[slot] = encode_leaf(start, ids.len() as u32);
        bounds
    }

    /// The children of a node over `range` (more than [`LEAF_PRIMS`]
    /// primitives), in curve order: its octants, then the largest child
    /// opened while there is room (into as many runs as fit), and
    /// neighbours that together fit in a leaf made one (module docs).
    fn children(&self, range: Range<usize>) -> Runs {
        let mut children = self.split(range, 8);
        loop {
            children.merge_small();
            let largest = (0..children.len)
                .filter(|&c| children.get(c).len() > LEAF_PRIMS)
                .max_by_key(|&c| (children.get(c).len(), std::cmp::Reverse(c)));
            match largest {
                Some(c) if children.len < 8 => {
                    let split = self.split(children.get(c), 9 - children.len);
                    children.replace(c, &split);
                }
                _ => return children,
            }
        }
    }

    /// `range` (more than one primitive) split once into two to `most`
    /// (at least 2) runs: by the highest bits its codes differ in, three
    /// (an octree level: one an axis) if their runs fit, else two, else
    /// one; codes all equal, into equal runs of at least [`MERGE_PRIMS`]
    /// where there are enough.
    fn split(&self, range: Range<usize>, most: usize) -> Runs {
        let mut runs = Runs::default();
        let (first, last) = (self.code(range.start), self.code(range.end - 1));
        if first == last {
            let n = range.len();
            let k = n.div_ceil(MERGE_PRIMS).clamp(2, most);
            for j in 0..k {
                runs.push(range.start + n * j / k..range.start + n * (j + 1) / k);
            }
            return runs;
        }
        // The codes agree above the highest bit they differ in, so the
        // bits from it down rise along the range.
        let top = 31 - (first ^ last).leading_zeros();
        for bits in (1..=3).rev() {
            let shift = (top + 1).saturating_sub(bits);
            let digit = |key: u64| (key >> 32) as u32 >> shift;
            runs = Runs::default();
            let mut start = range.start;
            while start < range.end && runs.len < 8 {
                let d = digit(self.keys[start]);
                let len = self.keys[start..range.end].partition_point(|&k| digit(k) <= d);
                runs.push(start..start + len);
                start += len;
            }
            if runs.len <= most {
                break;
            }
        }
        runs
    }
}

/// Up to eight consecutive runs of the sorted keys: a node's children.
#[derive(Debug, Clone, Copy, Default)]
struct Runs {
    /// Run k is `ends[k - 1]..ends[k]`, the first from `start`.
    start: u32,
    ends: [u32; 8],
    len: usize,
}

impl Runs {
    fn get(&self, k: usize) -> Range<usize> {
        let start = if k == 0 { self.start } else { self.ends[k - 1] };
        start as usize..self.ends[k] as usize
    }

    /// Appends `run`, which starts where the last one ends.
    fn push(&mut self, run: Range<usize>) {
        if self.len == 0 {
            self.start = run.start as u32;
        }
        debug_assert_eq!(self.get_end(), run.start);
        self.ends[self.len] = run.end as u32;
        self.len += 1;
    }

    fn get_end(&self) -> usize {
        if self.len == 0 {
            self.start as usize
        } else {
            self.ends[self.len - 1] as usize
        }
    }

    /// Run `k` replaced by `with`, which covers it (the total at most 8).
    fn replace(&mut self, k: usize, with: &Runs) {
        let mut ends = [0u32; 8];
        let mut n = 0;
        for j in 0..self.len {
            if j == k {
                for w in 0..with.len {
                    ends[n] = with.ends[w];
                    n += 1;
                }
            } else {
                ends[n] = self.ends[j];
                n += 1;
            }
        }
        self.ends = ends;
        self.len = n;
    }

    /// Neighbouring runs that together hold at most [`MERGE_PRIMS`]
    /// primitives made one, from the first on.
    fn merge_small(&mut self) {
        let mut ends = [0u32; 8];
        let mut n = 0;
        // Where the last of the merged runs starts.
        let mut last = self.start;
        for k in 0..self.len {
            if n > 0 && self.ends[k] - last <= MERGE_PRIMS as u32 {
                ends[n - 1] = self.ends[k];
            } else {
                last = if k == 0 { self.start } else { self.ends[k - 1] };
                ends[n] = self.ends[k];
                n += 1;
            }
        }
        self.ends = ends;
        self.len = n;
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::random_boxes;
    use super::super::build::BuildQuality;
    use super::super::node::{decode, ChildRef};
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

    fn preview(boxes: &[Aabb]) -> Bvh8 {
        Bvh8::build(boxes, BuildQuality::Preview)
    }

    /// The primitives under each child of each node, by a walk from the
    /// root: (node, its children's primitive counts).
    fn subtree_counts(bvh: &Bvh8) -> Vec<Vec<(bool, usize)>> {
        fn count(bvh: &Bvh8, c: ChildRef) -> usize {
            match c {
                ChildRef::Empty => 0,
                ChildRef::Leaf { count, .. } => count as usize,
                ChildRef::Node(n) => bvh.nodes[n as usize]
                    .child
                    .iter()
                    .map(|&c| count(bvh, decode(c)))
                    .sum(),
            }
        }
        bvh.nodes
            .iter()
            .map(|node| {
                node.child
                    .iter()
                    .map(|&c| decode(c))
                    .filter(|c| *c != ChildRef::Empty)
                    .map(|c| (matches!(c, ChildRef::Leaf { .. }), count(bvh, c)))
                    .collect()
            })
            .collect()
    }

    /// A valid tree (every primitive in one leaf, inside its leaf's box,
    /// depth as recorded) whose nodes are full: a node with fewer than
    /// eight children has only leaves, for it would have opened any child
    /// larger than a leaf; and no leaf holds more than eight.
    #[test]
    fn every_node_is_full_or_holds_only_leaves() {
        for (n, seed) in [(1, 1), (5, 2), (9, 3), (1000, 4), (150_000, 5)] {
            let boxes = random_boxes(n, seed);
            let bvh = preview(&boxes);
            bvh.validate_boxes(&boxes).unwrap();
            for (node, children) in subtree_counts(&bvh).iter().enumerate() {
                let leaves_only = children.iter().all(|&(leaf, _)| leaf);
                assert!(
                    children.len() == 8 || leaves_only || node == 0 && n <= LEAF_PRIMS,
                    "{n} boxes: node {node} has {children:?}"
                );
                for &(leaf, count) in children {
                    assert!(!leaf || (1..=LEAF_PRIMS).contains(&count));
                    assert!(leaf || count > LEAF_PRIMS, "a node over {count} primitives");
                }
            }
        }
    }

    /// A split covers its range with two to `most` runs in order, and
    /// no two neighbouring runs agree on the bits it split by: codes of
    /// different runs differ within the three bits below their common
    /// prefix, and runs of equal codes are equal in size within one.
    #[test]
    fn a_split_covers_its_range_with_two_to_most_runs() {
        let mut rng = seeded(6);
        for round in 0..300 {
            let n = 2 + (rng.unit() * 400.0) as usize;
            // Few distinct codes in some rounds: equal codes side by side.
            let distinct = if round % 3 == 0 { 3.0 } else { 1e6 };
            let mut keys: Vec<u64> = (0..n)
                .map(|i| ((rng.unit() * distinct) as u64 % (1 << 30)) << 32 | i as u64)
                .collect();
            keys.sort_unstable();
            let boxes = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); n];
            let cut = Cut {
                boxes: &boxes,
                keys: &keys,
            };
            let start = (rng.unit() * (n - 1) as f32) as usize;
            let end = (start + 2 + (rng.unit() * n as f32) as usize).min(n);
            for most in 2..=8 {
                let runs = cut.split(start..end, most);
                assert!((2..=most).contains(&runs.len), "{} runs", runs.len);
                assert_eq!(
                    (runs.get(0).start, runs.get(runs.len - 1).end),
                    (start, end)
                );
                let equal = cut.code(start) == cut.code(end - 1);
                for k in 0..runs.len {
                    assert!(!runs.get(k).is_empty());
                    if k > 0 {
                        assert_eq!(runs.get(k - 1).end, runs.get(k).start);
                        let (a, b) = (cut.code(runs.get(k).start - 1), cut.code(runs.get(k).start));
                        assert!(equal || a < b, "a run boundary inside equal codes");
                    }
                }
                if equal {
                    let lens: Vec<usize> = (0..runs.len).map(|k| runs.get(k).len()).collect();
                    let (lo, hi) = (lens.iter().min().unwrap(), lens.iter().max().unwrap());
                    assert!(hi - lo <= 1, "{lens:?}");
                }
            }
        }
    }

    /// Ten thousand identical boxes (one Morton cell) make a shallow tree
    /// of equal runs that still holds every box: no endless split.
    #[test]
    fn identical_boxes_split_into_equal_runs() {
        let boxes = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 10_000];
        let bvh = preview(&boxes);
        bvh.validate_boxes(&boxes).unwrap();
        // ⌈log8(10000 / 4)⌉ + 1 levels would do; equal runs stay near it.
        assert!(bvh.depth <= 6, "depth {}", bvh.depth);
    }

    /// Not the surface area heuristic's tree, but not far from it: on
    /// scattered boxes and on a surface (a sphere's triangles' boxes), the
    /// preview tree's SAH cost stays within 1.25 times the fastest SAH
    /// preset's (1.17 and 1.06 when written). A cut that split badly
    /// (runs across octants, starved nodes) would not.
    #[test]
    fn the_tree_costs_little_more_than_the_fastest_sah_tree() {
        let sphere: Vec<Aabb> = {
            let mut rng = seeded(7);
            (0..60_000)
                .map(|_| {
                    let p = rng.unit_vector() * 10.0;
                    let h = Vec3::splat(0.05);
                    Aabb::new(p - h, p + h)
                })
                .collect()
        };
        for (name, boxes) in [("scattered", random_boxes(60_000, 8)), ("sphere", sphere)] {
            let cost = |q| Bvh8::build(&boxes, q).stats().sah_cost;
            let (preview, fastest) = (cost(BuildQuality::Preview), cost(BuildQuality::Fastest));
            assert!(
                preview < 1.25 * fastest,
                "{name}: preview {preview:.2}, fastest {fastest:.2}"
            );
        }
    }
}
