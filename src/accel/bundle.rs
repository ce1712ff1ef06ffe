//! Bundles: up to [`BUNDLE_SIZE`] rays of a stream walk the tree together,
//! node by node, each node read once for all the bundle's rays that reach
//! it (the ray streams of Tsakok 2009, "Faster Incoherent Rays: Multi-BVH
//! Ray Stream Tracing", HPG; Embree's stream API traces occlusion this
//! way).
//!
//! A stack entry carries a node and the mask of the bundle's rays that
//! entered its box. At a node, each of those rays runs the single-ray box
//! test and adds its bit to the children it enters; the children that any
//! ray entered are then visited, the one some ray enters nearest first. At
//! a leaf, each ray of its mask runs the leaf test. For occlusion a ray it
//! blocks leaves the bundle: its bit is cleared from every mask popped
//! after. For closest hits a ray's nearest hit so far becomes the `tmax`
//! of its later node and leaf tests, as in its single walk. The rays of
//! each direction octant walk as one bundle, so that a node's near and
//! far planes are the same rows for all of them and are loaded once per
//! node.
//!
//! Exactness: a ray tests a node's children only where its own test
//! entered the node, in the single-ray test's own operations, so it
//! reaches the leaves its single walk may reach, with a `tmax` no smaller
//! than its closest hit's. It is blocked if and only if one of those
//! leaves blocks it, and its closest hit is the least of their hits in a
//! total order (t, then primitive id; [`super::hit::closer`]), whatever
//! the order of the leaves: its answers are [`Bvh8::occluded`]'s and
//! [`Bvh8::closest_hit`]'s, bit for bit.

use super::build::Bvh8;
use super::descend::nearest_last;
use super::node::{is_leaf, leaf_range};
use super::node_test::WIDEN;
use super::packet::{lanes_missing_box, reciprocals, PACKET_SIZE};
use super::query::Query;
use super::stack::Stack;
use crate::math::ray::ray_lanes;
use crate::math::{Aabb, Ray};
use wide::{f32x8, u32x8};

/// Most rays in one bundle: one bit each in a `u64` mask, the fastest of
/// the sizes tried (docs/embree.md, "Bundles").
pub const BUNDLE_SIZE: usize = 64;

/// The size of a tree's nodes and leaf blocks up to which a stream's
/// alike rays walk as bundles (`geometry::travel`): eight times the 32 MiB
/// of last-level cache it was measured on, between the sizes where bundles
/// went from level to slower (docs/embree.md, "Bundles"). A bundle saves
/// instructions (a node's test set up once for all its rays, no sort or
/// stack work per ray) but walks one node at a time; on a tree many times
/// the caches' size the waits for memory dominate, and single rays in
/// flight overlap them (`super::in_flight`).
pub const BUNDLE_MAX_BYTES: usize = 256 << 20;

/// One ray of a bundle as its node tests read it: the single-ray test's
/// numbers, one of each (the test broadcasts them), so that setting a
/// bundle up writes 32 bytes a ray with its end ([`Bundle::ends`]).
#[derive(Clone, Copy, Default)]
struct BundleRay {
    origin: [f32; 3],
    /// Minus the reciprocal direction, a zero component's reciprocal
    /// ±f32::MAX with the zero's sign, as in the single-ray test.
    neg_inv: [f32; 3],
    tmin: f32,
}

/// The octant of a ray's direction, the unit a bundle walks its rays in:
/// bit `axis` set where the component is negative, −0 included (as the
/// sign of its reciprocal, which decides the single-ray test's near
/// plane).
#[inline(always)]
pub fn octant(ray: &Ray) -> usize {
    let d = ray.direction;
    (d.x.is_sign_negative() as usize)
        | (d.y.is_sign_negative() as usize) << 1
        | (d.z.is_sign_negative() as usize) << 2
}

impl BundleRay {
    /// The single-ray node test (`RayBoxes`'s `NodeTest::test`) given a node's near and
    /// far planes, in the same operations: the children's entry distances
    /// and the lanes of those the ray may enter.
    #[inline(always)]
    fn test(&self, near: &[f32x8; 3], far: &[f32x8; 3], tmax: f32) -> (f32x8, f32x8) {
        let slab = |axis: usize, plane: f32x8| {
            (f32x8::splat(self.origin[axis]) - plane) * f32x8::splat(self.neg_inv[axis])
        };
        let tn = slab(0, near[0])
            .fast_max(slab(1, near[1]))
            .fast_max(slab(2, near[2]).fast_max(f32x8::splat(self.tmin)));
        let tf = slab(0, far[0])
            .fast_min(slab(1, far[1]))
            .fast_min(slab(2, far[2]).fast_min(f32x8::splat(tmax)));
        (tn, tn.simd_le(tf * f32x8::splat(WIDEN)))
    }
}

