//! Mesh file loaders: each turns one file into a [`LoadedAsset`] of plain
//! arrays in file order, or an [`InputError`] that names the file and, where
//! one applies, the line (`line 12`) or glTF location (`accessors[5]`).
//!
//! | Extension       | Loader              |
//! |-----------------|---------------------|
//! | `.obj`          | [`obj::load_obj`]   |
//! | `.gltf`, `.glb` | [`gltf::load_gltf`] |
//! | `.ply`          | [`ply::load_ply`]   |
//! | `.off`          | [`off::load_off`]   |
//! | `.stl`          | [`stl::load_stl`]   |
//!
//! Before a loader sees a file, its first bytes are checked against its
//! name (`sniff`): a file that holds another format (a binary glTF named
//! `.obj`) is refused saying what it holds, and a format strata does not
//! read (`.fbx`) is named, with what strata reads instead. The same check
//! tells a file given as a scene that is none ([`check_scene_file`]).
//!
//! Loaders never panic on bad input and never allocate more than the file
//! actually holds. What other tools read leniently (a material no library
//! defines, a stray PLY header line, a file without triangles) loads, with
//! a warning in [`LoadedAsset::warnings`] naming the file and line; what
//! strata cannot read is an error naming the feature (glTF 1.0, a required
//! glTF extension).

pub mod gltf;
pub mod obj;
pub mod off;
pub mod ply;
mod sniff;
pub mod stl;
mod strip;
mod text;

pub(crate) use ply::first_where;

use crate::error::{InputError, InputResult};
use crate::scene::asset::LoadedAsset;
use std::path::Path;

/// The extensions [`load_mesh_file`] understands, for error messages.
pub const SUPPORTED_EXTENSIONS: &[&str] = &["obj", "gltf", "glb", "ply", "off", "stl"];

/// The lower-case extension of `path`, if it is one [`load_mesh_file`]
/// reads, or, for a file named without one, that of the mesh format its
/// first bytes tell for sure (`sniff::told_mesh_extension`); else a
/// message naming the format (where strata knows it) and listing the ones
/// it reads.
pub fn check_extension(path: &Path) -> Result<String, String> {
    let extension = sniff::extension_of(path);
    if SUPPORTED_EXTENSIONS.contains(&extension.as_str()) {
        return Ok(extension);
    }
    if let Some(told) = extension
        .is_empty()
        .then(|| sniff::told_mesh_extension(path))
        .flatten()
    {
        return Ok(told.to_string());
    }
    let supported = SUPPORTED_EXTENSIONS
        .iter()
        .map(|e| format!(".{e}"))
        .collect::<Vec<_>>()
        .join(", ");
    let found = match sniff::not_read(&extension) {
        _ if extension.is_empty() => "a file without an extension".to_string(),
        Some(name) => format!("{name} files ('.{extension}')"),
        None => format!("'.{extension}' files"),
    };
    let convert = if sniff::not_read(&extension).is_some() {
        "; convert it to glTF (.glb), for example by importing it into Blender and exporting glTF 2.0"
    } else {
        ""
    };
    Err(format!(
        "cannot load {found} as a mesh; supported mesh formats are {supported}{convert}"
    ))
}

/// The precision a load keeps a file's coordinates in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// float32, as a scene traces them.
    Float32,
    /// float32 and, where the format can write more, the file's own
    /// float64 values beside them ([`LoadedMesh::exact_positions`]): a
    /// query mesh far from the origin, whose float32 rounding would move
    /// its faces (0.25 m at five million).
    ///
    /// [`LoadedMesh::exact_positions`]: crate::scene::asset::LoadedMesh::exact_positions
    Float64,
}

/// What a load reads of a mesh file beyond its faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reading {
    /// The precision its coordinates are kept in.
    pub coordinates: Coordinates,
    /// Whether its materials are read, and the textures they use: a
    /// render's. A file traced for its faces alone (`strata trace`, a query
    /// mesh) reads neither, so it pays for no image decoded, and a missing
    /// texture, a material library's mistake or a glTF's required texture
    /// extension is no error there.
    pub materials: bool,
}

