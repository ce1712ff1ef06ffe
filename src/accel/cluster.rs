//! Clusters of primitives near each other on a Morton curve, as the leaves
//! the fastest, fast and medium presets hand to PLOC over large meshes.
//!
//! PLOC (Meister and Bittner 2018) sorts its leaves along a Morton curve and
//! merges nodes that are each other's nearest neighbour within a window of
//! the sorted order. Its first iterations spend most of its time and memory
//! pairing primitives that are neighbours on the curve. Here a few rounds
//! of that merge (a window of one) run first, over a radix sort of 30-bit
//! Morton codes, and PLOC starts from the clusters they make: two rounds
//! leave under half as many clusters as primitives (0.45 on the
//! 13.9M-triangle dragon), three about a quarter (the dragon). That
//! shrinks what PLOC sorts and merges, the binary tree it writes, what
//! reinsertion searches and the cost tables the collapse fills over that
//! tree. A cluster of `rounds` rounds holds at most 2^rounds
//! primitives, which the 8-wide leaves hold whole ([`MAX_ROUNDS`]).
//!
//! What a cluster costs is the freedom to split it: its primitives share
//! a leaf. Two rounds, then PLOC with a window of two and a little
//! reinsertion, build a tree within 1.3% of the SAH cost of PLOC over
//! single primitives with a window of 14 in less than half its time
//! (docs/performance.md, "The full-quality build from clusters").

use super::collapse::LEAF_PRIMS;
use super::simd::prefetch::prefetch;
use crate::math::Aabb;
use glam::{UVec3, Vec3};
use obvhs::aabb::Aabb as Box3A;
use obvhs::ploc::morton::morton_encode_u32;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// The most rounds of pairing: clusters of up to 2^MAX_ROUNDS primitives
/// fit one leaf.
const MAX_ROUNDS: u32 = 3;
const _: () = assert!(1 << MAX_ROUNDS <= LEAF_PRIMS);

/// How many primitives along the curve the first round asks for a box
/// ahead of reading it: the boxes are in the mesh's order, not the
/// curve's, so each read is a jump (on the 13.9M-triangle dragon the
/// first round took 0.29 s on two threads, 0.22 s with the boxes
/// prefetched 32 ahead; 8 and 16 gained less, 64 and 128 no more).
const BOXES_AHEAD: usize = 32;

/// Primitive boxes a build reads, and frees when done if it owns them.
pub(super) enum Boxes<'a> {
    Borrowed(&'a [Aabb]),
    Owned(Vec<Aabb>),
}

impl Boxes<'_> {
    /// Frees the boxes if they are owned, on a thread of their own
    /// (`system::memory::drop_aside`): a large mesh's take tens of
    /// milliseconds to unmap.
    pub(super) fn drop_aside(self) {
        if let Boxes::Owned(boxes) = self {
            crate::system::memory::drop_aside(boxes);
        }
    }
}

impl std::ops::Deref for Boxes<'_> {
    type Target = [Aabb];
    fn deref(&self) -> &[Aabb] {
        match self {
            Boxes::Borrowed(b) => b,
            Boxes::Owned(b) => b,
        }
    }
}

/// Primitives grouped into clusters: `order` lists primitive ids along the
/// curve, cluster `c` holds `order[starts[c]..starts[c + 1]]` and has box
/// `boxes[c]`, in SIMD lanes as PLOC reads them.
pub(super) struct Clusters {
    pub order: Vec<u32>,
    pub starts: Vec<u32>,
    pub boxes: Vec<Box3A>,
    /// The other buffer of the rounds' boxes, done with: PLOC's clusters
    /// of its next pass take it, and its pages, already touched, rather
    /// than fresh ones (docs/performance.md, "Fewer fresh pages").
    pub spare: Vec<Box3A>,
}