/// A bundle's rays, their ends and the rays of each direction octant.
struct Bundle {
    rays: [BundleRay; BUNDLE_SIZE],
    /// Each ray's end, which its node tests read and its leaf tests
    /// lower ([`Query::leaf_bundle`]).
    ends: [f32; BUNDLE_SIZE],
    octants: [u64; 8],
}

impl Bundle {
    /// The rays not in `skip` that may enter a tree whose box is `bounds`.
    /// Eight rays at a time: their reciprocals in one division, and those
    /// that miss the box set aside at once (they would enter no node; see
    /// `lanes_missing_box`).
    #[inline(always)]
    fn new(rays: &[Ray], skip: impl Fn(usize) -> bool, bounds: &Aabb) -> Self {
        let mut bundle = Self {
            rays: [BundleRay::default(); BUNDLE_SIZE],
            ends: [0.0; BUNDLE_SIZE],
            octants: [0; 8],
        };
        for (g, eight) in rays.chunks(PACKET_SIZE).enumerate() {
            let soa = ray_lanes(eight);
            let inv = reciprocals(&soa);
            let misses = lanes_missing_box(&soa, &inv, bounds);
            let soa = soa.map(|v| v.to_array());
            let neg_inv = inv.map(|v| (-v).to_array());
            for (k, ray) in eight.iter().enumerate() {
                let i = g * PACKET_SIZE + k;
                if skip(i) || misses >> k & 1 == 1 {
                    continue;
                }
                bundle.rays[i] = BundleRay {
                    origin: [soa[0][k], soa[1][k], soa[2][k]],
                    neg_inv: [neg_inv[0][k], neg_inv[1][k], neg_inv[2][k]],
                    tmin: soa[6][k],
                };
                bundle.ends[i] = soa[7][k];
                bundle.octants[octant(ray)] |= 1 << i;
            }
        }
        bundle
    }
}

/// Where one octant's walk stands: the node's near and far plane rows for
/// its direction signs, the children it deferred with their rays, and the
/// node or leaf it visits next with the rays that reach it.
struct OctantWalk {
    near_rows: [usize; 3],
    far_rows: [usize; 3],
    stack: Stack<(u32, u64)>,
    current: u32,
    mask: u64,
}

impl OctantWalk {
    #[inline(always)]
    fn new(octant: usize, mask: u64) -> Self {
        // Row 2·axis holds the minima, 2·axis + 1 the maxima; a negative
        // direction enters through the maximum.
        let near_rows: [usize; 3] = std::array::from_fn(|a| 2 * a + (octant >> a & 1));
        Self {
            near_rows,
            far_rows: near_rows.map(|row| row ^ 1),
            stack: Stack::new(),
            current: 0,
            mask,
        }
    }

