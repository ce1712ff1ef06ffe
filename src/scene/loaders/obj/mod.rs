//! Wavefront OBJ loader (with MTL material libraries), built on `tobj`.
//!
//! Faces are fan-triangulated (`f 1 2 3 4 5` → `1 2 3`, `1 3 4`, `1 4 5`) and
//! keep the file's order. Every `o`/`g` object (and every change of
//! `usemtl` inside one) becomes one [`LoadedMesh`], in file order; objects
//! without faces are left out. Points (`l` with one vertex) and polylines
//! (`l`) are ignored. Relative (negative) indices count back from the last
//! vertex defined before the face.
//!
//! Shading normals come through only where the file has them: a mesh whose
//! faces all give a `vn` index for every vertex keeps them (indexed apart
//! from positions, as in the file); if any face of a mesh lacks them the mesh
//! gets none (`normals: None`) rather than invented ones. Texture
//! coordinates follow the same rule with `vt`, and are kept only for a mesh
//! whose material has a `map_Kd` texture to look up with them; `v` is
//! flipped (`1 − v`) into [`crate::texture`]'s space, whose `v` runs down
//! from the image's top row.
//!
//! Before `tobj` sees the text, a validation pass reports the common mistakes
//! with their line number (`mesh.obj: line 12: ...`): malformed or
//! non-finite `v`/`vt`/`vn` values, faces with fewer than three vertices,
//! index 0, non-integer indices, and indices out of range. Absolute indices
//! are checked against all `v`/`vt`/`vn` lines in the file, relative ones
//! against the lines before the face.
//!
//! # Materials
//!
//! `mtllib` names a material library relative to the OBJ file. Each
//! `newmtl` becomes one entry of [`LoadedAsset::materials`], in library
//! order, and `usemtl` sets the mesh's material index. As other tools do,
//! what names no material gives the scene's default material and a warning
//! at its line ([`LoadedAsset::warnings`]): a `usemtl` naming a material
//! that no earlier `mtllib` defines (once per name), a `usemtl` without a
//! name, an `mtllib` that cannot be read, a `newmtl` without a name (its
//! statements are left out).
//!
//! # Text
//!
//! UTF-8 (a byte-order mark dropped), UTF-16 with a byte-order mark, and
//! otherwise Latin-1, for OBJ and MTL files alike (see `loaders::text`). A
//! `\` in a library's or texture's file name is a path separator where no
//! file has the name as written (`map_Kd .\tex.jpg`). A file without
//! faces loads with a warning: nothing of it renders. In a file with no
//! `mtllib` at all, `usemtl` means the default material, without a word.
//!
//! | MTL statement             | [`Material`] field                                         |
//! |---------------------------|------------------------------------------------------------|
//! | `Kd r g b`                | `diffuse` (0.8 grey when absent)                           |
//! | `Ks r g b`                | `specular`                                                 |
//! | `Ns n`                    | `shininess` (Phong exponent)                               |
//! | `Ke r g b`                | `emission`                                                 |
//! | `Ni n`                    | `ior` (when `n > 0`; otherwise 1.5)                        |
//! | `d a`                     | `transparency = 1 − a` (clamped to [0, 1])                 |
//! | `Tr t` (only without `d`) | `transparency = t` (clamped to [0, 1])                     |
//! | `illum 3`, `5` or `7`     | `reflectivity = max(Ks r, g, b)`, `glossiness = 0` (mirror) |
//! | `illum 5` or `7`          | also `fresnel = true`                                      |
//! | `map_Kd [-clamp on] file` | `diffuse_texture`: the image multiplies `Kd`                |
//! | `norm file` (`map_Norm`)  | `maps.normal`: a tangent-space normal map (linear)          |
//! | `bump [-bm s] file` (`map_Bump`) | `maps.normal`: a height map (red, linear), heights × `s` in world units |
//! | `Ka` (ambient)            | ignored: strata computes the light that arrives            |
//! | `Tf`, other `map_*`, `disp`, others | ignored, with a warning (see `ignored.rs`) |
//!
//! A colour given as one number (`Kd 0.5`) is a grey. Every other field keeps
//! its [`Material::default`] value.
//!
//! # Textures
//!
//! ```text
//! newmtl crate
//! Kd 1 1 1                     # the texture multiplies Kd: keep it white to see the image as is
//! map_Kd textures/crate.png    # PNG, JPEG, BMP or TGA, relative to the .mtl file; the name may contain spaces
//! ```
//!
//! The image repeats outside [0, 1]; `-clamp on` clamps it to its edge
//! texels instead (see [`crate::texture`] for filtering and colour). Other
//! `map_Kd` options (`-o`, `-s`, `-mm`, ...) are read past with their
//! values, with a warning, and so is every statement strata does not map
//! to its material (`map_Ks`, `disp`, `Tf`, ...): one warning per kind
//! and library, at its first line. Each image file is decoded once however
//! many materials name it. A texture that is missing, unreadable or not a
//! PNG, JPEG, BMP or TGA image is an error at its `map_Kd` line:
//! `meshes/looks.mtl: line 3: cannot read texture
//! meshes/textures/crate.png: No such file or directory`.
//!
//! # Files
//!
//! - `mod.rs`: [`load_obj`], which hands the checked text to `tobj` and turns
//!   its models into a [`LoadedAsset`] (normals only where every face of a
//!   mesh had them).
//! - `scan.rs`: the validation pass described above, and the small rewrite of
//!   lines that `tobj` would misread.
//! - `mtl.rs`: material libraries: reading and checking `.mtl` files,
//!   decoding their textures, and mapping their materials to ours as in the
//!   table above.
//! - `ignored.rs`: what of a library is read past, and the warnings that
//!   say so.
//!
//! [`Material`]: crate::material::Material
//! [`Material::default`]: crate::material::Material::default