impl Clusters {
    /// The clusters of `rounds` rounds of pairing (1 to [`MAX_ROUNDS`])
    /// over primitives with boxes `boxes` inside `bounds`. Ties in Morton
    /// code keep id order (the sort is stable), so the clusters are the
    /// same on any thread count. The rounds write their starts and boxes
    /// into two buffers each, in turn: a round's output is the next one's
    /// input, and the round after overwrites the buffer the one before
    /// read. Owned boxes are freed once the first round has read them.
    pub(super) fn new(boxes: Boxes, bounds: Aabb, rounds: u32) -> Self {
        assert!((1..=MAX_ROUNDS).contains(&rounds), "{rounds} rounds");
        let order = morton_order(&boxes, bounds);
        let (mut pairs, mut starts, mut merged) = (Vec::new(), Vec::new(), Vec::new());
        // The first round reads the boxes through `order` rather than from
        // a sorted copy (24 bytes a primitive, written and read once); both
        // of its passes read them in curve order, so a read asks for the
        // box it will need `BOXES_AHEAD` places on.
        let first = |i: usize| {
            if let Some(&ahead) = order.get(i + BOXES_AHEAD) {
                prefetch(&boxes[ahead as usize]);
            }
            lanes(boxes[order[i] as usize])
        };
        pair_round(
            order.len(),
            |i| i as u32,
            first,
            (&mut pairs, &mut starts, &mut merged),
        );
        boxes.drop_aside();
        let (mut spare_starts, mut spare) = (Vec::new(), Vec::new());
        for _ in 1..rounds {
            pair_round(
                merged.len(),
                |i| starts[i],
                |i| merged[i],
                (&mut pairs, &mut spare_starts, &mut spare),
            );
            std::mem::swap(&mut starts, &mut spare_starts);
            std::mem::swap(&mut merged, &mut spare);
        }
        starts.push(order.len() as u32);
        Self {
            order,
            starts,
            boxes: merged,
            spare,
        }
    }
}

/// An [`Aabb`] in SIMD lanes.
pub(super) fn lanes(b: Aabb) -> Box3A {
    Box3A {
        min: b.min.into(),
        max: b.max.into(),
    }
}

/// [`Aabb::half_area`] of a box in lanes, the same operations in the same
/// order (so the same bits, and the same clusters).
fn half_area(b: &Box3A) -> f32 {
    let d = b.max - b.min;
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The buffers a round writes: whether each cluster pairs with the next,
/// and the merged clusters' starts (without the end) and boxes. Each is
/// cleared and filled to its length in parallel; one whose capacity
/// holds the round's output keeps its pages.
type RoundOut<'a> = (&'a mut Vec<bool>, &'a mut Vec<u32>, &'a mut Vec<Box3A>);

/// `buffer` cleared and filled with `n` copies of `value`, in parallel.
fn refill<T: Copy + Send + Sync>(buffer: &mut Vec<T>, n: usize, value: T) {
    buffer.clear();
    buffer.par_extend(
        (0..n)
            .into_par_iter()
            .with_min_len(PAIR_BLOCK)
            .map(|_| value),
    );
}

