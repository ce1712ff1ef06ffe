//! Which triangles share which edges and vertices, by exact vertex position.
//!
//! Vertices are welded by their f32 bit patterns, so two triangles share an
//! edge exactly when a watertight intersector must not let a ray through
//! between them, whatever the file's indexing. A triangle is *degenerate*
//! if its inradius (in f64) is at most a given size: a triangle of zero
//! area can never be hit, and a sliver thinner than float rounding cannot
//! be hit reliably, so neither can close a gap.

use crate::math::weld::{key, Welder};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// A point that two or more triangles share, with the triangles around it.
#[derive(Debug, Clone, PartialEq)]
pub enum Shared {
    /// The edge `a → b` of triangle `tris[0]`, which is `b → a` in
    /// `tris[1]`: two consistently wound, non-degenerate triangles and no
    /// others.
    Edge { a: Vec3, b: Vec3, tris: [u32; 2] },
    /// A vertex all of whose edges are [`Shared::Edge`]s, with the
    /// triangles of its fan.
    Vertex { p: Vec3, tris: Vec<u32> },
}

/// The mesh's shared edges and vertices, and whether it is closed.
#[derive(Debug, Clone, Default)]
pub struct Topology {
    pub edges: Vec<Shared>,
    pub vertices: Vec<Shared>,
    /// Every edge of every non-degenerate triangle is a shared edge: the
    /// mesh bounds a solid (it may still touch itself at vertices).
    pub closed: bool,
}

/// Twice-area normal of a triangle in f64 (exact inputs, tiny rounding).
pub fn normal(t: &[Vec3; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    (b - a).cross(c - a)
}

/// Radius of the largest circle inside the triangle (0 if degenerate).
pub fn inradius(t: &[Vec3; 3]) -> f64 {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let perimeter = (b - a).length() + (c - b).length() + (a - c).length();
    if perimeter > 0.0 {
        normal(t).length() / perimeter
    } else {
        0.0
    }
}

impl Topology {
    /// Triangles with an inradius of at most `thin` count as degenerate
    /// (exactly collinear ones always do).
    pub fn new(triangles: &[[Vec3; 3]], thin: f64) -> Self {
        let welded = Welded::new(triangles, thin);
        let across = welded.across_each();
        let mut topology = Topology {
            closed: welded.any_solid(),
            ..Topology::default()
        };
        let mut vertex_ok = vec![true; welded.points.len()];
        for (i, (w, others)) in welded.corners.iter().zip(&across).enumerate() {
            if welded.degenerate[i] {
                // Degenerate triangles touching a vertex make its fan
                // unreliable.
                for &v in w {
                    vertex_ok[v as usize] = false;
                }
                continue;
            }
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                if others[k] == NONE {
                    topology.closed = false;
                    vertex_ok[a as usize] = false;
                    vertex_ok[b as usize] = false;
                } else if a < b {
                    topology.edges.push(Shared::Edge {
                        a: welded.points[a as usize],
                        b: welded.points[b as usize],
                        tris: [i as u32, others[k]],
                    });
                }
            }
        }
        for (v, &ok) in vertex_ok.iter().enumerate() {
            // The fan: the triangles that leave the vertex, in order (a
            // vertex whose fan is reliable touches no degenerate one).
            let fan = welded.leaving.of(v as u32);
            if ok && fan.len() >= 3 {
                topology.vertices.push(Shared::Vertex {
                    p: welded.points[v],
                    tris: fan.iter().map(|&(_, t)| t).collect(),
                });
            }
        }
        topology
    }
}

/// Whether the mesh bounds a solid ([`Topology::closed`]), without listing
/// its shared edges and vertices: what `strata rays` says of a mesh.
pub fn is_closed(triangles: &[[Vec3; 3]], thin: f64) -> bool {
    let welded = Welded::new(triangles, thin);
    welded.any_solid()
        && (welded.corners.par_iter().enumerate()).all(|(i, w)| {
            welded.degenerate[i] || (0..3).all(|k| welded.across(w[k], w[(k + 1) % 3]).is_some())
        })
}

/// No triangle: an edge no other triangle shares.
const NONE: u32 = u32::MAX;

/// The triangles' corners welded (one index per position), which are
/// degenerate, and the directed edges by the vertex they leave.
///
/// Flat arrays throughout: a vertex's edges are one run of `(end,
/// triangle)` pairs, so finding an edge scans that vertex's few, and the
/// run is the vertex's fan. A map from each edge to a list of its
/// triangles (one allocation an edge) took 75 s and most of 6.7 GB on a
/// mesh of 14 million triangles, for `strata rays` to say whether it is
/// closed (docs/performance.md).
struct Welded {
    points: Vec<Vec3>,
    corners: Vec<[u32; 3]>,
    degenerate: Vec<bool>,
    leaving: Leaving,
}