mod ignored;
mod mtl;
mod scan;

use super::text::decode_text;
use super::{io_message, Coordinates, Reading};
use crate::error::{InputError, InputResult};
use crate::geometry::{MeshNormals, MeshUvs};
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use glam::{DVec3, Vec2};
use mtl::mtl_to_material;
use scan::{rewrite_for_tobj, scan_obj};
use std::borrow::Cow;
use std::path::Path;

/// Load an OBJ file (and the MTL libraries it names) into a [`LoadedAsset`].
///
/// Errors name the file and, for malformed content, the line. An OBJ without
/// faces loads as an asset without triangles.
pub fn load_obj(path: &Path) -> InputResult<LoadedAsset> {
    load_obj_with(path, Reading::RENDER)
}

/// [`load_obj`], reading what `reading` says: the coordinates kept in
/// float64 where asked (tobj reads them so, `use_f64`; a scene's float32
/// positions are those rounded); without materials, no `mtllib` is read
/// and `usemtl` lines say nothing.
pub fn load_obj_with(path: &Path, reading: Reading) -> InputResult<LoadedAsset> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let text = decode_text(path, &bytes)?;
    let mut scan = scan_obj(path, &text, reading.materials)?;

    let source: Cow<str> = if scan.needs_rewrite {
        Cow::Owned(rewrite_for_tobj(&text, scan.strip_colours))
    } else {
        text
    };
    // tobj's `merging`/`reordering` features add fields; the update keeps
    // this compiling if someone enables them.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let libraries = &scan.libraries;
    let (models, materials) = tobj::load_obj_buf(&mut source.as_bytes(), &options, |lib| {
        // A library the scan could not read (it warned) defines nothing:
        // an error here would make tobj drop every library's materials.
        let Some(materials) = libraries.get(lib) else {
            return Ok((Vec::new(), Default::default()));
        };
        // Later definitions of a name win, as in tobj's own loader.
        let names = materials
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), i))
            .collect();
        Ok((materials.clone(), names))
    })
    .map_err(|e| InputError::file(path, tobj_message(e)))?;
    // Every library was read and checked by the scan (or is missing and
    // defines nothing), so an error here can only mean the file had none.
    let materials = materials.unwrap_or_default();

    let mut asset = LoadedAsset {
        materials: materials
            .iter()
            .map(|m| (m.name.clone(), mtl_to_material(m)))
            .collect(),
        textures: std::mem::take(&mut scan.textures.textures),
        warnings: std::mem::take(&mut scan.warnings),
        ..Default::default()
    };

    // tobj's models hold the faces in file order, so walk the scan's faces
    // alongside to learn whether every face of a model had normals and
    // texture coordinates (tobj fills gaps in either with a neighbour's).
    let mut faces = scan.faces.iter();
    // tobj names the faces before any `o` or `g` "unnamed_object": no name
    // of the file's, so none of ours (errors would quote it as one).
    let name = |model: String| match model == TOBJ_DEFAULT_NAME && !scan.writes_default_name {
        true => String::new(),
        false => model,
    };
    for model in models {
        let mesh = model.mesh;
        let triangle_count = mesh.indices.len() / 3;
        let mut covered = 0usize;
        let mut all_have_normals = true;
        let mut all_have_texcoords = true;
        while covered < triangle_count {
            let Some(face) = faces.next() else { break };
            covered += face.triangles as usize;
            all_have_normals &= face.has_normals;
            all_have_texcoords &= face.has_texcoords;
        }
        if triangle_count == 0 {
            continue;
        }
        let indices = triangles(&mesh.indices);
        let normals = (all_have_normals
            && covered == triangle_count
            && !mesh.normals.is_empty()
            && mesh.normal_indices.len() == mesh.indices.len())
        .then(|| MeshNormals {
            values: vec3s(&mesh.normals).map(|n| n.as_vec3()).collect(),
            indices: triangles(&mesh.normal_indices),
        });
        let material = mesh.material_id.filter(|&i| i < asset.materials.len());
        // UVs only for a mesh whose material has a texture to look up.
        let textured = material.is_some_and(|i| asset.materials[i].1.is_textured());
        let uvs = (textured
            && all_have_texcoords
            && covered == triangle_count
            && !mesh.texcoords.is_empty()
            && mesh.texcoord_indices.len() == mesh.indices.len())
        .then(|| MeshUvs {
            // OBJ's v runs up from the image's bottom row; ours runs down
            // from its top row.
            values: mesh
                .texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0] as f32, 1.0 - t[1] as f32))
                .collect(),
            indices: triangles(&mesh.texcoord_indices),
        });
        asset.meshes.push(LoadedMesh {
            name: name(model.name),
            positions: vec3s(&mesh.positions).map(|p| p.as_vec3()).collect(),
            exact_positions: (reading.coordinates == Coordinates::Float64)
                .then(|| vec3s(&mesh.positions).collect()),
            indices,
            normals,
            material,
            uvs,
            tangents: None,
            mirrored: false,
        });
    }
    super::warn_without_triangles(&mut asset, path, "no faces");
    Ok(asset)
}

