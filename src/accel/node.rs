//! The 8-wide node layout.

use crate::math::Aabb;

/// Child slot encoding in [`Node8::child`].
pub const EMPTY: u32 = u32::MAX;
const LEAF_BIT: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 27;
const COUNT_MASK: u32 = 0xf;
const START_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// Most primitives in one leaf.
pub const MAX_LEAF_PRIMS: u32 = 8;
/// Largest primitive count the leaf encoding can address.
pub const MAX_PRIMS: usize = START_MASK as usize;

/// Eight child boxes in structure-of-arrays form (`bounds[2*axis]` = min,
/// `bounds[2*axis + 1]` = max) and their child references. Empty slots have
/// inverted infinite boxes, which every slab test rejects.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub struct Node8 {
    pub bounds: [[f32; 8]; 6],
    pub child: [u32; 8],
}

impl Node8 {
    pub const EMPTY: Node8 = Node8 {
        bounds: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
        ],
        child: [EMPTY; 8],
    };

    /// Sets child `slot`'s box in the rows.
    #[inline]
    pub fn set_box(&mut self, slot: usize, b: Aabb) {
        for axis in 0..3 {
            self.bounds[2 * axis][slot] = b.min[axis];
            self.bounds[2 * axis + 1][slot] = b.max[axis];
        }
    }
}

/// What a child slot refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChildRef {
    Empty,
    Node(u32),
    /// A range of `prim_ids`.
    Leaf {
        start: u32,
        count: u32,
    },
}

pub fn encode_leaf(start: u32, count: u32) -> u32 {
    debug_assert!((1..=MAX_LEAF_PRIMS).contains(&count) && start <= START_MASK);
    LEAF_BIT | ((count - 1) << COUNT_SHIFT) | start
}

/// True for a leaf (or the empty slot, which traversal never reaches:
/// its inverted box fails every slab test).
#[inline(always)]
pub fn is_leaf(c: u32) -> bool {
    c & LEAF_BIT != 0
}

/// The `(start, count)` of a leaf reference.
#[inline(always)]
pub fn leaf_range(c: u32) -> (u32, u32) {
    (c & START_MASK, ((c >> COUNT_SHIFT) & COUNT_MASK) + 1)
}

#[inline]
pub fn decode(c: u32) -> ChildRef {
    // Inner nodes first: traversal meets them most, and one bit test
    // tells them apart.
    if c & LEAF_BIT == 0 {
        ChildRef::Node(c)
    } else if c != EMPTY {
        ChildRef::Leaf {
            start: c & START_MASK,
            count: ((c >> COUNT_SHIFT) & COUNT_MASK) + 1,
        }
    } else {
        ChildRef::Empty
    }
}