/// One round of pairing over `len` clusters in curve order, cluster `i`
/// starting at `start(i)` with box `bounds(i)`: clusters i and i + 1 merge
/// where each is the other's nearer neighbour by the surface area of their
/// union, that is where `area[i]` is a local minimum (PLOC's merge with a
/// window of one). Minima are never adjacent, so no cluster pairs twice,
/// and cluster `i` starts a merged one unless `i - 1` paired. Blocks of
/// the curve find their pairs in parallel, then write their merged
/// clusters, also in parallel, where the blocks before them end: no
/// per-block buffers that would outlive the round in the allocator.
/// Writes the merged clusters into `out` ([`RoundOut`]).
fn pair_round(
    len: usize,
    start: impl Fn(usize) -> u32 + Sync,
    bounds: impl Fn(usize) -> Box3A + Sync,
    (pairs, starts, boxes): RoundOut,
) {
    // Whether each cluster pairs with the next.
    refill(pairs, len, false);
    pairs
        .par_chunks_mut(PAIR_BLOCK)
        .enumerate()
        .for_each(|(b, pairs)| {
            let lo = b * PAIR_BLOCK;
            let hi = lo + pairs.len();
            // Whether i pairs reads the areas of i - 1, i and i + 1,
            // whose boxes are i - 1 to i + 2: each read once here.
            let first = lo.saturating_sub(1);
            let boxes: Vec<Box3A> = (first..(hi + 2).min(len)).map(&bounds).collect();
            let area: Vec<f32> = boxes
                .windows(2)
                .map(|w| half_area(&w[0].union(&w[1])))
                .collect();
            let area_of = |i: usize| area[i - first];
            for (i, pair) in (lo..hi).zip(pairs.iter_mut()) {
                *pair = i + 1 < len
                    && (i == 0 || area_of(i) <= area_of(i - 1))
                    && (i + 2 == len || area_of(i) < area_of(i + 1));
            }
        });
    let pairs = &pairs[..];
    // Clusters start after no pair: each block's, in parallel, where the
    // blocks before it end.
    let heads = |b: usize| {
        let lo = b * PAIR_BLOCK;
        let hi = (lo + PAIR_BLOCK).min(len);
        (lo..hi).filter(|&i| i == 0 || !pairs[i - 1])
    };
    let blocks = len.div_ceil(PAIR_BLOCK);
    let counts: Vec<usize> = (0..blocks)
        .into_par_iter()
        .map(|b| heads(b).count())
        .collect();
    let total = counts.iter().sum();
    refill(starts, total, 0);
    refill(boxes, total, Box3A::empty());
    let mut parts = Vec::with_capacity(blocks);
    let (mut s_rest, mut b_rest) = (&mut starts[..], &mut boxes[..]);
    for &n in &counts {
        let (s, s_tail) = std::mem::take(&mut s_rest).split_at_mut(n);
        let (b, b_tail) = std::mem::take(&mut b_rest).split_at_mut(n);
        parts.push((s, b));
        (s_rest, b_rest) = (s_tail, b_tail);
    }
    parts.into_par_iter().enumerate().for_each(|(b, (s, out))| {
        for ((i, s), out) in heads(b).zip(s).zip(out) {
            *s = start(i);
            let own = bounds(i);
            *out = if pairs[i] {
                own.union(&bounds(i + 1))
            } else {
                own
            };
        }
    });
}

/// Clusters a pairing task takes: enough that a task's work (a fraction of
/// a millisecond) dwarfs its hand-off.
const PAIR_BLOCK: usize = 1 << 15;

/// Primitive ids sorted by the Morton code of their boxes' centres, ties
/// by id.
pub(super) fn morton_order(boxes: &[Aabb], bounds: Aabb) -> Vec<u32> {
    // A new array: a u32 is aligned as a u64 is not, so the standard
    // library cannot collect into the keys' allocation (checked). In
    // parallel: one thread took 60 ms of dragon-sub2's build over its 13.9
    // million keys, while the others waited (`perf record`).
    morton_keys(boxes, bounds)
        .par_iter()
        .map(|&k| k as u32)
        .collect()
}

/// Each primitive's key, its box centre's 30-bit Morton code
/// ([`morton_code`]) above its id (`code << 32 | id`), sorted: ids in
/// Morton order, ties by id.
pub(super) fn morton_keys(boxes: &[Aabb], bounds: Aabb) -> Vec<u64> {
    let extent = bounds.max - bounds.min;
    // Centres map to [0, 1023] on each axis; a flat axis maps to 0.
    let scale = Vec3::select(extent.cmpgt(Vec3::ZERO), 1023.0 / extent, Vec3::ZERO);
    let keys: Vec<u64> = boxes
        .par_iter()
        .enumerate()
        .map(|(i, b)| {
            let c = ((b.min + b.max) * 0.5 - bounds.min) * scale;
            let q = c.clamp(Vec3::ZERO, Vec3::splat(1023.0)).as_uvec3();
            (morton_code(q) as u64) << 32 | i as u64
        })
        .collect();
    sort_keys(keys)
}

