//! STL (stereolithography: what CAD tools and 3D printers exchange), binary
//! or ASCII. Each triangle is stored with its own three corners and no
//! indices; corners with the same coordinates (bit for bit) are made one
//! vertex, in order of first use, so a closed part is closed for the
//! renderer too and takes a third of the memory.
//!
//! - **Binary:** an 80-byte header, a little-endian `u32` triangle count,
//!   then 50 bytes a triangle (a normal, three corners, each three `f32`,
//!   and a 2-byte attribute). A file is binary when its length is exactly
//!   `84 + 50 × count`, even if its header starts with `solid` (many
//!   exporters write that), so the count is checked against the bytes
//!   before anything is allocated.
//! - **ASCII:** `solid NAME`, then per triangle `facet normal nx ny nz`,
//!   `outer loop`, three `vertex x y z`, `endloop`, `endfacet`, and
//!   `endsolid`. A loop of more than three vertices is fan-triangulated.
//!   Each `solid` becomes one mesh, named by its name.
//!
//! Stored normals are ignored (many writers leave them zero): surfaces are
//! flat-shaded from their corners, whose order (counter-clockwise seen
//! from outside) is kept. Mistakes are errors at their line (ASCII) or
//! triangle (binary): a coordinate that is no finite number, a loop of
//! fewer than three vertices, a statement out of place, a file that ends
//! inside a solid.
//!
//! Where the load keeps a file's coordinates in float64
//! ([`Coordinates::Float64`]), an ASCII file's decimals are kept as
//! written (`LoadedMesh::exact_positions`), as trimesh reads them, and
//! corners are one vertex where their float64 values are; binary STL is
//! float32 by its format.

use super::text::decode_text;
use super::{io_message, Coordinates};
use crate::error::{InputError, InputResult};
use crate::math::weld::{self, Welder};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use glam::{DVec3, Vec3};
use std::path::Path;

/// Load a binary or ASCII STL file; see the module documentation.
pub fn load_stl(path: &Path) -> InputResult<LoadedAsset> {
    load_stl_with(path, Coordinates::Float32)
}

/// [`load_stl`], keeping an ASCII file's coordinates as `coordinates`
/// says.
pub fn load_stl_with(path: &Path, coordinates: Coordinates) -> InputResult<LoadedAsset> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let binary_len = bytes
        .get(80..84)
        .map(|c| 84 + 50 * u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])));
    let mut asset = if binary_len == Some(bytes.len() as u64) {
        LoadedAsset {
            meshes: vec![read_binary(path, &bytes)?],
            ..LoadedAsset::default()
        }
    } else if bytes.trim_ascii_start().starts_with(b"solid")
        && !bytes[..bytes.len().min(1024)].contains(&0)
    {
        // Binary headers that start with `solid` (and lie about the count)
        // hold NUL bytes soon after; ASCII never does.
        read_ascii(path, &decode_text(path, &bytes)?, coordinates)?
    } else {
        let message = match binary_len {
            Some(len) => format!(
                "neither ASCII STL (text that starts with 'solid') nor binary STL: its \
                 header counts {} triangles, which take {len} bytes, but the file has {}",
                (len - 84) / 50,
                bytes.len()
            ),
            None => format!(
                "too short for binary STL ({} bytes, fewer than its 84-byte header), and \
                 ASCII STL starts with 'solid'",
                bytes.len()
            ),
        };
        return Err(InputError::file(path, message));
    };
    super::warn_without_triangles(&mut asset, path, "no triangles");
    Ok(asset)
}

/// Corners made vertices: one per distinct position, in order of first use.
struct Vertices {
    positions: Vec<Vec3>,
    welder: Welder<[u32; 3]>,
    /// The float64 positions, where kept: then corners are told apart by
    /// them (`exact_welder`), not by their float32 rounding.
    exact: Option<Vec<DVec3>>,
    exact_welder: Welder<[u64; 3]>,
}

impl Vertices {
    /// Vertices that keep float64 positions where `coordinates` asks,
    /// with room for `n` of them.
    fn new(coordinates: Coordinates, n: usize) -> Self {
        let exact = coordinates == Coordinates::Float64;
        Self {
            positions: Vec::with_capacity(n),
            welder: Welder::with_capacity(if exact { 0 } else { n }),
            exact: exact.then(|| Vec::with_capacity(n)),
            exact_welder: Welder::with_capacity(if exact { n } else { 0 }),
        }
    }

    /// The vertex at `p`, or where these vertices keep float64 positions,
    /// at `exact` (the value `p` rounds). +0 and -0 are one place.
    fn vertex(&mut self, p: Vec3, exact: DVec3) -> u32 {
        let (id, new) = match &mut self.exact {
            None => self.welder.id(weld::key(p)),
            Some(kept) => {
                let (id, new) = self.exact_welder.id(weld::exact_key(exact));
                if new {
                    kept.push(exact);
                }
                (id, new)
            }
        };
        if new {
            self.positions.push(p);
        }
        id
    }

