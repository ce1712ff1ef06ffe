//! Clusters of primitives near each other on a Morton curve, as the leaves
//! the fastest preset hands to PLOC.
//!
//! PLOC (Meister and Bittner 2018) sorts its leaves along a Morton curve and
//! merges nodes that are each other's nearest neighbour within a window of
//! the sorted order; the fastest preset's window is one node to each side.
//! Its first iterations spend most of its time and memory pairing
//! primitives that are neighbours on the curve. Here [`ROUNDS`] rounds of
//! that merge run first, over a radix sort of 30-bit Morton codes, and PLOC
//! starts from the clusters they make (a quarter as many as primitives on
//! the dragon). That shrinks what PLOC sorts and merges, the binary tree it
//! writes and the cost tables the collapse fills over that tree. A cluster
//! holds at most 2^ROUNDS primitives, which the 8-wide leaves hold whole.
//!
//! Only the fastest preset starts from clusters: the others' wider windows
//! and reinsertion make better trees than the clusters allow
//! (docs/embree.md, "Build and collapse").

use super::collapse::LEAF_PRIMS;
use crate::math::Aabb;
use glam::{UVec3, Vec3};
use obvhs::ploc::morton::morton_encode_u32;
use rayon::prelude::*;

/// Rounds of pairing: clusters hold up to 2^ROUNDS primitives; three
/// built fastest for the same SAH cost (docs/embree.md, "Build and
/// collapse").
const ROUNDS: u32 = 3;
const _: () = assert!(1 << ROUNDS <= LEAF_PRIMS);

/// Primitives grouped into clusters: `order` lists primitive ids along the
/// curve, cluster `c` holds `order[starts[c]..starts[c + 1]]` and has box
/// `boxes[c]`.
pub(super) struct Clusters {
    pub order: Vec<u32>,
    pub starts: Vec<u32>,
    pub boxes: Vec<Aabb>,
}

impl Clusters {
    /// The clusters of primitives with boxes `boxes` inside `bounds`. Ties
    /// in Morton code keep id order (the sort is stable), so the clusters
    /// are the same on any thread count.
    pub(super) fn new(boxes: &[Aabb], bounds: Aabb) -> Self {
        let order = morton_order(boxes, bounds);
        // The first round reads the boxes through `order` rather than from
        // a sorted copy (24 bytes a primitive, written and read once).
        let (mut starts, mut merged) =
            pair_round(order.len(), |i| i as u32, |i| boxes[order[i] as usize]);
        for _ in 1..ROUNDS {
            (starts, merged) = pair_round(merged.len(), |i| starts[i], |i| merged[i]);
        }
        starts.push(order.len() as u32);
        Self {
            order,
            starts,
            boxes: merged,
        }
    }
}

/// One round of pairing over `len` clusters in curve order, cluster `i`
/// starting at `start(i)` with box `bounds(i)`: clusters i and i + 1 merge
/// where each is the other's nearer neighbour by the surface area of their
/// union, that is where `area[i]` is a local minimum (PLOC's merge with a
/// window of one). Minima are never adjacent, so no cluster pairs twice.
/// Returns the merged clusters' starts (without the end) and boxes.
fn pair_round(
    len: usize,
    start: impl Fn(usize) -> u32,
    bounds: impl Fn(usize) -> Aabb + Sync,
) -> (Vec<u32>, Vec<Aabb>) {
    let area: Vec<f32> = (1..len)
        .into_par_iter()
        .map(|i| bounds(i - 1).union(bounds(i)).half_area())
        .collect();
    let mut starts = Vec::with_capacity(len / 2 + len / 4 + 2);
    let mut boxes = Vec::with_capacity(len / 2 + len / 4 + 1);
    let mut i = 0;
    while i < len {
        starts.push(start(i));
        let pair = i < area.len()
            && (i == 0 || area[i] <= area[i - 1])
            && (i + 1 == area.len() || area[i] < area[i + 1]);
        boxes.push(if pair {
            bounds(i).union(bounds(i + 1))
        } else {
            bounds(i)
        });
        i += 1 + pair as usize;
    }
    (starts, boxes)
}