/// The name tobj gives the faces no `o` or `g` line names.
const TOBJ_DEFAULT_NAME: &str = "unnamed_object";

fn vec3s(flat: &[f64]) -> impl Iterator<Item = DVec3> + '_ {
    flat.chunks_exact(3).map(DVec3::from_slice)
}

fn triangles(flat: &[u32]) -> Vec<[u32; 3]> {
    flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
}

fn tobj_message(e: tobj::LoadError) -> String {
    match e {
        tobj::LoadError::FaceVertexOutOfBounds => "a face refers to a vertex defined after the \
            end of its object; define vertices before the faces that use them"
            .to_string(),
        other => format!("cannot parse OBJ: {other}"),
    }
}

/// A number (any f32, infinities included), or a message naming `what`.
pub(super) fn parse_number(token: &str, what: &str) -> Result<f32, String> {
    token
        .parse::<f32>()
        .map_err(|_| format!("{what}: '{token}' is not a number"))
}

/// A finite number, or a message naming `what`. The OBJ scan and the MTL
/// reader both check numbers with it, so both refuse the same ones.
pub(super) fn parse_finite(token: &str, what: &str) -> Result<f32, String> {
    let value = parse_number(token, what)?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!(
            "{what}: '{token}' is not a finite number (NaN, infinite or too large)"
        ))
    }
}

