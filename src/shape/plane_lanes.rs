//! A scene's infinite planes tested eight at a time, one per SIMD lane:
//! every ray is tested against every plane (they are outside the BVH),
//! and a room of six walls cost a path-traced Cornell box 7% of its
//! instructions tested one by one (docs/mitsuba.md, "Path-traced scenes").
//! Each lane computes [`Plane::intersect`]'s expression in its order, with
//! IEEE operations and no fused multiply-add, so its `t` is bit for bit
//! the scalar one, and the closest plane is the one the scalar loop picks
//! (the nearest; of equal ones, the first).

use super::plane::Plane;
use crate::math::lanes::LANES;
use crate::math::Ray;
use wide::f32x8;

/// Scenes with fewer planes than this test them one by one (the
/// geometry's queries ask): eight lanes for one plane cost more than its
/// scalar test (dragon-gold's floor: 1.5% more instructions in its
/// render), six walls far less (a Cornell box's: 5% fewer); between
/// them not measured.
pub const LANES_FROM: usize = 4;

/// The planes of a scene in chunks of [`LANES`] (structure of arrays).
#[derive(Debug, Clone, Default)]
pub struct PlaneLanes {
    chunks: Vec<Chunk>,
}

#[derive(Debug, Clone, Copy)]
struct Chunk {
    point: [f32x8; 3],
    normal: [f32x8; 3],
    /// The lanes that hold a plane (the last chunk's others are zero).
    live: u32,
}

impl PlaneLanes {
    pub fn new(planes: &[Plane]) -> Self {
        let chunks = planes
            .chunks(LANES)
            .map(|part| {
                let axis = |f: fn(&Plane) -> [f32; 3], k: usize| {
                    f32x8::new(std::array::from_fn(|i| {
                        part.get(i).map_or(0.0, |p| f(p)[k])
                    }))
                };
                let point: fn(&Plane) -> [f32; 3] = |p| p.point.to_array();
                let normal: fn(&Plane) -> [f32; 3] = |p| p.normal.to_array();
                Chunk {
                    point: [0, 1, 2].map(|k| axis(point, k)),
                    normal: [0, 1, 2].map(|k| axis(normal, k)),
                    live: u32::MAX >> (32 - part.len()),
                }
            })
            .collect();
        Self { chunks }
    }

    /// Each lane's `t` and the mask of lanes whose plane `ray` hits in
    /// `(tmin, tmax)`: exactly [`Plane::intersect`] lane by lane.
    #[inline(always)]
    fn hits(chunk: &Chunk, ray: &Ray) -> (f32x8, u32) {
        let [nx, ny, nz] = chunk.normal;
        let [px, py, pz] = chunk.point;
        let (o, d) = (ray.origin, ray.direction);
        let s = f32x8::splat;
        let denom = s(d.x) * nx + s(d.y) * ny + s(d.z) * nz;
        let t = ((px - s(o.x)) * nx + (py - s(o.y)) * ny + (pz - s(o.z)) * nz) / denom;
        let hit = !denom.simd_eq(f32x8::ZERO) & t.simd_gt(s(ray.tmin)) & t.simd_lt(s(ray.tmax));
        (t, hit.to_bitmask() & chunk.live)
    }

    /// Whether any plane is hit in `(ray.tmin, ray.tmax)`.
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.chunks.iter().any(|c| Self::hits(c, ray).1 != 0)
    }

    /// The nearest plane hit in `(ray.tmin, ray.tmax)`, its `t` and index
    /// (of equally near ones, the first): what testing the planes in
    /// order, each against the nearest hit so far, finds.
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(f32, usize)> {
        let mut best: Option<(f32, usize)> = None;
        for (k, chunk) in self.chunks.iter().enumerate() {
            let (t, mut hit) = Self::hits(chunk, ray);
            let t = t.to_array();
            while hit != 0 {
                let i = hit.trailing_zeros() as usize;
                hit &= hit - 1;
                if best.is_none_or(|(b, _)| t[i] < b) {
                    best = Some((t[i], k * LANES + i));
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Random planes (some repeated, so that two are equally near) and
    /// rays (some parallel to a plane, some with a finite end): every
    /// answer is the scalar loop's, bit for bit.
    #[test]
    fn lanes_answer_what_the_planes_answer_one_by_one() {
        // A small LCG: shapes know only the math layer, tests included.
        let mut state = 61u32;
        let mut unit = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut v = |s: f32| Vec3::new(unit(), unit(), unit()) * s - s / 2.0;
        for count in [1usize, 2, 3, 4, 6, 8, 9, 17] {
            let mut planes: Vec<Plane> = (0..count)
                .map(|_| Plane {
                    point: v(8.0),
                    normal: v(2.0).normalize(),
                    material: 0,
                })
                .collect();
            if count > 2 {
                planes[count - 1] = planes[1];
            }
            let lanes = PlaneLanes::new(&planes);
            let mut found = 0;
            for k in 0..2000 {
                let mut ray = Ray::new(v(6.0), v(2.0));
                if k % 7 == 0 {
                    // Parallel to the first plane: its denominator is 0.
                    let n = planes[0].normal;
                    ray.direction -= ray.direction.dot(n) * n;
                    ray.direction -= ray.direction.dot(n) * n;
                }
                if k % 3 == 0 {
                    ray.tmax = 1.0 + v(4.0).x.abs();
                }
                let mut tmax = ray.tmax;
                let mut want = None;
                for (i, p) in planes.iter().enumerate() {
                    if let Some(t) = p.intersect(&Ray { tmax, ..ray }) {
                        tmax = t;
                        want = Some((t.to_bits(), i));
                    }
                }
                found += usize::from(want.is_some());
                let got = lanes.closest(&ray).map(|(t, i)| (t.to_bits(), i));
                assert_eq!(got, want, "{count} planes, ray {k}");
                let any = planes.iter().any(|p| p.intersect(&ray).is_some());
                assert_eq!(lanes.any_hit(&ray), any, "{count} planes, ray {k}");
            }
            assert!(found > 400, "{count} planes: {found} rays hit one");
        }
    }
}
