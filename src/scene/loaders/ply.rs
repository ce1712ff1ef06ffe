//! Stanford PLY, ASCII and binary (either endianness), through `ply-rs-bw`.
//!
//! `vertex` elements give `x y z` (float or double); `face` elements give a
//! `vertex_indices` (or `vertex_index`) list, fan-triangulated like OBJ
//! n-gons. Other elements and properties are read and ignored.
//!
//! Before anything is allocated, every element count in the header is
//! checked against the bytes the file actually holds (an ASCII element
//! takes at least two bytes per property, a binary one the size of its
//! fixed fields), so a header claiming 1e12 vertices is an error naming the
//! file, not an allocation. An index out of range is an error naming the face.

use super::io_message;
use crate::error::{InputError, InputResult};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, Header, PropertyAccess, PropertyType, ScalarType};
use std::io::BufReader;
use std::path::Path;

#[derive(Default)]
struct Vertex([f32; 3]);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, v: f32) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(name, v)
    }
    fn set_double(&mut self, name: &str, v: f64) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(name, v as f32)
    }
}

impl Vertex {
    fn set(&mut self, name: &str, v: f32) -> ply_rs_bw::ply::PropertyAccessResult {
        match name {
            "x" => self.0[0] = v,
            "y" => self.0[1] = v,
            "z" => self.0[2] = v,
            _ => {}
        }
        ply_rs_bw::ply::PropertyAccessResult::Ignored
    }
}

/// A face's vertex indices. Triangles, the bulk of big meshes, are stored
/// inline (24 bytes a face and no allocation); longer polygons on the heap.
/// An index that is no `u32` (a negative `int`) is kept, as i64, to be
/// reported, not wrapped.
#[derive(Default)]
enum Face {
    #[default]
    Empty,
    Triangle([u32; 3]),
    Polygon(Box<[u32]>),
    Invalid(i64),
}

impl Face {
    fn set<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> ply_rs_bw::ply::PropertyAccessResult {
        if name == "vertex_indices" || name == "vertex_index" {
            let mut idx = Vec::with_capacity(v.len());
            for k in v {
                let k: i64 = k.into();
                match u32::try_from(k) {
                    Ok(k) => idx.push(k),
                    Err(_) => {
                        *self = Face::Invalid(k);
                        return ply_rs_bw::ply::PropertyAccessResult::Ignored;
                    }
                }
            }
            *self = match <[u32; 3]>::try_from(idx.as_slice()) {
                Ok(tri) => Face::Triangle(tri),
                Err(_) => Face::Polygon(idx.into_boxed_slice()),
            };
        }
        ply_rs_bw::ply::PropertyAccessResult::Ignored
    }

    /// The first index outside `0..n`, if any.
    fn bad_index(&self, n: usize) -> Option<i64> {
        match self {
            Face::Empty => None,
            Face::Triangle(idx) => idx.iter().find(|&&k| k as usize >= n).map(|&k| k.into()),
            Face::Polygon(idx) => idx.iter().find(|&&k| k as usize >= n).map(|&k| k.into()),
            Face::Invalid(k) => Some(*k),
        }
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }
    fn set_list_char(&mut self, n: &str, v: Vec<i8>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uchar(&mut self, n: &str, v: Vec<u8>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_short(&mut self, n: &str, v: Vec<i16>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_ushort(&mut self, n: &str, v: Vec<u16>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_int(&mut self, n: &str, v: Vec<i32>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uint(&mut self, n: &str, v: Vec<u32>) -> ply_rs_bw::ply::PropertyAccessResult {
        self.set(n, v)
    }
}

fn scalar_size(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// Refuse element counts the file cannot hold, before any allocation.
fn check_counts(path: &Path, header: &Header, file_len: u64) -> InputResult<()> {
    for (name, e) in &header.elements {
        let min_bytes: u64 = e
            .properties
            .values()
            .map(|p| match (&header.encoding, &p.data_type) {
                (Encoding::Ascii, _) => 2,
                (_, PropertyType::Scalar(t)) => scalar_size(t),
                (_, PropertyType::List(t, _)) => scalar_size(t),
            })
            .sum::<u64>()
            .max(1);
        if (e.count as u64).saturating_mul(min_bytes) > file_len {
            return Err(InputError::file(
                path,
                format!(
                    "the header claims {} '{name}' elements, more than the file's {file_len} bytes can hold",
                    e.count
                ),
            ));
        }
    }
    Ok(())
}

pub fn load_ply(path: &Path) -> InputResult<LoadedAsset> {
    let file = std::fs::File::open(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let file_len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut reader = Reader::new(BufReader::new(file));
    let bad = |e: &dyn std::fmt::Display| InputError::file(path, format!("invalid PLY: {e}"));
    let vparser = Parser::<Vertex>::new();
    let fparser = Parser::<Face>::new();
    let header = vparser.read_header(&mut reader).map_err(|e| bad(&e))?;
    check_counts(path, &header, file_len)?;
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for (name, def) in &header.elements {
        match name.as_str() {
            "vertex" => {
                positions = vparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?
                    .into_iter()
                    .map(|v| Vec3::from(v.0))
                    .collect();
            }
            "face" => {
                faces = fparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?;
            }
            _ => {
                vparser
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| bad(&e))?;
            }
        }
    }
    let n = positions.len();
    let mut indices = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        if let Some(bad) = f.bad_index(n) {
            return Err(InputError::file(
                path,
                format!("face {i}: vertex index {bad} is out of range (the file has {n} vertices)"),
            ));
        }
        match f {
            Face::Triangle(t) => indices.push(*t),
            Face::Polygon(p) => {
                for k in 1..p.len().saturating_sub(1) {
                    indices.push([p[0], p[k], p[k + 1]]);
                }
            }
            Face::Empty | Face::Invalid(_) => {}
        }
    }
    drop(faces);
    let name = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().to_string());
    Ok(LoadedAsset {
        meshes: vec![LoadedMesh {
            name,
            positions,
            indices,
            normals: None,
            material: None,
            uvs: None,
        }],
        ..LoadedAsset::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("strata-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

    #[test]
    fn ascii_and_binary_give_the_same_quad() {
        let ascii = format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
        let a = load_ply(&write("q.ply", ascii.as_bytes())).unwrap();
        let mut bin = HEAD.replace("ascii", "binary_little_endian").into_bytes();
        for v in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for c in v {
                bin.extend(c.to_le_bytes());
            }
        }
        bin.push(4);
        for i in [0i32, 1, 2, 3] {
            bin.extend(i.to_le_bytes());
        }
        let b = load_ply(&write("qb.ply", &bin)).unwrap();
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(a.meshes[0].indices, b.meshes[0].indices);
        assert_eq!(a.meshes[0].indices, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn huge_counts_and_bad_indices_are_errors_naming_the_file_and_face() {
        let huge = HEAD.replace("vertex 4", "vertex 1000000000000");
        let e = load_ply(&write("huge.ply", huge.as_bytes())).unwrap_err();
        assert!(
            e.to_string().contains("huge.ply") && e.to_string().contains("1000000000000"),
            "{e}"
        );
        let oob = format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 9\n");
        let e = load_ply(&write("oob.ply", oob.as_bytes())).unwrap_err();
        assert!(
            e.to_string().contains("face 0") && e.to_string().contains("oob.ply"),
            "{e}"
        );
    }
}