/// The 30-bit Morton code of a cell (ten bits an axis): bit k of z, y
/// and x at bits 3k, 3k + 1 and 3k + 2 (obvhs's interleave, which puts
/// its first argument lowest), so bits 3k to 3k + 2 say which octant of
/// its level-(9 − k) cell a centre lies in.
fn morton_code(q: UVec3) -> u32 {
    morton_encode_u32(q.z as u16, q.y as u16, q.x as u16)
}

/// Bits of the code the first pass of [`sort_keys`] buckets by: four
/// octree levels, 4096 cells, each a few thousand primitives of a large
/// mesh, which the cache holds while they are sorted.
const TOP_BITS: u32 = 12;

/// Keys below which [`sort_keys`] sorts by comparison, in one piece.
const SMALL_SORT: usize = 1 << 12;

/// `keys` (`code << 32 | id`, the ids distinct and rising) sorted by
/// code, ties by id: ascending, as the keys are distinct. A radix sort
/// whose first pass, in parallel, moves each key to the bucket of its
/// code's top [`TOP_BITS`] (every block of the keys counts its digits,
/// then writes each key where the keys of smaller digits, and of its digit
/// in earlier blocks, end: the order of one sequential pass whatever the
/// blocks); the buckets are then sorted each on its own, in parallel, by
/// the code's other 18 bits in two passes of nine, in the caches. One pass
/// over the whole array rather than three (the sort before: 30 bits in
/// three passes of ten, each reading and writing every key). The keys of
/// the first pass live in atomics (relaxed: plain loads and stores) so
/// that blocks can write theirs into one array where they interleave.
fn sort_keys(mut keys: Vec<u64>) -> Vec<u64> {
    if keys.len() <= SMALL_SORT {
        keys.sort_unstable();
        return keys;
    }
    let shift = 62 - TOP_BITS;
    let digit = |k: u64| (k >> shift) as usize & ((1 << TOP_BITS) - 1);
    let block = keys
        .len()
        .div_ceil(4 * rayon::current_num_threads())
        .max(1 << 16);
    let counts: Vec<Vec<usize>> = keys
        .par_chunks(block)
        .map(|keys| {
            let mut count = vec![0usize; 1 << TOP_BITS];
            for &k in keys {
                count[digit(k)] += 1;
            }
            count
        })
        .collect();
    // Where each block's keys of each digit start (digit-major order), and
    // where each bucket ends.
    let mut starts = vec![vec![0usize; 1 << TOP_BITS]; counts.len()];
    let mut ends = Vec::with_capacity(1 << TOP_BITS);
    let mut sum = 0;
    for d in 0..1 << TOP_BITS {
        for (start, count) in starts.iter_mut().zip(&counts) {
            start[d] = sum;
            sum += count[d];
        }
        ends.push(sum);
    }
    let bucketed: Vec<AtomicU64> = (0..keys.len())
        .into_par_iter()
        .map(|_| AtomicU64::new(0))
        .collect();
    keys.par_chunks(block)
        .zip(starts)
        .for_each(|(keys, mut start)| {
            for &k in keys {
                let d = digit(k);
                bucketed[start[d]].store(k, Relaxed);
                start[d] += 1;
            }
        });
    // The keys' own allocation is the buckets' scratch from here on.
    let mut scratch = keys;
    // In place: an atomic has its value's layout.
    let mut sorted: Vec<u64> = bucketed.into_iter().map(AtomicU64::into_inner).collect();
    let mut buckets = Vec::with_capacity(ends.len());
    let (mut rest, mut rest_scratch) = (&mut sorted[..], &mut scratch[..]);
    let mut at = 0;
    for end in ends {
        let (bucket, r) = rest.split_at_mut(end - at);
        let (bucket_scratch, rs) = rest_scratch.split_at_mut(end - at);
        if bucket.len() > 1 {
            buckets.push((bucket, bucket_scratch));
        }
        (rest, rest_scratch, at) = (r, rs, end);
    }
    buckets
        .into_par_iter()
        .for_each(|(bucket, scratch)| sort_bucket(bucket, scratch));
    sorted
}

