//! Eight triangles at once: the watertight test of [`super::triangle`]
//! (Woop, Benthin and Wald 2013) in `wide::f32x8` lanes, over triangles
//! stored eight to a block in structure-of-arrays form.
//!
//! A BVH leaf is a run of lanes inside one block, so one leaf costs one
//! 8-wide test and one contiguous 320-byte read (five cache lines, the
//! primitive ids included) however many triangles it holds.
//!
//! Every lane performs exactly the scalar test's operations in the scalar
//! test's order (no fused multiply-adds, IEEE division, the same f64
//! fallback for edge functions that come out exactly zero), so a lane's
//! answer is bit for bit the scalar answer. The tests check that on random,
//! edge, vertex and degenerate cases; single rays, packets and CSG operands
//! can then mix the two tests and still agree.

use super::triangle::ShearedRay;
use crate::math::lanes::LANES;
use crate::math::offset::gamma;
use crate::math::ray::hit_before;
use crate::math::Ray;
use glam::Vec3;
use wide::f32x8;

/// Eight triangles in structure-of-arrays form with their primitive ids.
/// Lanes that hold no triangle (padding, or an analytic primitive sharing
/// the leaf) have NaN vertices, which no test accepts.
///
/// Aligned to a cache line (its size, 320 bytes, is five of them, so
/// nothing is added): a block is then known to span exactly five lines,
/// and its prefetch is five instructions rather than six, the sixth for a
/// line it could only reach at a 32-byte alignment (`accel::prefetch`).
/// The vectors of blocks already started on a line in practice.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub struct TriangleBlock {
    /// `v[3 * vertex + axis][lane]`.
    pub v: [[f32; LANES]; 9],
    /// Primitive id per lane; the scene stores the BVH's leaf slots here,
    /// `u32::MAX` (the BVH's `NO_PRIM`) for padding.
    pub id: [u32; LANES],
}

impl TriangleBlock {
    pub const EMPTY: TriangleBlock = TriangleBlock {
        v: [[f32::NAN; LANES]; 9],
        id: [u32::MAX; LANES],
    };

    /// The vertices in `lane`.
    #[inline]
    pub fn triangle(&self, lane: usize) -> [Vec3; 3] {
        std::array::from_fn(|k| {
            Vec3::new(
                self.v[3 * k][lane],
                self.v[3 * k + 1][lane],
                self.v[3 * k + 2][lane],
            )
        })
    }

    pub fn set(&mut self, lane: usize, tri: &[Vec3; 3], id: u32) {
        for (k, v) in tri.iter().enumerate() {
            for axis in 0..3 {
                self.v[3 * k + axis][lane] = v[axis];
            }
        }
        self.id[lane] = id;
    }
}

/// A hit in one lane of a block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneHit {
    pub lane: usize,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// The lanes (bits of `lanes`) that `ray` hits in `(tmin, tmax)`, with
/// their t, u and v, exactly as [`super::triangle::intersect`] computes
/// them lane by lane.
#[inline(always)]
pub fn intersect(
    ray: &Ray,
    s: &ShearedRay,
    block: &TriangleBlock,
    lanes: u32,
) -> (u32, [f32; LANES], [f32; LANES], [f32; LANES]) {
    let origin = [ray.origin.x, ray.origin.y, ray.origin.z];
    // Vertex `k` relative to the ray origin, along world axis `axis`.
    let rel =
        |k: usize, axis: usize| f32x8::from(block.v[3 * k + axis]) - f32x8::splat(origin[axis]);
    let (sx, sy) = (f32x8::splat(s.sx), f32x8::splat(s.sy));
    let (az_w, bz_w, cz_w) = (rel(0, s.kz), rel(1, s.kz), rel(2, s.kz));
    let ax = rel(0, s.kx) - sx * az_w;
    let ay = rel(0, s.ky) - sy * az_w;
    let bx = rel(1, s.kx) - sx * bz_w;
    let by = rel(1, s.ky) - sy * bz_w;
    let cx = rel(2, s.kx) - sx * cz_w;
    let cy = rel(2, s.ky) - sy * cz_w;
    finish(
        [ax, ay, bx, by, cx, cy],
        [az_w, bz_w, cz_w],
        f32x8::splat(s.sz),
        f32x8::splat(ray.tmin),
        f32x8::splat(ray.tmax),
        lanes,
    )
}

