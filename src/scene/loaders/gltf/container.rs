//! The container layer: a GLB file split into its JSON and BIN chunks, and
//! the JSON parsed and validated. Every length a GLB declares is checked
//! against the bytes really there before it is sliced.
//!
//! What strata cannot read is refused by name before the `gltf` crate's
//! own errors would hide it: glTF 1.0 (whose JSON the crate can only call
//! "invalid type: map, expected a sequence"), and each `extensionsRequired`
//! entry strata does not support (a Draco-compressed file would otherwise
//! fail on the accessors the extension replaces). A scene without `nodes`
//! reads as a scene of none, as other tools read it.

use crate::error::{InputError, InputResult};
use ::gltf::json;
use json::mesh::Semantic;
use json::validation::{Checked, Validate};
use std::path::Path;

pub(super) fn u32_le(bytes: &[u8]) -> u32 {
    u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
}

/// Split a GLB container into its JSON chunk and optional BIN chunk, checking
/// every declared length against the bytes actually present.
pub(super) fn split_glb<'a>(
    path: &Path,
    bytes: &'a [u8],
) -> InputResult<(&'a [u8], Option<&'a [u8]>)> {
    let header = |message: String| InputError::new(path, "GLB header", message);
    if bytes.len() < 12 {
        return Err(header(format!(
            "the file is only {} bytes, too short for the 12-byte GLB header",
            bytes.len()
        )));
    }
    let version = u32_le(&bytes[4..]);
    if version == 1 {
        return Err(header(format!(
            "binary glTF 1.0 (GLB version 1) is not supported; {CONVERT}"
        )));
    }
    if version != 2 {
        return Err(header(format!(
            "GLB version {version} is not supported (only version 2)"
        )));
    }
    let length = u32_le(&bytes[8..]) as usize;
    if length > bytes.len() {
        return Err(header(format!(
            "declares {length} bytes but the file has only {} (truncated?)",
            bytes.len()
        )));
    }
    if length < 12 {
        return Err(header(format!(
            "declares a total length of {length} bytes, less than the header itself"
        )));
    }
    let mut rest = &bytes[12..length];
    let (mut json, mut bin) = (None, None);
    let mut chunk = 0usize;
    while !rest.is_empty() {
        let at = |message: String| InputError::new(path, format!("GLB chunk {chunk}"), message);
        if rest.len() < 8 {
            return Err(at(format!(
                "only {} bytes left, too few for a chunk header (truncated?)",
                rest.len()
            )));
        }
        let chunk_length = u32_le(rest) as usize;
        let kind = &rest[4..8];
        let available = rest.len() - 8;
        if chunk_length > available {
            return Err(at(format!(
                "declares {chunk_length} bytes but only {available} remain (truncated?)"
            )));
        }
        let data = &rest[8..8 + chunk_length];
        match (chunk, kind) {
            (0, b"JSON") => json = Some(data),
            (0, _) => return Err(at("the first chunk must be the JSON chunk".to_string())),
            (1, b"BIN\0") => bin = Some(data),
            _ => {} // unknown chunks are to be ignored
        }
        rest = &rest[8 + chunk_length..];
        chunk += 1;
    }
    let json = json.ok_or_else(|| header("the file has no JSON chunk".to_string()))?;
    Ok((json, bin))
}

/// How to get a file strata reads from one it refuses; the tool is the one
/// whose test models these refusals were checked against.
const CONVERT: &str = "convert it to glTF 2.0 first, e.g. with `assimp export FILE out.glb -fglb2`";

/// What the extensions files most often require do, for the refusal.
const EXTENSION_WORDS: &[(&str, &str)] = &[
    ("KHR_draco_mesh_compression", "Draco-compressed meshes"),
    ("EXT_meshopt_compression", "meshopt-compressed buffers"),
    ("KHR_texture_basisu", "Basis Universal textures"),
];