/// Primitive ids sorted by the Morton code of their boxes' centres, ties
/// by id.
fn morton_order(boxes: &[Aabb], bounds: Aabb) -> Vec<u32> {
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
    radix_sort_by_high_30_bits(keys)
        .into_iter()
        .map(|k| k as u32)
        .collect()
}

/// The 30-bit Morton code of a cell (ten bits an axis): bit k of z, y
/// and x at bits 3k, 3k + 1 and 3k + 2 (obvhs's interleave, which puts
/// its first argument lowest).
fn morton_code(q: UVec3) -> u32 {
    morton_encode_u32(q.z as u16, q.y as u16, q.x as u16)
}

/// `keys` sorted stably by bits 32..62 (the Morton code above the id): an
/// LSD radix sort, three passes of ten bits.
fn radix_sort_by_high_30_bits(mut keys: Vec<u64>) -> Vec<u64> {
    let mut other = vec![0u64; keys.len()];
    for pass in 0..3 {
        let shift = 32 + 10 * pass;
        let digit = |k: u64| ((k >> shift) & 0x3ff) as usize;
        let mut start = vec![0usize; 1024];
        for &k in &keys {
            start[digit(k)] += 1;
        }
        let mut sum = 0;
        for s in &mut start {
            (*s, sum) = (sum, sum + *s);
        }
        for &k in &keys {
            let d = digit(k);
            other[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(&mut keys, &mut other);
    }
    keys
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

    #[test]
    fn radix_sort_is_a_stable_sort_by_the_code() {
        let mut rng = seeded(5);
        // Few distinct codes, so that ties are many and order among them shows.
        let keys: Vec<u64> = (0..20_000u64)
            .map(|i| (((rng.unit() * 300.0) as u64 * 0x0123_4567) % (1 << 30)) << 32 | i)
            .collect();
        let mut want = keys.clone();
        want.sort_by_key(|k| k >> 32);
        assert_eq!(radix_sort_by_high_30_bits(keys), want);
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
            let clusters = Clusters::new(&boxes, bounds);
            let mut seen = clusters.order.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..n as u32).collect::<Vec<u32>>());
            assert_eq!(clusters.starts.len(), clusters.boxes.len() + 1);
            assert_eq!(clusters.starts[0], 0);
            assert_eq!(*clusters.starts.last().unwrap(), n as u32);
            for (c, w) in clusters.boxes.iter().zip(clusters.starts.windows(2)) {
                let size = w[1] - w[0];
                assert!((1..=1 << ROUNDS).contains(&size), "a cluster of {size}");
                let members = &clusters.order[w[0] as usize..w[1] as usize];
                let union = members
                    .iter()
                    .fold(Aabb::EMPTY, |a, &id| a.union(boxes[id as usize]));
                assert_eq!(*c, union, "a cluster's box is its members' union");
            }
            if n >= 1001 {
                // Pairing merges: far fewer clusters than primitives.
                assert!(
                    clusters.boxes.len() < n / 2,
                    "{} clusters",
                    clusters.boxes.len()
                );
            }
        }
    }

    /// Neighbours along the order pair where each is the other's nearer
    /// neighbour: three boxes on a line, the middle one nearer the right.
    #[test]
    fn a_box_pairs_with_its_nearer_neighbour() {
        let unit = |x: f32| Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let boxes = [unit(0.0), unit(3.0), unit(4.5)];
        let (starts, merged) = pair_round(3, |i| i as u32, |i| boxes[i]);
        assert_eq!(starts, vec![0, 1]);
        assert_eq!(merged, vec![boxes[0], boxes[1].union(boxes[2])]);
    }
}