/// The closest hit among `lanes`: smallest t, then smallest primitive id
/// ([`hit_before`], the traversal's total order, so the answer does not
/// depend on which lane a triangle sits in).
#[inline(always)]
pub fn closest(ray: &Ray, s: &ShearedRay, block: &TriangleBlock, lanes: u32) -> Option<LaneHit> {
    let (mut hit, t, u, v) = intersect(ray, s, block, lanes);
    let mut best: Option<LaneHit> = None;
    while hit != 0 {
        let lane = hit.trailing_zeros() as usize;
        hit &= hit - 1;
        let better = match best {
            None => true,
            Some(b) => hit_before(t[lane], block.id[lane], b.t, block.id[b.lane]),
        };
        if better {
            best = Some(LaneHit {
                lane,
                t: t[lane],
                u: u[lane],
                v: v[lane],
            });
        }
    }
    best
}

/// The watertight test from the sheared coordinates on: edge functions
/// (with the f64 fallback on exact zeros), signs, t and its error bound.
/// Shared by both lane layouts so they cannot drift apart.
#[inline(always)]
fn finish(
    sheared: [f32x8; 6],
    world_z: [f32x8; 3],
    sz: f32x8,
    tmin: f32x8,
    tmax: f32x8,
    lanes: u32,
) -> (u32, [f32; LANES], [f32; LANES], [f32; LANES]) {
    let [ax, ay, bx, by, cx, cy] = sheared;
    let [az_w, bz_w, cz_w] = world_z;
    let mut e0 = cx * by - cy * bx;
    let mut e1 = ax * cy - ay * cx;
    let mut e2 = bx * ay - by * ax;
    let zero = f32x8::ZERO;
    let on_edge = (e0.simd_eq(zero) | e1.simd_eq(zero) | e2.simd_eq(zero)).to_bitmask() & lanes;
    if on_edge != 0 {
        // Rare: recompute the three edge functions of those lanes in f64,
        // as the scalar test does.
        let (axa, aya, bxa, bya, cxa, cya) = (
            ax.to_array(),
            ay.to_array(),
            bx.to_array(),
            by.to_array(),
            cx.to_array(),
            cy.to_array(),
        );
        let (mut e0a, mut e1a, mut e2a) = (e0.to_array(), e1.to_array(), e2.to_array());
        let mut m = on_edge;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let (ax, ay, bx, by, cx, cy) = (
                axa[i] as f64,
                aya[i] as f64,
                bxa[i] as f64,
                bya[i] as f64,
                cxa[i] as f64,
                cya[i] as f64,
            );
            e0a[i] = (cx * by - cy * bx) as f32;
            e1a[i] = (ax * cy - ay * cx) as f32;
            e2a[i] = (bx * ay - by * ax) as f32;
        }
        (e0, e1, e2) = (e0a.into(), e1a.into(), e2a.into());
    }
    let negative = e0.simd_lt(zero) | e1.simd_lt(zero) | e2.simd_lt(zero);
    let positive = e0.simd_gt(zero) | e1.simd_gt(zero) | e2.simd_gt(zero);
    let outside = (negative & positive).to_bitmask();
    // Most leaf tests miss every triangle: stop before the division.
    if lanes & !outside == 0 {
        return (0, [0.0; LANES], [0.0; LANES], [0.0; LANES]);
    }
    let det = e0 + e1 + e2;
    let (az, bz, cz) = (sz * az_w, sz * bz_w, sz * cz_w);
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    let inv_det = f32x8::splat(1.0) / det;
    let t = t_scaled * inv_det;
    let in_range = t.simd_gt(tmin) & t.simd_lt(tmax);
    let mut hit = (in_range.to_bitmask() & !outside & !det.simd_eq(zero).to_bitmask()) & lanes;
    if hit == 0 {
        return (0, [0.0; LANES], [0.0; LANES], [0.0; LANES]);
    }
    hit &= !at_origin(
        hit,
        t,
        [ax, ay, bx, by, cx, cy],
        [az_w, bz_w, cz_w],
        [az, bz, cz],
        [e0, e1, e2],
        inv_det,
    );
    (
        hit,
        t.to_array(),
        (e1 * inv_det).to_array(),
        (e2 * inv_det).to_array(),
    )
}

