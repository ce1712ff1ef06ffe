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
//! gets none (`normals: None`) rather than invented ones.
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
//! `mtllib` names a material library relative to the OBJ file (a missing one
//! is an error). Each `newmtl` becomes one entry of
//! [`LoadedAsset::materials`], in library order, and `usemtl` sets the
//! mesh's material index. A `usemtl` naming a material that no earlier
//! `mtllib` defines is an error; in a file with no `mtllib` at all, `usemtl`
//! is ignored and the meshes get the scene's default material.
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
//! | `Ka`, `Tf`, `map_*`, `bump`, others | ignored                                          |
//!
//! A colour given as one number (`Kd 0.5`) is a grey. Every other field keeps
//! its [`Material::default`] value.

use super::io_message;
use crate::error::{InputError, InputResult};
use crate::geometry::MeshNormals;
use crate::material::Material;
use crate::scene::asset::{LoadedAsset, LoadedMesh};
use glam::Vec3;
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// The materials of one `mtllib` line, in library order.
type MtlLibrary = Vec<tobj::Material>;

/// Load an OBJ file (and the MTL libraries it names) into a [`LoadedAsset`].
///
/// Errors name the file and, for malformed content, the line. An OBJ without
/// faces loads as an asset without triangles.
pub fn load_obj(path: &Path) -> InputResult<LoadedAsset> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::file(path, format!("cannot read: {}", io_message(&e))))?;
    let text = utf8_text(path, &bytes)?;
    let scan = scan_obj(path, text)?;

    let source: Cow<str> = if scan.needs_rewrite {
        Cow::Owned(rewrite_for_tobj(text, scan.strip_colours))
    } else {
        Cow::Borrowed(text)
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
        let materials = libraries.get(lib).ok_or(tobj::LoadError::OpenFileFailed)?;
        // Later definitions of a name win, as in tobj's own loader.
        let names = materials
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), i))
            .collect();
        Ok((materials.clone(), names))
    })
    .map_err(|e| InputError::file(path, tobj_message(e)))?;
    // Every library was read and checked by the scan, so an error here can
    // only mean the file had none; that is not a problem.
    let materials = materials.unwrap_or_default();

    let mut asset = LoadedAsset {
        materials: materials
            .iter()
            .map(|m| (m.name.clone(), mtl_to_material(m)))
            .collect(),
        ..Default::default()
    };

    // tobj's models hold the faces in file order, so walk the scan's faces
    // alongside to learn whether every face of a model had normals.
    let mut faces = scan.faces.iter();
    for model in models {
        let mesh = model.mesh;
        let triangle_count = mesh.indices.len() / 3;
        let mut covered = 0usize;
        let mut all_have_normals = true;
        while covered < triangle_count {
            let Some(face) = faces.next() else { break };
            covered += face.triangles as usize;
            all_have_normals &= face.has_normals;
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
            values: vec3s(&mesh.normals),
            indices: triangles(&mesh.normal_indices),
        });
        asset.meshes.push(LoadedMesh {
            name: model.name,
            positions: vec3s(&mesh.positions),
            indices,
            normals,
            material: mesh.material_id.filter(|&i| i < asset.materials.len()),
        });
    }
    Ok(asset)
}

/// Map one MTL material to ours; see the table in the module documentation.
fn mtl_to_material(m: &tobj::Material) -> Material {
    let defaults = Material::default();
    let specular = m.specular.map(Vec3::from).unwrap_or(Vec3::ZERO);
    let mut transparency = match m.dissolve {
        Some(d) => 1.0 - d,
        None => m
            .unknown_param
            .get("Tr")
            .and_then(|t| t.split_whitespace().next())
            .and_then(|t| t.parse::<f32>().ok())
            .unwrap_or(0.0),
    };
    if !transparency.is_finite() {
        transparency = 0.0;
    }
    let illum = m.illumination_model.unwrap_or(0);
    let mirror = matches!(illum, 3 | 5 | 7);
    Material {
        diffuse: m.diffuse.map(Vec3::from).unwrap_or(defaults.diffuse),
        specular,
        shininess: m.shininess.unwrap_or(0.0),
        reflectivity: if mirror { specular.max_element() } else { 0.0 },
        glossiness: 0.0,
        transparency: transparency.clamp(0.0, 1.0),
        ior: m
            .optical_density
            .filter(|n| n.is_finite() && *n > 0.0)
            .unwrap_or(defaults.ior),
        fresnel: matches!(illum, 5 | 7),
        emission: m.emissive.map(Vec3::from).unwrap_or(Vec3::ZERO),
        ..defaults
    }
}

