//! What a binding returns in float64, computed on the one triangle a query
//! found (the tree's walk and its watertight test stay in float32, relative
//! to the mesh's centre): where a ray meets that triangle's plane, and the
//! point of that triangle nearest to a point, with their barycentrics.
//!
//! The walk decides which triangle (and so the tie at a shared edge); these
//! say where on it, to float64's precision, so a hit point lies on its
//! triangle's plane to about 1e-16 of the coordinates' size, wherever the
//! mesh is placed (UTM coordinates, a mesh moved by 1e6).

use glam::DVec3;

/// Where a ray (origin, direction) meets the plane of the triangle
/// `[a, b, c]`: its t along the ray, and the barycentric weights `(u, v)`
/// of `b` and `c` of the point there (`(1 − u − v)·a + u·b + v·c`).
/// Cramer's rule on `o + t·d = a + u·(b − a) + v·(c − a)`, as Möller and
/// Trumbore (1997) write it, in float64. `None` for a ray parallel to the
/// plane (or a degenerate triangle), which the walk never reports as hit.
pub fn plane_hit(
    origin: DVec3,
    direction: DVec3,
    [a, b, c]: [DVec3; 3],
) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = origin - a;
    let q = s.cross(e1);
    let u = s.dot(p) / det;
    let v = direction.dot(q) / det;
    let t = e2.dot(q) / det;
    Some((t, u, v))
}

/// The point of triangle `[a, b, c]` nearest to `p` and its barycentric
/// weights `(u, v)` of `b` and `c`: Ericson (2005), "Real-Time Collision
/// Detection" §5.1.5, by the Voronoi regions of the corners and edges, in
/// float64.
pub fn closest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> (DVec3, f64, f64) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, 0.0, 0.0);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let u = d1 / (d1 - d3);
        return (a + u * ab, u, 0.0);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let v = d2 / (d2 - d6);
        return (a + v * ac, 0.0, v);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let (u, v) = (vb * denom, vc * denom);
    if !(u.is_finite() && v.is_finite()) {
        // A degenerate triangle inside every region's test: its corner.
        return (a, 0.0, 0.0);
    }
    (a + u * ab + v * ac, u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [DVec3; 3] = [
        DVec3::new(500_123.37, 5_000_456.71, 100.0),
        DVec3::new(500_124.37, 5_000_456.71, 100.5),
        DVec3::new(500_123.37, 5_000_457.71, 100.25),
    ];

    #[test]
    fn a_plane_hit_lies_on_the_plane_far_from_the_origin() {
        let [a, b, c] = TRI;
        let n = (b - a).cross(c - a).normalize();
        let origin = a + DVec3::new(0.3, 0.2, 10.0);
        let (t, u, v) = plane_hit(origin, DVec3::new(0.01, 0.02, -1.0), TRI).unwrap();
        let on = origin + t * DVec3::new(0.01, 0.02, -1.0);
        let by_weights = (1.0 - u - v) * a + u * b + v * c;
        assert!((on - a).dot(n).abs() < 1e-9, "{}", (on - a).dot(n));
        assert!((on - by_weights).length() < 1e-9);
        assert!(plane_hit(origin, b - a, TRI).is_none());
    }

    #[test]
    fn the_closest_point_agrees_with_a_fine_search_of_the_triangle() {
        let points = [
            DVec3::new(0.3, 0.3, 1.0),
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(2.0, -0.5, 0.3),
            DVec3::new(0.7, 0.7, -0.2),
            DVec3::new(-0.5, 2.0, 0.0),
        ];
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        for p in points {
            let (q, u, v) = closest_on_triangle(p, tri);
            assert!((q - (u * tri[1] + v * tri[2])).length() < 1e-12);
            let n = 400;
            let best = (0..=n)
                .flat_map(|i| (0..=n - i).map(move |j| (i, j)))
                .map(|(i, j)| (p - DVec3::new(i as f64, j as f64, 0.0) / n as f64).length())
                .fold(f64::INFINITY, f64::min);
            let d = (p - q).length();
            assert!(
                d <= best + 1e-12 && d >= best - 2.0 / n as f64,
                "{p} {d} {best}"
            );
        }
    }
}