/// A required extension strata reads that the `gltf` crate does not know:
/// integer vertex attributes (`super::accessor::Attribute`), which change
/// nothing in the document's structure.
const QUANTIZATION: &str = "KHR_mesh_quantization";

/// The beginnings of the names of extensions that change only how a
/// surface looks (its material and textures): a file read for its faces
/// alone may require them (`KHR_texture_basisu`, `EXT_texture_webp`), and
/// reads them no more than its materials.
const LOOKS: [&str; 3] = ["KHR_materials_", "KHR_texture_", "EXT_texture_"];

/// Where in the document the looks are, which a file read for its faces
/// alone does not read, so their mistakes are none of its own.
const LOOKS_PARTS: [&str; 4] = ["materials[", "textures[", "images[", "samplers["];

/// The extensions a file may require: the `gltf` crate's, and
/// [`QUANTIZATION`].
fn readable_extensions() -> Vec<&'static str> {
    let mut names = json::extensions::ENABLED_EXTENSIONS.to_vec();
    names.push(QUANTIZATION);
    names
}

/// Parse and validate the JSON document; without `materials`, the
/// extensions and parts that are only looks ([`LOOKS`], [`LOOKS_PARTS`])
/// are not checked.
///
/// The `gltf` crate's validator indexes the POSITION accessor without a
/// bounds check, so that reference is checked first.
pub(super) fn parse_root(
    path: &Path,
    json_bytes: &[u8],
    materials: bool,
) -> InputResult<json::Root> {
    let root: json::Root = match json::deserialize::from_slice(json_bytes) {
        Ok(root) => root,
        Err(e) => lenient_root(path, json_bytes)
            .unwrap_or_else(|| Err(InputError::file(path, format!("invalid glTF JSON: {e}"))))?,
    };
    if version_1(&json::Value::String(root.asset.version.clone())) {
        return Err(gltf_1_refusal(path));
    }
    check_required_extensions(path, &root, materials)?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
            {
                if index.value() >= root.accessors.len() {
                    return Err(InputError::new(
                        path,
                        format!("meshes[{m}].primitives[{p}]"),
                        format!(
                            "POSITION refers to accessors[{}] but the file has {} accessors",
                            index.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let mut problems: Vec<(String, json::validation::Error)> = Vec::new();
    root.validate(&root, json::Path::new, &mut |where_, error| {
        problems.push((where_().to_string(), error))
    });
    // We read neither POSITION's min/max nor custom attributes, so files
    // that get those wrong still load; and the crate refuses a required
    // extension it does not know that strata reads.
    problems.retain(|(where_, error)| {
        let quantization = *error == json::validation::Error::Unsupported
            && where_.starts_with("extensionsRequired[")
            && where_.ends_with(&format!("\"{QUANTIZATION}\""));
        let unused_bounds = where_.contains(".attributes[")
            && (where_.ends_with(".min") || where_.ends_with(".max"));
        let custom_attribute =
            *error == json::validation::Error::Invalid && where_.contains(".attributes[");
        let looks = !materials
            && (LOOKS_PARTS.iter().any(|p| where_.starts_with(p))
                || where_.starts_with("extensionsRequired[")
                    && LOOKS.iter().any(|p| where_.contains(&format!("\"{p}"))));
        !(quantization || unused_bounds || custom_attribute || looks)
    });
    if let Some((location, error)) = problems.first() {
        let mut message = format!("invalid glTF: {error}");
        if problems.len() > 1 {
            let others: Vec<String> = problems[1..]
                .iter()
                .take(4)
                .map(|(w, e)| format!("{w}: {e}"))
                .collect();
            message.push_str(&format!(
                " (and {} more: {}{})",
                problems.len() - 1,
                others.join("; "),
                if problems.len() > 5 { "; ..." } else { "" }
            ));
        }
        return Err(InputError::new(path, location.clone(), message));
    }
    Ok(root)
}

/// After the `gltf` crate refused `json_bytes`: the refusal of a glTF 1.0
/// file, or the document read with each scene that lacks `nodes` given
/// none; `None` where neither applies (the crate's error stands).
fn lenient_root(path: &Path, json_bytes: &[u8]) -> Option<InputResult<json::Root>> {
    let mut value: json::Value = json::deserialize::from_slice(json_bytes).ok()?;
    // glTF 1.0 named its objects in dictionaries where 2.0 has arrays.
    let dictionaries = ["meshes", "nodes", "accessors", "buffers", "scenes"]
        .iter()
        .any(|key| value.get(key).is_some_and(json::Value::is_object));
    let version = value.pointer("/asset/version").cloned();
    if dictionaries || version.as_ref().is_some_and(version_1) {
        return Some(Err(gltf_1_refusal(path)));
    }
    let mut patched = false;
    if let Some(scenes) = value.get_mut("scenes").and_then(json::Value::as_array_mut) {
        for scene in scenes.iter_mut().filter_map(json::Value::as_object_mut) {
            if !scene.contains_key("nodes") {
                scene.insert("nodes".to_string(), json::Value::Array(Vec::new()));
                patched = true;
            }
        }
    }
    if !patched {
        return None;
    }
    json::deserialize::from_value(value).ok().map(Ok)
}

/// An `asset.version` of 1.x (`"1.0"`, `"1.0.2"`, or the number `1`).
fn version_1(version: &json::Value) -> bool {
    match version {
        json::Value::String(text) => text.split('.').next() == Some("1"),
        json::Value::Number(n) => n.as_f64().is_some_and(|v| (1.0..2.0).contains(&v)),
        _ => false,
    }
}

fn gltf_1_refusal(path: &Path) -> InputError {
    InputError::new(
        path,
        "asset.version",
        format!("glTF 1.0 is not supported (only glTF 2.0); {CONVERT}"),
    )
}

/// Each `extensionsRequired` entry the `gltf` crate is not built to read
/// is refused by name, before validation reports what the extension
/// stands in for (a Draco file's accessors have no `bufferView`); one of
/// looks alone ([`LOOKS`]) is let be where `materials` are not read.
fn check_required_extensions(path: &Path, root: &json::Root, materials: bool) -> InputResult<()> {
    let enabled = readable_extensions();
    let looks = |name: &str| !materials && LOOKS.iter().any(|p| name.starts_with(p));
    let Some((i, name)) = root
        .extensions_required
        .iter()
        .enumerate()
        .find(|(_, name)| !enabled.contains(&name.as_str()) && !looks(name))
    else {
        return Ok(());
    };
    let what = EXTENSION_WORDS
        .iter()
        .find(|(n, _)| n == name)
        .map_or(String::new(), |(_, words)| format!(" ({words})"));
    Err(InputError::new(
        path,
        format!("extensionsRequired[{i}]"),
        format!(
            "glTF extension {name}{what} is not supported, and the file requires it; \
             strata reads {}; {}",
            enabled.join(", "),
            CONVERT.replace("to glTF 2.0 ", "to plain glTF 2.0 ")
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;

    #[test]
    fn malformed_json_and_validation_errors() {
        let dir = temp_dir("json-errors");
        let path = write(
            &dir,
            "broken.gltf",
            b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [",
        );
        expect_error(load_gltf(&path), "broken.gltf", "", "invalid glTF JSON");
        let b = triangle_builder();
        expect_error(
            load_json(&b, r#""nodes":[{"mesh":3}]"#),
            "scene.gltf",
            "nodes[0].mesh",
            "Index out of bounds",
        );
        // The gltf crate's own validator would panic on this one.
        expect_error(
            load_json(
                &b,
                r#""meshes":[{"primitives":[{"attributes":{"POSITION":9}}]}]"#,
            ),
            "scene.gltf",
            "meshes[0].primitives[0]",
            "accessors[9]",
        );
        expect_error(
            load_json(
                &b,
                r#""extensionsRequired":["KHR_draco_mesh_compression"],"extensionsUsed":["KHR_draco_mesh_compression"]"#,
            ),
            "scene.gltf",
            "extensionsRequired[0]",
            "glTF extension KHR_draco_mesh_compression (Draco-compressed meshes) is not supported",
        );
    }

    #[test]
    fn gltf_1_is_refused_by_name() {
        let dir = temp_dir("gltf1");
        // glTF 1.0 names its objects in dictionaries; some files give the
        // version as a number, or deserialize as 2.0 would.
        for (name, text) in [
            (
                "dict.gltf",
                r#"{"asset":{"version":"1.0"},"meshes":{"m":{}}}"#,
            ),
            ("number.gltf", r#"{"asset":{"version":1},"nodes":{}}"#),
            ("plain.gltf", r#"{"asset":{"version":"1.0.3"}}"#),
        ] {
            expect_error(
                load_gltf(&write(&dir, name, text.as_bytes())),
                name,
                "asset.version",
                "glTF 1.0 is not supported",
            );
        }
    }

    #[test]
    fn a_scene_without_nodes_loads_empty_with_a_warning() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"scene":0,"scenes":[{{}}],"nodes":[{{"mesh":0}}]"#);
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.triangle_count(), 0);
        let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(said[0].contains("scene.gltf: scenes[0]: the scene lists no nodes"));
        // Lines only: no triangles, said once.
        let mut b = Builder::default();
        b.vec3(&TRIANGLE, false);
        let lines = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"mode":1}]}],"nodes":[{"mesh":0}]"#;
        let asset = load_json(&b, lines).unwrap();
        assert_eq!(asset.warnings.len(), 1);
        assert!(asset.warnings[0].message.starts_with("no triangles"));
    }

    #[test]
    fn custom_attributes_and_missing_bounds_are_tolerated() {
        let mut b = Builder::default();
        b.vec3(&TRIANGLE, false);
        let asset = load_json(
            &b,
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"_BATCHID":0}}]}],"nodes":[{"mesh":0}]"#,
        )
        .unwrap();
        assert_eq!(asset.triangle_count(), 1);
    }

    #[test]
    fn bad_glb_headers() {
        let b = triangle_builder();
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}}]"#);
        let good = b.glb(&rest);
        let dir = temp_dir("glb");
        let mut v1 = good.clone();
        v1[4] = 1;
        expect_error(
            load_gltf(&write(&dir, "v1.glb", &v1)),
            "v1.glb",
            "GLB header",
            "version 1",
        );
        let mut long = good.clone();
        long[8..12].copy_from_slice(&(good.len() as u32 + 1).to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "long.glb", &long)),
            "long.glb",
            "GLB header",
            "truncated",
        );
        let mut tiny = good.clone();
        tiny[8..12].copy_from_slice(&3u32.to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "tiny.glb", &tiny)),
            "tiny.glb",
            "GLB header",
            "less than the header",
        );
        expect_error(
            load_gltf(&write(&dir, "text.glb", b"hello")),
            "text.glb",
            "GLB header",
            "magic",
        );
        let mut chunk = good.clone();
        chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        expect_error(
            load_gltf(&write(&dir, "chunk.glb", &chunk)),
            "chunk.glb",
            "GLB chunk 0",
            "truncated",
        );

        // Every truncation of a valid GLB is an error, never a panic.
        let path = dir.join("cut.glb");
        for len in 0..good.len() {
            let mut cut = good[..len].to_vec();
            if len >= 12 {
                cut[8..12].copy_from_slice(&(len as u32).to_le_bytes());
            }
            std::fs::write(&path, &cut).unwrap();
            assert!(load_gltf(&path).is_err(), "truncated to {len} bytes");
            std::fs::write(&path, &good[..len]).unwrap();
            assert!(load_gltf(&path).is_err(), "cut to {len} bytes");
        }
        std::fs::write(&path, &good).unwrap();
        assert_eq!(load_gltf(&path).unwrap().triangle_count(), 1);
    }
}