fn vec3s(flat: &[f32]) -> Vec<Vec3> {
    flat.chunks_exact(3).map(Vec3::from_slice).collect()
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

/// The file as text (a leading byte-order mark dropped), or an error at the
/// first line that is not UTF-8.
fn utf8_text<'a>(path: &Path, bytes: &'a [u8]) -> InputResult<&'a str> {
    match std::str::from_utf8(bytes) {
        Ok(text) => Ok(text.strip_prefix('\u{feff}').unwrap_or(text)),
        Err(e) => {
            let good = &bytes[..e.valid_up_to()];
            let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
            Err(InputError::new(
                path,
                format!("line {line}"),
                "not UTF-8 text (is this really an OBJ/MTL text file?)",
            ))
        }
    }
}

/// What the validation pass learned about one `f` line.
#[derive(Clone, Copy)]
struct FaceInfo {
    triangles: u32,
    has_normals: bool,
}

/// The result of the validation pass over an OBJ file.
struct ObjScan {
    faces: Vec<FaceInfo>,
    /// Material libraries keyed by the text after `mtllib`, as tobj asks for them.
    libraries: HashMap<PathBuf, MtlLibrary>,
    /// The text needs adjusting before tobj can read it (see [`rewrite_for_tobj`]).
    needs_rewrite: bool,
    /// Some `v` lines have colours and others not: drop the colours.
    strip_colours: bool,
}

/// How many `v`, `vt` and `vn` lines a file has, for absolute indices.
#[derive(Default, Clone, Copy)]
struct Counts {
    v: usize,
    vt: usize,
    vn: usize,
    /// Whether any `mtllib` line exists.
    mtllib: bool,
}

fn count_elements(text: &str) -> Counts {
    let mut counts = Counts::default();
    for line in text.split('\n') {
        match line.split_whitespace().next() {
            Some("v") => counts.v += 1,
            Some("vt") => counts.vt += 1,
            Some("vn") => counts.vn += 1,
            Some("mtllib") => counts.mtllib = true,
            _ => {}
        }
    }
    counts
}

fn parse_number(token: &str, what: &str) -> Result<f32, String> {
    token
        .parse::<f32>()
        .map_err(|_| format!("{what}: '{token}' is not a number"))
}

fn parse_finite(token: &str, what: &str) -> Result<f32, String> {
    let value = parse_number(token, what)?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!(
            "{what}: '{token}' is not a finite number (NaN, infinite or too large)"
        ))
    }
}

/// Check one index of a face corner: `kind` names it for messages,
/// `so_far` is how many elements precede the face, `total` how many the file has.
fn check_index(
    text: &str,
    (singular, plural): (&str, &str),
    so_far: usize,
    total: usize,
) -> Result<(), String> {
    let index: isize = text
        .parse()
        .map_err(|_| format!("'{text}' is not an integer {singular} index"))?;
    if index == 0 {
        return Err(format!(
            "{singular} index 0 is invalid (OBJ indices start at 1)"
        ));
    }
    if index < 0 {
        if index.unsigned_abs() > so_far {
            return Err(format!(
                "relative {singular} index {index} reaches before the first {singular} \
                 (only {so_far} {plural} are defined before this line)"
            ));
        }
    } else if index as usize > total {
        return Err(format!(
            "{singular} index {index} is out of range (the file defines {total} {plural})"
        ));
    }
    Ok(())
}

/// Validate a face's vertex tokens; returns whether every corner has a normal.
fn check_face(tokens: &[&str], defined: Counts, total: Counts) -> Result<bool, String> {
    if tokens.len() < 3 {
        return Err(format!(
            "a face needs at least 3 vertices, this one has {}",
            tokens.len()
        ));
    }
    let mut has_normals = true;
    for token in tokens {
        let parts: Vec<&str> = token.split('/').collect();
        if parts.len() > 3 {
            return Err(format!(
                "'{token}' is not a face vertex (expected v, v/vt, v//vn or v/vt/vn)"
            ));
        }
        if parts[0].is_empty() {
            return Err(format!("'{token}' has no vertex index"));
        }
        check_index(parts[0], ("vertex", "vertices"), defined.v, total.v)?;
        if let Some(vt) = parts.get(1).filter(|p| !p.is_empty()) {
            check_index(
                vt,
                ("texture coordinate", "texture coordinates"),
                defined.vt,
                total.vt,
            )?;
        }
        match parts.get(2).filter(|p| !p.is_empty()) {
            Some(vn) => check_index(vn, ("normal", "normals"), defined.vn, total.vn)?,
            None => has_normals = false,
        }
    }
    Ok(has_normals)
}