    /// The mesh of these vertices; they are ready for the next.
    fn take_mesh(&mut self, name: String, indices: Vec<[u32; 3]>) -> LoadedMesh {
        self.welder.clear();
        self.exact_welder.clear();
        LoadedMesh {
            name,
            positions: std::mem::take(&mut self.positions),
            exact_positions: self.exact.as_mut().map(std::mem::take),
            indices,
            ..LoadedMesh::default()
        }
    }
}

fn read_binary(path: &Path, bytes: &[u8]) -> InputResult<LoadedMesh> {
    let records = bytes[84..].chunks_exact(50);
    // A closed mesh has about half as many vertices as triangles: room
    // for them up front, not the map grown and rehashed again and again.
    let mut vertices = Vertices::new(Coordinates::Float32, records.len() / 2);
    let mut indices = Vec::with_capacity(records.len());
    for (t, record) in records.enumerate() {
        let mut corner = [0u32; 3];
        for (k, id) in corner.iter_mut().enumerate() {
            // After the 12-byte normal, three f32 a corner.
            let at = 12 + 12 * k;
            let p = Vec3::from_array(std::array::from_fn(|c| {
                let b = &record[at + 4 * c..at + 4 * c + 4];
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            }));
            if !p.is_finite() {
                return Err(InputError::file(
                    path,
                    format!("triangle {t}: corner {k} is not finite: {p}"),
                ));
            }
            *id = vertices.vertex(p, p.as_dvec3());
        }
        indices.push(corner);
    }
    let name = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    Ok(vertices.take_mesh(name, indices))
}

/// Where an ASCII file's reading is: the statement expected next.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    Solid,
    Facet,
    Loop,
    Vertex,
    EndFacet,
}

fn read_ascii(path: &Path, text: &str, coordinates: Coordinates) -> InputResult<LoadedAsset> {
    let mut asset = LoadedAsset::default();
    let mut expect = Expect::Solid;
    let mut name = String::new();
    let mut vertices = Vertices::new(coordinates, 0);
    let mut indices = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut last = 0;
    for (i, line) in text.split('\n').enumerate() {
        let n = i + 1;
        let at = |message: String| InputError::new(path, format!("line {n}"), message);
        let line = line.trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        last = n;
        let out_of_place = || {
            let wanted = match expect {
                Expect::Solid => "solid",
                Expect::Facet => "facet or endsolid",
                Expect::Loop => "outer loop",
                Expect::Vertex => "vertex or endloop",
                Expect::EndFacet => "endfacet",
            };
            at(format!("expected {wanted}, found '{keyword}'"))
        };
        expect = match (expect, keyword) {
            (Expect::Solid, "solid") => {
                name = line["solid".len()..].trim().to_string();
                Expect::Facet
            }
            (Expect::Facet, "facet") => Expect::Loop,
            (Expect::Facet, "endsolid") => {
                let mesh =
                    vertices.take_mesh(std::mem::take(&mut name), std::mem::take(&mut indices));
                asset.meshes.push(mesh);
                Expect::Solid
            }
            (Expect::Loop, "outer") if words.next() == Some("loop") => {
                corners.clear();
                Expect::Vertex
            }
            (Expect::Vertex, "vertex") => {
                let coordinates: Vec<&str> = words.collect();
                let [x, y, z] = coordinates[..] else {
                    return Err(at(format!(
                        "vertex needs three coordinates x y z, found '{}'",
                        coordinates.join(" ")
                    )));
                };
                let mut p = [0.0f32; 3];
                let mut exact = [0.0f64; 3];
                for ((c, e), token) in p.iter_mut().zip(&mut exact).zip([x, y, z]) {
                    *c = token
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| at(format!("'{token}' is not a finite number")))?;
                    if vertices.exact.is_some() {
                        // A float32 number parses as a float64 one too.
                        *e = token.parse::<f64>().unwrap_or_default();
                    }
                }
                corners.push(vertices.vertex(Vec3::from(p), DVec3::from(exact)));
                Expect::Vertex
            }
            (Expect::Vertex, "endloop") => {
                if corners.len() < 3 {
                    return Err(at(format!(
                        "a loop needs 3 vertices or more, this one has {}",
                        corners.len()
                    )));
                }
                for k in 1..corners.len() - 1 {
                    indices.push([corners[0], corners[k], corners[k + 1]]);
                }
                Expect::EndFacet
            }
            (Expect::EndFacet, "endfacet") => Expect::Facet,
            _ => return Err(out_of_place()),
        };
    }
    if expect != Expect::Solid {
        return Err(InputError::new(
            path,
            format!("line {last}"),
            "the file ends inside a solid (no endsolid)",
        ));
    }
    Ok(asset)
}

#[cfg(test)]
mod tests {
    use crate::scene::loaders::load_mesh_file;
    use crate::scene::loaders::test_files::{temp_dir, write};

    const SQUARE: &str = "solid square\n\
        facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 1 1 0\n endloop\nendfacet\n\
        facet normal 0 0 0\n outer loop\n  vertex 0 0 0\n  vertex 1 1 0\n  vertex -0 1 0\n endloop\nendfacet\n\
        endsolid square\n";

