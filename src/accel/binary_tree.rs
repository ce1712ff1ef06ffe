//! The binary trees the collapse reads ([`super::collapse`]), through one
//! view ([`Binary`]): obvhs's `Bvh2` (48-byte nodes, leaves among them),
//! which its reinsertion needs, and strata's own [`BinaryTree`], which
//! PLOC writes for the preset that does not reinsert (fastest): one
//! 32-byte node an inner node (its box and two child references, no count
//! in a float lane) and the leaves' boxes apart, 24 bytes each, so a tree
//! of `n` leaves holds 56n bytes rather than 96n (docs/performance.md,
//! "The build's peak memory").

use crate::math::Aabb;
use glam::Vec3;
use obvhs::bvh2::node::Bvh2Node;

/// A child reference in a [`BinaryTree`] (and a cluster's in PLOC): an
/// inner node's index, or a leaf's with this bit set.
pub(super) const LEAF: u32 = 1 << 31;

/// An inner node of a [`BinaryTree`]: the box of its subtree and its two
/// children's references ([`LEAF`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct BinaryNode {
    pub bounds: Aabb,
    pub child: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<BinaryNode>() == 32);

impl Default for BinaryNode {
    fn default() -> Self {
        Self {
            bounds: Aabb::EMPTY,
            child: [0; 2],
        }
    }
}

/// A binary tree of clusters: inner nodes (the root first, children after
/// their parents), and leaf `j` with box `leaves[j]` holding the
/// primitives `ids[starts[j]..starts[j + 1]]`.
#[derive(Debug, Clone, Default)]
pub(super) struct BinaryTree {
    pub nodes: Vec<BinaryNode>,
    pub leaves: Vec<Aabb>,
    pub starts: Vec<u32>,
    pub ids: Vec<u32>,
}

impl BinaryTree {
    /// The collapse's view of a tree's parts (held apart, so that they
    /// can be freed one by one).
    pub(super) fn view_of<'a>(
        nodes: &'a [BinaryNode],
        leaves: &'a [Aabb],
        starts: &'a [u32],
    ) -> OwnView<'a> {
        debug_assert_eq!(starts.len(), leaves.len() + 1);
        debug_assert_eq!(nodes.len() + 1, leaves.len());
        OwnView {
            nodes,
            leaves,
            starts,
        }
    }
}

/// What the collapse reads of a binary tree, whatever its layout. A node
/// is a `usize` reference; inner nodes are numbered densely by
/// [`Binary::slot`], for the collapse's per-node tables.
pub(super) trait Binary: Copy + Send + Sync {
    /// The root's reference.
    fn root(self) -> usize;
    /// How many inner nodes there are (slots run from 0 to this).
    fn inner_count(self) -> usize;
    fn is_leaf(self, i: usize) -> bool;
    /// Node `i`'s box, min and max.
    fn bounds(self, i: usize) -> (Vec3, Vec3);
    /// Inner node `i`'s children, left then right.
    fn children(self, i: usize) -> (usize, usize);
    /// Where leaf `i`'s primitives start among the tree's ids, and how many.
    fn leaf_range(self, i: usize) -> (usize, usize);
    /// Inner node `i`'s dense index.
    fn slot(self, i: usize) -> usize;
}

/// obvhs's tree: leaves among the nodes, children side by side.
impl Binary for &[Bvh2Node] {
    #[inline]
    fn root(self) -> usize {
        0
    }

    fn inner_count(self) -> usize {
        self.len() / 2
    }

    #[inline]
    fn is_leaf(self, i: usize) -> bool {
        self[i].prim_count > 0
    }

    #[inline]
    fn bounds(self, i: usize) -> (Vec3, Vec3) {
        // Three lanes: with obvhs's small nodes, the fourth holds counts.
        let b = self[i].aabb();
        (Vec3::from(b.min), Vec3::from(b.max))
    }

    #[inline]
    fn children(self, i: usize) -> (usize, usize) {
        let first = self[i].first_index as usize;
        (first, first + 1)
    }

    #[inline]
    fn leaf_range(self, i: usize) -> (usize, usize) {
        (self[i].first_index as usize, self[i].prim_count as usize)
    }

    /// obvhs stores the two children of a node side by side with the left
    /// one at an odd index, so half of it numbers the inner nodes from 0.
    #[inline]
    fn slot(self, i: usize) -> usize {
        self[i].first_index as usize / 2
    }
}

/// [`BinaryTree`]'s view: references are inner indices, or leaf indices
/// with [`LEAF`] set.
#[derive(Debug, Clone, Copy)]
pub(super) struct OwnView<'a> {
    nodes: &'a [BinaryNode],
    leaves: &'a [Aabb],
    starts: &'a [u32],
}

const LEAF_REF: usize = LEAF as usize;

impl Binary for OwnView<'_> {
    #[inline]
    fn root(self) -> usize {
        if self.nodes.is_empty() {
            LEAF_REF
        } else {
            0
        }
    }

    fn inner_count(self) -> usize {
        self.nodes.len()
    }

    #[inline]
    fn is_leaf(self, i: usize) -> bool {
        i & LEAF_REF != 0
    }

    #[inline]
    fn bounds(self, i: usize) -> (Vec3, Vec3) {
        let b = if self.is_leaf(i) {
            self.leaves[i & !LEAF_REF]
        } else {
            self.nodes[i].bounds
        };
        (b.min, b.max)
    }

    #[inline]
    fn children(self, i: usize) -> (usize, usize) {
        let [l, r] = self.nodes[i].child;
        (l as usize, r as usize)
    }

    #[inline]
    fn leaf_range(self, i: usize) -> (usize, usize) {
        let j = i & !LEAF_REF;
        let first = self.starts[j] as usize;
        (first, self.starts[j + 1] as usize - first)
    }

    #[inline]
    fn slot(self, i: usize) -> usize {
        i
    }
}
