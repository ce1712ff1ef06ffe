//! Material libraries (`.mtl`) for the OBJ loader: reading and checking them
//! line by line (errors name the library and the line) before `tobj` parses
//! them, decoding the textures `map_Kd` names, and turning tobj's materials
//! into ours.
//!
//! As other tools do, a library that cannot be read, and the statements of
//! a `newmtl` without a name, are left out with a warning at their line;
//! a `\` in a file name is a path separator where no file has that name.

use super::super::io_message;
use super::super::text::decode_text;
use super::ignored::{map_kd_option, why_statement_is_ignored, Ignored, Values};
use super::parse_finite;
use crate::error::{InputError, InputResult};
use crate::material::{Maps, Material, NormalMap, NormalMapKind};
use crate::texture::{Encoding, Image, Texture, Textures, Wrap};
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The materials of one `mtllib` line, in library order.
pub(super) type MtlLibrary = Vec<tobj::Material>;

/// The textures of an OBJ file's material libraries, each image file
/// decoded once however many `map_Kd` lines name it.
#[derive(Default)]
pub(super) struct TextureFiles {
    pub(super) textures: Textures,
    images: HashMap<PathBuf, u32>,
}

impl TextureFiles {
    /// The index of the texture of `file` with `wrap`, the file read and
    /// decoded the first time it is named.
    fn load(&mut self, file: &Path, wrap: Wrap, encoding: Encoding) -> Result<u32, String> {
        let image = match self.images.get(file) {
            Some(&image) => image,
            None => {
                let bytes = std::fs::read(file).map_err(|e| {
                    format!("cannot read texture {}: {}", file.display(), io_message(&e))
                })?;
                let image = Image::decode_file(&bytes, file)
                    .map_err(|e| format!("texture {}: {e}", file.display()))?;
                let image = self.textures.add_image(image);
                self.images.insert(file.to_path_buf(), image);
                image
            }
        };
        Ok(self.textures.add_texture(Texture {
            image,
            wrap: [wrap; 2],
            encoding,
        }))
    }
}

/// `name` (from an `mtllib` or `map_Kd` line) in `dir`. Windows exporters
/// write `\` between folders (`.\tex.jpg`); where no file has the name
/// as written, each `\` is read as a `/`.
fn resolve(dir: &Path, name: &str) -> PathBuf {
    let as_written = dir.join(name);
    if name.contains('\\') && !as_written.exists() {
        dir.join(name.replace('\\', "/"))
    } else {
        as_written
    }
}

/// Load the material libraries named after `mtllib` on line `line` of the
/// OBJ file. tobj reads the whole rest of the line as one file name (names
/// may contain spaces); if no such file exists and the text has several
/// words, each word is a library. A library that cannot be read is a
/// warning at that line, and the second value is then `false`; a problem
/// inside one is an error naming the library and its line.
pub(super) fn load_library(
    obj_path: &Path,
    line: usize,
    name: &str,
    textures: &mut TextureFiles,
    warnings: &mut Vec<InputError>,
) -> InputResult<(MtlLibrary, bool)> {
    let dir = obj_path.parent().unwrap_or(Path::new(""));
    let whole = resolve(dir, name);
    let files: Vec<PathBuf> = if whole.is_file() || !name.contains(char::is_whitespace) {
        vec![whole]
    } else {
        name.split_whitespace().map(|n| resolve(dir, n)).collect()
    };
    let mut materials = Vec::new();
    let mut all_read = true;
    for file in files {
        match std::fs::read(&file) {
            Ok(bytes) => {
                materials.append(&mut parse_mtl(&file, &bytes, textures, warnings)?);
            }
            Err(e) => {
                all_read = false;
                warnings.push(InputError::new(
                    obj_path,
                    format!("line {line}"),
                    format!(
                        "cannot read material library {}: {}; the faces that name its \
                         materials get the default material",
                        file.display(),
                        io_message(&e)
                    ),
                ));
            }
        }
    }
    Ok((materials, all_read))
}

