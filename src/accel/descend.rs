//! How a depth-first walk goes down one node of the 8-wide BVH, once its
//! node test ([`super::node_test`]) has said which children to enter: in
//! order, the nearest one next and the others pushed farthest first
//! ([`Bvh8::descend_nearest`]), or in any order ([`descend_any`]).

use super::build::Bvh8;
use super::node::{is_leaf, leaf_range};
use super::prefetch::prefetch;
use super::stack::Stack;
use crate::math::lanes::LANES;
use wide::{f32x8, u32x8};

/// `t` as a key whose unsigned order is the order of t (negative values
/// flipped below the positive ones), for sorting distances as integers.
#[inline(always)]
pub(super) fn order_key(t: f32) -> u32 {
    let bits = t.to_bits();
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }
}

/// One compare-exchange stage of an 8-lane bitonic sorting network (Batcher
/// 1968) that sorts descending: lane i meets lane i ^ j, and keeps the larger
/// if it is first in its pair within a run of 2k lanes sorting down.
const fn bitonic_stage(k: usize, j: usize) -> ([u32; 8], [u32; 8]) {
    let mut partner = [0; 8];
    let mut keep_max = [0; 8];
    let mut i = 0;
    while i < 8 {
        partner[i] = (i ^ j) as u32;
        let first = i < i ^ j;
        let down = i & k == 0;
        keep_max[i] = if first == down { u32::MAX } else { 0 };
        i += 1;
    }
    (partner, keep_max)
}

const BITONIC: [([u32; 8], [u32; 8]); 6] = [
    bitonic_stage(2, 1),
    bitonic_stage(4, 2),
    bitonic_stage(4, 1),
    bitonic_stage(8, 4),
    bitonic_stage(8, 2),
    bitonic_stage(8, 1),
];

/// The children in `mask` as stack entries (child | key << 32, key the
/// entry distance's [`order_key`] with its low three bits replaced by the
/// slot), sorted farthest first; the lanes after the last child hold
/// nothing of use. Branch-free: a sorting network in one register and a
/// permute of the child references, where an insertion sort mispredicted
/// about one branch per node that has several children.
///
/// Clearing the key's low bits moves it toward smaller t (for negative t
/// too), so comparing it with a limit's key with those bits set (`| 7`)
/// never culls a child whose entry is within the limit.
#[inline(always)]
pub(super) fn nearest_last(tn: f32x8, mask: u32, child: &[u32; 8]) -> [u64; 8] {
    let bits = tn.to_bits();
    let sign = u32x8::splat(1 << 31);
    let negative = (bits & sign).simd_eq(sign);
    let keys = negative.select(!bits, bits | sign);
    let slot = u32x8::new([0, 1, 2, 3, 4, 5, 6, 7]);
    let lane_bit = u32x8::splat(1) << slot;
    let hit = (u32x8::splat(mask) & lane_bit).simd_eq(lane_bit);
    let mut keys = hit.select((keys & u32x8::splat(!7)) | slot, u32x8::ZERO);
    for (partner, keep_max) in BITONIC {
        let other = keys.shuffle(u32x8::new(partner));
        keys = u32x8::new(keep_max).select(keys.max(other), keys.min(other));
    }
    let children = u32x8::from(*child).shuffle(keys & u32x8::splat(7));
    let (lo, hi) = (
        children.unpack_lo(keys).to_array(),
        children.unpack_hi(keys).to_array(),
    );
    std::array::from_fn(|i| {
        let pair = if i < 4 {
            &lo[2 * i..]
        } else {
            &hi[2 * (i - 4)..]
        };
        pair[0] as u64 | (pair[1] as u64) << 32
    })
}

/// The first of the children in `mask` (not empty), with the others
/// pushed onto `stack` in slot order and no key: a walk in any order
/// neither sorts nor prunes what it deferred.
#[inline(always)]
pub(super) fn descend_any(stack: &mut Stack<u64>, child: &[u32; 8], mask: u32) -> u32 {
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        stack.push(child[rest.trailing_zeros() as usize % 8] as u64);
        rest &= rest - 1;
    }
    child[mask.trailing_zeros() as usize % 8]
}

