//! Which triangles share which edges and vertices, by exact vertex position.
//!
//! Vertices are welded by their f32 bit patterns, so two triangles share an
//! edge exactly when a watertight intersector must not let a ray through
//! between them, whatever the file's indexing. A triangle is *degenerate*
//! if its inradius (in f64) is at most a given size: a triangle of zero
//! area can never be hit, and a sliver thinner than float rounding cannot
//! be hit reliably, so neither can close a gap.

use glam::{DVec3, Vec3};
use std::collections::HashMap;

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

fn key(v: Vec3) -> [u32; 3] {
    // +0 and -0 are the same point.
    (v + Vec3::ZERO).to_array().map(f32::to_bits)
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
        // Weld positions.
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let mut points: Vec<Vec3> = Vec::new();
        let welded: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    *ids.entry(key(v)).or_insert_with(|| {
                        points.push(v);
                        points.len() as u32 - 1
                    })
                })
            })
            .collect();
        let degenerate: Vec<bool> = triangles
            .iter()
            .zip(&welded)
            .map(|(t, w)| {
                w[0] == w[1]
                    || w[1] == w[2]
                    || w[0] == w[2]
                    || normal(t) == DVec3::ZERO
                    || inradius(t) <= thin
            })
            .collect();

        // Directed edges: (from, to) → triangles using it, any area.
        let mut directed: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (i, w) in welded.iter().enumerate() {
            for k in 0..3 {
                directed
                    .entry((w[k], w[(k + 1) % 3]))
                    .or_default()
                    .push(i as u32);
            }
        }
        let good = |tris: Option<&Vec<u32>>| match tris {
            Some(t) if t.len() == 1 => !degenerate[t[0] as usize],
            _ => false,
        };
        // An undirected edge is shared if each direction is used exactly
        // once, by a non-degenerate triangle.
        let is_shared = |a: u32, b: u32| good(directed.get(&(a, b))) && good(directed.get(&(b, a)));

        let mut topology = Topology {
            closed: true,
            ..Topology::default()
        };
        let mut fans: Vec<Vec<u32>> = vec![Vec::new(); points.len()];
        let mut vertex_ok = vec![true; points.len()];
        for (i, w) in welded.iter().enumerate() {
            if degenerate[i] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                fans[a as usize].push(i as u32);
                if !is_shared(a, b) {
                    topology.closed = false;
                    vertex_ok[a as usize] = false;
                    vertex_ok[b as usize] = false;
                } else if a < b {
                    let other = directed[&(b, a)][0];
                    topology.edges.push(Shared::Edge {
                        a: points[a as usize],
                        b: points[b as usize],
                        tris: [i as u32, other],
                    });
                }
            }
        }
        // Degenerate triangles touching a vertex make its fan unreliable.
        for (i, w) in welded.iter().enumerate() {
            if degenerate[i] {
                for &v in w {
                    vertex_ok[v as usize] = false;
                }
            }
        }
        for (v, tris) in fans.into_iter().enumerate() {
            if vertex_ok[v] && tris.len() >= 3 {
                topology
                    .vertices
                    .push(Shared::Vertex { p: points[v], tris });
            }
        }
        if triangles.iter().zip(&degenerate).all(|(_, &d)| d) {
            topology.closed = false;
        }
        topology
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
    }
}