    fn binary(header: &[u8], triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut bytes = header.to_vec();
        bytes.resize(80, b' ');
        bytes.extend((triangles.len() as u32).to_le_bytes());
        for t in triangles {
            bytes.extend([0u8; 12]);
            for c in t.iter().flatten() {
                bytes.extend(c.to_le_bytes());
            }
            bytes.extend([0u8; 2]);
        }
        bytes
    }

    #[test]
    fn ascii_corners_are_welded_and_winding_kept() {
        let dir = temp_dir("stl-ascii");
        let asset = load_mesh_file(&write(&dir, "sq.stl", SQUARE.as_bytes())).unwrap();
        assert_eq!(asset.meshes.len(), 1);
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.name, "square");
        assert_eq!(mesh.positions.len(), 4, "six corners, four places");
        assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3]]);
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
        // Two solids are two meshes; a loop of four is a fan.
        let quad = "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                    vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n";
        let two = format!("{quad}{SQUARE}");
        let asset = load_mesh_file(&write(&dir, "two.stl", two.as_bytes())).unwrap();
        assert_eq!(asset.meshes.len(), 2);
        assert_eq!(asset.meshes[0].indices, [[0, 1, 2], [0, 2, 3]]);
    }

    /// Kept in float64, an ASCII file's corners are its decimals, and two
    /// that float32 would round to one place stay two vertices.
    #[test]
    fn ascii_decimals_kept_in_float64_are_welded_by_their_own_values() {
        use crate::scene::loaders::{load_mesh_file_with, Reading};
        let dir = temp_dir("stl-exact");
        let text = "solid far\nfacet normal 0 0 0\nouter loop\nvertex 5000456.71 0 0\n\
                    vertex 5000457.71 0 0\nvertex 5000456.71 1 0\nendloop\nendfacet\n\
                    facet normal 0 0 0\nouter loop\nvertex 5000456.7 0 0\nvertex 5000456.71 1 0\n\
                    vertex 5000456.71 1 1\nendloop\nendfacet\nendsolid far\n";
        let path = write(&dir, "far.stl", text.as_bytes());
        let rounded = load_mesh_file(&path).unwrap();
        let exact = load_mesh_file_with(&path, Reading::EXACT_FACES).unwrap();
        let (r, e) = (&rounded.meshes[0], &exact.meshes[0]);
        assert!(r.exact_positions.is_none());
        assert_eq!(
            r.positions.len(),
            4,
            "5000456.7 and .71 round to one float32"
        );
        assert_eq!(r.indices, [[0, 1, 2], [0, 2, 3]]);
        let kept = e.exact_positions.as_ref().unwrap();
        assert_eq!(kept[0].x, 5000456.71);
        assert_eq!(kept[3].x, 5000456.7);
        assert_eq!(e.indices, [[0, 1, 2], [3, 2, 4]]);
        assert_eq!(e.positions.len(), kept.len());
        assert_eq!(
            e.positions[3], r.positions[0],
            "each float32 position its value rounded"
        );
    }

    #[test]
    fn binary_is_told_by_its_length_even_under_a_solid_header() {
        let dir = temp_dir("stl-binary");
        let tris = [
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        ];
        let bytes = binary(b"solid exported by a CAD tool", &tris);
        let asset = load_mesh_file(&write(&dir, "part.stl", &bytes)).unwrap();
        let mesh = &asset.meshes[0];
        assert_eq!((mesh.name.as_str(), mesh.positions.len()), ("part", 4));
        assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3]]);
        // A count the bytes do not hold is refused, not allocated.
        let mut lying = bytes.clone();
        lying[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = load_mesh_file(&write(&dir, "lying.stl", &lying)).unwrap_err();
        assert!(e.to_string().contains("counts 4294967295 triangles"), "{e}");
        let mut nan = bytes;
        nan[84 + 50 + 12 + 4..84 + 50 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = load_mesh_file(&write(&dir, "nan.stl", &nan)).unwrap_err();
        assert!(
            e.to_string().contains("triangle 1: corner 0 is not finite"),
            "{e}"
        );
    }

    #[test]
    fn ascii_mistakes_are_errors_at_their_lines() {
        let dir = temp_dir("stl-errors");
        let cases = [
            (
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
                "line 4: vertex needs three coordinates x y z, found '0 0'",
            ),
            (
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\n",
                "line 4: 'nan' is not a finite number",
            ),
            (
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n",
                "line 5: a loop needs 3 vertices or more, this one has 1",
            ),
            (
                "solid x\nvertex 0 0 0\n",
                "line 2: expected facet or endsolid, found 'vertex'",
            ),
            (
                "solid x\nfacet normal 0 0 1\n",
                "line 2: the file ends inside a solid",
            ),
            ("hello", "too short for binary STL"),
        ];
        for (text, needle) in cases {
            let e = load_mesh_file(&write(&dir, "bad.stl", text.as_bytes())).unwrap_err();
            assert!(
                e.to_string().contains(needle),
                "{e}\nshould contain: {needle}"
            );
        }
        let empty = load_mesh_file(&write(&dir, "empty.stl", b"solid\nendsolid\n")).unwrap();
        assert_eq!(empty.warnings.len(), 1, "no triangles: a warning");
    }
}
