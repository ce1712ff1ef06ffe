//! Single-ray traversal of the 8-wide BVH: closest hit and any hit.
//!
//! Children are visited nearest first. Box tests are made conservative by
//! widening the far distance by 1 + 2γ(3) (Ize 2013, "Robust BVH Ray
//! Traversal", JCGT 2(2)), so a ray that grazes a box corner is never
//! culled before its triangle test. Zero direction components are replaced
//! by ±f32::MAX reciprocals so no slab computes 0·∞ = NaN.

use super::build::Bvh8;
use super::collapse::LEAF_BLOCK;
use super::hit::{closer, tie_ray, PrimHit};
use super::node::{decode, is_leaf, leaf_range, ChildRef};
use super::prefetch::prefetch;
use crate::math::offset::gamma;
use crate::math::Ray;
use wide::{f32x8, u32x8};

/// A traversal stack that keeps its top [`STACK_INLINE`] entries inline
/// and moves older ones to the heap rather than ever dropping a node.
///
/// The heap part holds the *bottom* of the stack, so the hot operations
/// test one length: a push spills the older half when the inline part is
/// full, and a pop refills from the heap only when it is empty.
pub(crate) struct Stack<T> {
    inline: [T; STACK_INLINE],
    len: usize,
    spill: Vec<T>,
}

/// Entries a stack holds inline. A ray needs at most seven per level of an
/// 8-wide tree (about 45 on a 14M-triangle mesh, depth 7 to 8 in practice,
/// and far fewer on average); every ray pays for zeroing these, so 32 is
/// the compromise: 64 made the zeroing a `memset` call costing 6% of a
/// random ray's instructions on the bunny. A power of two, so indices are
/// masked instead of bounds-checked.
const STACK_INLINE: usize = 32;

impl<T: Copy + Default> Stack<T> {
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            inline: [T::default(); STACK_INLINE],
            len: 0,
            spill: Vec::new(),
        }
    }

    /// Empties the stack, keeping its memory. Entries are always written
    /// before they are read, so the old ones need no clearing.
    #[inline(always)]
    pub(crate) fn clear(&mut self) {
        self.len = 0;
        self.spill.clear();
    }

    #[inline(always)]
    pub(crate) fn push(&mut self, e: T) {
        if self.len == STACK_INLINE {
            self.spill_bottom();
        }
        self.inline[self.len % STACK_INLINE] = e;
        self.len += 1;
    }

    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            if self.spill.is_empty() {
                return None;
            }
            self.refill();
        }
        self.len -= 1;
        Some(self.inline[self.len % STACK_INLINE])
    }

    /// Makes room for `n` (at most half the inline part) more pushes that
    /// stay inline: the children of one node.
    #[inline(always)]
    fn reserve(&mut self, n: usize) {
        debug_assert!(n <= STACK_INLINE / 2);
        if self.len + n > STACK_INLINE {
            self.spill_bottom();
        }
    }

    /// Pushes the first `n - 1` of `entries` (in order, so the last of
    /// them ends on top) and returns entry `n - 1` without pushing it: one
    /// block write for a node's sorted children, the nearest kept back.
    #[inline(always)]
    fn push_all_but_nth(&mut self, entries: &[T; 8], n: usize) -> T {
        debug_assert!((1..=8).contains(&n));
        self.reserve(8);
        let top = &mut self.inline[self.len..self.len + 8];
        top.copy_from_slice(entries);
        self.len += n - 1;
        entries[(n - 1) % 8]
    }

    /// Moves the older half of the inline entries to the heap.
    #[cold]
    #[inline(never)]
    fn spill_bottom(&mut self) {
        let half = STACK_INLINE / 2;
        self.spill.extend_from_slice(&self.inline[..half]);
        self.inline.copy_within(half..self.len, 0);
        self.len -= half;
    }

    /// Moves up to half an inline stack back from the (non-empty) heap.
    #[cold]
    #[inline(never)]
    fn refill(&mut self) {
        let k = self.spill.len().min(STACK_INLINE / 2);
        let rest = self.spill.len() - k;
        self.inline[..k].copy_from_slice(&self.spill[rest..]);
        self.spill.truncate(rest);
        self.len = k;
    }
}