/// The lanes (bits of `lanes`) whose triangle `ray` crosses in
/// `(tmin, tmax]`, with their t: [`super::triangle::crossing`] lane by
/// lane, bit for bit. Lanes whose f32 edge functions are all nonzero (all
/// but a ray through an edge or a vertex) take their signs from those
/// values in lanes; the rest resolve their edges one by one with the
/// scalar test's own [`super::triangle::owned_edge`].
#[inline(always)]
pub fn crossings(
    ray: &Ray,
    s: &ShearedRay,
    block: &TriangleBlock,
    lanes: u32,
) -> (u32, [f32; LANES]) {
    let origin = [ray.origin.x, ray.origin.y, ray.origin.z];
    let rel =
        |k: usize, axis: usize| f32x8::from(block.v[3 * k + axis]) - f32x8::splat(origin[axis]);
    let (sx, sy) = (f32x8::splat(s.sx), f32x8::splat(s.sy));
    let (az_w, bz_w, cz_w) = (rel(0, s.kz), rel(1, s.kz), rel(2, s.kz));
    let ax = rel(0, s.kx) - sx * az_w;
    let ay = rel(0, s.ky) - sy * az_w;
    let bx = rel(1, s.kx) - sx * bz_w;
    let by = rel(1, s.ky) - sy * bz_w;
    let cx = rel(2, s.kx) - sx * cz_w;
    let cy = rel(2, s.ky) - sy * cz_w;
    let mut e0 = cx * by - cy * bx;
    let mut e1 = ax * cy - ay * cx;
    let mut e2 = bx * ay - by * ax;
    let (mut s0, mut s1, mut s2) = (e0, e1, e2);
    let zero = f32x8::ZERO;
    let unsure = |e: f32x8| e.simd_eq(zero) | e.is_nan();
    let unsure = (unsure(e0) | unsure(e1) | unsure(e2)).to_bitmask() & lanes;
    if unsure != 0 {
        let [ax, ay, bx, by, cx, cy] = [ax, ay, bx, by, cx, cy].map(|x| x.to_array());
        let mut e = [e0.to_array(), e1.to_array(), e2.to_array()];
        let mut sign = e;
        let step = s.tie_step(ray);
        for i in crate::math::lanes::mask_lanes(unsure) {
            let edges = [
                (bx[i], by[i], cx[i], cy[i]),
                (cx[i], cy[i], ax[i], ay[i]),
                (ax[i], ay[i], bx[i], by[i]),
            ];
            for (k, (px, py, qx, qy)) in edges.into_iter().enumerate() {
                (e[k][i], sign[k][i]) = super::triangle::owned_edge(px, py, qx, qy, step);
            }
        }
        (e0, e1, e2) = (e[0].into(), e[1].into(), e[2].into());
        (s0, s1, s2) = (sign[0].into(), sign[1].into(), sign[2].into());
    }
    let positive = s0.simd_gt(zero) & s1.simd_gt(zero) & s2.simd_gt(zero);
    let negative = s0.simd_lt(zero) & s1.simd_lt(zero) & s2.simd_lt(zero);
    let owned = (positive | negative).to_bitmask() & lanes;
    if owned == 0 {
        return (0, [0.0; LANES]);
    }
    let det = e0 + e1 + e2;
    let sz = f32x8::splat(s.sz);
    let (az, bz, cz) = (sz * az_w, sz * bz_w, sz * cz_w);
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    let inv_det = f32x8::splat(1.0) / det;
    let t = t_scaled * inv_det;
    let in_range = t.simd_gt(f32x8::splat(ray.tmin)) & t.simd_le(f32x8::splat(ray.tmax));
    let mut hit = in_range.to_bitmask() & !det.simd_eq(zero).to_bitmask() & owned;
    if hit == 0 {
        return (0, [0.0; LANES]);
    }
    hit &= !at_origin(
        hit,
        t,
        [ax, ay, bx, by, cx, cy],
        [az_w, bz_w, cz_w],
        [az, bz, cz],
        [e0, e1, e2],
        inv_det,
    );
    (hit, t.to_array())
}

