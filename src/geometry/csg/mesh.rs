//! Closed triangle meshes as CSG operands: inside and outside from the
//! parity of crossings along the line.
//!
//! Parity is only as good as the crossing count, so a ray through an edge
//! or a vertex must count each sheet of surface exactly once. The watertight
//! test of Woop, Benthin and Wald (2013) promises *at least* one hit there;
//! a ray through a cube face's diagonal hits both of its triangles, which
//! would turn the rest of the line inside out. [`crossing`] therefore breaks
//! ties with a consistent rule: an edge function that is exactly zero counts
//! as inside only if the edge, oriented with the triangle's interior on its
//! left, points up in the sheared 2D frame (or right, if horizontal). That
//! is the same as nudging the ray by an infinitesimal (−ε, ε²) in that frame
//! (a symbolic perturbation), so of two triangles on opposite sides of a
//! shared edge exactly one owns it, and fans around a vertex own it once.
//! Where the surface folds back (a silhouette edge), both or neither own
//! it, which leaves the parity unchanged, as it should.

use crate::accel::Bvh8;
use crate::math::weld::{self, Welder};
use crate::math::Ray;
use crate::shape::triangle::ShearedRay;
use glam::Vec3;
use std::collections::HashMap;

/// Where a line crosses one triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriCrossing {
    pub t: f32,
    /// Barycentric weights of v1 and v2.
    pub u: f32,
    pub v: f32,
    /// The winding normal `(v1 − v0) × (v2 − v0)` faces the ray (points
    /// against its direction).
    pub toward: bool,
}

/// Where the whole line through `ray` crosses triangle `v` (any t, ignoring
/// `tmin` and `tmax`), with ties on edges and vertices broken consistently
/// (see the module docs). The shear is that of [`crate::shape::triangle`].
#[inline]
pub fn crossing(ray: &Ray, s: &ShearedRay, v: &[Vec3; 3]) -> Option<TriCrossing> {
    // Vertices relative to the ray origin, sheared into ray space.
    let a = v[0] - ray.origin;
    let b = v[1] - ray.origin;
    let c = v[2] - ray.origin;
    let p = [
        (a[s.kx] - s.sx * a[s.kz], a[s.ky] - s.sy * a[s.kz]),
        (b[s.kx] - s.sx * b[s.kz], b[s.ky] - s.sy * b[s.kz]),
        (c[s.kx] - s.sx * c[s.kz], c[s.ky] - s.sy * c[s.kz]),
    ];
    let [(ax, ay), (bx, by), (cx, cy)] = p;
    // Edge functions of the edges b→c, c→a and a→b.
    let mut e = [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax];
    if e.contains(&0.0) {
        let [ax, ay, bx, by, cx, cy] = [ax, ay, bx, by, cx, cy].map(f64::from);
        e = [
            (cx * by - cy * bx) as f32,
            (ax * cy - ay * cx) as f32,
            (bx * ay - by * ax) as f32,
        ];
    }
    let negative = e.iter().any(|&x| x < 0.0);
    let positive = e.iter().any(|&x| x > 0.0);
    if negative == positive {
        // Outside (mixed signs), or degenerate (all zero).
        return None;
    }
    // On an edge line: own it only if the edge, turned so that the
    // interior lies on its left, points up (or right).
    for (i, &ei) in e.iter().enumerate() {
        if ei == 0.0 {
            let (from, to) = (p[(i + 1) % 3], p[(i + 2) % 3]);
            let (mut dx, mut dy) = (to.0 - from.0, to.1 - from.1);
            if positive {
                (dx, dy) = (-dx, -dy);
            }
            if !(dy > 0.0 || (dy == 0.0 && dx > 0.0)) {
                return None;
            }
        }
    }
    let det = e[0] + e[1] + e[2];
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t_scaled = e[0] * (s.sz * a[s.kz]) + e[1] * (s.sz * b[s.kz]) + e[2] * (s.sz * c[s.kz]);
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !t.is_finite() {
        return None;
    }
    Some(TriCrossing {
        t,
        u: e[1] * inv_det,
        v: e[2] * inv_det,
        toward: det > 0.0,
    })
}

/// Every crossing of the whole line through `ray` with `tris`, unsorted,
/// as `(index in tris, crossing)`. With a BVH over `tris` only the
/// triangles whose boxes the line may meet are tested.
pub fn crossings(
    tris: &[[Vec3; 3]],
    bvh: Option<&Bvh8>,
    ray: &Ray,
    out: &mut Vec<(u32, TriCrossing)>,
) {
    let line = Ray {
        tmin: f32::NEG_INFINITY,
        tmax: f32::INFINITY,
        ..*ray
    };
    let sheared = ShearedRay::new(&line);
    let mut test = |i: u32| {
        if let Some(c) = crossing(&line, &sheared, &tris[i as usize]) {
            out.push((i, c));
        }
    };
    match bvh {
        Some(bvh) => bvh.visit_line(&line, test),
        None => (0..tris.len() as u32).for_each(&mut test),
    }
}

/// Why a set of triangles does not bound a solid: an edge not shared by
/// exactly two of them.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenEdge {
    pub from: Vec3,
    pub to: Vec3,
    /// How many triangles use the edge (1 for a hole, 3 or more where
    /// sheets meet).
    pub uses: u32,
}