/// The factor far distances are widened by, 1 + 2γ(3) (Ize 2013).
pub(crate) const WIDEN: f32 = 1.0 + 2.0 * gamma(3);

/// Per-ray values reused by every node test.
pub(crate) struct RayBoxes {
    origin: [f32x8; 3],
    /// Minus the reciprocal direction. A slab is computed as
    /// (origin − bound)·(−1/d): the value of (bound − origin)·(1/d), since
    /// negation is exact (only a zero's sign may differ), with the bound as
    /// the subtraction's second operand, which x86 reads straight from
    /// memory (6 fewer loads per node test, 630 → 611 instructions per
    /// random dragon ray).
    neg_inv: [f32x8; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl RayBoxes {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        // The whole ray in one register: [o, d, tmin, tmax]. Lanes 3 to 5
        // become the reciprocal direction, with zero components replaced
        // by ±f32::MAX (the zero's sign) so no slab computes 0·∞ = NaN
        // (the other lanes' quotients are unused).
        let c = f32x8::from(ray.components());
        let zero_d = c.simd_eq(f32x8::ZERO);
        let signed_max = (c & f32x8::splat(-0.0)) | f32x8::splat(f32::MAX);
        let inv = zero_d.select(signed_max, f32x8::splat(1.0) / c);
        // Row 2·axis holds the minima and 2·axis + 1 the maxima: a negative
        // direction (the reciprocal keeps its sign) enters through the maximum.
        let neg = inv.to_bitmask() as usize >> 3;
        let inv = inv.to_array();
        let near = [neg & 1, 2 | (neg >> 1 & 1), 4 | (neg >> 2 & 1)];
        let far = near.map(|row| row ^ 1);
        let c = c.to_array();
        Self {
            origin: [c[0], c[1], c[2]].map(f32x8::splat),
            neg_inv: [-inv[3], -inv[4], -inv[5]].map(f32x8::splat),
            near,
            far,
        }
    }

    /// The eight children's entry and exit distances, clipped to [tmin, tmax].
    #[inline(always)]
    fn slabs(&self, bounds: &[[f32; 8]; 6], tmin: f32, tmax: f32) -> (f32x8, f32x8) {
        let slab = |axis: usize, side: usize| {
            (self.origin[axis] - f32x8::from(bounds[side])) * self.neg_inv[axis]
        };
        // No slab is NaN (finite bounds or ±∞ for empty slots, finite
        // nonzero reciprocals), so the plain min/max instructions suffice;
        // `f32x8::max` would add a NaN check and a blend to each.
        let tn = slab(0, self.near[0])
            .fast_max(slab(1, self.near[1]))
            .fast_max(slab(2, self.near[2]).fast_max(f32x8::splat(tmin)));
        let tf = slab(0, self.far[0])
            .fast_min(slab(1, self.far[1]))
            .fast_min(slab(2, self.far[2]).fast_min(f32x8::splat(tmax)));
        (tn, tf)
    }

    /// Entry distances and the mask of children the ray may enter.
    #[inline(always)]
    pub(crate) fn test(&self, bounds: &[[f32; 8]; 6], tmin: f32, tmax: f32) -> (f32x8, u32) {
        let (tn, tf) = self.slabs(bounds, tmin, tmax);
        let tf = tf * f32x8::splat(WIDEN);
        (tn, tn.simd_le(tf).to_bitmask())
    }

    /// Like [`RayBoxes::test`] for a line that may run through boxes at
    /// negative t: both ends are widened by their own magnitude, so a
    /// box behind the origin is not culled by rounding either.
    #[inline(always)]
    fn test_line(&self, bounds: &[[f32; 8]; 6], tmin: f32, tmax: f32) -> u32 {
        let (tn, tf) = self.slabs(bounds, tmin, tmax);
        let g = f32x8::splat(2.0 * gamma(3));
        (tn - g * tn.abs()).simd_le(tf + g * tf.abs()).to_bitmask()
    }
}

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
/// about one branch per node that has several children (callgrind's
/// branch simulation on random dragon rays).
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

impl Bvh8 {
    /// The nearest of the children in `mask` (not empty), with the others
    /// pushed onto `stack` farthest first: the step both traversals take at
    /// a node. One child needs no sort; two need one comparison; three or
    /// more go through [`nearest_last`]. The two-child case costs an extra
    /// branch, which mispredicts on some nodes, but saves the network's
    /// six stages where two boxes are hit (callgrind, 50k dragon rays:
    /// −4.4% instructions for random closest hits, −2.7% for random
    /// occlusion, −1.3% and −0.5% for camera rays; interleaved wall-time
    /// A/B, `strata trace --threads 1`, medians of 3–7 runs: closest +13%
    /// random, +13% inside, +8% grazing, +6% edges, −1.5% camera; occlusion
    /// +10% camera, +11% edges, +2% random, +1% inside, −5% grazing).
    /// Children hit are all prefetched first (see
    /// [`super::prefetch`]). The nearest one included, and before the sort:
    /// prefetching only the pushed ones, after the sort, was 1–7% slower on
    /// random dragon rays, and only the two nearest 2–11% slower
    /// (interleaved wall-time A/B).
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
        if self.prefetch {
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

    /// Prefetches the node, or the leaf's entry of `leaf_data`, that child
    /// reference `c` names.
    #[inline(always)]
    pub(crate) fn prefetch_child<L>(&self, c: u32, leaf_data: &[L]) {
        if !is_leaf(c) {
            if let Some(node) = self.nodes.get(c as usize) {
                prefetch(node);
            }
        } else if let Some(leaf) = leaf_data.get(leaf_range(c).0 as usize / LEAF_BLOCK) {
            prefetch(leaf);
        }
    }

    /// A leaf test for [`Bvh8::closest`] from a per-primitive one:
    /// `hit_prim(slot, id, ray)` must return a hit only if it is nearer
    /// than `ray.tmax`.
    #[inline(always)]
    pub fn closest_in_leaf<F>(
        &self,
        start: u32,
        count: u32,
        ray: &Ray,
        mut hit_prim: F,
    ) -> Option<PrimHit>
    where
        F: FnMut(u32, u32, &Ray) -> Option<PrimHit>,
    {
        let mut ray = *ray;
        let mut best: Option<PrimHit> = None;
        for slot in start..start + count {
            let test = tie_ray(&ray, best.as_ref());
            if let Some(h) = hit_prim(slot, self.prim_ids[slot as usize], &test) {
                if closer(&h, best.as_ref()) {
                    ray.tmax = h.t;
                    best = Some(h);
                }
            }
        }
        best
    }

    /// The primitives of leaf `start..start + count`, for per-primitive
    /// tests: (slot, id).
    #[inline(always)]
    pub fn leaf_prims(&self, start: u32, count: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        (start..start + count).map(|slot| (slot, self.prim_ids[slot as usize]))
    }

    /// Calls `visit` for every primitive whose box the line
    /// `origin + t·direction` may meet for t in `[tmin, tmax]`, which may be
    /// infinite: CSG needs the crossings of the whole line, behind the
    /// origin too. No order; `visit` sees each candidate once.
    pub fn visit_line<F>(&self, ray: &Ray, mut visit: F)
    where
        F: FnMut(u32),
    {
        if self.nodes.is_empty() {
            return;
        }
        let boxes = RayBoxes::new(ray);
        let mut stack: Stack<u32> = Stack::new();
        stack.push(0);
        while let Some(child) = stack.pop() {
            match decode(child) {
                ChildRef::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let mut mask = boxes.test_line(&node.bounds, ray.tmin, ray.tmax);
                    while mask != 0 {
                        let slot = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push(node.child[slot]);
                    }
                }
                ChildRef::Leaf { start, count } => {
                    for &prim in &self.prim_ids[start as usize..(start + count) as usize] {
                        visit(prim);
                    }
                }
                ChildRef::Empty => {}
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::build::BuildQuality;
    use super::*;
    use crate::accel::NO_PRIM;
    use crate::math::Aabb;
    use crate::sampling::stream::{seeded, Draw};
    use crate::shape::sphere::Sphere;
    use glam::Vec3;

    /// Leaf tests here read spheres by id: no block-shaped leaf data.
    const NO_DATA: &[()] = &[];

    /// Whether a sphere of leaf `start..start + count` of `bvh` blocks `r`:
    /// the any-hit leaf test of the walk tests here and in `stream` and
    /// `bundle`.
    pub(in crate::accel) fn spheres_block(
        bvh: &Bvh8,
        spheres: &[Sphere],
        start: u32,
        count: u32,
        r: &Ray,
    ) -> bool {
        bvh.leaf_prims(start, count)
            .any(|(_, id)| sphere_hit(spheres, id, r).is_some())
    }

    /// Random spheres in the 20-unit cube around the origin (`count` of
    /// them, radii from 0.05 to 0.05 + `spread`), then `copies` identical
    /// spheres of radius `radius` at `center` (hits at equal t, which the
    /// primitive id decides), and their tree: the scene of the walk tests
    /// in `stream` and `bundle`.
    pub(in crate::accel) fn sphere_cloud(
        seed: u64,
        count: usize,
        spread: f32,
        (center, radius, copies): (Vec3, f32, usize),
    ) -> (Vec<Sphere>, Bvh8) {
        let mut rng = seeded(seed);
        let mut spheres: Vec<Sphere> = (0..count)
            .map(|_| Sphere {
                center: Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 20.0 - 10.0,
                radius: 0.05 + rng.unit() * spread,
            })
            .collect();
        spheres.extend((0..copies).map(|_| Sphere { center, radius }));
        let boxes: Vec<Aabb> = spheres.iter().map(|s| s.bounds()).collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        (spheres, bvh)
    }

    /// Sphere `id`'s hit on `r` as traversal reports it: the leaf test of
    /// the traversal tests here and in `stream` and `bundle`.
    pub(in crate::accel) fn sphere_hit(spheres: &[Sphere], id: u32, r: &Ray) -> Option<PrimHit> {
        spheres[id as usize].intersect(r).map(|t| PrimHit {
            t,
            prim: id,
            u: 0.0,
            v: 0.0,
            part: 0,
        })
    }

    /// Random spheres, checked against brute force for every preset.
    #[test]
    fn closest_and_any_hit_agree_with_brute_force_for_every_quality() {
        let mut spheres = Vec::new();
        let mut rng = seeded(1);
        let mut rnd = || rng.unit();
        for _ in 0..500 {
            let c = Vec3::new(rnd(), rnd(), rnd()) * 20.0 - 10.0;
            spheres.push(Sphere {
                center: c,
                radius: 0.05 + rnd() * 0.5,
            });
        }
        let boxes: Vec<Aabb> = spheres.iter().map(|s| s.bounds()).collect();
        for quality in [
            BuildQuality::Fastest,
            BuildQuality::Fast,
            BuildQuality::Medium,
            BuildQuality::High,
        ] {
            let bvh = Bvh8::build(&boxes, quality);
            let mut seen: Vec<u32> = bvh
                .prim_ids
                .iter()
                .copied()
                .filter(|&id| id != NO_PRIM)
                .collect();
            seen.sort();
            assert_eq!(
                seen,
                (0..500).collect::<Vec<_>>(),
                "each primitive in exactly one leaf"
            );
            for _ in 0..2000 {
                let o = Vec3::new(rnd(), rnd(), rnd()) * 30.0 - 15.0;
                let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                let mut ray = Ray::new(o, d);
                ray.tmax = 5.0 + rnd() * 40.0;
                let hit = |id: u32, r: &Ray| sphere_hit(&spheres, id, r);
                let brute = (0..500u32)
                    .filter_map(|i| hit(i, &ray))
                    .min_by(|a, b| a.t.total_cmp(&b.t));
                let got = bvh.closest(&ray, NO_DATA, |start, count, r| {
                    bvh.closest_in_leaf(start, count, r, |_, id, r| hit(id, r))
                });
                assert_eq!(got.map(|h| h.prim), brute.map(|h| h.prim), "{quality:?}");
                assert_eq!(
                    bvh.any_hit(&ray, NO_DATA, |start, count, r| {
                        spheres_block(&bvh, &spheres, start, count, r)
                    }),
                    brute.is_some()
                );
            }
        }
    }

    /// Pushes past the inline part spill to the heap and come back in
    /// last-in first-out order, with block pushes mixed in.
    #[test]
    fn stack_spills_and_refills_in_order() {
        let mut stack: Stack<u64> = Stack::new();
        let mut model: Vec<u64> = Vec::new();
        let mut next = 0u64;
        for round in 0..200u64 {
            if round % 3 == 0 {
                let block: [u64; 8] = std::array::from_fn(|i| next + i as u64);
                let n = (round % 8 + 1) as usize;
                let kept = stack.push_all_but_nth(&block, n);
                assert_eq!(kept, block[n - 1]);
                model.extend_from_slice(&block[..n - 1]);
                next += 8;
            } else {
                stack.push(next);
                model.push(next);
                next += 1;
            }
            if round % 5 == 4 {
                assert_eq!(stack.pop(), model.pop());
            }
        }
        assert!(model.len() > 2 * STACK_INLINE, "the test reaches the heap");
        while let Some(e) = model.pop() {
            assert_eq!(stack.pop(), Some(e));
        }
        assert_eq!(stack.pop(), None);
    }

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

    #[test]
    fn axis_parallel_rays_and_empty_trees() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        let bvh = Bvh8::build(&boxes, BuildQuality::Auto);
        // A ray along +x exactly in the box's bottom face plane.
        let ray = Ray::new(Vec3::new(-1.0, 0.0, 0.5), Vec3::X);
        let hit = bvh.closest(&ray, NO_DATA, |start, _, _| {
            Some(PrimHit {
                t: 1.0,
                prim: bvh.prim_ids[start as usize],
                u: 0.0,
                v: 0.0,
                part: 0,
            })
        });
        assert!(hit.is_some());
        let empty = Bvh8::build(&[], BuildQuality::Auto);
        assert!(empty.closest(&ray, NO_DATA, |_, _, _| None).is_none());
        assert!(!empty.any_hit(&ray, NO_DATA, |_, _, _| true));
    }

    #[test]
    fn visit_line_finds_every_box_the_line_meets_on_both_sides_of_the_origin() {
        let boxes: Vec<Aabb> = (0..200)
            .map(|i| {
                let c = Vec3::new(i as f32 - 100.0, (i % 7) as f32, 0.0);
                Aabb::new(c - Vec3::splat(0.4), c + Vec3::splat(0.4))
            })
            .collect();
        let bvh = Bvh8::build(&boxes, BuildQuality::Auto);
        let mut line = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
        line.tmin = f32::NEG_INFINITY;
        let mut seen = Vec::new();
        bvh.visit_line(&line, |id| seen.push(id));
        seen.sort();
        let expected: Vec<u32> = (0..200).filter(|i| i % 7 == 0).collect();
        assert!(expected.iter().all(|i| seen.contains(i)), "{seen:?}");
        // Clipped to t ≥ 0 only the boxes ahead remain candidates.
        line.tmin = 0.0;
        let mut ahead = Vec::new();
        bvh.visit_line(&line, |id| ahead.push(id));
        assert!(ahead.iter().all(|&i| boxes[i as usize].max.x >= 0.0));
    }

    #[test]
    fn many_identical_boxes_build_and_are_all_found() {
        // Degenerate input: 10k identical boxes (e.g. duplicate triangles).
        let boxes = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 10_000];
        let bvh = Bvh8::build(&boxes, BuildQuality::Medium);
        let ray = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        let mut visited = 0;
        bvh.any_hit(&ray, NO_DATA, |_, count, _| {
            visited += count;
            false
        });
        assert_eq!(visited, 10_000, "no node dropped however deep the tree");
    }
}
