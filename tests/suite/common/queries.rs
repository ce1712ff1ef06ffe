//! Brute-force answers of the mesh queries, every triangle tested, which
//! the queries through a tree and through instances are held to; the
//! nearest-point check both run; and a ray's crossing of a triangle in f64.

use super::{seeded, Draw};
use glam::{DVec3, Vec3};
use strata::geometry::nearest::closest_point_on_triangle;
use strata::geometry::Crossing;
use strata::math::Ray;
use strata::shape::triangle::{crossing, ShearedRay};

/// Every crossing by a test of every triangle, sorted as `crossings`
/// sorts (by t, then triangle); a triangle's id is its index in `tris`.
pub fn brute_crossings(tris: &[[Vec3; 3]], ray: &Ray) -> Vec<Crossing> {
    let s = ShearedRay::new(ray);
    let mut out: Vec<Crossing> = tris
        .iter()
        .enumerate()
        .filter_map(|(i, tri)| {
            crossing(ray, &s, tri).map(|t| Crossing {
                t,
                prim: i as u32,
                part: 0,
            })
        })
        .collect();
    out.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
    out
}

/// A nearest point as the checks compare it: the point, its distance and
/// its triangle's id in the numbering of the triangles brute force tests.
pub type NearestAnswer = (Vec3, f32, u64);

/// The nearest point of `tris` to `p` no farther than `max_distance`, by a
/// test of every triangle (on a tie, the lower id).
pub fn brute_nearest(tris: &[[Vec3; 3]], p: Vec3, max_distance: f32) -> Option<NearestAnswer> {
    tris.iter()
        .enumerate()
        .map(|(k, tri)| {
            let q = closest_point_on_triangle(p, tri);
            ((p - q).length_squared(), k as u64, q)
        })
        .filter(|&(d2, _, _)| d2.sqrt() <= max_distance)
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|(d2, k, q)| (q, d2.sqrt(), k))
}

/// Where [`check_nearest`] puts its points: in the box `lo..hi` grown by
/// `far` box sizes on each side for every fourth point, `near` for the
/// rest, so that most lie close to the surface and some far away.
pub struct Around {
    pub lo: Vec3,
    pub hi: Vec3,
    pub far: f32,
    pub near: f32,
}

/// The nearest-point query `got(p, limit)` at `points` random points
/// (drawn from `seed`) placed as `around` says: with no limit it is brute
/// force over `tris`; with limits around that answer's distance d (d
/// itself, which the limit holds, just under and just over d, and random
/// limits below d and below 2d) it is the reference `want(p, limit)`.
pub fn check_nearest(
    tris: &[[Vec3; 3]],
    around: &Around,
    (points, seed): (usize, u64),
    got: impl Fn(Vec3, f32) -> Option<NearestAnswer>,
    want: impl Fn(Vec3, f32) -> Option<NearestAnswer>,
) {
    let (lo, hi) = (around.lo, around.hi);
    let mut rng = seeded(seed);
    for i in 0..points {
        let grow = if i % 4 == 0 { around.far } else { around.near };
        let p = lo + (hi - lo) * Vec3::new(rng.unit(), rng.unit(), rng.unit()) * (1.0 + 2.0 * grow)
            - (hi - lo) * grow;
        let brute = brute_nearest(tris, p, f32::INFINITY);
        assert_eq!(got(p, f32::INFINITY), brute, "point {i}: {p}");
        let d = brute.unwrap().1;
        for limit in [
            d,
            d * 0.999,
            d * 1.001,
            d * rng.unit(),
            d * 2.0 * rng.unit(),
        ] {
            assert_eq!(
                got(p, limit),
                want(p, limit),
                "point {i}: {p} within {limit}"
            );
        }
    }
}

/// Where the line o + t·d crosses the triangle's plane, and the least of
/// the crossing's barycentric weights (negative: outside).
pub fn barycentric(tri: &[DVec3; 3], o: DVec3, d: DVec3) -> (f64, f64) {
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return (f64::NAN, -1.0);
    }
    let s = o - tri[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (t, u.min(v).min(1.0 - u - v))
}
