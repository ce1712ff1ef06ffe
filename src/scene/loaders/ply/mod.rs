//! Stanford PLY, ASCII and binary (either endianness): the header through
//! `ply-rs-bw`, ASCII bodies by `ascii`, binary ones by `binary`, both
//! from the whole file read into memory once.
//!
//! | File              | Holds                                                         |
//! |-------------------|---------------------------------------------------------------|
//! | `mod.rs`          | [`load_ply`]: the file read once, its header, the counts checked, one mesh |
//! | `header.rs`       | header lines other tools skip (old Blender exports), made comments |
//! | `ascii.rs`        | an ASCII body, line by line in parallel chunks                |
//! | `binary.rs`       | a binary body, fixed-size records in parallel, others walked  |
//! | `face.rs`         | a face's indices, and the fan triangulation both bodies share |
//! | `point.rs`        | a vertex position, float32 or (for exact coordinates) float64 |
//! | `strips.rs`       | triangle strips (`tristrips`), read by `ply-rs-bw`'s own parser |
//! | `binary_tests.rs` | the binary reader against `ply-rs-bw`'s, on generated files   |
//!
//! Imports point one way: this entry uses the header, the two body
//! readers and the strips, and the body readers use `face`; nothing below
//! names the entry.
//!
//! `vertex` elements give `x y z` (float or double, a double rounded to
//! float32 or, where the load asks, kept: `point`); `face` elements give a
//! `vertex_indices` (or `vertex_index`) list, fan-triangulated like OBJ
//! n-gons; `tristrips` elements give strips of triangles, each ended by −1.
//! Other elements and properties are read and ignored.
//!
//! Before anything is allocated for them, every element count in the
//! header is checked against the bytes the file actually holds (an ASCII
//! element takes at least two bytes per property, a binary one the size
//! of its fixed fields), so a header claiming 1e12 vertices is an error
//! naming the file, not an allocation. An index out of range is an error
//! naming the face.
//!
//! As other tools do, a header line before the first `element` that starts
//! with no keyword (old Blender exports) is skipped with a warning (see
//! `header`), and a file without faces loads with a warning.

mod ascii;
mod binary;
#[cfg(test)]
mod binary_tests;
mod face;
mod header;
mod point;
mod strips;

pub(crate) use binary::first_where;

use super::{io_message, Coordinates};
use crate::error::{InputError, InputResult};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use binary::Scalar;
use face::out_of_range;
use glam::{DVec3, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, Encoding, Header, PropertyType, ScalarType};
use point::Point;
use rayon::prelude::*;
use std::io::Read;
use std::path::Path;