/// Helpers for the unit tests of all three files: they load OBJ text through
/// [`load_obj`], the way a user's file would be loaded.
#[cfg(test)]
mod test_helpers {
    use super::super::test_files::{temp_dir, write};
    use super::load_obj;
    use crate::error::InputResult;
    use crate::scene::asset::LoadedAsset;
    use glam::Vec3;

    /// Load `text` as `mesh.obj` from a fresh temporary directory.
    pub(super) fn load_text(text: &str) -> InputResult<LoadedAsset> {
        let dir = temp_dir("text");
        load_obj(&write(&dir, "mesh.obj", text.as_bytes()))
    }

    /// The world-space corners of every triangle, in order.
    pub(super) fn corners(asset: &LoadedAsset) -> Vec<[Vec3; 3]> {
        asset
            .meshes
            .iter()
            .flat_map(|m| {
                m.indices.iter().map(|t| {
                    [
                        m.positions[t[0] as usize],
                        m.positions[t[1] as usize],
                        m.positions[t[2] as usize],
                    ]
                })
            })
            .collect()
    }

    /// The unit square's corners as `v` 1 to 4, for faces to index.
    pub(super) const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
}

#[cfg(test)]
mod tests {
    use super::test_helpers::{corners, load_text, SQUARE};
    use super::*;
    use glam::Vec3;

    use super::super::test_files::{temp_dir, write};

    #[test]
    fn quad_and_pentagon_fan_triangulate_in_file_order() {
        let text = format!(
            "{SQUARE}v 2 0 0\nv 3 0 0\nv 3 1 0\nv 2.5 2 0\nv 2 1 0\n\
             f 1 2 3 4\nf 5 6 7 8 9\nf 1 2 3\n"
        );
        let asset = load_text(&text).unwrap();
        assert_eq!(asset.meshes.len(), 1);
        assert_eq!(asset.triangle_count(), 2 + 3 + 1);
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        assert_eq!(
            corners(&asset),
            vec![
                [v(0., 0.), v(1., 0.), v(1., 1.)],
                [v(0., 0.), v(1., 1.), v(0., 1.)],
                [v(2., 0.), v(3., 0.), v(3., 1.)],
                [v(2., 0.), v(3., 1.), v(2.5, 2.)],
                [v(2., 0.), v(2.5, 2.), v(2., 1.)],
                [v(0., 0.), v(1., 0.), v(1., 1.)],
            ]
        );
    }