impl Reading {
    /// A render's: float32, materials and textures.
    pub const RENDER: Self = Self {
        coordinates: Coordinates::Float32,
        materials: true,
    };
    /// Faces to trace as a scene does (`strata trace`, `rays`, `bench`):
    /// float32, no materials.
    pub const FACES: Self = Self {
        coordinates: Coordinates::Float32,
        materials: false,
    };
    /// A query mesh's faces (`raycast::Mesh::load`): float64 where the
    /// file writes more, no materials.
    pub const EXACT_FACES: Self = Self {
        coordinates: Coordinates::Float64,
        materials: false,
    };
}

/// Load any supported mesh file, chosen by its extension (case-insensitive):
/// `.obj`, `.gltf`, `.glb`, `.ply`, `.off` or `.stl`; a file without one by
/// the format its first bytes tell ([`check_extension`]). Any other
/// extension, or first bytes that say the file holds another format, is an
/// [`InputError`] naming the file and what it is.
pub fn load_mesh_file(path: &Path) -> InputResult<LoadedAsset> {
    load_mesh_file_with(path, Reading::RENDER)
}

/// [`load_mesh_file`], reading what `reading` says.
pub fn load_mesh_file_with(path: &Path, reading: Reading) -> InputResult<LoadedAsset> {
    let extension = check_extension(path).map_err(|e| InputError::file(path, e))?;
    let (head, len) = sniff::read_head(path)?;
    sniff::check_mesh_head(path, &extension, &head, len)?;
    match extension.as_str() {
        "obj" => obj::load_obj_with(path, reading),
        "gltf" | "glb" => gltf::load_gltf_with(path, reading.materials),
        "off" => off::load_off_with(path, reading.coordinates),
        "stl" => stl::load_stl_with(path, reading.coordinates),
        _ => ply::load_ply_with(path, reading.coordinates),
    }
}

/// Check, by its name and first bytes, that `path` is a scene file (see
/// `sniff`): a mesh, a format strata does not read, or binary data given
/// as a scene is an error saying what it is. Then the file's text.
pub fn read_scene_file(path: &Path) -> InputResult<String> {
    let (head, len) = sniff::read_head(path)?;
    sniff::check_scene_head(path, &head, len)?;
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        InputError::new(
            path,
            format!("line {line}"),
            "not UTF-8 text; a scene file is TOML, which is UTF-8",
        )
    })
}

pub(crate) use crate::error::io_message;

/// Warn, naming `path`, that a loaded file holds no triangles, so nothing
/// of it renders (a points-only OBJ, a PLY without faces). `found` says
/// what the file lacks, in its own format's words.
pub(crate) fn warn_without_triangles(asset: &mut LoadedAsset, path: &Path, found: &str) {
    if asset.triangle_count() == 0 {
        asset.warnings.push(InputError::file(
            path,
            format!("{found}, so nothing of this file renders (points and lines are not drawn)"),
        ));
    }
}

/// Vertices no triangle uses are never traced, so they may hold anything:
/// a scanner's organised mesh keeps its missing samples as NaN vertices
/// that no face uses, and Open3D, MeshLab and trimesh read such files.
/// Each vertex that is not finite and that no triangle of `indices` uses
/// is given the position of one a triangle does (so that a box of all the
/// positions, which frames a model in its studio, does not move). The
/// first vertex a triangle uses that is not finite is an error: its index
/// and what is wrong with it (its triangle is not named: a polygon's
/// triangles are not its face's number in the file). `indices` must be in
/// range.
pub(crate) fn settle_unused_vertices(
    positions: &mut [glam::Vec3],
    indices: &[[u32; 3]],
) -> Result<(), (usize, String)> {
    use rayon::prelude::*;
    if positions.par_iter().all(|p| p.is_finite()) {
        return Ok(());
    }
    let used = used_vertices(indices, positions.len());
    let bad = |i: &usize| used[*i] && !positions[*i].is_finite();
    if let Some(vertex) = (0..positions.len()).find(bad) {
        let p = positions[vertex];
        return Err((
            vertex,
            format!("vertex {vertex} is not finite: {p} (a face uses it)"),
        ));
    }
    let stand_in = match indices.first() {
        Some(t) => positions[t[0] as usize],
        None => positions
            .iter()
            .copied()
            .find(|p| p.is_finite())
            .unwrap_or_default(),
    };
    for p in positions.iter_mut().filter(|p| !p.is_finite()) {
        *p = stand_in;
    }
    Ok(())
}