/// Check that `tris` is closed: with vertices of equal position welded,
/// every edge is shared by exactly two triangles. Triangles with a repeated
/// vertex are ignored (they never produce a crossing). Reports the first
/// offending edge in triangle order, so the message is reproducible.
pub fn check_closed(tris: &[[Vec3; 3]]) -> Result<(), OpenEdge> {
    // Weld by exact position (+0.0 makes −0.0 and 0.0 one vertex).
    let mut welder = Welder::with_capacity(tris.len() / 2);
    let mut id = |p: Vec3| welder.id(weld::key(p)).0;
    let welded: Vec<[u32; 3]> = tris.iter().map(|t| t.map(&mut id)).collect();
    let edges = |w: &[u32; 3]| {
        let degenerate = w[0] == w[1] || w[1] == w[2] || w[0] == w[2];
        let e = [(0, 1), (1, 2), (2, 0)].map(|(i, j)| (w[i].min(w[j]), w[i].max(w[j]), i, j));
        (!degenerate).then_some(e)
    };
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for w in &welded {
        for (lo, hi, _, _) in edges(w).into_iter().flatten() {
            *uses.entry((lo, hi)).or_default() += 1;
        }
    }
    for (w, tri) in welded.iter().zip(tris) {
        for (lo, hi, i, j) in edges(w).into_iter().flatten() {
            let n = uses[&(lo, hi)];
            if n != 2 {
                return Err(OpenEdge {
                    from: tri[i],
                    to: tri[j],
                    uses: n,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// The cube [-1, 1]³ as 12 outward-wound triangles, each face split
    /// along a diagonal.
    pub fn cube() -> Vec<[Vec3; 3]> {
        let v = |i: usize| {
            Vec3::new(
                if i & 1 != 0 { 1.0 } else { -1.0 },
                if i & 2 != 0 { 1.0 } else { -1.0 },
                if i & 4 != 0 { 1.0 } else { -1.0 },
            )
        };
        // Faces as quads, counter-clockwise seen from outside.
        let quads = [
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
        ];
        quads
            .iter()
            .flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]])
            .collect()
    }

    fn count(tris: &[[Vec3; 3]], ray: &Ray) -> usize {
        let mut out = Vec::new();
        crossings(tris, None, ray, &mut out);
        out.len()
    }

    #[test]
    fn the_cube_is_outward_wound_and_closed() {
        let tris = cube();
        for t in &tris {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let centre = (t[0] + t[1] + t[2]) / 3.0;
            assert!(n.dot(centre) > 0.0);
        }
        assert_eq!(check_closed(&tris), Ok(()));
    }

    #[test]
    fn a_missing_triangle_or_a_doubled_sheet_is_open() {
        let mut tris = cube();
        tris.pop();
        assert_eq!(check_closed(&tris).unwrap_err().uses, 1);
        let mut tris = cube();
        let extra = tris[0];
        tris.push([extra[0], extra[2], extra[1]]);
        assert_eq!(check_closed(&tris).unwrap_err().uses, 3);
    }

    #[test]
    fn toward_means_the_winding_normal_faces_the_ray() {
        let tris = cube();
        let mut rng = seeded(5);
        let mut rnd = || rng.range(-1.0, 1.0);
        let mut seen = 0;
        for _ in 0..2000 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 4.0;
            let d = Vec3::new(rnd(), rnd(), rnd()) * 1.2 - o;
            let ray = Ray::new(o, d);
            let mut out = Vec::new();
            crossings(&tris, None, &ray, &mut out);
            for (i, c) in out {
                let t = &tris[i as usize];
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                assert_eq!(c.toward, n.dot(d) < 0.0);
                let p = ray.at(c.t);
                let q = t[0] + c.u * (t[1] - t[0]) + c.v * (t[2] - t[0]);
                assert!((p - q).length() < 1e-5, "{p} vs {q}");
                seen += 1;
            }
        }
        assert!(seen > 1000);
    }

    #[test]
    fn rays_through_diagonals_edges_and_vertices_count_each_face_once() {
        let tris = cube();
        // Through face centres: exactly on the diagonals.
        for d in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert_eq!(count(&tris, &Ray::new(-3.0 * d, d)), 2, "{d}");
        }
        // Along the space diagonal, through two corners shared by six triangles.
        let d = Vec3::ONE;
        assert_eq!(count(&tris, &Ray::new(-2.0 * d, d)), 2);
        // Through the middle of an edge between two faces.
        let ray = Ray::new(Vec3::new(-3.0, 1.0, 0.3), Vec3::new(3.0, -1.0, 0.0));
        assert_eq!(count(&tris, &ray), 2);
        // Through points on diagonals and edges at many slopes.
        for i in 0..200 {
            let s = i as f32 / 200.0 * 2.0 - 1.0;
            let target = Vec3::new(s, s, 1.0);
            let d = Vec3::new(0.1 * s, -0.2, -1.0);
            assert_eq!(count(&tris, &Ray::new(target - 4.0 * d, d)) % 2, 0);
        }
    }

    #[test]
    fn grazing_a_face_in_its_plane_keeps_the_parity_even() {
        let tris = cube();
        for ray in [
            Ray::new(Vec3::new(-3.0, 1.0, 0.0), Vec3::X),
            Ray::new(Vec3::new(-3.0, 1.0, 1.0), Vec3::X),
            Ray::new(Vec3::new(-3.0, 1.0, 0.25), Vec3::new(1.0, 0.0, 0.1)),
        ] {
            assert_eq!(count(&tris, &ray) % 2, 0, "{ray:?}");
        }
    }
}