    #[test]
    fn negative_indices_count_back_from_the_last_vertex() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf -1 -2 1\n";
        let asset = load_text(text).unwrap();
        assert_eq!(
            corners(&asset),
            vec![
                [Vec3::ZERO, Vec3::X, Vec3::Y],
                [Vec3::new(5., 6., 5.), Vec3::new(6., 5., 5.), Vec3::ZERO],
            ]
        );
    }

    #[test]
    fn faces_no_object_names_have_no_name() {
        let text = format!("{SQUARE}f 1 2 3\no named\nf 1 3 4\n");
        let asset = load_text(&text).unwrap();
        let names: Vec<&str> = asset.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["", "named"]);
        // The name tobj gives unnamed faces, written in the file, is kept.
        let text = format!("{SQUARE}o unnamed_object\nf 1 2 3\n");
        assert_eq!(load_text(&text).unwrap().meshes[0].name, "unnamed_object");
    }

    #[test]
    fn objects_become_meshes_in_file_order() {
        let text = format!("{SQUARE}o first\nf 1 2 3\no second\nf 1 3 4\nf 4 3 2\ng empty\n");
        let asset = load_text(&text).unwrap();
        let names: Vec<&str> = asset.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["first", "second"]);
        assert_eq!(asset.meshes[0].indices.len(), 1);
        assert_eq!(asset.meshes[1].indices.len(), 2);
        let c = corners(&asset);
        assert_eq!(c[1], [Vec3::ZERO, Vec3::new(1., 1., 0.), Vec3::Y]);
        assert_eq!(c[2], [Vec3::Y, Vec3::new(1., 1., 0.), Vec3::X]);
    }

    #[test]
    fn normals_only_when_the_file_has_them() {
        let plain = load_text(&format!("{SQUARE}f 1 2 3 4\n")).unwrap();
        assert!(plain.meshes[0].normals.is_none());

        let text = format!("{SQUARE}vn 0 0 1\nvn 0 0 -1\nf 1//1 2//1 3//2 4//2\n");
        let with = load_text(&text).unwrap();
        let normals = with.meshes[0].normals.as_ref().expect("normals");
        assert_eq!(normals.indices.len(), 2);
        let looked_up: Vec<[Vec3; 3]> = normals
            .indices
            .iter()
            .map(|t| t.map(|i| normals.values[i as usize]))
            .collect();
        let (up, down) = (Vec3::Z, -Vec3::Z);
        assert_eq!(looked_up, vec![[up, up, down], [up, down, down]]);
    }

    #[test]
    fn mixed_normals_in_one_mesh_are_dropped_not_invented() {
        let text = format!("{SQUARE}vn 0 0 1\no a\nf 1//1 2//1 3//1\nf 1 3 4\no b\nf 1//1 3//1 4//1\no c\nf 2 3 4\n");
        let asset = load_text(&text).unwrap();
        let has: Vec<bool> = asset.meshes.iter().map(|m| m.normals.is_some()).collect();
        assert_eq!(has, [false, true, false]);
        // A corner without vn in an otherwise normal face drops them too.
        let asset = load_text(&format!("{SQUARE}vn 0 0 1\nf 1//1 2 3//1\n")).unwrap();
        assert!(asset.meshes[0].normals.is_none());
    }

    #[test]
    fn empty_and_faceless_files_load_without_triangles_and_warn() {
        assert_eq!(load_text("").unwrap().triangle_count(), 0);
        let points = load_text("# nothing\nv 1 2 3\nv 0 0 0\nl 1 2\n").unwrap();
        assert_eq!(points.triangle_count(), 0);
        assert!(load_text("").unwrap().meshes.is_empty());
        assert_eq!(points.warnings.len(), 1);
        let shown = points.warnings[0].to_string();
        assert!(shown.contains("mesh.obj: no faces"), "{shown}");
    }

    #[test]
    fn utf16_files_with_a_byte_order_mark_load_like_utf8() {
        let text = format!("{SQUARE}f 1 2 3 4\r\n");
        let plain = load_text(&text).unwrap();
        for big_endian in [false, true] {
            let mut bytes = if big_endian {
                vec![0xfe, 0xff]
            } else {
                vec![0xff, 0xfe]
            };
            for unit in text.encode_utf16() {
                bytes.extend(if big_endian {
                    unit.to_be_bytes()
                } else {
                    unit.to_le_bytes()
                });
            }
            assert_eq!(load_text_bytes(&bytes).unwrap(), plain);
        }
    }

    #[test]
    fn missing_file_names_the_file() {
        let err = load_obj(Path::new("/definitely/not/here.obj")).unwrap_err();
        assert_eq!(
            err.to_string(),
            "/definitely/not/here.obj: cannot read: No such file or directory"
        );
    }

    #[test]
    fn garbage_never_panics() {
        let err = load_text_bytes(&[b'\n', 0x80, 0x00, b'\n']).unwrap_err();
        assert_eq!(err.location, "line 2");
        // Pseudo-random bytes and pseudo-random OBJ-ish text.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let words = [
            "v", "vn", "vt", "f", "l", "o", "g", "usemtl", "mtllib", "1", "-1", "0", "2/3", "1//1",
            "-7", "1e38", "nan", "x", "\n", "\n", "\n", "3", "/", "//", "1/1/1",
        ];
        let dir = temp_dir("fuzz");
        for round in 0..300 {
            let bytes: Vec<u8> = if round % 3 == 0 {
                (0..next() % 200).map(|_| next() as u8).collect()
            } else {
                let mut s = String::new();
                for _ in 0..next() % 120 {
                    s.push_str(words[(next() % words.len() as u64) as usize]);
                    s.push(' ');
                }
                s.into_bytes()
            };
            let _ = load_obj(&write(&dir, "fuzz.obj", &bytes));
        }
    }

    fn load_text_bytes(bytes: &[u8]) -> InputResult<LoadedAsset> {
        let dir = temp_dir("bytes");
        load_obj(&write(&dir, "mesh.obj", bytes))
    }
}