impl Bvh8 {
    /// The nearest of the children in `mask` (not empty), with the others
    /// pushed onto `stack` farthest first: the step a nearest-first walk
    /// takes at a node, alone or in flight. One child needs no sort; two need one comparison; three or
    /// more go through [`nearest_last`]. The two-child case costs an extra
    /// branch, which mispredicts on some nodes, but saves the network's
    /// six stages where two boxes are hit. Children hit are all prefetched
    /// first ([`super::prefetch`]), the nearest one included, and before
    /// the sort (docs/embree.md, "Node descent").
    #[inline(always)]
    pub(super) fn descend_nearest<L>(
        &self,
        stack: &mut Stack<u64>,
        leaf_data: &[L],
        child: &[u32; 8],
        tn: f32x8,
        mask: u32,
    ) -> u32 {
        if mask & (mask - 1) == 0 {
            return child[mask.trailing_zeros() as usize % 8];
        }
        if self.prefetches_entered(mask) {
            let mut m = mask;
            while m != 0 {
                self.prefetch_child(child[m.trailing_zeros() as usize % 8], leaf_data);
                m &= m - 1;
            }
        }
        let rest = mask & (mask - 1);
        if rest & (rest - 1) == 0 {
            // Two children: one comparison of the same keys the network
            // sorts by (entry distance, then slot), the farther pushed.
            let (i, j) = (
                mask.trailing_zeros() as usize % 8,
                rest.trailing_zeros() as usize % 8,
            );
            let t = tn.to_array();
            let key = |slot: usize| (order_key(t[slot]) & !7) | slot as u32;
            let (ki, kj) = (key(i), key(j));
            let (near, far, far_key) = if ki <= kj { (i, j, kj) } else { (j, i, ki) };
            stack.push(child[far] as u64 | (far_key as u64) << 32);
            return child[near];
        }
        let entries = nearest_last(tn, mask, child);
        let n = mask.count_ones() as usize;
        stack.push_all_but_nth(&entries, n) as u32
    }

    /// Whether [`Bvh8::descend_nearest`] prefetches the children in
    /// `mask`, the one it returns among them: where the tree prefetches
    /// and more than one child is entered.
    #[inline(always)]
    pub(super) fn prefetches_entered(&self, mask: u32) -> bool {
        self.prefetch && mask & (mask - 1) != 0
    }

    /// Prefetches the node, or the leaf's entry of `leaf_data`, that child
    /// reference `c` names.
    #[inline(always)]
    pub(crate) fn prefetch_child<L>(&self, c: u32, leaf_data: &[L]) {
        if !is_leaf(c) {
            if let Some(node) = self.nodes.get(c as usize) {
                prefetch(node);
            }
        } else if let Some(leaf) = leaf_data.get(leaf_range(c).0 as usize / LANES) {
            prefetch(leaf);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// The sorting network orders every subset of children farthest first
    /// (up to the three low bits of the key), pairs each key with its own
    /// child, and never raises a distance.
    #[test]
    fn nearest_last_sorts_every_mask_farthest_first() {
        let mut rng = seeded(7);
        let child: [u32; 8] = std::array::from_fn(|i| 100 + i as u32);
        for round in 0..2000 {
            let tn: [f32; 8] = std::array::from_fn(|i| match round % 4 {
                // Ties, zeros of both signs and negative distances too.
                0 => (rng.range(0.0, 4.0) as i32) as f32,
                1 => rng.range(-10.0, 10.0),
                2 => [0.0, -0.0, 1e-40, -1e-40, f32::INFINITY, 3.0, 3.0, 1e30][i],
                _ => rng.range(0.0, 1e6),
            });
            for mask in 1..=255u32 {
                let entries = nearest_last(f32x8::from(tn), mask, &child);
                let n = mask.count_ones() as usize;
                let mut slots: Vec<usize> = Vec::new();
                for (k, &e) in entries[..n].iter().enumerate() {
                    let key = (e >> 32) as u32;
                    let slot = (key & 7) as usize;
                    assert_eq!(e as u32, child[slot], "entry {k} keeps its own child");
                    assert!(
                        key & !7 <= order_key(tn[slot]),
                        "a key never raises the distance"
                    );
                    if k > 0 {
                        let prev = (entries[k - 1] >> 32) as u32;
                        assert!(prev > key, "farthest first: {tn:?} {mask:#b}");
                        let bucket = |slot: usize| order_key(tn[slot]) & !7;
                        assert!(bucket((prev & 7) as usize) >= bucket(slot));
                    }
                    slots.push(slot);
                }
                slots.sort();
                let expected: Vec<usize> = (0..8).filter(|i| mask >> i & 1 == 1).collect();
                assert_eq!(slots, expected, "each child exactly once");
            }
        }
    }
}
