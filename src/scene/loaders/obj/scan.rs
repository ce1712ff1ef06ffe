//! The validation pass over OBJ text, before `tobj` sees it.
//!
//! [`scan_obj`] checks, line by line, everything `tobj` would reject or
//! silently mangle, so that the user gets the line number of the mistake
//! rather than tobj's message about the whole file. It also loads the
//! material libraries that `mtllib` lines name (see `mtl.rs`), because a
//! `usemtl` is checked against the materials defined before it.
//! [`rewrite_for_tobj`] then adjusts the few valid lines tobj would misread.
//!
//! What other tools read with a default material is read here too, with a
//! warning at its line (collected in [`ObjScan::warnings`]): a `usemtl`
//! naming no material (each name once; in a file without `mtllib`, where
//! `usemtl` means the default material, none), a `usemtl` without a name,
//! an `mtllib` that cannot be read (its `usemtl`s then say nothing more).

use super::mtl::{load_library, MtlLibrary, TextureFiles};
use super::{parse_finite, parse_number};
use crate::error::{InputError, InputResult};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What the validation pass learned about one `f` line.
#[derive(Clone, Copy)]
pub(super) struct FaceInfo {
    pub(super) triangles: u32,
    pub(super) has_normals: bool,
    pub(super) has_texcoords: bool,
}

/// The result of the validation pass over an OBJ file.
pub(super) struct ObjScan {
    pub(super) faces: Vec<FaceInfo>,
    /// Material libraries keyed by the text after `mtllib`, as tobj asks for them.
    pub(super) libraries: HashMap<PathBuf, MtlLibrary>,
    /// The textures their `map_Kd` lines name, each file decoded once.
    pub(super) textures: TextureFiles,
    /// The text needs adjusting before tobj can read it (see [`rewrite_for_tobj`]).
    pub(super) needs_rewrite: bool,
    /// Some `v` lines have colours and others not: drop the colours.
    pub(super) strip_colours: bool,
    /// What was read leniently, each naming its file and line.
    pub(super) warnings: Vec<InputError>,
    /// An `o` or `g` line names tobj's name for unnamed faces
    /// ([`super::TOBJ_DEFAULT_NAME`]): a model of that name is the file's.
    pub(super) writes_default_name: bool,
}

/// What a `usemtl` without a name becomes for tobj: a name no library
/// defines, so the faces after it get the default material.
pub(super) const NO_MATERIAL: &str = "\u{0}";

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

/// Check one index of a face corner, and return it counted from 0 in the
/// whole file: `singular` and `plural` name the element ("vertex",
/// "vertices") for messages, `so_far` is how many elements precede the
/// face, `total` how many the file has.
fn check_index(
    text: &str,
    (singular, plural): (&str, &str),
    so_far: usize,
    total: usize,
) -> Result<usize, String> {
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
        Ok(so_far - index.unsigned_abs())
    } else if index as usize > total {
        Err(format!(
            "{singular} index {index} is out of range (the file defines {total} {plural})"
        ))
    } else {
        Ok(index as usize - 1)
    }
}

/// Validate a face's vertex tokens; returns whether every corner has a
/// normal, and whether every corner has texture coordinates. A corner at
/// a vertex of `not_finite` (its index from 0 and its line, in order) is
/// an error naming that vertex's line.
fn check_face(
    tokens: &[&str],
    defined: Counts,
    total: Counts,
    not_finite: &[(usize, usize)],
) -> Result<(bool, bool), String> {
    if tokens.len() < 3 {
        return Err(format!(
            "a face needs at least 3 vertices, this one has {}",
            tokens.len()
        ));
    }
    let (mut has_normals, mut has_texcoords) = (true, true);
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
        let vertex = check_index(parts[0], ("vertex", "vertices"), defined.v, total.v)?;
        if let Ok(k) = not_finite.binary_search_by_key(&vertex, |&(k, _)| k) {
            return Err(format!(
                "'{token}' uses the vertex on line {}, whose coordinates are not finite \
                 numbers (NaN, infinite or too large)",
                not_finite[k].1
            ));
        }
        match parts.get(1).filter(|p| !p.is_empty()) {
            Some(vt) => {
                let names = ("texture coordinate", "texture coordinates");
                check_index(vt, names, defined.vt, total.vt)?;
            }
            None => has_texcoords = false,
        }
        match parts.get(2).filter(|p| !p.is_empty()) {
            Some(vn) => {
                check_index(vn, ("normal", "normals"), defined.vn, total.vn)?;
            }
            None => has_normals = false,
        }
    }
    Ok((has_normals, has_texcoords))
}