/// `used[i]`: whether a face of `faces` (every index below `n`) uses
/// vertex `i`.
pub(crate) fn used_vertices(faces: &[[u32; 3]], n: usize) -> Vec<bool> {
    let mut used = vec![false; n];
    for &k in faces.iter().flatten() {
        if let Some(u) = used.get_mut(k as usize) {
            *u = true;
        }
    }
    used
}

/// The first face of `faces` that uses `vertex` (0 where none does).
pub(crate) fn first_face_using(faces: &[[u32; 3]], vertex: usize) -> usize {
    faces
        .iter()
        .position(|f| f.contains(&(vertex as u32)))
        .unwrap_or(0)
}

/// Temporary files for the loaders' unit tests.
#[cfg(test)]
pub(crate) mod test_files {
    use std::path::{Path, PathBuf};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A fresh directory for one test, removed again when dropped.
    pub struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    pub fn temp_dir(tag: &str) -> TempDir {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "strata-loader-{}-{}-{}",
            std::process::id(),
            tag,
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    pub fn write(dir: &Path, name: &str, contents: &[u8]) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    /// A PNG file's bytes: `width × height` 8-bit sRGB texels, row by row
    /// from the top.
    pub fn png(width: u32, height: u32, texels: &[[u8; 3]]) -> Vec<u8> {
        let image = image::RgbImage::from_raw(width, height, texels.concat()).unwrap();
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
        bytes.into_inner()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use test_files::{temp_dir, write};

    #[test]
    fn dispatches_by_extension_case_insensitively() {
        let dir = temp_dir("dispatch");
        let path = write(&dir, "tri.OBJ", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let asset = load_mesh_file(&path).unwrap();
        assert_eq!(asset.triangle_count(), 1);
    }

    /// A file named without an extension is read by the mesh format its
    /// first bytes tell for sure, as its named twin is; OBJ's first lines
    /// are too weak a sign, so such a file stays unread.
    #[test]
    fn a_file_without_an_extension_is_read_by_what_its_bytes_say() {
        let dir = temp_dir("dispatch-sniffed");
        let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let stl = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                    vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        for (named, bytes) in [
            ("t.ply", &ply[..]),
            ("t.off", &off[..]),
            ("t.stl", &stl[..]),
        ] {
            let twin = load_mesh_file(&write(&dir, named, bytes)).unwrap();
            let bare = load_mesh_file(&write(&dir, "bare", bytes)).unwrap();
            assert_eq!(
                bare.meshes[0].positions, twin.meshes[0].positions,
                "{named}"
            );
            assert_eq!(bare.meshes[0].indices, twin.meshes[0].indices, "{named}");
            assert_eq!(
                check_extension(&dir.join("bare")).as_deref(),
                Ok(&named[2..])
            );
        }
        let obj = write(&dir, "bare", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let err = load_mesh_file(&obj).unwrap_err();
        assert!(err.to_string().contains("without an extension"), "{err}");
    }

    #[test]
    fn gltf_extension_goes_to_the_gltf_loader() {
        let dir = temp_dir("dispatch-gltf");
        let path = write(&dir, "broken.gltf", b"{ not json");
        let err = load_mesh_file(&path).unwrap_err();
        assert!(err.file.ends_with("broken.gltf"), "{err}");
        assert!(err.to_string().contains("JSON"), "{err}");
    }

    #[test]
    fn unknown_extension_lists_supported_ones() {
        let dir = temp_dir("dispatch-fbx");
        let path = write(&dir, "bunny.fbx", b"Kaydara FBX Binary  \x00");
        let err = load_mesh_file(&path).unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("bunny.fbx: cannot load FBX files ('.fbx')"),
            "{text}"
        );
        assert!(text.contains("convert it to glTF"), "{text}");
        assert!(
            text.contains(".obj, .gltf, .glb, .ply, .off, .stl"),
            "{text}"
        );
        let err = load_mesh_file(Path::new("no_extension")).unwrap_err();
        assert!(err.to_string().contains("without an extension"), "{err}");
    }
}