/// Validate an MTL file line by line (errors name it and the line), bring
/// colours into the `r g b` form tobj needs, decode the textures, then let
/// tobj parse it.
fn parse_mtl(
    path: &Path,
    bytes: &[u8],
    textures: &mut TextureFiles,
    warnings: &mut Vec<InputError>,
) -> InputResult<MtlLibrary> {
    let text = decode_text(path, bytes)?;
    let mut normalized = String::with_capacity(text.len());
    // Inside a `newmtl` without a name, whose statements no `usemtl` can
    // reach: they are left out (an empty line each, so lines keep their
    // numbers).
    let mut unnamed = false;
    let mut ignored = Ignored::new(path);
    for (number, raw) in text.split('\n').enumerate() {
        let at = |message: String| InputError::new(path, format!("line {}", number + 1), message);
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let tokens: Vec<&str> = words.collect();
        let after_keyword = line.get(keyword.len()..).unwrap_or("").trim();
        if keyword == "newmtl" {
            unnamed = after_keyword.is_empty();
            if unnamed {
                warnings.push(at(
                    "newmtl without a material name: its statements are left out, \
                     and a usemtl without a name gets the default material"
                        .to_string(),
                ));
            }
        }
        if unnamed {
            normalized.push('\n');
            continue;
        }
        match keyword {
            "newmtl" => normalized.push_str(line),
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
            "map_Kd" => {
                let MapKd {
                    wrap,
                    file,
                    ignored: options,
                    ..
                } = parse_map_kd(keyword, after_keyword).map_err(&at)?;
                for (option, why) in options {
                    ignored.note(&format!("map_Kd option {option}"), why, number + 1);
                }
                let dir = path.parent().unwrap_or(Path::new(""));
                let texture = textures
                    .load(&resolve(dir, file), wrap, Encoding::Srgb)
                    .map_err(&at)?;
                // tobj keeps the rest of the line as the texture's name: hand
                // it the index of the decoded texture, which
                // `mtl_to_material` reads back.
                normalized.push_str(&format!("map_Kd {texture}"));
            }
            "map_Bump" | "map_bump" | "bump" | "norm" | "map_Norm" => {
                let MapKd {
                    wrap,
                    file,
                    ignored: options,
                    bump_multiplier,
                } = parse_map_kd(keyword, after_keyword).map_err(&at)?;
                for (option, why) in options {
                    ignored.note(&format!("{keyword} option {option}"), why, number + 1);
                }
                let dir = path.parent().unwrap_or(Path::new(""));
                // Heights and normals are data: no sRGB curve.
                let texture = textures
                    .load(&resolve(dir, file), wrap, Encoding::Linear)
                    .map_err(&at)?;
                let kind = if keyword.eq_ignore_ascii_case("norm") || keyword == "map_Norm" {
                    "normal"
                } else {
                    "height"
                };
                // Handed to tobj as an unknown statement, which
                // `mtl_to_material` reads back.
                normalized.push_str(&format!(
                    "{NORMAL_MAP_KEY} {texture} {kind} {}",
                    bump_multiplier.unwrap_or(1.0)
                ));
            }
            "map_Ka" | "map_Ks" | "map_Ns" | "map_ns" | "map_NS" | "map_d" => {
                // tobj reads these, and would misread one without a name.
                if after_keyword.is_empty() {
                    return Err(at(format!("{keyword} needs a file name")));
                }
                normalized.push_str(line);
            }
            _ => normalized.push_str(line),
        }
        if let Some(why) = why_statement_is_ignored(keyword) {
            ignored.note(keyword, why, number + 1);
        }
        normalized.push('\n');
    }
    ignored.warn(warnings);
    tobj::load_mtl_buf(&mut normalized.as_bytes())
        .map(|(materials, _)| materials)
        .map_err(|e| InputError::file(path, format!("cannot parse MTL: {e}")))
}

/// The statement `parse_mtl` puts in place of a normal or bump map, for
/// tobj to keep as an unknown one: `texture-index normal|height scale`.
const NORMAL_MAP_KEY: &str = "strata_normal_map";