/// The text after the first space, trimmed, as tobj reads `usemtl`/`mtllib`.
fn after_first_space(line: &str) -> &str {
    line.split_once(' ')
        .map(|(_, rest)| rest.trim())
        .unwrap_or("")
}

/// The validation pass: checks everything tobj would reject (or silently
/// mangle), with line numbers, and loads the material libraries.
fn scan_obj(path: &Path, text: &str) -> InputResult<ObjScan> {
    let total = count_elements(text);
    let mut defined = Counts::default();
    let mut scan = ObjScan {
        faces: Vec::new(),
        libraries: HashMap::new(),
        needs_rewrite: false,
        strip_colours: false,
    };
    let mut coloured_vertices = 0usize;
    let mut material_names: HashSet<String> = HashSet::new();

    for (number, line) in text.split('\n').enumerate() {
        let at = |message: String| InputError::new(path, format!("line {}", number + 1), message);
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let rest: Vec<&str> = match keyword {
            "v" | "vt" | "vn" | "f" | "l" => words.collect(),
            _ => Vec::new(),
        };
        match keyword {
            "v" => {
                if !matches!(rest.len(), 3 | 4 | 6) {
                    return Err(at(format!(
                        "a vertex needs 3 coordinates x y z (optionally followed by w, \
                         or by r g b), this one has {} numbers",
                        rest.len()
                    )));
                }
                let mut xyz = [0.0f32; 3];
                for (i, token) in rest[..3].iter().enumerate() {
                    xyz[i] = parse_finite(token, "vertex coordinate").map_err(&at)?;
                }
                if rest.len() == 4 {
                    let w = parse_finite(rest[3], "vertex weight w").map_err(&at)?;
                    if w == 0.0 || xyz.iter().any(|c| !(c / w).is_finite()) {
                        return Err(at(format!(
                            "vertex weight w = {w} would make the coordinates infinite"
                        )));
                    }
                }
                if rest.len() == 6 {
                    for token in &rest[3..] {
                        parse_number(token, "vertex colour").map_err(&at)?;
                    }
                    coloured_vertices += 1;
                }
                defined.v += 1;
            }
            "vt" => {
                if rest.is_empty() {
                    return Err(at("a texture coordinate needs at least u".to_string()));
                }
                for token in rest.iter().take(2) {
                    parse_finite(token, "texture coordinate").map_err(&at)?;
                }
                if rest.len() == 1 {
                    scan.needs_rewrite = true;
                }
                defined.vt += 1;
            }
            "vn" => {
                if rest.len() < 3 {
                    return Err(at(format!(
                        "a normal needs 3 numbers x y z, this one has {}",
                        rest.len()
                    )));
                }
                for token in &rest[..3] {
                    parse_finite(token, "normal component").map_err(&at)?;
                }
                defined.vn += 1;
            }
            "f" => {
                let has_normals = check_face(&rest, defined, total).map_err(&at)?;
                scan.faces.push(FaceInfo {
                    triangles: (rest.len() - 2) as u32,
                    has_normals,
                });
            }
            "l" => {
                // Polylines are ignored, but tobj triangulates an `l` with three
                // or more vertices and rejects malformed ones: drop them first.
                let well_formed = matches!(rest.len(), 1 | 2)
                    && rest.iter().all(|t| {
                        let parts: Vec<&str> = t.split('/').collect();
                        parts.len() <= 3
                            && parts
                                .iter()
                                .all(|p| p.is_empty() || p.parse::<isize>().is_ok())
                    });
                if !well_formed {
                    scan.needs_rewrite = true;
                }
            }
            "usemtl" => {
                let name = after_first_space(line);
                if name.is_empty() {
                    return Err(at(
                        "usemtl needs a material name, separated by a space".to_string()
                    ));
                }
                if !material_names.contains(name) && total.mtllib {
                    return Err(at(format!(
                        "material '{name}' is not defined by any mtllib before this line"
                    )));
                }
            }
            "mtllib" => {
                let name = after_first_space(line);
                if name.is_empty() {
                    return Err(at(
                        "mtllib needs a file name, separated by a space".to_string()
                    ));
                }
                let library = load_library(path, name).map_err(|e| match e {
                    LibraryError::Input(e) => e,
                    LibraryError::Read(message) => at(message),
                })?;
                material_names.extend(library.iter().map(|m| m.name.clone()));
                scan.libraries.insert(PathBuf::from(name), library);
            }
            _ => {}
        }
    }
    if coloured_vertices > 0 && coloured_vertices < defined.v {
        scan.needs_rewrite = true;
        scan.strip_colours = true;
    }
    Ok(scan)
}

