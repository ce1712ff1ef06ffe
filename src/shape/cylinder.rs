//! Finite cylinder with optional caps.
//!
//! ```toml
//! [[objects]]
//! cylinder = { base = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], radius = 0.5, height = 2.0, caps = true }
//! ```
//!
//! The scene compiler folds `base` and `axis` into the object transform, so
//! this file only knows the canonical cylinder: radius `r` around +z, from
//! z = 0 to z = `height`. Parts: 0 = side, 1 = bottom cap, 2 = top cap.

use crate::math::offset::gamma;
use crate::math::Ray;
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    pub radius: f32,
    pub height: f32,
    pub caps: bool,
}

pub const SIDE: u32 = 0;
pub const BOTTOM: u32 = 1;
pub const TOP: u32 = 2;

impl Cylinder {
    /// Where the line meets the infinite side x² + y² = r² (unordered), or
    /// `None` if it misses or runs parallel to the axis. Solved like the
    /// sphere, from the distance of the 2D line to the axis.
    fn side_roots(&self, ray: &Ray) -> Option<[f32; 2]> {
        let (o, d) = (ray.origin, ray.direction);
        let a = d.x * d.x + d.y * d.y;
        if a.is_nan() || a <= 0.0 {
            return None;
        }
        let b = -(o.x * d.x + o.y * d.y);
        let c = o.x * o.x + o.y * o.y - self.radius * self.radius;
        let lx = o.x + (b / a) * d.x;
        let ly = o.y + (b / a) * d.y;
        let disc = a * (self.radius * self.radius - (lx * lx + ly * ly));
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = b + b.signum() * disc.sqrt();
        Some(if q == 0.0 {
            let h = (-c / a).max(0.0).sqrt();
            [-h, h]
        } else {
            [c / q, q / a]
        })
    }

    /// Every crossing of the (infinite) line with the surface, unsorted.
    fn all_hits(&self, ray: &Ray, out: &mut [(f32, u32); 4]) -> usize {
        let mut n = 0;
        let (o, d) = (ray.origin, ray.direction);
        for t in self.side_roots(ray).into_iter().flatten() {
            let z = o.z + t * d.z;
            if (0.0..=self.height).contains(&z) {
                out[n] = (t, SIDE);
                n += 1;
            }
        }
        if self.caps && d.z != 0.0 {
            for (z, part) in [(0.0, BOTTOM), (self.height, TOP)] {
                let t = (z - o.z) / d.z;
                let x = o.x + t * d.x;
                let y = o.y + t * d.y;
                if x * x + y * y <= self.radius * self.radius {
                    out[n] = (t, part);
                    n += 1;
                }
            }
        }
        n
    }

    /// The first hit in `(tmin, tmax)`, with its part.
    pub fn intersect(&self, ray: &Ray) -> Option<(f32, u32)> {
        let mut hits = [(0.0, 0); 4];
        let n = self.all_hits(ray, &mut hits);
        hits[..n]
            .iter()
            .filter(|(t, _)| *t > ray.tmin && *t < ray.tmax)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .copied()
    }

    /// The part of the whole line inside the capped cylinder, as
    /// `((t_in, part_in), (t_out, part_out))` with `t_in < t_out`, or `None`.
    /// Computed as the overlap of the infinite cylinder's interval and the
    /// slab 0 < z < height, so a line through the rim, where side and cap
    /// meet, can neither lose nor double a crossing (CSG counts on that).
    pub fn solid_span(&self, ray: &Ray) -> Option<((f32, u32), (f32, u32))> {
        let (o, d) = (ray.origin, ray.direction);
        let (mut start, mut end) = match self.side_roots(ray) {
            Some([t0, t1]) => ((t0.min(t1), SIDE), (t0.max(t1), SIDE)),
            // Parallel to the axis: inside the side everywhere or nowhere.
            None if d.x == 0.0
                && d.y == 0.0
                && o.x * o.x + o.y * o.y < self.radius * self.radius =>
            {
                ((f32::NEG_INFINITY, SIDE), (f32::INFINITY, SIDE))
            }
            None => return None,
        };
        if d.z != 0.0 {
            let bottom = (-o.z / d.z, BOTTOM);
            let top = ((self.height - o.z) / d.z, TOP);
            let (near, far) = if bottom.0 <= top.0 {
                (bottom, top)
            } else {
                (top, bottom)
            };
            if near.0 > start.0 {
                start = near;
            }
            if far.0 < end.0 {
                end = far;
            }
        } else if !(o.z > 0.0 && o.z < self.height) {
            return None;
        }
        (start.0 < end.0).then_some((start, end))
    }