/// The wrap mode and file name of a `map_Kd` statement, or of a bump or
/// normal map's (`keyword`; the text after it): `[options] file name`,
/// the name being the rest of the line (it may contain spaces).
/// `-clamp on|off` is read, and `-bm` on a bump or normal map; the other
/// options (`-o`, `-s`, `-mm`, ...) are read past with their values, and
/// come back with why, to be warned about.
fn parse_map_kd<'a>(keyword: &str, text: &'a str) -> Result<MapKd<'a>, String> {
    let mut wrap = Wrap::Repeat;
    let mut ignored = Vec::new();
    let mut bump_multiplier = None;
    let mut rest = text.trim();
    while rest.starts_with('-') {
        let (option, mut after) = first_word(rest);
        if option == "-clamp" {
            let (value, after) = first_word(after);
            wrap = match value {
                "on" => Wrap::ClampToEdge,
                "off" => Wrap::Repeat,
                _ => return Err(format!("{keyword} -clamp needs on or off, found '{value}'")),
            };
            rest = after;
            continue;
        }
        if option == "-bm" && keyword != "map_Kd" {
            let (value, after) = first_word(after);
            bump_multiplier = Some(parse_finite(value, "-bm")?);
            rest = after;
            continue;
        }
        let (values, why) = map_kd_option(option);
        match values {
            Values::Words(n) => {
                for _ in 0..n {
                    after = first_word(after).1;
                }
            }
            Values::UpToThreeNumbers => {
                for _ in 0..3 {
                    let (word, next) = first_word(after);
                    if word.parse::<f32>().is_err() {
                        break;
                    }
                    after = next;
                }
            }
        }
        ignored.push((option, why));
        rest = after;
    }
    if rest.is_empty() {
        return Err(format!("{keyword} needs a file name"));
    }
    Ok(MapKd {
        wrap,
        file: rest,
        ignored,
        bump_multiplier,
    })
}

/// A `map_Kd` (or bump or normal map) statement as read: its wrap mode and
/// file name, `-bm`, and the options read past with why.
struct MapKd<'a> {
    wrap: Wrap,
    file: &'a str,
    ignored: Vec<(&'a str, &'static str)>,
    bump_multiplier: Option<f32>,
}