/// The text after the first space, trimmed, as tobj reads `usemtl`/`mtllib`.
fn after_first_space(line: &str) -> &str {
    line.split_once(' ')
        .map(|(_, rest)| rest.trim())
        .unwrap_or("")
}

/// The validation pass: checks everything tobj would reject (or silently
/// mangle), with line numbers, and, with `materials`, loads the material
/// libraries (without, `mtllib` and `usemtl` lines say nothing).
pub(super) fn scan_obj(path: &Path, text: &str, materials: bool) -> InputResult<ObjScan> {
    let total = count_elements(text);
    let mut defined = Counts::default();
    let mut scan = ObjScan {
        faces: Vec::new(),
        libraries: HashMap::new(),
        textures: TextureFiles::default(),
        needs_rewrite: false,
        strip_colours: false,
        warnings: Vec::new(),
        writes_default_name: false,
    };
    let mut coloured_vertices = 0usize;
    let mut material_names: HashSet<String> = HashSet::new();
    // Undefined names already warned about, and whether a library could not
    // be read (whose materials then go unnamed without more warnings).
    let mut warned_names: HashSet<String> = HashSet::new();
    let mut library_missing = false;
    // The vertices whose coordinates are not finite, with their lines.
    let mut not_finite: Vec<(usize, usize)> = Vec::new();

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
                    xyz[i] = parse_number(token, "vertex coordinate").map_err(&at)?;
                }
                if !xyz.iter().all(|c| c.is_finite()) {
                    // An error only where a face uses it (a depth image's
                    // mesh keeps its missing pixels; tobj leaves a vertex no
                    // face uses out of every mesh).
                    not_finite.push((defined.v, number + 1));
                } else if rest.len() == 4 {
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
                let (has_normals, has_texcoords) =
                    check_face(&rest, defined, total, &not_finite).map_err(&at)?;
                scan.faces.push(FaceInfo {
                    triangles: (rest.len() - 2) as u32,
                    has_normals,
                    has_texcoords,
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
                    scan.needs_rewrite = true;
                    if materials {
                        scan.warnings
                            .push(at("usemtl without a material name (after a space): \
                             the faces after it get the default material"
                                .to_string()));
                    }
                } else if materials
                    && total.mtllib
                    && !material_names.contains(name)
                    && !library_missing
                    && warned_names.insert(name.to_string())
                {
                    // (A file without any mtllib, as many exporters write
                    // `usemtl Default`, means the default material: no word.)
                    scan.warnings.push(at(format!(
                        "material '{name}' is not defined by any mtllib before this \
                         line: its faces get the default material"
                    )));
                }
            }
            "mtllib" if !materials => {}
            "mtllib" => {
                let name = after_first_space(line);
                if name.is_empty() {
                    scan.warnings.push(at(
                        "mtllib without a file name (after a space) is ignored".to_string()
                    ));
                    continue;
                }
                let (library, all_read) = load_library(
                    path,
                    number + 1,
                    name,
                    &mut scan.textures,
                    &mut scan.warnings,
                )?;
                library_missing |= !all_read;
                material_names.extend(library.iter().map(|m| m.name.clone()));
                scan.libraries.insert(PathBuf::from(name), library);
            }
            "o" | "g" => {
                let mut names = line.split_whitespace().skip(1);
                scan.writes_default_name |= names.any(|w| w == super::TOBJ_DEFAULT_NAME);
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
pub(super) fn rewrite_for_tobj(text: &str, strip_colours: bool) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.split('\n') {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("l") => {}
            Some("usemtl") if after_first_space(line).is_empty() => {
                out.push_str("usemtl ");
                out.push_str(NO_MATERIAL);
            }
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

#[cfg(test)]
mod tests {
    use super::super::load_obj;
    use super::super::test_helpers::{corners, load_text, SQUARE};
    use crate::scene::loaders::test_files::{temp_dir, write};
    use glam::Vec3;

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

    #[test]
    fn unknown_or_unnamed_usemtl_gets_the_default_material_and_one_warning() {
        let dir = temp_dir("usemtl");
        write(&dir, "lib.mtl", b"newmtl known\n");
        let obj = format!(
            "mtllib lib.mtl\n{SQUARE}usemtl unknown\nf 1 2 3\nusemtl known\nf 1 3 4\n\
             usemtl unknown\nf 2 3 4\nusemtl\nf 1 2 4\n"
        );
        let asset = load_obj(&write(&dir, "a.obj", obj.as_bytes())).unwrap();
        let materials: Vec<_> = asset.meshes.iter().map(|m| m.material).collect();
        // The last two faces both have the default material: one mesh.
        assert_eq!(materials, [None, Some(0), None]);
        assert_eq!(asset.meshes[2].indices.len(), 2);
        let said: Vec<_> = asset.warnings.iter().map(|w| w.location.as_str()).collect();
        assert_eq!(said, ["line 6", "line 12"], "{:?}", asset.warnings);
        assert!(asset.warnings[0].file.ends_with("a.obj"));
        assert!(asset.warnings[0].message.contains("'unknown'"));
        assert!(asset.warnings[1]
            .message
            .contains("without a material name"));
        // Without any mtllib, usemtl means the default material: no word.
        let asset = load_text(&format!("{SQUARE}usemtl whatever\nf 1 2 3\n")).unwrap();
        assert_eq!(asset.meshes[0].material, None);
        assert!(asset.materials.is_empty());
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    }

    #[test]
    fn bad_vertices_report_their_line() {
        expect_line_error("v 0 0 0\nv 1 0\n", 2, "3 coordinates");
        expect_line_error("v 0 0 0\n\nv 1 zero 0\n", 3, "'zero' is not a number");
        // Not finite (NaN, infinite, beyond float32): an error at the
        // line of a face that uses it, naming the vertex's line.
        let tri = "v 1 0 0\nv 0 1 0\n";
        expect_line_error(
            &format!("# c\nv nan 0 0\n{tri}f 1 2 3\n"),
            5,
            "vertex on line 2",
        );
        expect_line_error(&format!("v 0 0 inf\n{tri}f -1 -2 -3\n"), 4, "line 1, whose");
        expect_line_error(&format!("v 1e39 0 0\n{tri}f 2 3 1\n"), 4, "not finite");
        expect_line_error("v 0 0 0 0\n", 1, "weight");
        expect_line_error("v 0 0 0\nvn 0 NaN 1\n", 2, "not a finite number");
        expect_line_error("vn 0 1\n", 1, "3 numbers");
    }

    /// A vertex no face uses may be anything, as a depth image's mesh
    /// keeps its missing pixels (trimesh reads such a file; strata's PLY
    /// and OFF readers and its arrays take it too).
    #[test]
    fn a_vertex_no_face_uses_may_be_nan() {
        let text = "v 0 0 0\nv nan nan nan\nv 1 0 0\nv inf 0 1e39\nv 0 1 0\nf 1 3 5\n";
        let asset = load_text(text).unwrap();
        assert_eq!(corners(&asset), [[Vec3::ZERO, Vec3::X, Vec3::Y]]);
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
}