/// One bucket of [`sort_keys`] (keys whose codes agree in their top
/// [`TOP_BITS`]) sorted by the code's lower 18 bits, stably, in two passes
/// of nine bits through `scratch` (as long); a small one by comparison.
fn sort_bucket(bucket: &mut [u64], scratch: &mut [u64]) {
    if bucket.len() <= 64 {
        bucket.sort_unstable();
        return;
    }
    const BITS: u32 = (30 - TOP_BITS) / 2;
    let pass = |from: &[u64], to: &mut [u64], shift: u32| {
        let digit = |k: u64| (k >> shift) as usize & ((1 << BITS) - 1);
        let mut start = [0usize; 1 << BITS];
        for &k in from.iter() {
            start[digit(k)] += 1;
        }
        let mut sum = 0;
        for s in &mut start {
            (*s, sum) = (sum, sum + *s);
        }
        for &k in from {
            let d = digit(k);
            to[start[d]] = k;
            start[d] += 1;
        }
    };
    pass(bucket, scratch, 32);
    pass(scratch, bucket, 32 + BITS);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    #[test]
    fn morton_code_interleaves_three_axes_into_one_code() {
        assert_eq!(morton_code(UVec3::new(0, 0, 0b1)), 0b1);
        assert_eq!(morton_code(UVec3::new(0, 0, 0b11)), 0b1001);
        assert_eq!(morton_code(UVec3::new(0, 0, 0x3ff)), 0x0924_9249);
        assert_eq!(morton_code(UVec3::new(0, 0x3ff, 0)), 0x0924_9249 << 1);
        assert_eq!(morton_code(UVec3::new(0x3ff, 0, 0)), 0x0924_9249 << 2);
        // The three axes never share a bit.
        assert_eq!(morton_code(UVec3::splat(0x3ff)), (1 << 30) - 1);
    }

    /// The sort orders keys by code, ties by id, whatever their spread:
    /// few distinct codes (ties in every bucket), codes spread over every
    /// bucket, and codes crowded into one bucket of the first pass (its
    /// own two passes do all the work); below and above the size it
    /// sorts in one piece.
    #[test]
    fn sort_keys_sorts_by_code_then_id() {
        let mut rng = seeded(5);
        let code = |spread: usize, u: f32| match spread {
            0 => ((u * 300.0) as u64 * 0x0123_4567) % (1 << 30),
            1 => (u * (1u64 << 30) as f32) as u64 % (1 << 30),
            _ => (0x2aa << 18) | ((u * (1 << 18) as f32) as u64 % (1 << 18)),
        };
        for spread in 0..3 {
            for n in [1000u64, 20_000, 300_000] {
                let keys: Vec<u64> = (0..n).map(|i| code(spread, rng.unit()) << 32 | i).collect();
                let mut want = keys.clone();
                want.sort_by_key(|k| k >> 32);
                assert_eq!(sort_keys(keys), want, "{n} keys");
            }
        }
    }

    #[test]
    fn clusters_cover_every_primitive_once_and_bound_their_members() {
        let mut rng = seeded(9);
        for n in [1usize, 2, 3, 1001, 20_000] {
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| {
                    let c = rng.cube(10.0);
                    Aabb::new(c - Vec3::splat(0.1), c + Vec3::splat(0.2))
                })
                .collect();
            let bounds = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
            for rounds in 1..=MAX_ROUNDS {
                let clusters = Clusters::new(Boxes::Borrowed(&boxes), bounds, rounds);
                let mut seen = clusters.order.clone();
                seen.sort_unstable();
                assert_eq!(seen, (0..n as u32).collect::<Vec<u32>>());
                assert_eq!(clusters.starts.len(), clusters.boxes.len() + 1);
                assert_eq!(clusters.starts[0], 0);
                assert_eq!(*clusters.starts.last().unwrap(), n as u32);
                for (c, w) in clusters.boxes.iter().zip(clusters.starts.windows(2)) {
                    let size = w[1] - w[0];
                    assert!((1..=1 << rounds).contains(&size), "a cluster of {size}");
                    let members = &clusters.order[w[0] as usize..w[1] as usize];
                    let union = members
                        .iter()
                        .fold(Aabb::EMPTY, |a, &id| a.union(boxes[id as usize]));
                    assert_eq!(*c, lanes(union), "a cluster's box is its members' union");
                }
                if n >= 1001 {
                    // Each round merges: about a third of the clusters are
                    // a local minimum of area and pair with the next.
                    let most = n as f64 * 0.75f64.powi(rounds as i32);
                    assert!(
                        (clusters.boxes.len() as f64) < most,
                        "{} clusters after {rounds} rounds",
                        clusters.boxes.len()
                    );
                }
            }
        }
    }

    /// The parallel pairing makes the clusters of one walk along the curve
    /// (the rule as first written: visit each cluster, merge it with the
    /// next where its area is a local minimum, skip that one), over many
    /// blocks and with ties among the areas, on 1 and 3 threads.
    #[test]
    fn parallel_pairing_pairs_as_one_walk() {
        fn walk(boxes: &[Aabb]) -> (Vec<u32>, Vec<Aabb>) {
            let len = boxes.len();
            let area: Vec<f32> = (1..len)
                .map(|i| boxes[i - 1].union(boxes[i]).half_area())
                .collect();
            let (mut starts, mut merged, mut i) = (Vec::new(), Vec::new(), 0);
            while i < len {
                starts.push(i as u32);
                let pair = i < area.len()
                    && (i == 0 || area[i] <= area[i - 1])
                    && (i + 1 == area.len() || area[i] < area[i + 1]);
                merged.push(if pair {
                    boxes[i].union(boxes[i + 1])
                } else {
                    boxes[i]
                });
                i += 1 + pair as usize;
            }
            (starts, merged)
        }
        let mut rng = seeded(3);
        // Into buffers that hold other clusters already, as the rounds
        // after the first write.
        let mut stale = (vec![true; 9], vec![7u32; 3 * PAIR_BLOCK], Vec::new());
        let mut round = |boxes: &[Aabb]| {
            let (pairs, starts, merged) = &mut stale;
            let out = (&mut *pairs, &mut *starts, &mut *merged);
            pair_round(boxes.len(), |i| i as u32, |i| lanes(boxes[i]), out);
            let merged: Vec<Aabb> = merged
                .iter()
                .map(|b| Aabb::new(b.min.into(), b.max.into()))
                .collect();
            (starts.clone(), merged)
        };
        for n in [
            1usize,
            2,
            5,
            PAIR_BLOCK - 1,
            PAIR_BLOCK + 1,
            3 * PAIR_BLOCK + 7,
        ] {
            // Corners on a coarse grid: many equal areas.
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| {
                    let c = (rng.cube(8.0) * 2.0).round();
                    Aabb::new(c, c + Vec3::splat(1.0))
                })
                .collect();
            let want = walk(&boxes);
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| round(&boxes));
                assert_eq!(got, want, "{n} clusters, {threads} threads");
            }
        }
    }

    /// Neighbours along the order pair where each is the other's nearer
    /// neighbour: three boxes on a line, the middle one nearer the right.
    #[test]
    fn a_box_pairs_with_its_nearer_neighbour() {
        let unit = |x: f32| Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let boxes = [unit(0.0), unit(3.0), unit(4.5)];
        let (mut pairs, mut starts, mut merged) = (Vec::new(), Vec::new(), Vec::new());
        let out = (&mut pairs, &mut starts, &mut merged);
        pair_round(3, |i| i as u32, |i| lanes(boxes[i]), out);
        assert_eq!(starts, vec![0, 1]);
        assert_eq!(
            merged,
            vec![lanes(boxes[0]), lanes(boxes[1].union(boxes[2]))]
        );
    }
}