fn scalar_size(t: &ScalarType) -> u64 {
    Scalar::of(t).size() as u64
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

/// Load a PLY file into one mesh; see the module documentation.
pub fn load_ply(path: &Path) -> InputResult<LoadedAsset> {
    load_ply_with(path, Coordinates::Float32)
}

/// [`load_ply`], keeping the file's coordinates as `coordinates` says:
/// for [`Coordinates::Float64`], `double` properties as written (`float`
/// ones are float32 by the header, whatever digits an ASCII file writes).
pub fn load_ply_with(path: &Path, coordinates: Coordinates) -> InputResult<LoadedAsset> {
    match coordinates {
        Coordinates::Float32 => read_ply::<Vec3>(path),
        Coordinates::Float64 => read_ply::<DVec3>(path),
    }
}

/// The file's one mesh, its positions read as `P` ([`Point::split`]).
fn read_ply<P: Point>(path: &Path) -> InputResult<LoadedAsset> {
    let mut file = std::fs::File::open(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let bad = |e: &dyn std::fmt::Display| InputError::file(path, format!("invalid PLY: {e}"));
    // The whole file at once (one allocation of its size, one copy from
    // the page cache): the bodies are then plain byte slices, walked
    // without a reader's per-value calls. The buffer is filled in parallel,
    // each part read at its offset: the first touch of a fresh page, which
    // the kernel clears, costs more than copying it, and one reader would
    // touch them and copy one page at a time.
    let size = file.metadata().map_or(0, |m| m.len());
    let mut bytes = vec![0u8; usize::try_from(size).unwrap_or(0)];
    let filled: Vec<usize> = bytes
        .par_chunks_mut(READ_PART)
        .enumerate()
        .map(|(k, part)| read_at(&file, part, (k * READ_PART) as u64))
        .collect::<std::io::Result<_>>()
        .map_err(|e| bad(&e))?;
    // A part short of its length ends the file (it shrank since its size
    // was read).
    let end = filled
        .iter()
        .enumerate()
        .find(|&(k, &n)| n < bytes[k * READ_PART..].len().min(READ_PART))
        .map_or(bytes.len(), |(k, &n)| k * READ_PART + n);
    bytes.truncate(end);
    std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(end as u64)).map_err(|e| bad(&e))?;
    // Whatever the file holds past the size it gave.
    file.read_to_end(&mut bytes).map_err(|e| bad(&e))?;
    let mut warnings = Vec::new();
    if let Some(fixed) = header::without_stray_lines(path, &bytes, &mut warnings) {
        bytes = fixed;
    }
    let file_len = bytes.len() as u64;
    let mut reader = Reader::new(&bytes[..]);
    let header = Parser::<DefaultElement>::new()
        .read_header(&mut reader)
        .map_err(|e| bad(&e))?;
    check_counts(path, &header, file_len)?;
    // The reader's count has already moved past `end_header` (our line
    // tests pin this): it is the number of the body's first line.
    let line = reader.line();
    let body = reader.into_inner();
    let (read, mut indices, first_vertex_line) = if header.encoding == Encoding::Ascii {
        let body = ascii::read_body(path, &header, body, line.saturating_sub(1))?;
        let n = body.positions.len();
        let indices = (body.faces)
            .triangulate(n)
            .map_err(|(i, bad)| out_of_range(path, i, bad, n))?;
        (body.positions, indices, Some(body.first_vertex_line))
    } else {
        let (positions, indices) = binary::read_body(path, &header, body, line)?;
        (positions, indices, None)
    };
    let (mut positions, exact_positions) = P::split(read);
    if strips::has_strips(&header) {
        indices.extend(strips::strip_triangles(path, &bytes, positions.len())?);
    }
    if let Err((vertex, message)) = super::settle_unused_vertices(&mut positions, &indices) {
        let line = first_vertex_line
            .and_then(|first| ascii::line_of_element(body, line.saturating_sub(1), first, vertex));
        return Err(InputError::file(path, message).on_line(line));
    }
    // The file's bytes are not needed past here; unmapping a large mesh's
    // (264 MB for the 13.9M-triangle dragon) took 20 ms on this thread.
    crate::system::memory::drop_aside(bytes);
    let mesh = LoadedMesh {
        positions,
        exact_positions,
        indices,
        ..LoadedMesh::default()
    };
    Ok(mesh_asset(path, mesh, warnings))
}

/// Bytes a task of the file's read copies: a few pages' clears and copies
/// dwarf the hand-off.
const READ_PART: usize = 1 << 22;

/// Reads `part.len()` bytes of `file` from `offset`, fewer only at its end;
/// returns how many.
fn read_at(file: &std::fs::File, part: &mut [u8], offset: u64) -> std::io::Result<usize> {
    #[cfg(unix)]
    let read = |buf: &mut [u8], at: u64| std::os::unix::fs::FileExt::read_at(file, buf, at);
    #[cfg(windows)]
    let read = |buf: &mut [u8], at: u64| std::os::windows::fs::FileExt::seek_read(file, buf, at);
    let mut filled = 0;
    while filled < part.len() {
        match read(&mut part[filled..], offset + filled as u64) {
            Ok(0) => break,
            Ok(k) => filled += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// The file's one `mesh`, named after the file, with the header's
/// `warnings` and one more if it has no triangles.
fn mesh_asset(path: &Path, mesh: LoadedMesh, warnings: Vec<InputError>) -> LoadedAsset {
    let name = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().to_string());
    let mut asset = LoadedAsset {
        meshes: vec![LoadedMesh { name, ..mesh }],
        warnings,
        ..LoadedAsset::default()
    };
    super::warn_without_triangles(&mut asset, path, "no faces");
    asset
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file written into a directory of its own, removed (with the
    /// directory) when dropped: at the end of the statement that made it.
    struct PlyFile {
        _dir: super::super::test_files::TempDir,
        path: std::path::PathBuf,
    }

    impl std::ops::Deref for PlyFile {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.path
        }
    }

    fn write(name: &str, bytes: &[u8]) -> PlyFile {
        let dir = super::super::test_files::temp_dir("ply");
        let path = super::super::test_files::write(&dir, name, bytes);
        PlyFile { _dir: dir, path }
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

    /// A scanner's organised mesh: NaN and infinite vertices that no face
    /// uses load, in ASCII and binary, and take the place of a vertex a
    /// face uses (no box of the positions grows); one a face uses is an
    /// error naming the vertex and, in ASCII, its line.
    #[test]
    fn vertices_no_face_uses_may_be_nan() {
        let head = HEAD.replace("vertex 4", "vertex 6");
        let nan = [f32::NAN; 3];
        let inf = [f32::INFINITY, 0.0, 0.0];
        let points = [
            nan,
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            inf,
        ];
        let file = |binary: bool, face: [i32; 4]| {
            if !binary {
                let text = |p: [f32; 3]| format!("{} {} {}\n", p[0], p[1], p[2]).to_lowercase();
                // A blank line among them, which carries no element.
                let body: String = points.iter().map(|&p| text(p)).collect();
                let body = body.replacen('\n', "\n\n", 1);
                let face = format!("4 {} {} {} {}\n", face[0], face[1], face[2], face[3]);
                return format!("{head}{body}{face}").into_bytes();
            }
            let mut bin = head.replace("ascii", "binary_little_endian").into_bytes();
            bin.extend(points.iter().flatten().flat_map(|c| c.to_le_bytes()));
            bin.push(4);
            bin.extend(face.iter().flat_map(|i| i.to_le_bytes()));
            bin
        };
        let quad = load_ply(&write(
            "quad.ply",
            format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n").as_bytes(),
        ))
        .unwrap();
        let corners = |a: &LoadedAsset| {
            let m = &a.meshes[0];
            m.indices
                .iter()
                .map(|t| t.map(|k| m.positions[k as usize]))
                .collect::<Vec<_>>()
        };
        for binary in [false, true] {
            let a = load_ply(&write("scan.ply", &file(binary, [1, 2, 3, 4]))).unwrap();
            assert_eq!(corners(&a), corners(&quad), "binary {binary}");
            assert!(a.meshes[0]
                .positions
                .iter()
                .all(|p| (0.0..=1.0).contains(&p.max_element())));
            let e = load_ply(&write("scan.ply", &file(binary, [1, 2, 5, 4]))).unwrap_err();
            let text = e.to_string();
            assert!(
                text.contains("vertex 5 is not finite: [inf, 0, 0] (a face uses it)"),
                "{text}"
            );
            // Vertex 5 (the 6th) is on line 16, after the blank line.
            assert_eq!(text.contains("line 16:"), !binary, "{text}");
        }
    }

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

    /// A grid of n × n quads as an ASCII PLY body (with a blank line every
    /// 1000 lines) and as the same mesh in binary: the header line count
    /// and the two files.
    fn grid(n: u32) -> (String, Vec<u8>) {
        grid_of(n, false)
    }

    /// [`grid`], each quad as two triangles where `triangles` is set.
    fn grid_of(n: u32, triangles: bool) -> (String, Vec<u8>) {
        let verts = (n + 1) * (n + 1);
        let faces = if triangles { 2 * n * n } else { n * n };
        let head = format!("ply\nformat ascii 1.0\nelement vertex {verts}\nproperty float x\nproperty float y\nproperty float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n");
        let mut ascii = head.clone();
        let mut bin = head.replace("ascii", "binary_little_endian").into_bytes();
        let mut lines = 0;
        let mut line = |ascii: &mut String, text: String| {
            ascii.push_str(&text);
            lines += 1;
            if lines % 1000 == 0 {
                ascii.push_str("  \n");
            }
        };
        for k in 0..verts {
            let p = [(k % (n + 1)) as f32 * 0.1, (k / (n + 1)) as f32 / 3.0, 0.5];
            line(&mut ascii, format!("{} {} {}\n", p[0], p[1], p[2]));
            p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        for q in 0..n * n {
            let (i, j) = (q % n, q / n);
            let a = j * (n + 1) + i;
            let quad = [a, a + 1, a + n + 2, a + n + 1];
            let polygons = match triangles {
                true => vec![
                    vec![quad[0], quad[1], quad[2]],
                    vec![quad[0], quad[2], quad[3]],
                ],
                false => vec![quad.to_vec()],
            };
            for p in polygons {
                let text: Vec<String> = p.iter().map(|v| v.to_string()).collect();
                line(&mut ascii, format!("{} {}\n", p.len(), text.join(" ")));
                bin.push(p.len() as u8);
                p.iter().for_each(|v| bin.extend((*v as i32).to_le_bytes()));
            }
        }
        (ascii, bin)
    }

    /// A large ASCII mesh of triangles, read in parallel chunks straight
    /// into rows of indices, is its binary twin, and an index out of range
    /// deep in it names the same face in both.
    #[test]
    fn large_ascii_triangles_read_into_rows_as_binary_ones() {
        let (ascii, bin) = grid_of(200, true); // 40,401 vertices, 80,000 triangles
        let a = load_ply(&write("tris.ply", ascii.as_bytes())).unwrap();
        let b = load_ply(&write("trisb.ply", &bin)).unwrap();
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(a.meshes[0].indices, b.meshes[0].indices);
        assert_eq!(a.meshes[0].indices.len(), 80_000);
        // Face 61,234's last index out of range, in both files.
        let face = 61_234usize;
        let [x, y, z] = a.meshes[0].indices[face];
        let (from, to) = (format!("3 {x} {y} {z}\n"), format!("3 {x} {y} 99999\n"));
        let at = ascii
            .match_indices(&from)
            .map(|(k, _)| k)
            .collect::<Vec<_>>();
        assert_eq!(at.len(), 1, "the face's line is unique");
        let broken = format!("{}{to}{}", &ascii[..at[0]], &ascii[at[0] + from.len()..]);
        let mut broken_bin = bin.clone();
        let record = bin.len() - (80_000 - face) * 13;
        broken_bin[record + 9..record + 13].copy_from_slice(&99999i32.to_le_bytes());
        for (name, bytes) in [
            ("bad.ply", broken.as_bytes()),
            ("badb.ply", &broken_bin[..]),
        ] {
            let e = load_ply(&write(name, bytes)).unwrap_err().to_string();
            assert!(
                e.contains(&format!("face {face}: vertex index 99999 is out of range")),
                "{name}: {e}"
            );
        }
    }

    /// An ASCII body of several parallel chunks reads as its binary twin,
    /// and a bad line deep in it is reported with its own line number,
    /// before a truncation that comes later.
    #[test]
    fn large_ascii_bodies_read_in_chunks_as_binary_ones() {
        let (ascii, bin) = grid(250); // 63,001 vertices and 62,500 quads
        let a = load_ply(&write("grid.ply", ascii.as_bytes())).unwrap();
        let b = load_ply(&write("gridb.ply", &bin)).unwrap();
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(a.meshes[0].indices, b.meshes[0].indices);
        assert_eq!(a.meshes[0].indices.len(), 125_000);

        // Break vertex 50,000's line (file line: 9 header lines, the
        // vertex lines before it, and a blank line after every 1000).
        let lines: Vec<&str> = ascii.split_inclusive('\n').collect();
        let at = 9 + 50_000 + 50;
        let (x, y) = ((50_000 % 251) as f32 * 0.1, (50_000 / 251) as f32 / 3.0);
        assert_eq!(lines[at], format!("{x} {y} 0.5\n"));
        let mut broken = lines.clone();
        broken[at] = "0.1 oops 0.5\n";
        let broken: String = broken.concat();
        let e = load_ply(&write("broken.ply", broken.as_bytes())).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("line {}: 'oops' is not a float", at + 1)),
            "{e}"
        );
        // The same file cut short in its faces still names the bad vertex.
        let cut = &broken[..broken.len() - 40_000];
        let e = load_ply(&write("cut.ply", cut.as_bytes())).unwrap_err();
        assert!(e.to_string().contains("'oops'"), "{e}");
        let end = ascii[..ascii.len() - 40_000].rfind('\n').unwrap() + 1;
        let e = load_ply(&write("cut2.ply", &ascii.as_bytes()[..end])).unwrap_err();
        assert!(
            e.to_string()
                .contains("ends before its 62500 'face' elements"),
            "{e}"
        );
    }

    /// Four vertices of a unit square, then `strips` (ASCII lines of a
    /// `tristrips` element, or the one list as `int`s in a binary file),
    /// after one face where `face` is given.
    fn strip_file(binary: bool, face: Option<[i32; 3]>, strips: &[&[i32]]) -> Vec<u8> {
        let faces = face.map_or(0, |_| 1);
        let format = if binary {
            "binary_little_endian"
        } else {
            "ascii"
        };
        let mut out = format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nelement face {faces}\nproperty list uchar int vertex_indices\n\
             element tristrips {}\nproperty list int int vertex_indices\nend_header\n",
            strips.len()
        )
        .into_bytes();
        let corners = [
            [0.0f32, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        for v in corners {
            if binary {
                out.extend(v.iter().flat_map(|c| c.to_le_bytes()));
            } else {
                out.extend(format!("{} {} {}\n", v[0], v[1], v[2]).into_bytes());
            }
        }
        let mut list = |count_bytes: Vec<u8>, items: &[i32]| {
            if binary {
                out.extend(count_bytes);
                out.extend(items.iter().flat_map(|k| k.to_le_bytes()));
            } else {
                let words: Vec<String> = items.iter().map(i32::to_string).collect();
                out.extend(format!("{} {}\n", items.len(), words.join(" ")).into_bytes());
            }
        };
        if let Some(face) = face {
            list(vec![3], &face);
        }
        for strip in strips {
            list((strip.len() as i32).to_le_bytes().to_vec(), strip);
        }
        out
    }

    #[test]
    fn triangle_strips_are_read_from_ascii_and_binary_files() {
        for binary in [false, true] {
            // One strip over the square, then one ended early and joined
            // by a repeated index; after a face.
            let bytes = strip_file(
                binary,
                Some([0, 2, 1]),
                &[&[0, 1, 2, 3], &[0, 1, -1, 2, 2, 3]],
            );
            let asset = load_ply(&write("strips.ply", &bytes)).unwrap();
            let mesh = &asset.meshes[0];
            assert_eq!(mesh.positions.len(), 4);
            assert_eq!(
                mesh.indices,
                [[0, 2, 1], [0, 1, 2], [1, 3, 2]],
                "binary: {binary}"
            );
            assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
            // An index past the vertices, or below −1, is an error naming
            // the strip.
            for bad in [4, -2] {
                let bytes = strip_file(binary, None, &[&[0, 1, 2], &[1, bad, 3]]);
                let e = load_ply(&write("bad.ply", &bytes)).unwrap_err().to_string();
                assert!(
                    e.contains("bad.ply")
                        && e.contains(&format!("tristrips 1: vertex index {bad}")),
                    "{e}"
                );
            }
        }
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

    /// The same random vertices as ASCII and as binary: bit-identical
    /// positions, whatever the float (the ASCII text is Rust's shortest
    /// round-trip form, which parses back to the same bits).
    #[test]
    fn ascii_floats_parse_to_the_bits_the_binary_file_holds() {
        use crate::sampling::stream::{seeded, Draw};
        let mut rng = seeded(7);
        let n = 500;
        let values: Vec<f32> = (0..3 * n)
            .map(|_| {
                let scale = 10f32.powi(rng.range(-30.0, 30.0) as i32);
                rng.range(-0.5, 0.5) * scale
            })
            .collect();
        let head = format!(
            "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        );
        let mut ascii = head.clone();
        for v in values.chunks(3) {
            ascii += &format!("{} {} {}\n", v[0], v[1], v[2]);
        }
        ascii += "3 0 1 2\n";
        let mut bin = head.replace("ascii", "binary_little_endian").into_bytes();
        for v in &values {
            bin.extend(v.to_le_bytes());
        }
        bin.push(3);
        for i in [0i32, 1, 2] {
            bin.extend(i.to_le_bytes());
        }
        let a = load_ply(&write("fa.ply", ascii.as_bytes())).unwrap();
        let b = load_ply(&write("fb.ply", &bin)).unwrap();
        let bits = |m: &LoadedAsset| -> Vec<u32> {
            m.meshes[0]
                .positions
                .iter()
                .flat_map(|p| p.to_array())
                .map(f32::to_bits)
                .collect()
        };
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(
            bits(&a),
            values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn ascii_bodies_skip_what_a_mesh_does_not_use() {
        // Doubles, extra vertex properties, an extra element with a list,
        // blank lines, a pentagon, the singular `vertex_index`.
        let text = "ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty double x\n\
                    property float nx\nproperty double y\nproperty double z\nproperty uchar red\n\
                    element edge 1\nproperty list uchar int pair\nproperty int weight\n\
                    element face 2\nproperty uchar flags\nproperty list uchar uint vertex_index\n\
                    end_header\n0.5 9 0 0 255\n\n1 9 0 0 1\n1 9 1 0 2\n2 0 1 -7\n\
                    0 3 0 1 2\n1 5 0 1 2 0 1\n";
        let a = load_ply(&write("skip.ply", text.as_bytes())).unwrap();
        let m = &a.meshes[0];
        assert_eq!(
            m.positions,
            vec![
                Vec3::new(0.5, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0)
            ]
        );
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 1, 2], [0, 2, 0], [0, 0, 1]]);
    }

    #[test]
    fn ascii_errors_name_the_file_and_line() {
        let cases = [
            // (body, line, words in the message)
            (
                "0 0 0\n1 0 x\n1 1 0\n0 1 0\n3 0 1 2\n",
                11,
                "'x' is not a float",
            ),
            (
                "0 0 0\n1 0 0\n1 1\n0 1 0\n3 0 1 2\n",
                12,
                "coordinate is missing",
            ),
            (
                "0 0 0\n1 0 0 4\n1 1 0\n0 1 0\n3 0 1 2\n",
                11,
                "unexpected '4'",
            ),
            (
                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1\n",
                14,
                "vertex index is missing",
            ),
            (
                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n300 0 1 2\n",
                14,
                "'300' is not a uchar",
            ),
            (
                "0 0 0\n1 0 0\n1 1 0\n",
                13,
                "ends before its 4 'vertex' elements",
            ),
            (
                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2.5\n",
                14,
                "'2.5' is not a int",
            ),
        ];
        for (body, line, words) in cases {
            let e = load_ply(&write("bad.ply", format!("{HEAD}{body}").as_bytes())).unwrap_err();
            let text = e.to_string();
            assert!(
                text.starts_with(&format!("{}: line {line}: ", e.file)),
                "{text}"
            );
            assert!(text.contains("bad.ply") && text.contains(words), "{text}");
        }
        // Bytes that are not text, on the line they are on.
        let mut junk = format!("{HEAD}0 0 0\n1 0 0\n").into_bytes();
        junk.extend([0xff, 0xfe, b' ', b'0', b'\n']);
        let e = load_ply(&write("junk.ply", &junk)).unwrap_err();
        assert!(
            e.to_string()
                .contains("line 12: cannot read: not ASCII text"),
            "{e}"
        );
        // NaN or infinite coordinates, in ASCII (with the line) and binary.
        let nan = format!("{HEAD}0 0 0\n1 nan 0\n1 1 0\n0 1 0\n3 0 1 2\n");
        let e = load_ply(&write("nan.ply", nan.as_bytes())).unwrap_err();
        assert!(
            e.to_string().contains("line 11: vertex 1 is not finite"),
            "{e}"
        );
        let mut bin = HEAD.replace("ascii", "binary_little_endian").into_bytes();
        for c in [
            0.0f32,
            0.0,
            0.0,
            1.0,
            0.0,
            0.0,
            1.0,
            f32::INFINITY,
            0.0,
            0.0,
            1.0,
            0.0,
        ] {
            bin.extend(c.to_le_bytes());
        }
        bin.push(3);
        for i in [0i32, 1, 2] {
            bin.extend(i.to_le_bytes());
        }
        let e = load_ply(&write("inf.ply", &bin)).unwrap_err();
        assert!(e.to_string().contains("vertex 2 is not finite"), "{e}");
        // A negative index is named with its face, as in binary files.
        let neg = format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 -1 2\n");
        let e = load_ply(&write("neg.ply", neg.as_bytes())).unwrap_err();
        assert!(e.to_string().contains("face 0: vertex index -1"), "{e}");
    }
}
