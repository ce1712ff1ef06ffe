//! Object File Format (`.off`, from Geomview; the Princeton Shape
//! Benchmark and many mesh-processing tools write it): four parts of text.
//!
//! ```text
//! OFF                 # the header keyword (COFF, NOFF, STOFF, ... too)
//! 4 1 0               # vertex, face and edge counts (edges unused)
//! 0 0 0               # one vertex a line: x y z
//! 1 0 0
//! 1 1 0
//! 0 1 0
//! 4  0 1 2 3          # one face a line: n, then n vertex indices from 0
//! ```
//!
//! A face of n vertices is fan-triangulated like OBJ n-gons (`0 1 2 3` →
//! `0 1 2`, `0 2 3`), faces and triangles in file order. `#` starts a
//! comment anywhere on a line; blank lines are skipped; the counts may
//! follow the keyword on its own line (`OFF 4 1 0`). The extra columns of
//! the keyword's prefixes (`ST` texture coordinates, `C` colours, `N`
//! normals, after a vertex's x y z) and a face's colour after its
//! indices are read past and ignored. 4-dimensional (`4OFF`, `nOFF`) and
//! binary (`OFF BINARY`) files are refused by name.
//!
//! Every mistake is an error at its line: a count or coordinate that is no
//! number, a face with fewer than three vertices or fewer indices than it
//! says, an index out of range, a file that ends before its counts are
//! read. Counts that the file's bytes cannot hold are refused before
//! anything is allocated for them. Text after the last face is ignored
//! with a warning, and a file without faces loads with one.

use super::sniff::is_off_keyword;
use super::text::decode_text;
use super::{io_message, Coordinates};
use crate::error::{InputError, InputResult};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use glam::{DVec3, Vec3};
use std::path::Path;

/// Load an OFF file into one mesh; see the module documentation.
pub fn load_off(path: &Path) -> InputResult<LoadedAsset> {
    load_off_with(path, Coordinates::Float32)
}

/// [`load_off`], keeping the file's coordinates as `coordinates` says.
pub fn load_off_with(path: &Path, coordinates: Coordinates) -> InputResult<LoadedAsset> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    // A binary OFF file's header is text, its body not: say so before the
    // text decoder finds its NUL bytes.
    let first_line = bytes.split(|&b| b == b'\n').next().unwrap_or(&[]);
    if String::from_utf8_lossy(first_line)
        .split_whitespace()
        .any(|w| w == "BINARY")
    {
        return Err(at(
            path,
            1,
            "binary OFF files are not supported; write it as text",
        ));
    }
    let text = decode_text(path, &bytes)?;
    parse_off(path, &text, coordinates)
}

fn at(path: &Path, line: usize, message: impl Into<String>) -> InputError {
    InputError::new(path, format!("line {line}"), message)
}

/// The lines of `text` that hold something, numbered from 1, comments cut.
fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n').enumerate().filter_map(|(i, line)| {
        let line = line.split('#').next().unwrap_or("").trim();
        (!line.is_empty()).then_some((i + 1, line))
    })
}

/// A whole number of an OFF count or index, or a message naming `what`.
fn whole(token: &str, what: &str) -> Result<u64, String> {
    token
        .parse::<u64>()
        .map_err(|_| format!("{what} must be a whole number of 0 or more, found '{token}'"))
}