impl Welded {
    fn new(triangles: &[[Vec3; 3]], thin: f64) -> Self {
        let mut welder = Welder::with_capacity(triangles.len() / 2);
        let mut points: Vec<Vec3> = Vec::with_capacity(triangles.len() / 2);
        let corners: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    let (id, new) = welder.id(key(v));
                    if new {
                        points.push(v);
                    }
                    id
                })
            })
            .collect();
        drop(welder);
        let degenerate: Vec<bool> = (triangles.par_iter().zip(&corners))
            .map(|(t, w)| {
                w[0] == w[1]
                    || w[1] == w[2]
                    || w[0] == w[2]
                    || normal(t) == DVec3::ZERO
                    || inradius(t) <= thin
            })
            .collect();
        let leaving = Leaving::new(&corners, points.len());
        Self {
            points,
            corners,
            degenerate,
            leaving,
        }
    }

    /// Whether any triangle is not degenerate: a mesh of none bounds
    /// nothing.
    fn any_solid(&self) -> bool {
        self.degenerate.iter().any(|&d| !d)
    }

    /// The one triangle that uses the directed edge a → b, if exactly one
    /// does and it is not degenerate.
    fn only(&self, a: u32, b: u32) -> Option<u32> {
        let mut users = self.leaving.of(a).iter().filter(|&&(end, _)| end == b);
        match (users.next(), users.next()) {
            (Some(&(_, t)), None) if !self.degenerate[t as usize] => Some(t),
            _ => None,
        }
    }

    /// The triangle across the edge a → b from the one triangle that uses
    /// it: the edge is shared if each direction is used exactly once, by a
    /// triangle that is not degenerate.
    fn across(&self, a: u32, b: u32) -> Option<u32> {
        self.only(a, b).and(self.only(b, a))
    }

    /// For each triangle, the triangle across each of its edges (edge k
    /// runs from corner k to the next), or [`NONE`]; all [`NONE`] for a
    /// degenerate one.
    fn across_each(&self) -> Vec<[u32; 3]> {
        (self.corners.par_iter().zip(&self.degenerate))
            .map(|(w, &degenerate)| {
                std::array::from_fn(|k| match degenerate {
                    true => NONE,
                    false => self.across(w[k], w[(k + 1) % 3]).unwrap_or(NONE),
                })
            })
            .collect()
    }
}

/// Every directed edge `a → b` of the welded triangles, listed by `a`:
/// `(b, triangle)` pairs, each vertex's in triangle order.
struct Leaving {
    /// Where each vertex's run starts in `ends`; one more at the end.
    first: Vec<usize>,
    ends: Vec<(u32, u32)>,
}

impl Leaving {
    fn new(corners: &[[u32; 3]], vertices: usize) -> Self {
        let mut first = vec![0usize; vertices + 1];
        for &v in corners.iter().flatten() {
            first[v as usize + 1] += 1;
        }
        for v in 0..vertices {
            first[v + 1] += first[v];
        }
        let mut next = first.clone();
        let mut ends = vec![(0, 0); first[vertices]];
        for (i, w) in corners.iter().enumerate() {
            for k in 0..3 {
                let slot = &mut next[w[k] as usize];
                ends[*slot] = (w[(k + 1) % 3], i as u32);
                *slot += 1;
            }
        }
        Self { first, ends }
    }