    /// At an inner node: each ray of the mask runs its node test, and the
    /// walk moves into the child some ray enters nearest, with the rays
    /// that enter it, pushing the others farthest first. False if no ray
    /// enters any child.
    #[inline(always)]
    fn enter_node<L>(&mut self, bvh: &Bvh8, bundle: &Bundle, leaf_data: &[L]) -> bool {
        let node = &bvh.nodes[self.current as usize];
        let near = self.near_rows.map(|row| f32x8::from(node.bounds[row]));
        let far = self.far_rows.map(|row| f32x8::from(node.bounds[row]));
        // Per child, the rays entering it (bits 0–31 and 32–63 in two
        // registers) and the least entry distance among them.
        let mut rays_lo = u32x8::ZERO;
        let mut rays_hi = u32x8::ZERO;
        let mut nearest = f32x8::splat(f32::INFINITY);
        let mut m = self.mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize % BUNDLE_SIZE;
            m &= m - 1;
            let (tn, enters) = bundle.rays[i].test(&near, &far, bundle.ends[i]);
            let lanes = enters.to_bits();
            let bit = 1u64 << i;
            rays_lo |= lanes & u32x8::splat(bit as u32);
            rays_hi |= lanes & u32x8::splat((bit >> 32) as u32);
            nearest = nearest.fast_min(enters.select(tn, f32x8::splat(f32::INFINITY)));
        }
        let (lo, hi) = (rays_lo.to_array(), rays_hi.to_array());
        let rays_in: [u64; 8] = std::array::from_fn(|k| lo[k] as u64 | (hi[k] as u64) << 32);
        let children = (0..8).fold(0u32, |c, k| c | ((rays_in[k] != 0) as u32) << k);
        if children == 0 {
            return false;
        }
        // Every child entered is prefetched before the sort, the one visited
        // next too: its first loads waited on memory.
        if bvh.prefetch {
            let mut c = children;
            while c != 0 {
                bvh.prefetch_child(node.child[c.trailing_zeros() as usize], leaf_data);
                c &= c - 1;
            }
        }
        // The nearest child next, the others pushed farthest first, which
        // beat slot order (docs/embree.md, "Bundles").
        let entries = nearest_last(nearest, children, &node.child);
        let n = children.count_ones() as usize;
        for &e in &entries[..n - 1] {
            let (child, slot) = (e as u32, (e >> 32) as usize & 7);
            self.stack.push((child, rays_in[slot]));
        }
        let last = entries[n - 1];
        self.current = last as u32;
        self.mask = rays_in[(last >> 32) as usize & 7];
        true
    }

    /// Moves to the next deferred child that a ray of `alive` entered;
    /// false once none is left.
    #[inline(always)]
    fn pop(&mut self, alive: u64) -> bool {
        while let Some((child, rays)) = self.stack.pop() {
            self.mask = rays & alive;
            if self.mask != 0 {
                self.current = child;
                return true;
            }
        }
        false
    }

    /// Walks to the end: at each leaf, `visit(ends, start, count, mask)`
    /// with the rays that reach it (bit i: ray i) and the bundle's ends,
    /// which it may lower; it returns the rays that leave the bundle
    /// (blocked). Ends when no ray is left or nothing is left to visit.
    ///
    /// A leaf is tested one step late: the walk first takes the next node
    /// or leaf from the stack, so that the leaf's block, prefetched when
    /// its parent was entered, arrives meanwhile. A ray blocked or hit
    /// there is then one step late to leave the bundle or shrink its
    /// `tmax`, which costs it at most a test and changes no answer.
    #[inline(always)]
    fn run<L>(
        mut self,
        bvh: &Bvh8,
        bundle: &mut Bundle,
        leaf_data: &[L],
        mut visit: impl FnMut(&mut [f32; BUNDLE_SIZE], u32, u32, u64) -> u64,
    ) {
        let mut alive = self.mask;
        let mut waiting: Option<(u32, u64)> = None;
        let mut test_leaf =
            |ends: &mut [f32; BUNDLE_SIZE], leaf: u32, mask: u64, alive: &mut u64| {
                let (start, count) = leaf_range(leaf);
                let reach = mask & *alive;
                if reach != 0 {
                    *alive &= !visit(ends, start, count, reach);
                }
            };
        loop {
            if is_leaf(self.current) {
                if let Some((leaf, mask)) = waiting.replace((self.current, self.mask)) {
                    test_leaf(&mut bundle.ends, leaf, mask, &mut alive);
                    if alive == 0 {
                        return;
                    }
                }
            } else if self.enter_node(bvh, bundle, leaf_data) {
                continue;
            }
            if !self.pop(alive) {
                break;
            }
        }
        if let Some((leaf, mask)) = waiting {
            test_leaf(&mut bundle.ends, leaf, mask, &mut alive);
        }
    }
}