    /// Outward normal of `part` at object-space point `p`.
    pub fn normal(&self, p: Vec3, part: u32) -> Vec3 {
        match part {
            BOTTOM => -Vec3::Z,
            TOP => Vec3::Z,
            _ => {
                let n = Vec3::new(p.x, p.y, 0.0).normalize();
                if n.is_finite() {
                    n
                } else {
                    Vec3::X
                }
            }
        }
    }

    /// Re-project `p` onto `part`, returning the point, its error bound and the outward normal.
    pub fn surface_at(&self, p: Vec3, part: u32) -> (Vec3, Vec3, Vec3) {
        let n = self.normal(p, part);
        let q = match part {
            BOTTOM => Vec3::new(p.x, p.y, 0.0),
            TOP => Vec3::new(p.x, p.y, self.height),
            _ => Vec3::new(n.x * self.radius, n.y * self.radius, p.z),
        };
        (
            q,
            gamma(5) * q.abs() + gamma(3) * Vec3::splat(self.radius),
            n,
        )
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.x * p.x + p.y * p.y < self.radius * self.radius && p.z > 0.0 && p.z < self.height
    }

    pub fn bounds(&self) -> crate::math::Aabb {
        crate::math::Aabb::new(
            Vec3::new(-self.radius, -self.radius, 0.0),
            Vec3::new(self.radius, self.radius, self.height),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    const C: Cylinder = Cylinder {
        radius: 1.0,
        height: 2.0,
        caps: true,
    };

    #[test]
    fn side_caps_and_inside_rays() {
        let side = Ray::new(Vec3::new(-5.0, 0.0, 1.0), Vec3::X);
        assert_eq!(C.intersect(&side).map(|h| h.1), Some(SIDE));
        assert!((C.intersect(&side).unwrap().0 - 4.0).abs() < 1e-5);
        let top = Ray::new(Vec3::new(0.3, 0.2, 5.0), -Vec3::Z);
        let (t, part) = C.intersect(&top).unwrap();
        assert_eq!(part, TOP);
        assert!((t - 3.0).abs() < 1e-6);
        let inside = Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::Z);
        assert_eq!(C.intersect(&inside), Some((1.0, TOP)));
    }

    #[test]
    fn solid_span_matches_the_first_and_last_hit() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut rnd = || rng.random_range(-1.0f32..1.0);
        let mut spans = 0;
        for _ in 0..5000 {
            let o = Vec3::new(rnd() * 3.0, rnd() * 3.0, 1.0 + rnd() * 3.0);
            // Aim at the cylinder's box, so most rays hit.
            let d = Vec3::new(rnd() * 1.2, rnd() * 1.2, 1.0 + rnd() * 1.2) - o;
            let mut hits = [(0.0, 0); 4];
            let n = C.all_hits(&Ray::new(o, d), &mut hits);
            let hits = &mut hits[..n];
            hits.sort_by(|a, b| a.0.total_cmp(&b.0));
            match C.solid_span(&Ray::new(o, d)) {
                Some((a, b)) => {
                    spans += 1;
                    assert!((a.0 - hits[0].0).abs() < 1e-4, "{a:?} vs {hits:?}");
                    assert!((b.0 - hits[n - 1].0).abs() < 1e-4, "{b:?} vs {hits:?}");
                    assert!(C.contains(Ray::new(o, d).at(0.5 * (a.0 + b.0))));
                }
                None => assert!(n <= 1 || (hits[n - 1].0 - hits[0].0).abs() < 1e-4),
            }
        }
        assert!(spans > 1000);
        // Along the axis and across it, where one of the two constraints is unbounded.
        let along = C.solid_span(&Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z));
        assert_eq!(along, Some(((1.0, BOTTOM), (3.0, TOP))));
        let across = C.solid_span(&Ray::new(Vec3::new(-3.0, 0.0, 1.0), Vec3::X));
        assert_eq!(across, Some(((2.0, SIDE), (4.0, SIDE))));
        assert!(C
            .solid_span(&Ray::new(Vec3::new(-3.0, 0.0, 2.5), Vec3::X))
            .is_none());
    }

    #[test]
    fn uncapped_cylinder_is_open_and_misses_above() {
        let open = Cylinder { caps: false, ..C };
        let down = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        assert!(open.intersect(&down).is_none());
        let above = Ray::new(Vec3::new(-5.0, 0.0, 2.5), Vec3::X);
        assert!(open.intersect(&above).is_none());
    }
}