/// The lanes of `hit` whose t lies within its rounding error of the
/// origin, the pbrt-v4 bound of the scalar test's `origin_error_bound`
/// (see it for why z appears in two units): hits on the ray's own origin
/// surface. Lanes whose triangle is wholly ahead need no bound
/// (`super::triangle::ahead`), and when all are, none is computed.
#[inline(always)]
fn at_origin(
    hit: u32,
    t: f32x8,
    xy: [f32x8; 6],
    world_z: [f32x8; 3],
    z: [f32x8; 3],
    e: [f32x8; 3],
    inv_det: f32x8,
) -> u32 {
    let near = hit & !ahead_lanes(z[0], z[1], z[2]);
    if near == 0 {
        return 0;
    }
    let [ax, ay, bx, by, cx, cy] = xy;
    // Plain `vmaxps`: a NaN here would have made t NaN and the lane a miss
    // already, so the NaN handling of `f32x8::max` (a compare and a blend
    // per call) cannot change a reported lane.
    let max3 = |a: f32x8, b: f32x8, c: f32x8| a.abs().fast_max(b.abs()).fast_max(c.abs());
    let max_z = max3(z[0], z[1], z[2]);
    let delta_z = f32x8::splat(gamma(3)) * max_z;
    let max_world_z = max3(world_z[0], world_z[1], world_z[2]);
    let max_x = max3(ax, bx, cx);
    let max_y = max3(ay, by, cy);
    let g5 = f32x8::splat(gamma(5));
    let delta_x = g5 * (max_x + max_world_z);
    let delta_y = g5 * (max_y + max_world_z);
    let delta_e = f32x8::splat(2.0)
        * (f32x8::splat(gamma(2)) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = max3(e[0], e[1], e[2]);
    let bound = f32x8::splat(3.0)
        * (f32x8::splat(gamma(3)) * max_e * max_z + delta_e * max_z + delta_z * max_e)
        * inv_det.abs();
    t.simd_le(bound).to_bitmask() & near
}

/// The lanes whose triangle lies wholly ahead of the ray's origin:
/// [`super::triangle::ahead`] lane by lane.
#[inline(always)]
fn ahead_lanes(az: f32x8, bz: f32x8, cz: f32x8) -> u32 {
    let zero = f32x8::ZERO;
    (az.simd_gt(zero) & bz.simd_gt(zero) & cz.simd_gt(zero)).to_bitmask()
}

/// Up to eight rays in lanes, sheared as [`ShearedRay`] does for each:
/// the other way round from [`intersect`], for testing one triangle
/// against a packet of coherent rays (eight rays for the price of about
/// one 8-wide test). Each ray keeps its own axis permutation, chosen by
/// per-lane selects, so every lane is again exactly the scalar test.
pub struct ShearedRays {
    origin: [f32x8; 3],
    /// Per permuted axis (kx, ky, kz): lane masks of "world axis 0" and
    /// "world axis 1" (else axis 2).
    is_axis0: [f32x8; 3],
    is_axis1: [f32x8; 3],
    sx: f32x8,
    sy: f32x8,
    sz: f32x8,
    tmin: f32x8,
}

impl ShearedRays {
    /// `rays` (at most [`LANES`]); unused lanes repeat the first ray.
    /// [`ShearedRay::new`] in lanes: the same dominant axis (the first
    /// largest |d|), the same winding swap and the same divisions.
    pub fn new(rays: &[Ray]) -> Self {
        Self::from_lanes(&crate::math::ray::ray_lanes(rays))
    }

    /// [`ShearedRays::new`] given the rays already in lanes
    /// ([`crate::math::ray::ray_lanes`]).
    #[inline(always)]
    pub fn from_lanes(soa: &[f32x8; 8]) -> Self {
        let d = [soa[3], soa[4], soa[5]];
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        let y_wins = ay.simd_gt(ax);
        let z_wins = az.simd_gt(y_wins.select(ay, ax));
        // kz's lane masks: axis 0, 1 or 2.
        let kz2 = z_wins;
        let kz1 = y_wins & !z_wins;
        let kz0 = !(kz1 | kz2);
        let dz = kz0.select(d[0], kz1.select(d[1], d[2]));
        let swap = dz.simd_lt(f32x8::ZERO);
        let keep = !swap;
        // kx = kz + 1 and ky = kz + 2 (mod 3), exchanged when d[kz] < 0.
        let kx0 = (kz2 & keep) | (kz1 & swap);
        let kx1 = (kz0 & keep) | (kz2 & swap);
        let ky0 = (kz2 & swap) | (kz1 & keep);
        let ky1 = (kz0 & swap) | (kz2 & keep);
        let pick = |m0: f32x8, m1: f32x8| m0.select(d[0], m1.select(d[1], d[2]));
        let sz = f32x8::splat(1.0) / dz;
        Self {
            origin: [soa[0], soa[1], soa[2]],
            is_axis0: [kx0, ky0, kz0],
            is_axis1: [kx1, ky1, kz1],
            sx: pick(kx0, kx1) * sz,
            sy: pick(ky0, ky1) * sz,
            sz,
            tmin: soa[6],
        }
    }

    /// The lanes of `active` whose ray hits `tri` in `(tmin, tmax[lane])`,
    /// with t, u and v per lane, exactly as [`super::triangle::intersect`].
    #[inline(always)]
    pub fn intersect(
        &self,
        tri: &[Vec3; 3],
        tmax: f32x8,
        active: u32,
    ) -> (u32, [f32; LANES], [f32; LANES], [f32; LANES]) {
        // Vertex k relative to each ray's origin, per world axis.
        let rel = |k: usize| -> [f32x8; 3] {
            std::array::from_fn(|axis| f32x8::splat(tri[k][axis]) - self.origin[axis])
        };
        let (va, vb, vc) = (rel(0), rel(1), rel(2));
        // Component k (0: kx, 1: ky, 2: kz) of each lane's permutation.
        let pick = |v: &[f32x8; 3], k: usize| {
            self.is_axis0[k].select(v[0], self.is_axis1[k].select(v[1], v[2]))
        };
        let (az_w, bz_w, cz_w) = (pick(&va, 2), pick(&vb, 2), pick(&vc, 2));
        let ax = pick(&va, 0) - self.sx * az_w;
        let ay = pick(&va, 1) - self.sy * az_w;
        let bx = pick(&vb, 0) - self.sx * bz_w;
        let by = pick(&vb, 1) - self.sy * bz_w;
        let cx = pick(&vc, 0) - self.sx * cz_w;
        let cy = pick(&vc, 1) - self.sy * cz_w;
        finish(
            [ax, ay, bx, by, cx, cy],
            [az_w, bz_w, cz_w],
            self.sz,
            self.tmin,
            tmax,
            active,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::triangle;
    use super::*;
    use rand::{RngExt, SeedableRng};

    type Rng = rand::rngs::Xoshiro256PlusPlus;

    /// A point of the cube of side `scale` centred on the origin.
    fn cube(rng: &mut Rng, scale: f32) -> Vec3 {
        (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * scale
    }

    /// Every lane agrees with the scalar test bit for bit.
    fn check(ray: &Ray, block: &TriangleBlock) {
        let s = ShearedRay::new(ray);
        let (hit, t, u, v) = intersect(ray, &s, block, 0xff);
        for lane in 0..LANES {
            let scalar = triangle::intersect(ray, &s, &block.triangle(lane));
            let simd = (hit >> lane & 1 == 1).then(|| (t[lane], u[lane], v[lane]));
            assert_eq!(
                scalar.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits())),
                simd.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits())),
                "lane {lane}: {:?} ray {ray:?}",
                block.triangle(lane)
            );
        }
    }

    #[test]
    fn lanes_match_the_scalar_test_bit_for_bit() {
        let mut rng = Rng::seed_from_u64(7);
        let mut hits = 0;
        for round in 0..4000 {
            let scale = [1e-4, 1.0, 1e5][round % 3];
            let mut block = TriangleBlock::EMPTY;
            for lane in 0..LANES {
                let c = cube(&mut rng, scale);
                let tri = [
                    c + cube(&mut rng, scale),
                    c + cube(&mut rng, scale),
                    c + cube(&mut rng, scale),
                ];
                block.set(lane, &tri, lane as u32);
            }
            // Aim at a random point of a random lane's triangle, or at one
            // of its vertices or edge midpoints (exact-zero edge functions).
            let target_tri = block.triangle(round % LANES);
            let (b1, b2) = (rng.random::<f32>(), rng.random::<f32>());
            let target = match round % 4 {
                0 => target_tri[0],
                1 => (target_tri[1] + target_tri[2]) * 0.5,
                _ => {
                    let (b1, b2) = if b1 + b2 > 1.0 {
                        (1.0 - b1, 1.0 - b2)
                    } else {
                        (b1, b2)
                    };
                    target_tri[0]
                        + (target_tri[1] - target_tri[0]) * b1
                        + (target_tri[2] - target_tri[0]) * b2
                }
            };
            let origin = target + cube(&mut rng, scale * 4.0);
            let mut ray = Ray::new(origin, target - origin);
            if round % 5 == 0 {
                ray.tmax = rng.random::<f32>() * 1.5;
            }
            check(&ray, &block);
            hits += intersect(&ray, &ShearedRay::new(&ray), &block, 0xff)
                .0
                .count_ones();
        }
        assert!(hits > 2000, "the cases must exercise hits, got {hits}");
    }

    /// [`crossings`] agrees with the scalar [`triangle::crossing`] bit
    /// for bit, on random triangles and on rays through shared edges and
    /// vertices (fans, exact zeros, with and without the axis-aligned
    /// shear) and degenerate lanes.
    #[test]
    fn crossing_lanes_match_the_scalar_test_bit_for_bit() {
        let mut rng = Rng::seed_from_u64(13);
        let mut hits = 0;
        for round in 0..6000 {
            let scale = [1e-4, 1.0, 1e5][round % 3];
            let mut block = TriangleBlock::EMPTY;
            let apex = cube(&mut rng, scale);
            let lanes = 5 + round % 4;
            for lane in 0..lanes {
                // A fan around `apex` of `lanes` triangles, some lanes
                // random or degenerate instead.
                let ring = |k: usize| {
                    let a = k as f32 / lanes as f32 * std::f32::consts::TAU;
                    apex + Vec3::new(a.cos(), a.sin(), 0.3 * (k % 2) as f32) * scale
                };
                let tri = match (round / 3 + lane) % 7 {
                    0 => std::array::from_fn(|_| apex + cube(&mut rng, scale)),
                    1 => [apex, ring(lane), apex],
                    _ => [apex, ring(lane), ring(lane + 1)],
                };
                block.set(lane, &tri, lane as u32);
            }
            let lane = round % lanes;
            let tri = block.triangle(lane);
            let target = match round % 5 {
                0 => tri[0],
                1 => (tri[0] + tri[1]) * 0.5,
                2 => tri[1],
                _ => {
                    tri[0]
                        + (tri[1] - tri[0]) * rng.random::<f32>() * 0.5
                        + (tri[2] - tri[0]) * rng.random::<f32>() * 0.5
                }
            };
            let dir = match round % 3 {
                0 => Vec3::new(0.0, 0.0, if round % 2 == 0 { 1.0 } else { -1.0 }),
                _ => cube(&mut rng, 2.0),
            };
            let mut ray = Ray::new(target - dir * 3.0, dir);
            if round % 7 == 0 {
                ray.tmax = 3.0;
                ray.tmin = rng.random::<f32>() * 3.0;
            }
            let s = ShearedRay::new(&ray);
            let (hit, t) = crossings(&ray, &s, &block, 0xff);
            for (lane, &t) in t.iter().enumerate() {
                let scalar = triangle::crossing(&ray, &s, &block.triangle(lane));
                let simd = (hit >> lane & 1 == 1).then_some(t);
                assert_eq!(
                    scalar.map(f32::to_bits),
                    simd.map(f32::to_bits),
                    "round {round} lane {lane}: {:?} ray {ray:?}",
                    block.triangle(lane)
                );
            }
            hits += hit.count_ones();
        }
        assert!(hits > 3000, "the cases must exercise crossings, got {hits}");
    }

    /// Rays in lanes, each with its own dominant axis and so its own
    /// permutation, agree with the scalar test bit for bit.
    #[test]
    fn ray_lanes_match_the_scalar_test_bit_for_bit() {
        let mut rng = Rng::seed_from_u64(11);
        let mut hits = 0;
        for round in 0..3000 {
            let scale = [1e-4, 1.0, 1e5][round % 3];
            let c = cube(&mut rng, scale);
            let tri = [
                c + cube(&mut rng, scale),
                c + cube(&mut rng, scale),
                c + cube(&mut rng, scale),
            ];
            let rays: Vec<Ray> = (0..LANES)
                .map(|lane| {
                    let (b1, b2) = (rng.random::<f32>(), rng.random::<f32>());
                    let (b1, b2) = if b1 + b2 > 1.0 {
                        (1.0 - b1, 1.0 - b2)
                    } else {
                        (b1, b2)
                    };
                    let target = match (round + lane) % 5 {
                        0 => tri[1],
                        1 => (tri[0] + tri[2]) * 0.5,
                        _ => tri[0] + (tri[1] - tri[0]) * b1 + (tri[2] - tri[0]) * b2,
                    };
                    let origin = target + cube(&mut rng, scale * 4.0);
                    let mut ray = Ray::new(origin, target - origin);
                    ray.tmin = if lane % 3 == 0 { 0.5 } else { 0.0 };
                    ray
                })
                .collect();
            let tmax: [f32; LANES] =
                std::array::from_fn(|i| if i % 4 == 1 { 0.9 } else { f32::INFINITY });
            let active = if round % 2 == 0 { 0xff } else { 0b1011_0110 };
            let (hit, t, u, v) = ShearedRays::new(&rays).intersect(&tri, tmax.into(), active);
            for lane in 0..LANES {
                let ray = Ray {
                    tmax: tmax[lane],
                    ..rays[lane]
                };
                let scalar = triangle::intersect(&ray, &ShearedRay::new(&ray), &tri)
                    .filter(|_| active >> lane & 1 == 1);
                let simd = (hit >> lane & 1 == 1).then(|| (t[lane], u[lane], v[lane]));
                assert_eq!(
                    scalar.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits())),
                    simd.map(|(t, u, v)| (t.to_bits(), u.to_bits(), v.to_bits())),
                    "lane {lane}: {tri:?} ray {ray:?}"
                );
            }
            hits += hit.count_ones();
        }
        assert!(hits > 4000, "the cases must exercise hits, got {hits}");
    }

    #[test]
    fn axis_aligned_rays_shared_edges_and_degenerate_lanes() {
        // Two triangles sharing an edge on the x = y diagonal, a degenerate
        // (collinear) one, a zero-area one, and NaN padding.
        let mut block = TriangleBlock::EMPTY;
        let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        block.set(0, &[quad[0], quad[1], quad[2]], 0);
        block.set(1, &[quad[0], quad[2], quad[3]], 1);
        block.set(2, &[Vec3::ZERO, Vec3::X, Vec3::X * 2.0], 2);
        block.set(3, &[Vec3::ONE; 3], 3);
        for i in 0..=8 {
            let p = Vec3::new(i as f32 / 8.0, i as f32 / 8.0, 0.0);
            for d in [Vec3::Z, -Vec3::Z, Vec3::new(0.0, 0.0, 1e-20)] {
                let ray = Ray::new(p - d, d);
                check(&ray, &block);
            }
        }
        // Through the shared edge's midpoint: at least one of the two hits.
        let ray = Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z);
        let s = ShearedRay::new(&ray);
        assert_ne!(intersect(&ray, &s, &block, 0b11).0, 0);
        // The lane mask is honoured and NaN lanes never hit.
        assert_eq!(intersect(&ray, &s, &block, 0b1111_0000).0, 0);
    }

    #[test]
    fn closest_breaks_ties_by_primitive_id_not_lane() {
        let tri = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let mut block = TriangleBlock::EMPTY;
        block.set(2, &tri, 9);
        block.set(5, &tri, 4);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z);
        let s = ShearedRay::new(&ray);
        let h = closest(&ray, &s, &block, 0xff).unwrap();
        assert_eq!((h.lane, h.t), (5, 1.0));
    }
}