impl Bvh8 {
    /// `out[i] = self.walk(&rays[i], ..)` for up to [`BUNDLE_SIZE`] rays
    /// walked as bundles, one per direction octant, one `query` shared by
    /// all; rays whose `out[i]` is already an answer by `done` (for
    /// occlusion, a ray a cheaper test found blocked) are not walked.
    /// Each ray's node tests use its own end, which a closest hit
    /// shortens as in its single walk.
    pub fn walk_bundle<Q, L>(
        &self,
        rays: &[Ray],
        leaf_data: &[L],
        query: &mut Q,
        out: &mut [Q::Answer],
        done: impl Fn(&Q::Answer) -> bool,
    ) where
        Q: Query,
    {
        assert!(rays.len() <= BUNDLE_SIZE && out.len() == rays.len());
        let mut states: [Option<Q::State>; BUNDLE_SIZE] = std::array::from_fn(|_| None);
        for (i, ray) in rays.iter().enumerate() {
            if !done(&out[i]) {
                states[i] = Some(query.start(ray));
            }
        }
        let mut ended = 0u64;
        if !self.nodes.is_empty() {
            let mut bundle = Bundle::new(rays, |i| states[i].is_none(), &self.bounds);
            for (octant, rays_of_octant) in bundle.octants.into_iter().enumerate() {
                if rays_of_octant != 0 {
                    let walk = OctantWalk::new(octant, rays_of_octant);
                    walk.run(self, &mut bundle, leaf_data, |ends, start, count, mask| {
                        let end = query.leaf_bundle(&mut states, rays, ends, start, count, mask);
                        ended |= end;
                        end
                    });
                }
            }
        }
        for (i, (o, state)) in out.iter_mut().zip(&states).enumerate() {
            if let Some(state) = state {
                *o = query.answer(state, ended >> i & 1 == 1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::BuildQuality;
    use super::super::hit::PrimHit;
    use super::super::query::{ClosestHit, Occlusion};
    use super::super::walk::tests::{sphere_cloud, sphere_hit, spheres_block};
    use super::*;
    use crate::sampling::stream::{seeded, Draw};
    use crate::shape::sphere::Sphere;
    use glam::Vec3;
    use std::cell::RefCell;
    use std::collections::{BTreeMap, BTreeSet};

    const NO_DATA: &[()] = &[];

    /// Random spheres around the origin and a clump of identical ones (hits
    /// at equal t, which the primitive id decides), and their tree.
    fn cloud() -> (Vec<Sphere>, Bvh8) {
        sphere_cloud(7, 2000, 0.5, (CLUMP, 0.7, 40))
    }

    const CLUMP: Vec3 = Vec3::new(4.0, -3.0, 2.0);

    /// `n` rays from `eye` in every octant: a third towards random points
    /// of the cloud (every other one at the clump), a third along
    /// directions with zero components, a third away from it; segments
    /// and whole rays.
    fn rays_from(eye: Vec3, n: usize, seed: u64) -> Vec<Ray> {
        let mut rng = seeded(seed);
        (0..n)
            .map(|i| {
                let p = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 24.0 - 12.0;
                let d = match i % 3 {
                    0 if i % 2 == 0 => CLUMP + (p / 24.0) - eye,
                    0 => p - eye,
                    1 => {
                        let axis = i / 3 % 3;
                        let mut d = p - eye;
                        d[axis] = if i % 2 == 0 { 0.0 } else { -0.0 };
                        d
                    }
                    _ => eye - p,
                };
                let mut ray = Ray::new(eye, d);
                if i % 4 == 0 {
                    ray.tmax = 0.3 + rng.unit() * 1.5;
                }
                ray
            })
            .collect()
    }

    /// Bundles of every size from 0 to [`BUNDLE_SIZE`] rays, each from its
    /// own eye (one inside the cloud, one far outside it), with the eye.
    fn bundles(seed: u64) -> Vec<(Vec3, Vec<Ray>)> {
        [
            (Vec3::ZERO, BUNDLE_SIZE),
            (Vec3::new(30.0, -25.0, 12.0), BUNDLE_SIZE),
            (Vec3::new(3.0, 2.0, -1.0), 37),
            (Vec3::new(-4.0, 0.5, 9.0), 9),
            (Vec3::new(1.0, 1.0, 1.0), 1),
            (Vec3::ZERO, 0),
        ]
        .into_iter()
        .enumerate()
        .map(|(k, (eye, n))| (eye, rays_from(eye, n, seed + k as u64)))
        .collect()
    }

    /// A ray's direction, which tells a bundle's rays apart in a leaf test.
    fn key(r: &Ray) -> [u32; 3] {
        r.direction.to_array().map(f32::to_bits)
    }

    type Leaves = RefCell<BTreeMap<[u32; 3], BTreeSet<u32>>>;

    /// Notes that ray `r` reached the leaf at `start`; never blocks.
    fn reach(leaves: &Leaves, r: &Ray, start: u32) -> bool {
        !leaves.borrow_mut().entry(key(r)).or_default().insert(start)
    }

    /// Every ray's answer is its single walk's, for bundles of any size,
    /// with rays already answered left alone; and every ray of a bundle
    /// tests exactly the leaves its single walk may reach (both walks with
    /// a leaf test that never blocks, which then visit them all).
    #[test]
    fn bundles_answer_and_reach_what_single_rays_do() {
        let (spheres, bvh) = cloud();
        let blocks = |start, count, r: &Ray| spheres_block(&bvh, &spheres, start, count, r);
        let mut seen_blocked = 0;
        for (eye, rays) in bundles(11) {
            let n = rays.len();
            let answered = |i: usize| i % 7 == 3;
            let expected: Vec<bool> = rays
                .iter()
                .enumerate()
                .map(|(i, r)| answered(i) || bvh.occluded(r, NO_DATA, |s, c, r| blocks(s, c, r)))
                .collect();
            let mut got: Vec<bool> = (0..n).map(answered).collect();
            let walked = RefCell::new(BTreeSet::new());
            let mut query = Occlusion::new(|_: &mut (), s, c, r: &Ray| {
                walked.borrow_mut().insert(key(r));
                blocks(s, c, r)
            });
            bvh.walk_bundle(&rays, NO_DATA, &mut query, &mut got, |&b| b);
            assert_eq!(got, expected, "eye {eye}, {n} rays");
            for (i, r) in rays.iter().enumerate() {
                let was_walked = walked.borrow().contains(&key(r));
                assert!(!(answered(i) && was_walked), "ray {i} was answered already");
            }
            seen_blocked += expected.iter().filter(|&&b| b).count();

            let single: Leaves = Default::default();
            for r in &rays {
                bvh.occluded(r, NO_DATA, |s, _, r| reach(&single, r, s));
            }
            let bundled: Leaves = Default::default();
            let mut none = vec![false; n];
            let mut query = Occlusion::new(|_: &mut (), s, _, r: &Ray| reach(&bundled, r, s));
            bvh.walk_bundle(&rays, NO_DATA, &mut query, &mut none, |&b| b);
            assert_eq!(bundled, single, "eye {eye}, {n} rays: leaves reached");
            assert!(none.iter().all(|&b| !b));
        }
        assert!(seen_blocked > 20, "some rays are blocked: {seen_blocked}");
    }

    /// Every ray's closest hit is its single walk's, bit for bit, ties at
    /// equal t (the clump) included.
    #[test]
    fn bundles_find_the_closest_hits_single_rays_do() {
        let (spheres, bvh) = cloud();
        let hit = |start: u32, count: u32, r: &Ray| {
            bvh.closest_in_leaf(start, count, r, |_, id, r| sphere_hit(&spheres, id, r))
        };
        let bits = |h: Option<PrimHit>| h.map(|h| (h.t.to_bits(), h.prim));
        let (mut found, mut ties) = (0, 0);
        for (eye, rays) in bundles(21) {
            let n = rays.len();
            let expected: Vec<_> = rays
                .iter()
                .map(|r| bvh.closest_hit(r, NO_DATA, |s, c, r| hit(s, c, r)))
                .collect();
            let mut got = vec![None; n];
            let mut query = ClosestHit::new(|_: &mut (), s, c, r: &Ray| hit(s, c, r));
            bvh.walk_bundle(&rays, NO_DATA, &mut query, &mut got, |_| false);
            assert_eq!(
                got.iter().map(|&h| bits(h)).collect::<Vec<_>>(),
                expected.iter().map(|&h| bits(h)).collect::<Vec<_>>(),
                "eye {eye}, {n} rays"
            );
            found += expected.iter().flatten().count();
            ties += expected.iter().flatten().filter(|h| h.prim >= 2000).count();
        }
        assert!(found > 30 && ties > 5, "{found} hits, {ties} on the clump");
    }

    #[test]
    fn octants_follow_the_signs_of_the_direction() {
        let ray = |d: Vec3| Ray::new(Vec3::ZERO, d);
        assert_eq!(octant(&ray(Vec3::new(1.0, 2.0, 3.0))), 0);
        assert_eq!(octant(&ray(Vec3::new(-1.0, 2.0, 3.0))), 1);
        assert_eq!(octant(&ray(Vec3::new(1.0, -0.0, 3.0))), 2);
        assert_eq!(octant(&ray(Vec3::new(-1.0, -2.0, -3.0))), 7);
    }

    /// An empty tree walks nothing.
    #[test]
    fn empty_trees_answer_every_ray() {
        let bvh = Bvh8::build(&[], BuildQuality::Medium);
        let rays = rays_from(Vec3::ZERO, 20, 1);
        let mut blocked: Vec<bool> = (0..20).map(|i| i % 2 == 0).collect();
        let mut query = Occlusion::new(|_: &mut (), _, _, _: &Ray| unreachable!());
        bvh.walk_bundle(&rays, NO_DATA, &mut query, &mut blocked, |&b| b);
        assert_eq!(blocked, (0..20).map(|i| i % 2 == 0).collect::<Vec<_>>());
    }
}