/// Prepare text that tobj can read as we mean it: drop `l` lines (tobj
/// would triangulate or reject some), give one-number `vt` lines a v of 0,
/// and drop vertex colours when only some vertices have them (tobj would
/// fail on the others). Line count is kept.
fn rewrite_for_tobj(text: &str, strip_colours: bool) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.split('\n') {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("l") => {}
            Some("v") if strip_colours => {
                let tokens: Vec<&str> = words.collect();
                if tokens.len() == 6 {
                    out.push_str("v ");
                    out.push_str(&tokens[..3].join(" "));
                } else {
                    out.push_str(line);
                }
            }
            Some("vt") => {
                let tokens: Vec<&str> = words.collect();
                if tokens.len() == 1 {
                    out.push_str("vt ");
                    out.push_str(tokens[0]);
                    out.push_str(" 0");
                } else {
                    out.push_str(line);
                }
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

enum LibraryError {
    /// A problem inside a library, already naming the library file.
    Input(InputError),
    /// The library could not be read; to be reported at the `mtllib` line.
    Read(String),
}

/// Load the material libraries named after `mtllib`. tobj reads the whole
/// rest of the line as one file name (names may contain spaces); if no such
/// file exists and the text has several words, each word is a library.
fn load_library(obj_path: &Path, name: &str) -> Result<MtlLibrary, LibraryError> {
    let dir = obj_path.parent().unwrap_or(Path::new(""));
    let whole = dir.join(name);
    let files: Vec<PathBuf> = if whole.is_file() || !name.contains(char::is_whitespace) {
        vec![whole]
    } else {
        name.split_whitespace().map(|n| dir.join(n)).collect()
    };
    let mut materials = Vec::new();
    for file in files {
        let bytes = std::fs::read(&file).map_err(|e| {
            LibraryError::Read(format!(
                "cannot read material library {}: {}",
                file.display(),
                io_message(&e)
            ))
        })?;
        materials.append(&mut parse_mtl(&file, &bytes).map_err(LibraryError::Input)?);
    }
    Ok(materials)
}

/// Validate an MTL file line by line (errors name it and the line), bring
/// colours into the `r g b` form tobj needs, then let tobj parse it.
fn parse_mtl(path: &Path, bytes: &[u8]) -> InputResult<MtlLibrary> {
    let text = utf8_text(path, bytes)?;
    let mut normalized = String::with_capacity(text.len());
    for (number, raw) in text.split('\n').enumerate() {
        let at = |message: String| InputError::new(path, format!("line {}", number + 1), message);
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let tokens: Vec<&str> = words.collect();
        let after_keyword = line.get(keyword.len()..).unwrap_or("").trim();
        match keyword {
            "newmtl" => {
                if after_keyword.is_empty() {
                    return Err(at("newmtl needs a material name".to_string()));
                }
                normalized.push_str(line);
            }
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let rgb = parse_colour(keyword, &tokens).map_err(&at)?;
                normalized.push_str(&format!("{keyword} {} {} {}", rgb[0], rgb[1], rgb[2]));
            }
            "Ns" | "Ni" | "d" | "Tr" => {
                let value = tokens
                    .iter()
                    .find(|t| **t != "-halo")
                    .ok_or_else(|| at(format!("{keyword} needs a number")))?;
                let value = parse_finite(value, keyword).map_err(&at)?;
                normalized.push_str(&format!("{keyword} {value}"));
            }
            "illum" => {
                let ok = tokens.len() == 1 && tokens[0].parse::<u8>().is_ok();
                if !ok {
                    return Err(at(format!(
                        "illum needs one illumination model number 0-10, found '{after_keyword}'"
                    )));
                }
                normalized.push_str(line);
            }
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Ns" | "map_ns" | "map_NS" | "map_d"
            | "map_Bump" | "map_bump" | "bump" => {
                if after_keyword.is_empty() {
                    return Err(at(format!("{keyword} needs a file name")));
                }
                normalized.push_str(line);
            }
            _ => normalized.push_str(line),
        }
        normalized.push('\n');
    }
    tobj::load_mtl_buf(&mut normalized.as_bytes())
        .map(|(materials, _)| materials)
        .map_err(|e| InputError::file(path, format!("cannot parse MTL: {e}")))
}

/// `r g b`, or one number for a grey; other MTL colour forms are refused.
fn parse_colour(keyword: &str, tokens: &[&str]) -> Result<[f32; 3], String> {
    match tokens {
        [] => Err(format!("{keyword} needs a colour r g b")),
        [form, ..] if *form == "spectral" || *form == "xyz" => Err(format!(
            "{keyword} {form} colours are not supported; give r g b"
        )),
        [grey] => {
            let v = parse_finite(grey, keyword)?;
            Ok([v; 3])
        }
        [_, _] => Err(format!(
            "{keyword} needs r g b (or one number for a grey), found 2 numbers"
        )),
        [r, g, b, ..] => Ok([
            parse_finite(r, keyword)?,
            parse_finite(g, keyword)?,
            parse_finite(b, keyword)?,
        ]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::super::test_files::{temp_dir, write};

    fn load_text(text: &str) -> InputResult<LoadedAsset> {
        let dir = temp_dir("text");
        load_obj(&write(&dir, "mesh.obj", text.as_bytes()))
    }

    /// The world-space corners of every triangle, in order.
    fn corners(asset: &LoadedAsset) -> Vec<[Vec3; 3]> {
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

    fn expect_line_error(text: &str, line: usize, needle: &str) {
        let err = load_text(text).expect_err("expected an error");
        let shown = err.to_string();
        assert!(shown.contains("mesh.obj"), "{shown}");
        assert_eq!(err.location, format!("line {line}"), "{shown}");
        assert!(
            shown.contains(&format!("line {line}:")),
            "{shown} should name line {line}"
        );
        assert!(shown.contains(needle), "{shown} should contain '{needle}'");
    }

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

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
    fn mtl_values_map_to_materials() {
        let dir = temp_dir("mtl");
        write(
            &dir,
            "looks.mtl",
            b"# test library\nnewmtl matte\nKd 0.5 0.25 0.125\n\
              newmtl mirror\nKd 0 0 0\nKs 0.9 0.8 0.7\nNs 200\nillum 3\n\
              newmtl glass\nKd 0.1\nd 0.25\nNi 1.33\nillum 7\n\
              newmtl lamp\nKe 4 3 2\nTr 0.5\n",
        );
        let obj =
            format!("mtllib looks.mtl\n{SQUARE}o a\nusemtl mirror\nf 1 2 3\no b\nusemtl lamp\nf 1 3 4\no c\nf 2 3 4\n");
        let asset = load_obj(&write(&dir, "scene.obj", obj.as_bytes())).unwrap();
        let names: Vec<&str> = asset.materials.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["matte", "mirror", "glass", "lamp"]);
        let m = |name: &str| asset.materials.iter().find(|(n, _)| n == name).unwrap().1;

        let matte = m("matte");
        assert_eq!(matte.diffuse, Vec3::new(0.5, 0.25, 0.125));
        assert_eq!(matte.specular, Vec3::ZERO);
        assert_eq!(matte.reflectivity, 0.0);
        assert_eq!(matte.transparency, 0.0);

        let mirror = m("mirror");
        assert_eq!(mirror.specular, Vec3::new(0.9, 0.8, 0.7));
        assert_eq!(mirror.shininess, 200.0);
        assert_eq!(mirror.reflectivity, 0.9);
        assert_eq!(mirror.glossiness, 0.0);
        assert!(!mirror.fresnel);

        let glass = m("glass");
        assert_eq!(glass.diffuse, Vec3::splat(0.1));
        assert_eq!(glass.transparency, 0.75);
        assert_eq!(glass.ior, 1.33);
        assert!(glass.fresnel);

        let lamp = m("lamp");
        assert_eq!(lamp.emission, Vec3::new(4.0, 3.0, 2.0));
        assert_eq!(lamp.transparency, 0.5);
        assert_eq!(lamp.diffuse, Material::default().diffuse);

        let materials: Vec<Option<usize>> = asset.meshes.iter().map(|m| m.material).collect();
        // Object c has no usemtl of its own but inherits the current one, as OBJ does.
        assert_eq!(materials, [Some(1), Some(3), Some(3)]);
    }

    #[test]
    fn missing_mtl_is_an_error_naming_it() {
        let err = load_text(&format!("{SQUARE}mtllib nowhere.mtl\nf 1 2 3\n")).unwrap_err();
        let shown = err.to_string();
        assert!(shown.contains("nowhere.mtl"), "{shown}");
        assert!(shown.contains("No such file or directory"), "{shown}");
        assert_eq!(err.location, "line 5");
    }

    #[test]
    fn mtl_errors_name_the_library_and_line() {
        let dir = temp_dir("badmtl");
        write(&dir, "bad.mtl", b"newmtl a\nKd 1 1 1\nNs lots\n");
        let obj = write(&dir, "m.obj", b"mtllib bad.mtl\nv 0 0 0\n");
        let err = load_obj(&obj).unwrap_err();
        assert!(err.file.ends_with("bad.mtl"), "{err}");
        assert_eq!(err.location, "line 3");
        write(&dir, "two.mtl", b"newmtl a\nKd 1 1\n");
        let obj = write(&dir, "n.obj", b"mtllib two.mtl\n");
        let err = load_obj(&obj).unwrap_err();
        assert!(
            err.file.ends_with("two.mtl") && err.location == "line 2",
            "{err}"
        );
    }

    #[test]
    fn unknown_usemtl_is_an_error_only_with_a_library() {
        let dir = temp_dir("usemtl");
        write(&dir, "lib.mtl", b"newmtl known\n");
        let obj = format!("mtllib lib.mtl\n{SQUARE}usemtl unknown\nf 1 2 3\n");
        let err = load_obj(&write(&dir, "a.obj", obj.as_bytes())).unwrap_err();
        assert_eq!(err.location, "line 6", "{err}");
        assert!(err.to_string().contains("unknown"), "{err}");
        let asset = load_text(&format!("{SQUARE}usemtl whatever\nf 1 2 3\n")).unwrap();
        assert_eq!(asset.meshes[0].material, None);
        assert!(asset.materials.is_empty());
    }

    #[test]
    fn bad_vertices_report_their_line() {
        expect_line_error("v 0 0 0\nv 1 0\n", 2, "3 coordinates");
        expect_line_error("v 0 0 0\n\nv 1 zero 0\n", 3, "'zero' is not a number");
        expect_line_error("# c\nv nan 0 0\n", 2, "not a finite number");
        expect_line_error("v 0 0 inf\n", 1, "not a finite number");
        expect_line_error("v 1e39 0 0\n", 1, "not a finite number");
        expect_line_error("v 0 0 0 0\n", 1, "weight");
        expect_line_error("v 0 0 0\nvn 0 NaN 1\n", 2, "not a finite number");
        expect_line_error("vn 0 1\n", 1, "3 numbers");
    }

    #[test]
    fn bad_faces_report_their_line() {
        expect_line_error(&format!("{SQUARE}f 1 2\n"), 5, "at least 3 vertices");
        expect_line_error(&format!("{SQUARE}f 1 2 3\nf 0 1 2\n"), 6, "index 0");
        expect_line_error(&format!("{SQUARE}f 1 2 x\n"), 5, "'x' is not an integer");
        expect_line_error(&format!("{SQUARE}f 1 2 3.5\n"), 5, "not an integer");
        expect_line_error(&format!("{SQUARE}f 1 2 5\n"), 5, "out of range");
        expect_line_error(&format!("{SQUARE}f -1 -2 -5\n"), 5, "before the first");
        expect_line_error(
            &format!("v 0 0 0\nf -1 -2 -3\n{SQUARE}"),
            2,
            "only 1 vertices",
        );
        expect_line_error(&format!("{SQUARE}f 1//1 2//1 3//1\n"), 5, "normal index 1");
        expect_line_error(&format!("{SQUARE}vt 0 0\nf 1/2 2/1 3/1\n"), 6, "texture");
        expect_line_error(&format!("{SQUARE}f 1/1/1/1 2 3\n"), 5, "not a face vertex");
        expect_line_error(
            &format!("{SQUARE}f 99999999999999999999 2 3\n"),
            5,
            "integer",
        );
    }

    #[test]
    fn absolute_indices_may_refer_forward_within_an_object() {
        // Absolute indices are checked against the whole file.
        let asset = load_text("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(corners(&asset), vec![[Vec3::ZERO, Vec3::X, Vec3::Y]]);
    }

    #[test]
    fn empty_and_faceless_files_load_without_triangles() {
        assert_eq!(load_text("").unwrap().triangle_count(), 0);
        assert_eq!(
            load_text("# nothing\nv 1 2 3\n").unwrap().triangle_count(),
            0
        );
        assert!(load_text("").unwrap().meshes.is_empty());
    }

    #[test]
    fn lines_points_colours_and_short_texcoords_are_tolerated() {
        let text =
            "v 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.5\nl 1 2 3 4\nl 1\nl\nf 1/1 2/1 3/1\n";
        let asset = load_text(text).unwrap();
        assert_eq!(
            corners(&asset),
            vec![[Vec3::ZERO, Vec3::X, Vec3::new(1., 1., 0.)]]
        );
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
        let err = load_text_bytes(&[0xff, 0xfe, 0x00, 0x80, b'\n']).unwrap_err();
        assert_eq!(err.location, "line 1");
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

    #[test]
    fn garbage_material_libraries_never_panic() {
        let dir = temp_dir("mtlfuzz");
        write(
            &dir,
            "f.obj",
            b"mtllib f.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        );
        let words = [
            "newmtl", "a", "Kd", "Ks", "Ke", "Ka", "Ns", "Ni", "d", "Tr", "illum", "map_Kd",
            "bump", "map_Bump", "1", "0.5", "-3", "300", "x", "spectral", "xyz", "-halo", "nan",
            "\n", "\n", "\n", "\t", "#",
        ];
        let mut state = 0x0dd_b1a5_e5ca_fe01u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut loaded = 0;
        for _ in 0..300 {
            let mut s = String::from("newmtl a\n");
            for _ in 0..next() % 40 {
                s.push_str(words[(next() % words.len() as u64) as usize]);
                s.push(' ');
            }
            write(&dir, "f.mtl", s.as_bytes());
            if let Ok(asset) = load_obj(&dir.join("f.obj")) {
                loaded += 1;
                let index = asset.meshes[0].material.expect("usemtl a");
                assert_eq!(asset.materials[index].0, "a");
            }
        }
        assert!(loaded > 0);
    }

    #[test]
    fn mutated_numbers_in_a_valid_obj_never_panic() {
        let dir = temp_dir("objmutate");
        let good = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\no a\n\
                    f 1/1/1 2/1/1 3/1/1 4/1/1\ng b\nf -4//-1 -3//-1 -2//-1\nf 1 2 3\n";
        let replacements = [
            "0",
            "1",
            "2",
            "4",
            "5",
            "-1",
            "-4",
            "-5",
            "-9",
            "99",
            "1e39",
            "nan",
            "inf",
            "x",
            "",
            "1/",
            "//",
            "1/1/1/1",
            "-9223372036854775808",
            "9223372036854775807",
        ];
        let tokens: Vec<&str> = good.split(' ').collect();
        let mut state = 0x5eed_5eed_5eed_5eedu64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..400 {
            let mut t: Vec<String> = tokens.iter().map(|s| s.to_string()).collect();
            for _ in 0..1 + next() % 3 {
                let at = (next() % t.len() as u64) as usize;
                let with = replacements[(next() % replacements.len() as u64) as usize];
                // Keep the line structure: replace only what precedes a newline.
                let tail = t[at].find('\n').map(|i| t[at][i..].to_string());
                t[at] = format!("{with}{}", tail.unwrap_or_default());
            }
            let _ = load_obj(&write(&dir, "m.obj", t.join(" ").as_bytes()));
        }
    }

    fn load_text_bytes(bytes: &[u8]) -> InputResult<LoadedAsset> {
        let dir = temp_dir("bytes");
        load_obj(&write(&dir, "mesh.obj", bytes))
    }
}