/// The first word of `text` and the rest after it, both trimmed.
fn first_word(text: &str) -> (&str, &str) {
    let text = text.trim_start();
    match text.find(char::is_whitespace) {
        Some(i) => (&text[..i], text[i..].trim_start()),
        None => (text, ""),
    }
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

/// An MTL colour, which tobj reads as float64 (`use_f64`, for OBJ
/// coordinates), rounded once to ours.
fn rgb(c: [f64; 3]) -> Vec3 {
    DVec3::from(c).as_vec3()
}

/// Map one MTL material to ours; see the table in the [`obj` module
/// documentation](super).
pub(super) fn mtl_to_material(m: &tobj::Material) -> Material {
    let defaults = Material::default();
    let specular = m.specular.map(rgb).unwrap_or(Vec3::ZERO);
    let mut transparency = match m.dissolve {
        Some(d) => 1.0 - d as f32,
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
        diffuse: m.diffuse.map(rgb).unwrap_or(defaults.diffuse),
        specular,
        shininess: m.shininess.map_or(0.0, |s| s as f32),
        reflectivity: if mirror { specular.max_element() } else { 0.0 },
        glossiness: 0.0,
        transparency: transparency.clamp(0.0, 1.0),
        ior: m
            .optical_density
            .map(|n| n as f32)
            .filter(|n| n.is_finite() && *n > 0.0)
            .unwrap_or(defaults.ior),
        fresnel: matches!(illum, 5 | 7),
        emission: m.emissive.map(rgb).unwrap_or(Vec3::ZERO),
        // `parse_mtl` put the texture's index in place of the file name.
        diffuse_texture: m.diffuse_texture.as_deref().and_then(|t| t.parse().ok()),
        maps: Maps {
            normal: m.unknown_param.get(NORMAL_MAP_KEY).and_then(|v| {
                let mut words = v.split_whitespace();
                let texture = words.next()?.parse().ok()?;
                let kind = match words.next()? {
                    "normal" => NormalMapKind::Normal,
                    _ => NormalMapKind::Height,
                };
                let scale = words.next()?.parse().ok()?;
                Some(NormalMap {
                    texture,
                    kind,
                    scale,
                })
            }),
            ..Maps::default()
        },
        ..defaults
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_helpers::SQUARE;
    use super::super::{load_obj, load_obj_with};
    use crate::material::Material;
    use crate::scene::asset::LoadedAsset;
    use crate::scene::loaders::test_files::{temp_dir, write};
    use crate::scene::loaders::Reading;
    use glam::Vec3;

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

    /// A quad with texture coordinates, in objects `a` (material a), `b`
    /// (b), `c` (c) and `plain` (a, but without `vt` indices).
    const TEXTURED_QUADS: &str = "mtllib looks.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0.25 1\n\
        o a\nusemtl a\nf 1/1 2/2 3/3 4/4\no b\nusemtl b\nf 1/1 2/2 3/3\n\
        o c\nusemtl c\nf 1/1 2/2 3/3\no plain\nusemtl a\nf 1/1 2/2 3/3\nf 1 3 4\n";

    #[test]
    fn map_kd_textures_are_decoded_once_and_textured_meshes_get_uvs() {
        use crate::scene::loaders::test_files::png;
        use crate::texture::Wrap;
        use glam::Vec2;
        let dir = temp_dir("map_kd");
        let texels = [[255, 128, 0], [0, 64, 255]];
        write(&dir, "two texels.png", &png(2, 1, &texels));
        write(
            &dir,
            "looks.mtl",
            b"newmtl a\nKd 0.5 0.5 0.5\nmap_Kd two texels.png\n\
              newmtl b\nmap_Kd -clamp on two texels.png\nnewmtl c\nKd 1 0 0\n",
        );
        let asset = load_obj(&write(&dir, "q.obj", TEXTURED_QUADS.as_bytes())).unwrap();
        // One file named twice: one image, two textures (two wrap modes).
        assert_eq!(asset.textures.images.len(), 1);
        assert_eq!(asset.textures.images[0].texels(), texels);
        let wraps: Vec<_> = asset.textures.textures.iter().map(|t| t.wrap).collect();
        assert_eq!(wraps, [[Wrap::Repeat; 2], [Wrap::ClampToEdge; 2]]);
        let textures: Vec<_> = asset
            .materials
            .iter()
            .map(|(_, m)| m.diffuse_texture)
            .collect();
        assert_eq!(textures, [Some(0), Some(1), None]);
        assert_eq!(asset.materials[0].1.diffuse, Vec3::splat(0.5), "Kd stays");

        let uvs = |name: &str| {
            asset
                .meshes
                .iter()
                .find(|m| m.name == name)
                .unwrap()
                .uvs
                .clone()
        };
        let a = uvs("a").expect("textured, with vt");
        // v flipped: OBJ's v = 0 is the image's bottom row, ours its top.
        let corners: Vec<[Vec2; 3]> = a
            .indices
            .iter()
            .map(|t| t.map(|i| a.values[i as usize]))
            .collect();
        let uv = Vec2::new;
        assert_eq!(
            corners,
            [
                [uv(0., 1.), uv(1., 1.), uv(1., 0.)],
                [uv(0., 1.), uv(1., 0.), uv(0.25, 0.)]
            ]
        );
        assert!(uvs("b").is_some());
        assert!(uvs("c").is_none(), "no texture, no UVs");
        assert!(
            uvs("plain").is_none(),
            "a face without vt: no UVs, none invented"
        );
    }

    #[test]
    fn missing_or_bad_textures_name_the_file_and_the_mtl_line() {
        let dir = temp_dir("bad_map_kd");
        write(&dir, "q.obj", TEXTURED_QUADS.as_bytes());
        write(&dir, "text.png", b"just text");
        let png = crate::scene::loaders::test_files::png(2, 2, &[[1, 2, 3]; 4]);
        write(&dir, "cut.png", &png[..png.len() / 2]);
        write(&dir, "ok.png", &png);
        let cases: [(&[u8], &str); 5] = [
            (b"map_Kd gone.png", "cannot read texture"),
            (b"map_Kd text.png", "a text file, not an image"),
            (b"map_Kd cut.png", "cannot decode"),
            (b"map_Kd -clamp maybe ok.png", "-clamp needs on or off"),
            (b"map_Kd -clamp on", "needs a file name"),
        ];
        for (statement, needle) in cases {
            let mut mtl = b"newmtl a\nKd 1 1 1\n".to_vec();
            mtl.extend_from_slice(statement);
            mtl.extend_from_slice(b"\nnewmtl b\nnewmtl c\n");
            write(&dir, "looks.mtl", &mtl);
            let err = load_obj(&dir.join("q.obj")).unwrap_err();
            let shown = err.to_string();
            assert!(err.file.ends_with("looks.mtl"), "{shown}");
            assert_eq!(err.location, "line 3", "{shown}");
            assert!(shown.contains(needle), "{shown} should say '{needle}'");
            if !needle.contains("option") && !needle.contains("-clamp") && !needle.contains("name")
            {
                let file = std::str::from_utf8(&statement[7..]).unwrap();
                assert!(shown.contains(file), "{shown} should name {file}");
            }
            // Read for its faces alone (`strata trace`, a query mesh), the
            // file reads no library: its faces, no material, no word.
            let faces = load_obj_with(&dir.join("q.obj"), Reading::FACES).unwrap();
            assert!(faces.materials.is_empty() && faces.textures.images.is_empty());
            assert!(faces.warnings.is_empty(), "{:?}", faces.warnings);
            assert!(faces
                .meshes
                .iter()
                .all(|m| m.material.is_none() && m.uvs.is_none()));
            let triangles: usize = faces.meshes.iter().map(|m| m.indices.len()).sum();
            assert_eq!(triangles, 6);
        }
        // A usemtl naming a material no library defines is a word in a
        // render, none where materials are not read.
        write(&dir, "looks.mtl", b"newmtl a\nKd 1 1 1\n");
        let render = load_obj(&dir.join("q.obj")).unwrap();
        assert!(render
            .warnings
            .iter()
            .any(|w| w.to_string().contains("'b' is not defined")));
        let faces = load_obj_with(&dir.join("q.obj"), Reading::FACES).unwrap();
        assert!(faces.warnings.is_empty(), "{:?}", faces.warnings);
        let positions = |a: &LoadedAsset| -> Vec<Vec3> {
            a.meshes.iter().flat_map(|m| m.positions.clone()).collect()
        };
        assert_eq!(positions(&faces), positions(&render));
    }

    /// What a library holds that strata does not read is a warning at
    /// its line, once per kind: `map_Kd` options, bump and normal maps,
    /// other statements. The texture itself still loads.
    #[test]
    fn ignored_statements_and_options_are_one_warning_per_kind() {
        let dir = temp_dir("mtl_ignored");
        write(&dir, "q.obj", TEXTURED_QUADS.as_bytes());
        write(
            &dir,
            "ok.png",
            &crate::scene::loaders::test_files::png(1, 1, &[[9, 9, 9]]),
        );
        for name in ["bump.png", "n.png"] {
            write(
                &dir,
                name,
                &crate::scene::loaders::test_files::png(1, 1, &[[128, 128, 255]]),
            );
        }
        write(
            &dir,
            "looks.mtl",
            b"newmtl a\nKa 0.1 0.1 0.1\nKd 1 1 1\nmap_Kd -s 2 2 1 -o 0.5 -clamp on ok.png\n\
              map_Bump -bm 0.3 bump.png\nnorm n.png\nTf 1 1 1\n\
              newmtl b\nmap_Kd -s 4 ok.png\nbump bump.png\nmap_Bump bump.png\nnewmtl c\n",
        );
        let asset = load_obj(&dir.join("q.obj")).unwrap();
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        let mtl = dir.join("looks.mtl");
        let at = |line: usize, rest: &str| format!("{}: line {line}: {rest}", mtl.display());
        assert_eq!(
            said,
            [
                at(4, "map_Kd option -s is ignored (and on 1 more line): the texture is looked up where the file's texture coordinates say, unmoved and unscaled"),
                at(4, "map_Kd option -o is ignored: the texture is looked up where the file's texture coordinates say, unmoved and unscaled"),
                at(7, "Tf is ignored: strata's glass has no colour filter (only d or Tr)"),
            ]
        );
        // Bump and normal maps are read, as data; the last one counts.
        use crate::material::NormalMapKind;
        let map = |name: &str| {
            let m = asset.materials.iter().find(|(n, _)| n == name).unwrap().1;
            m.maps.normal.map(|n| (n.kind, n.scale))
        };
        assert_eq!(map("a"), Some((NormalMapKind::Normal, 1.0)));
        assert_eq!(map("b"), Some((NormalMapKind::Height, 1.0)));
        assert_eq!(map("c"), None);
        let height = asset.materials[1].1.maps.normal.unwrap().texture;
        assert_eq!(
            asset.textures.textures[height as usize].encoding,
            crate::texture::Encoding::Linear
        );
        // -clamp after the ignored options is still read; the image loads.
        let a = asset.materials.iter().find(|(n, _)| n == "a").unwrap().1;
        let texture = a.diffuse_texture.expect("map_Kd read past its options");
        assert_eq!(
            asset.textures.textures[texture as usize].wrap,
            [crate::texture::Wrap::ClampToEdge; 2]
        );
    }

    #[test]
    fn a_missing_mtl_is_one_warning_and_other_libraries_still_count() {
        let dir = temp_dir("missing_mtl");
        write(&dir, "here.mtl", b"newmtl red\nKd 1 0 0\n");
        let obj = format!(
            "{SQUARE}mtllib nowhere.mtl\nmtllib here.mtl\nusemtl lost\nf 1 2 3\n\
             usemtl red\nf 1 3 4\nusemtl lost2\nf 2 3 4\n"
        );
        let asset = load_obj(&write(&dir, "m.obj", obj.as_bytes())).unwrap();
        assert_eq!(asset.warnings.len(), 1, "{:?}", asset.warnings);
        let shown = asset.warnings[0].to_string();
        assert!(shown.contains("m.obj: line 5:"), "{shown}");
        assert!(shown.contains("nowhere.mtl"), "{shown}");
        assert!(shown.contains("No such file or directory"), "{shown}");
        let materials: Vec<_> = asset.meshes.iter().map(|m| m.material).collect();
        assert_eq!(materials, [None, Some(0), None]);
        assert_eq!(asset.materials[0].1.diffuse, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn an_unnamed_newmtl_is_left_out_with_a_warning() {
        let dir = temp_dir("unnamed_mtl");
        write(
            &dir,
            "e.mtl",
            b"newmtl a\nKd 0 1 0\nnewmtl  \nKd 1 0 0\nmap_Kd gone.png\nnewmtl b\nKd 0 0 1\n",
        );
        let obj = format!("mtllib e.mtl\n{SQUARE}usemtl \nf 1 2 3\nusemtl b\nf 1 3 4\n");
        let asset = load_obj(&write(&dir, "e.obj", obj.as_bytes())).unwrap();
        let names: Vec<&str> = asset.materials.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        // The unnamed material's Kd went nowhere: a keeps its own.
        assert_eq!(asset.materials[0].1.diffuse, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(asset.meshes[0].material, None);
        assert_eq!(asset.meshes[1].material, Some(1));
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(said[0].contains("e.mtl: line 3: newmtl without a material name"));
        assert!(said[1].contains("e.obj: line 6: usemtl without a material name"));
    }

    #[test]
    fn backslashes_in_file_names_are_folders_where_no_file_has_the_name() {
        use crate::scene::loaders::test_files::png;
        let dir = temp_dir("backslash");
        std::fs::create_dir(dir.join("tex")).unwrap();
        write(&dir.join("tex"), "spider.png", &png(1, 1, &[[9, 8, 7]]));
        std::fs::create_dir(dir.join("lib")).unwrap();
        write(
            &dir.join("lib"),
            "s.mtl",
            b"newmtl skin\nmap_Kd ..\\tex\\spider.png\n",
        );
        let obj = format!("mtllib .\\lib\\s.mtl\n{SQUARE}usemtl skin\nf 1 2 3\n");
        let asset = load_obj(&write(&dir, "s.obj", obj.as_bytes())).unwrap();
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
        assert_eq!(asset.materials[0].1.diffuse_texture, Some(0));
        assert_eq!(asset.textures.images[0].texels(), [[9, 8, 7]]);
    }

    #[test]
    fn latin1_and_utf16_libraries_are_read() {
        let dir = temp_dir("latin1_mtl");
        // "newmtl grün" in Latin-1 (ü is one byte, 0xfc), after a comment.
        write(&dir, "l.mtl", b"# \xa9 1999\nnewmtl gr\xfcn\nKd 0 0.5 0\n");
        let obj = format!("mtllib l.mtl\n{SQUARE}usemtl grün\nf 1 2 3\n");
        let asset = load_obj(&write(&dir, "l.obj", obj.as_bytes())).unwrap();
        assert_eq!(asset.materials[0].0, "grün");
        assert_eq!(asset.meshes[0].material, Some(0));
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
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
}
