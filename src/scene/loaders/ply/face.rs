//! A PLY face's vertex indices, as both body readers hand them over, and
//! the one fan triangulation and range check they share, so that an
//! ASCII and a binary file of the same mesh give the same triangles and
//! the same error. The ASCII reader writes a triangle's indices as a row
//! of [`FaceRows`], and keeps a [`Face`] only for the faces that are not
//! one.

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
            Face::Triangle(idx) => first_outside(idx, n),
            Face::Polygon(idx) => first_outside(idx, n),
            Face::Invalid(k) => Some(*k),
        }
    }
}

/// The first of `indices` outside `0..n`, if any.
fn first_outside(indices: &[u32], n: usize) -> Option<i64> {
    indices
        .iter()
        .find(|&&k| k as usize >= n)
        .map(|&k| k.into())
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
        push_face(&mut indices, i, f, n)?;
    }
    Ok(indices)
}

/// Face `i`'s triangles appended to `indices`, its indices checked
/// against the vertex count `n`; else `i` and its bad index.
fn push_face(
    indices: &mut Vec<[u32; 3]>,
    i: usize,
    f: &Face,
    n: usize,
) -> Result<(), (usize, i64)> {
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
    Ok(())
}

/// An element's faces, one row a face as a reader writes them in
/// parallel: a triangle's indices in its row, and every other face (a
/// polygon, a face without indices or with a negative one) in `others`
/// with its index, in order, its row unread. A mesh of triangles, as
/// large scans are, is then its rows, with no second array: a [`Face`]
/// a face took 24 bytes, twice a row, and freeing those 21 MB for the
/// dragon kept the build's temporaries resident (glibc took the size as
/// its mmap threshold; docs/performance.md, "The faces that set glibc's
/// threshold").
#[derive(Default)]
pub(super) struct FaceRows {
    pub rows: Vec<[u32; 3]>,
    pub others: Vec<(usize, Face)>,
}

impl FaceRows {
    /// `more` after these faces, its indices moved past them.
    pub(super) fn append(&mut self, more: FaceRows) {
        let base = self.rows.len();
        self.rows.extend(more.rows);
        self.others
            .extend(more.others.into_iter().map(|(i, f)| (base + i, f)));
    }

    /// The faces fan-triangulated, as [`triangulate`] makes them, every
    /// index checked against the vertex count `n`; else the first bad
    /// face and its bad index. Rows alone are returned as they are.
    pub(super) fn triangulate(self, n: usize) -> Result<Vec<[u32; 3]>, (usize, i64)> {
        let bad = |t: &[u32; 3]| first_outside(t, n);
        if self.others.is_empty() {
            return match super::binary::first_where(&self.rows, |t| bad(t).is_some()) {
                Some(i) => Err((i, bad(&self.rows[i]).unwrap_or_default())),
                None => Ok(self.rows),
            };
        }
        let mut indices = Vec::with_capacity(self.rows.len());
        let mut others = self.others.iter().peekable();
        for (i, row) in self.rows.iter().enumerate() {
            match others.next_if(|(j, _)| *j == i) {
                Some((_, f)) => push_face(&mut indices, i, f, n)?,
                None => match bad(row) {
                    Some(k) => return Err((i, k)),
                    None => indices.push(*row),
                },
            }
        }
        Ok(indices)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `faces` as a reader writes them: triangles in their rows, the rest
    /// beside them, their rows holding indices no check would pass (so a
    /// row read by mistake shows).
    fn as_rows(faces: &[Face]) -> FaceRows {
        let mut rows = FaceRows::default();
        for (i, f) in faces.iter().enumerate() {
            match f {
                Face::Triangle(t) => rows.rows.push(*t),
                other => {
                    rows.rows.push([u32::MAX; 3]);
                    let copy = match other {
                        Face::Polygon(p) => Face::Polygon(p.clone()),
                        Face::Invalid(k) => Face::Invalid(*k),
                        _ => Face::Empty,
                    };
                    rows.others.push((i, copy));
                }
            }
        }
        rows
    }

    /// Rows with other faces among them, or appended in two parts, give
    /// the triangles and the first bad face that the same faces in one
    /// list give, for every vertex count from too few to enough.
    #[test]
    fn face_rows_triangulate_as_the_faces_they_hold() {
        let faces = [
            Face::Triangle([0, 1, 2]),
            Face::Polygon([0, 1, 2, 3].into()),
            Face::Empty,
            Face::Triangle([3, 4, 5]),
            Face::Polygon([5, 6, 0, 1, 2].into()),
            Face::Triangle([2, 7, 1]),
            Face::Invalid(-4),
            Face::Triangle([0, 0, 8]),
        ];
        for n in 0..=9 {
            for end in [1, 3, 6, faces.len()] {
                let faces = &faces[..end];
                let want = triangulate(faces, n);
                assert_eq!(
                    as_rows(faces).triangulate(n),
                    want,
                    "{n} vertices, {end} faces"
                );
                let mut parts = as_rows(&faces[..end / 2]);
                parts.append(as_rows(&faces[end / 2..]));
                assert_eq!(
                    parts.triangulate(n),
                    want,
                    "{n} vertices, {end} faces in two"
                );
            }
        }
        // Triangles alone come back as their rows.
        let triangles = [Face::Triangle([0, 1, 2]), Face::Triangle([2, 1, 3])];
        assert_eq!(
            as_rows(&triangles).triangulate(4),
            Ok(vec![[0, 1, 2], [2, 1, 3]])
        );
        assert_eq!(as_rows(&triangles).triangulate(3), Err((1, 3)));
    }
}