    /// The edges that leave vertex `a`.
    fn of(&self, a: u32) -> &[(u32, u32)] {
        &self.ends[self.first[a as usize]..self.first[a as usize + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rays::tests::octahedron;

    #[test]
    fn an_octahedron_is_closed_with_12_edges_and_6_vertices() {
        let t = Topology::new(&octahedron(1.0, Vec3::ZERO), 0.0);
        assert!(t.closed);
        assert_eq!(t.edges.len(), 12);
        assert_eq!(t.vertices.len(), 6);
    }

    #[test]
    fn open_and_degenerate_meshes() {
        let mut tris = octahedron(1.0, Vec3::ZERO);
        tris.pop();
        let t = Topology::new(&tris, 0.0);
        assert!(!t.closed);
        assert_eq!(
            t.edges.len(),
            9,
            "the three edges of the hole are not shared"
        );
        // A degenerate triangle on an edge makes that edge unshared.
        let mut tris = octahedron(1.0, Vec3::ZERO);
        let [a, b, _] = tris[0];
        tris.push([a, b, 0.5 * (a + b)]);
        let t = Topology::new(&tris, 0.0);
        assert_eq!(t.edges.len(), 11);
        assert!(t.vertices.len() < 6);
        // Nothing but slivers bounds nothing.
        let slivers = [[a, b, 0.5 * (a + b)], [b, a, 0.5 * (a + b)]];
        assert!(!Topology::new(&slivers, 0.0).closed);
        assert!(!is_closed(&slivers, 0.0));
        assert!(!is_closed(&[], 0.0));
    }

    /// The octahedron's faces each cut into four, `levels` times: closed,
    /// consistently wound, every vertex shared by four or six faces.
    fn subdivided(levels: u32) -> Vec<[Vec3; 3]> {
        let mut tris = octahedron(1.0, Vec3::ZERO);
        for _ in 0..levels {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        tris
    }

    /// The definition, by brute force over every triangle: what
    /// `Topology::new` finds with its arrays, on meshes with holes, a
    /// face given twice, one wound the other way and slivers.
    #[test]
    fn shared_edges_and_vertices_are_those_a_count_over_every_triangle_finds() {
        let same = |p: Vec3, q: Vec3| key(p) == key(q);
        let mut cases = vec![subdivided(2)];
        let mut holed = subdivided(2);
        holed.remove(40);
        holed.remove(7);
        cases.push(holed);
        let mut twice = subdivided(2);
        twice.push(twice[10]);
        let [a, b, c] = twice[20];
        twice[20] = [a, c, b];
        let [a, b, _] = twice[30];
        twice.push([a, b, a * 0.25 + b * 0.75]);
        cases.push(twice);
        // A face made three slivers, one along each of its edges: each
        // neighbour finds only a degenerate face across it.
        let mut slivers = subdivided(2);
        let [a, b, c] = slivers[50];
        slivers[50] = [a, b, (a + b) * 0.5];
        slivers.extend([[b, c, (b + c) * 0.5], [c, a, (c + a) * 0.5]]);
        cases.push(slivers);
        for (case, tris) in cases.iter().enumerate() {
            let thin = 1e-6;
            let degenerate = |t: &[Vec3; 3]| {
                same(t[0], t[1]) || same(t[1], t[2]) || same(t[0], t[2]) || inradius(t) <= thin
            };
            let users = |a: Vec3, b: Vec3| -> Vec<usize> {
                (0..tris.len())
                    .filter(|&i| {
                        (0..3).any(|k| same(tris[i][k], a) && same(tris[i][(k + 1) % 3], b))
                    })
                    .collect()
            };
            let only = |a: Vec3, b: Vec3| match users(a, b)[..] {
                [t] if !degenerate(&tris[t]) => Some(t as u32),
                _ => None,
            };
            let mut edges = Vec::new();
            let mut unshared: Vec<Vec3> = Vec::new();
            for (i, t) in tris.iter().enumerate().filter(|(_, t)| !degenerate(t)) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    match only(a, b).and(only(b, a)) {
                        Some(other) => edges.push((i as u32, other)),
                        None => unshared.extend([a, b]),
                    }
                }
            }
            let found = Topology::new(tris, thin);
            let mut pairs: Vec<(u32, u32)> = found
                .edges
                .iter()
                .flat_map(|e| match e {
                    Shared::Edge { tris: [i, j], .. } => [(*i, *j), (*j, *i)],
                    _ => panic!("an edge"),
                })
                .collect();
            pairs.sort();
            edges.sort();
            assert_eq!(pairs, edges, "case {case}: shared edges");
            assert_eq!(found.closed, unshared.is_empty(), "case {case}");
            assert_eq!(is_closed(tris, thin), found.closed, "case {case}");
            let mut vertices = 0;
            for t in tris.iter() {
                for &p in t {
                    let fan: Vec<u32> = (0..tris.len() as u32)
                        .filter(|&i| tris[i as usize].iter().any(|&q| same(p, q)))
                        .collect();
                    let ok = unshared.iter().all(|&q| !same(p, q))
                        && fan.iter().all(|&i| !degenerate(&tris[i as usize]))
                        && fan.len() >= 3;
                    let listed = found
                        .vertices
                        .iter()
                        .find(|v| matches!(v, Shared::Vertex { p: q, .. } if same(p, *q)));
                    match listed {
                        Some(Shared::Vertex { tris, .. }) => {
                            assert!(ok && *tris == fan, "case {case}: {p}")
                        }
                        _ => assert!(!ok, "case {case}: {p} missing"),
                    }
                    vertices += ok as usize;
                }
            }
            assert!(vertices > 0, "case {case} has shared vertices");
        }
    }
}
