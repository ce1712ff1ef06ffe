//! Meshes for the Embree validation, written as OBJ files: a generated UV
//! sphere, a closed box full of degenerate triangles, and translated or
//! scaled copies of any mesh.

use glam::{DVec3, Vec3};
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::Path;
use strata::scene::loaders::load_mesh_file;

/// Vertices welded by exact position, and faces.
#[derive(Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    ids: HashMap<[u32; 3], u32>,
}

impl Mesh {
    pub fn vertex(&mut self, p: Vec3) -> u32 {
        let key = p.to_array().map(f32::to_bits);
        *self.ids.entry(key).or_insert_with(|| {
            self.positions.push(p);
            self.positions.len() as u32 - 1
        })
    }

    /// A vertex that is not welded to any other (for stray triangles).
    pub fn loose_vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        self.positions.len() as u32 - 1
    }

    /// Write as OBJ. Rust prints the shortest decimal that reads back as
    /// the same f32, so the file holds exactly these vertices.
    pub fn write_obj(&self, path: &Path, comment: &str) {
        let mut text = format!("# {comment}\n");
        for p in &self.positions {
            writeln!(text, "v {} {} {}", p.x, p.y, p.z).unwrap();
        }
        for f in &self.faces {
            writeln!(text, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1).unwrap();
        }
        std::fs::write(path, text).unwrap();
    }
}

/// A closed UV sphere: `stacks` rings of `slices` quads (two triangles
/// each; fans of thin triangles at the poles), wound outward.
pub fn uv_sphere(center: DVec3, radius: f64, stacks: u32, slices: u32) -> Mesh {
    let mut mesh = Mesh::default();
    let point = |i: u32, j: u32| -> Vec3 {
        let theta = std::f64::consts::PI * i as f64 / stacks as f64;
        let phi = 2.0 * std::f64::consts::PI * (j % slices) as f64 / slices as f64;
        let p = if i == 0 {
            DVec3::Z
        } else if i == stacks {
            -DVec3::Z
        } else {
            DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            )
        };
        (center + radius * p).as_vec3()
    };
    for i in 0..stacks {
        for j in 0..slices {
            let a = mesh.vertex(point(i, j));
            let b = mesh.vertex(point(i + 1, j));
            let c = mesh.vertex(point(i + 1, j + 1));
            let d = mesh.vertex(point(i, j + 1));
            if i != 0 {
                mesh.faces.push([a, b, d]);
            }
            if i != stacks - 1 {
                mesh.faces.push([b, c, d]);
            }
        }
    }
    mesh
}

/// A closed box of `n`×`n` quads a face, wound outward, spoilt on purpose:
///
/// * some triangles are split at a point of one edge, with a zero-area
///   "needle" triangle filling the T-junction on the other side (exact
///   midpoints: exactly collinear; other points: rounding makes slivers);
/// * triangles with repeated vertices (a segment and a point);
/// * duplicated faces, some with the winding reversed (coincident, so two
///   triangles at exactly equal t);
/// * stray zero-area triangles inside the box.
pub fn degenerate_box(n: u32) -> Mesh {
    let mut mesh = Mesh::default();
    let coord = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let place = |i: u32, j: u32| {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[(axis + 1) % 3] = coord(i);
                p[(axis + 2) % 3] = coord(j);
                Vec3::from(p)
            };
            let outward = Vec3::from({
                let mut p = [0.0; 3];
                p[axis] = sign;
                p
            });
            for i in 0..n {
                for j in 0..n {
                    let a = mesh.vertex(place(i, j));
                    let b = mesh.vertex(place(i + 1, j));
                    let c = mesh.vertex(place(i + 1, j + 1));
                    let d = mesh.vertex(place(i, j + 1));
                    for mut t in [[a, b, c], [a, c, d]] {
                        let [p, q, r] = t.map(|k| mesh.positions[k as usize]);
                        if (q - p).cross(r - p).dot(outward) < 0.0 {
                            t.swap(1, 2);
                        }
                        mesh.faces.push(t);
                    }
                }
            }
        }
    }

    // T-junctions closed by needles, on edges no other change touches.
    let mut touched: HashSet<(u32, u32)> = HashSet::new();
    let undirected = |a: u32, b: u32| (a.min(b), a.max(b));
    let original = mesh.faces.len();
    for (count, f) in (0..original).step_by(7).enumerate() {
        let k = count % 3;
        let t = mesh.faces[f];
        // Split the edge c → a, where (a, b, c) is t rotated by k.
        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        if t.iter()
            .enumerate()
            .any(|(i, &v)| touched.contains(&undirected(v, t[(i + 1) % 3])))
        {
            continue;
        }
        for i in 0..3 {
            touched.insert(undirected(t[i], t[(i + 1) % 3]));
        }
        let (pa, pc) = (mesh.positions[a as usize], mesh.positions[c as usize]);
        let s = if count % 2 == 0 { 0.5 } else { 0.3 };
        let m = mesh.vertex(pa + s * (pc - pa));
        mesh.faces[f] = [a, b, m];
        mesh.faces.push([m, b, c]);
        mesh.faces.push([c, a, m]);
    }

    // Repeated vertices: a segment and a point, on the surface.
    for f in [3usize, 40, 77] {
        let [a, b, _] = mesh.faces[f];
        mesh.faces.push([a, a, b]);
        mesh.faces.push([b, b, b]);
    }
    // Coincident duplicates, same and reversed winding.
    for f in [10usize, 55, 130, 200] {
        let [a, b, c] = mesh.faces[f];
        mesh.faces.push([a, b, c]);
        mesh.faces.push([a, c, b]);
    }
    // Stray zero-area triangles inside.
    let line = [
        Vec3::new(-0.5, -0.25, 0.0),
        Vec3::new(0.0, 0.0, 0.125),
        Vec3::new(0.5, 0.25, 0.25),
    ];
    let l = line.map(|p| mesh.loose_vertex(p));
    mesh.faces.push(l);
    let p = mesh.loose_vertex(Vec3::new(0.1, 0.2, 0.3));
    mesh.faces.push([p, p, p]);
    mesh
}

/// A copy of a mesh file with every vertex mapped by `f` (in f32), in the
/// same triangle order.
pub fn transformed_copy(source: &Path, dest: &Path, f: impl Fn(Vec3) -> Vec3, comment: &str) {
    let asset = load_mesh_file(source).unwrap_or_else(|e| panic!("{e}"));
    let mut mesh = Mesh::default();
    for m in &asset.meshes {
        let base = mesh.positions.len() as u32;
        for &p in &m.positions {
            mesh.loose_vertex(f(p));
        }
        mesh.faces
            .extend(m.indices.iter().map(|t| t.map(|i| i + base)));
    }
    mesh.write_obj(dest, comment);
}
