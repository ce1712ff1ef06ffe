//! A PLY face's vertex indices, as both body readers hand them over, and
//! the one fan triangulation and range check they share, so that an
//! ASCII and a binary file of the same mesh give the same triangles and
//! the same error.

use crate::error::InputError;
use std::path::Path;

/// A face's vertex indices. Triangles, the bulk of big meshes, are stored
/// inline (24 bytes a face and no allocation); longer polygons on the heap.
/// An index that is no `u32` (a negative `int`) is kept, as i64, to be
/// reported, not wrapped.
#[derive(Default, Debug, PartialEq)]
pub(super) enum Face {
    #[default]
    Empty,
    Triangle([u32; 3]),
    Polygon(Box<[u32]>),
    Invalid(i64),
}

impl Face {
    /// The face of valid indices `idx`: inline if a triangle.
    pub(super) fn of(idx: &[u32]) -> Face {
        match <[u32; 3]>::try_from(idx) {
            Ok(tri) => Face::Triangle(tri),
            Err(_) => Face::Polygon(idx.into()),
        }
    }

    /// The first index outside `0..n`, if any.
    pub(super) fn bad_index(&self, n: usize) -> Option<i64> {
        match self {
            Face::Empty => None,
            Face::Triangle(idx) => idx.iter().find(|&&k| k as usize >= n).map(|&k| k.into()),
            Face::Polygon(idx) => idx.iter().find(|&&k| k as usize >= n).map(|&k| k.into()),
            Face::Invalid(k) => Some(*k),
        }
    }
}

/// The error of face `i`, whose index `bad` is not one of the `n` vertices.
pub(super) fn out_of_range(path: &Path, i: usize, bad: i64, n: usize) -> InputError {
    InputError::file(
        path,
        format!("face {i}: vertex index {bad} is out of range (the file has {n} vertices)"),
    )
}

/// `faces` fan-triangulated, every index checked against the vertex count
/// `n`; else the first bad face and its bad index.
pub(super) fn triangulate(faces: &[Face], n: usize) -> Result<Vec<[u32; 3]>, (usize, i64)> {
    let mut indices = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        if let Some(bad) = f.bad_index(n) {
            return Err((i, bad));
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
    Ok(indices)
}