/// Read OFF text; `path` names the file in errors.
pub(crate) fn parse_off(
    path: &Path,
    text: &str,
    coordinates: Coordinates,
) -> InputResult<LoadedAsset> {
    let mut lines = content_lines(text);
    let Some((header_line, header)) = lines.next() else {
        return Err(InputError::file(
            path,
            "the file is empty; an OFF file starts with the line OFF",
        ));
    };
    let mut words = header.split_whitespace();
    let keyword = words.next().unwrap_or("");
    if !is_off_keyword(keyword) {
        return Err(at(
            path,
            header_line,
            format!("an OFF file starts with OFF (or COFF, NOFF, STOFF, ...), found '{keyword}'"),
        ));
    }
    if keyword.contains(['4', 'n']) {
        return Err(at(
            path,
            header_line,
            format!("{keyword}: OFF files of other than three dimensions are not supported"),
        ));
    }
    // The counts follow the keyword on its line, or on the next.
    let on_header: Vec<&str> = words.collect();
    let (counts_line, counts) = if on_header.is_empty() {
        match lines.next() {
            Some((n, line)) => (n, line.split_whitespace().collect()),
            None => {
                return Err(at(
                    path,
                    header_line,
                    "the file ends before the counts line (vertices faces edges)",
                ))
            }
        }
    } else {
        (header_line, on_header)
    };
    let count = |i: usize, what: &str| -> InputResult<u64> {
        let token = counts.get(i).ok_or_else(|| {
            at(
                path,
                counts_line,
                format!(
                    "the counts line needs the vertex and face counts (then edges), found '{}'",
                    counts.join(" ")
                ),
            )
        })?;
        whole(token, what).map_err(|m| at(path, counts_line, m))
    };
    let (n_vertices, n_faces) = (count(0, "the vertex count")?, count(1, "the face count")?);
    // A vertex takes at least "0 0 0\n", a face "3 0 1 2\n": refuse counts
    // the file cannot hold before allocating for them.
    let least = n_vertices
        .saturating_mul(6)
        .saturating_add(n_faces.saturating_mul(8));
    if least > text.len() as u64 + 1 {
        return Err(at(
            path,
            counts_line,
            format!(
                "the counts claim {n_vertices} vertices and {n_faces} faces, more than the \
                 file's {} bytes can hold",
                text.len()
            ),
        ));
    }
    let ends = |read: u64, of: u64, what: &str| {
        InputError::file(
            path,
            format!(
                "the file ends after {read} of the {of} {what} that the counts on line \
                 {counts_line} announce"
            ),
        )
    };

    let mut positions = Vec::with_capacity(n_vertices as usize);
    let mut exact_positions =
        (coordinates == Coordinates::Float64).then(|| Vec::with_capacity(n_vertices as usize));
    // The vertices that are not finite, with their lines.
    let mut not_finite = Vec::new();
    for k in 0..n_vertices {
        let (n, line) = lines
            .next()
            .ok_or_else(|| ends(k, n_vertices, "vertices"))?;
        let tokens: Vec<&str> = line.split_whitespace().take(3).collect();
        let [x, y, z] = tokens[..] else {
            return Err(at(
                path,
                n,
                format!("vertex {k} needs three coordinates x y z, found '{line}'"),
            ));
        };
        let mut p = [0.0f32; 3];
        for (c, token) in p.iter_mut().zip([x, y, z]) {
            *c = match token.parse::<f32>() {
                // NaN or infinite: checked once the faces are known (a
                // vertex no face uses may be NaN), so its line is kept.
                Ok(v) => {
                    if !v.is_finite() && not_finite.last() != Some(&(k, n)) {
                        not_finite.push((k, n));
                    }
                    v
                }
                Err(_) => {
                    return Err(at(
                        path,
                        n,
                        format!("vertex {k}: '{token}' is not a number"),
                    ))
                }
            };
        }
        positions.push(Vec3::from(p));
        if let Some(exact) = &mut exact_positions {
            // Each token read as float32 above is a number.
            let [x, y, z] = [x, y, z].map(|t| t.parse::<f64>().unwrap_or(f64::NAN));
            exact.push(DVec3::new(x, y, z));
        }
    }

    let mut indices = Vec::with_capacity(n_faces as usize);
    let mut face = Vec::new();
    for f in 0..n_faces {
        let (n, line) = lines.next().ok_or_else(|| ends(f, n_faces, "faces"))?;
        let mut tokens = line.split_whitespace();
        let size = whole(
            tokens.next().unwrap_or(""),
            &format!("face {f}'s vertex count"),
        )
        .map_err(|m| at(path, n, m))?;
        if size < 3 {
            return Err(at(
                path,
                n,
                format!("face {f} has {size} vertices; a face needs 3 or more"),
            ));
        }
        face.clear();
        // `take` bounds the work by the line, not by the count it claims.
        for token in tokens.by_ref().take(size as usize) {
            let index =
                whole(token, &format!("face {f}'s vertex index")).map_err(|m| at(path, n, m))?;
            if index >= n_vertices {
                return Err(at(
                    path,
                    n,
                    format!(
                        "face {f}: vertex index {index} is out of range (the file has \
                         {n_vertices} vertices, numbered from 0)"
                    ),
                ));
            }
            face.push(index as u32);
        }
        if (face.len() as u64) < size {
            return Err(at(
                path,
                n,
                format!(
                    "face {f} says {size} vertices but lists {} indices",
                    face.len()
                ),
            ));
        }
        // What follows the indices is the face's colour: ignored.
        for k in 1..face.len() - 1 {
            indices.push([face[0], face[k], face[k + 1]]);
        }
    }

    if let Err((vertex, message)) = super::settle_unused_vertices(&mut positions, &indices) {
        let line = not_finite
            .iter()
            .find(|&&(k, _)| k as usize == vertex)
            .map_or(0, |&(_, n)| n);
        return Err(at(path, line, message));
    }

    let mut warnings = Vec::new();
    if let Some((n, _)) = lines.next() {
        warnings.push(at(
            path,
            n,
            format!(
                "text after the {n_faces} faces that the counts on line {counts_line} \
                 announce is ignored"
            ),
        ));
    }
    let name = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let mut asset = LoadedAsset {
        meshes: vec![LoadedMesh {
            name,
            positions,
            exact_positions,
            indices,
            ..LoadedMesh::default()
        }],
        warnings,
        ..LoadedAsset::default()
    };
    super::warn_without_triangles(&mut asset, path, "no faces");
    Ok(asset)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loaders::load_mesh_file;
    use crate::scene::loaders::test_files::{temp_dir, write};

    fn parse(text: &str) -> InputResult<LoadedAsset> {
        parse_off(Path::new("m.off"), text, Coordinates::Float32)
    }

    fn error(text: &str) -> String {
        match parse(text) {
            Ok(_) => panic!("read:\n{text}"),
            Err(e) => e.to_string(),
        }
    }

    /// A vertex no face uses may be NaN or infinite (a scanner's
    /// organised mesh): it loads, standing in for a vertex a face uses.
    #[test]
    fn vertices_no_face_uses_may_be_nan() {
        let a = parse("OFF\n5 1 0\nnan nan nan\n0 0 0\n1 0 0\n0 1 0\n-inf 0 0\n3 1 2 3\n").unwrap();
        let m = &a.meshes[0];
        assert_eq!(m.indices, vec![[1, 2, 3]]);
        assert!(m
            .positions
            .iter()
            .all(|p| p.is_finite() && p.max_element() <= 1.0));
    }

    #[test]
    fn ngons_become_fans_in_file_order() {
        let asset = parse(
            "OFF\n# a square and a triangle\n\n5 2 0\n\
             0 0 0\n1 0 0\n1 1 0\n0 1 0  # corner\n2 2 2\n\
             4  0 1 2 3\n3 1 4 2\n",
        )
        .unwrap();
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.name, "m");
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(mesh.positions[3], Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    }

    #[test]
    fn extra_columns_and_counts_on_the_header_line_are_read_past() {
        // COFF: a colour after each vertex; a colour after the face too.
        let coff = parse("COFF 3 1 3\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 0.5 0.5 0.5\n").unwrap();
        assert_eq!(coff.meshes[0].indices, [[0, 1, 2]]);
        // NOFF: a normal after each vertex; no edge count.
        let noff = parse("NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 2 1 0\n").unwrap();
        assert_eq!(noff.meshes[0].indices, [[2, 1, 0]]);
        assert_eq!(noff.meshes[0].normals, None);
    }

    #[test]
    fn mistakes_are_errors_at_their_lines() {
        let square = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
        let cases = [
            ("", "m.off: the file is empty"),
            ("# nothing\nPLY\n", "m.off: line 2: an OFF file starts with OFF"),
            ("4OFF\n", "m.off: line 1: 4OFF: OFF files of other than three dimensions"),
            ("OFF\n", "m.off: line 1: the file ends before the counts line"),
            ("OFF\nfour 1 0\n", "m.off: line 2: the vertex count must be a whole number of 0 or more, found 'four'"),
            ("OFF\n4\n", "m.off: line 2: the counts line needs the vertex and face counts"),
            ("OFF\n-1 0 0\n", "line 2: the vertex count must be a whole number"),
            ("OFF\n1000000000 1 0\n0 0 0\n", "m.off: line 2: the counts claim 1000000000 vertices and 1 faces, more than the file's"),
            ("OFF\n3 0 0\n0 0 0\n1 0\n0 1 0\n", "m.off: line 4: vertex 1 needs three coordinates x y z, found '1 0'"),
            ("OFF\n3 0 0\n0 0 0\n1 0 x\n0 1 0\n", "line 4: vertex 1: 'x' is not a number"),
            ("OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n", "line 4: vertex 1 is not finite: [1, 0, inf] (a face uses it)"),
            ("OFF\n3 0 0\n0 0 0\n1 0 0\n", "m.off: the file ends after 2 of the 3 vertices that the counts on line 2 announce"),
        ];
        for (text, needle) in cases {
            let e = error(text);
            assert!(e.contains(needle), "{e}\nshould contain: {needle}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        let faces = [
            ("2 0 1\n", "line 7: face 0 has 2 vertices; a face needs 3 or more"),
            ("4 0 1 2\n", "line 7: face 0 says 4 vertices but lists 3 indices"),
            ("3 0 1 4\n", "line 7: face 0: vertex index 4 is out of range (the file has 4 vertices, numbered from 0)"),
            ("3 0 -1 2\n", "line 7: face 0's vertex index must be a whole number of 0 or more, found '-1'"),
            ("3.5 0 1 2\n", "line 7: face 0's vertex count must be a whole number"),
            ("# no face\n", "the file ends after 0 of the 1 faces"),
            ("4294967296 0 1 2\n", "face 0 says 4294967296 vertices but lists 3 indices"),
        ];
        for (face, needle) in faces {
            let e = error(&format!("{square}{face}"));
            assert!(e.contains(needle), "{e}\nshould contain: {needle}");
        }
    }

    #[test]
    fn what_is_read_leniently_is_a_warning() {
        let trailing = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n").unwrap();
        assert_eq!(trailing.meshes[0].indices.len(), 1);
        let said: Vec<String> = trailing.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            said,
            ["m.off: line 7: text after the 1 faces that the counts on line 2 announce is ignored"]
        );
        let points = parse("OFF\n1 0 0\n0 0 0\n").unwrap();
        assert_eq!(points.warnings.len(), 1);
        assert!(
            points.warnings[0].message.contains("no faces"),
            "{:?}",
            points.warnings
        );
    }

    #[test]
    fn loads_by_extension_and_refuses_binary_off() {
        let dir = temp_dir("off");
        let path = write(
            &dir,
            "tri.OFF",
            b"OFF\r\n3 1 0\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n",
        );
        assert_eq!(load_mesh_file(&path).unwrap().triangle_count(), 1);
        let binary = write(&dir, "b.off", b"OFF BINARY\n\x00\x00\x00\x03");
        let e = load_mesh_file(&binary).unwrap_err();
        assert!(
            e.to_string()
                .contains("line 1: binary OFF files are not supported"),
            "{e}"
        );
    }

    /// Bytes cut and changed anywhere give a mesh or an error, never a
    /// panic (the fuzz target `off` does the same at length).
    #[test]
    fn mangled_files_never_panic() {
        let text = b"OFF\n# c\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 1 2 1 1 1\n";
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as usize
        };
        for _ in 0..2000 {
            let mut bytes = text.to_vec();
            for _ in 0..1 + next() % 3 {
                let i = next() % bytes.len();
                bytes[i] = b"0123456789 -.#\nOFe"[next() % 18];
            }
            bytes.truncate(next() % (bytes.len() + 1));
            let _ = parse(&String::from_utf8_lossy(&bytes));
        }
    }
}
