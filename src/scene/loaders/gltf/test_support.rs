//! Shared by the glTF loader's unit tests: a builder for glTF files around
//! one binary buffer, GLB and base64 encoders, and assertions on loaded
//! meshes and errors. It re-exports what every test module needs besides,
//! so one `use super::super::test_support::*` brings it all.

pub(super) use super::load_gltf;
pub(super) use crate::error::InputResult;
pub(super) use crate::scene::asset::{LoadedAsset, LoadedMesh};
pub(super) use crate::scene::loaders::test_files::{temp_dir, write};
pub(super) use glam::Vec3;
use std::path::{Path, PathBuf};

/// Builds one binary buffer with views and accessors into it.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) views: Vec<String>,
    accessors: Vec<String>,
}

impl Builder {
    pub(super) fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
            bytes.len()
        ));
        self.views.len() - 1
    }

    pub(super) fn accessor(&mut self, json: String) -> usize {
        self.accessors.push(json);
        self.accessors.len() - 1
    }

    pub(super) fn vec3(&mut self, values: &[[f32; 3]], bounds: bool) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        let bounds = if bounds {
            let lo = (0..3).map(|k| values.iter().map(|v| v[k]).fold(f32::MAX, f32::min));
            let hi = (0..3).map(|k| values.iter().map(|v| v[k]).fold(f32::MIN, f32::max));
            let list = |it: &mut dyn Iterator<Item = f32>| {
                it.map(|v| format!("{v:?}")).collect::<Vec<_>>().join(",")
            };
            format!(
                r#","min":[{}],"max":[{}]"#,
                list(&mut { lo }),
                list(&mut { hi })
            )
        } else {
            String::new()
        };
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{},"type":"VEC3"{bounds}}}"#,
            values.len()
        ))
    }

    /// `FLOAT` `VEC2` values, such as texture coordinates.
    pub(super) fn vec2(&mut self, values: &[[f32; 2]]) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        self.raw_accessor(&bytes, 5126, "VEC2", false)
    }

    /// An accessor over `bytes` in a view of their own: `component` is the
    /// glTF componentType, `kind` the type (`"VEC2"`), each element tightly
    /// packed.
    pub(super) fn raw_accessor(
        &mut self,
        bytes: &[u8],
        component: u32,
        kind: &str,
        normalized: bool,
    ) -> usize {
        let size = match component {
            5120 | 5121 => 1,
            5122 | 5123 => 2,
            _ => 4,
        } * match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let view = self.view(bytes);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":{component},"count":{},"type":"{kind}","normalized":{normalized}}}"#,
            bytes.len() / size
        ))
    }

    pub(super) fn positions(&mut self, values: &[[f32; 3]]) -> usize {
        self.vec3(values, true)
    }

    pub(super) fn u16s(&mut self, values: &[u16]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5123,"count":{},"type":"SCALAR"}}"#,
            values.len()
        ))
    }

    pub(super) fn u8s(&mut self, values: &[u8]) -> usize {
        let view = self.view(values);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5121,"count":{},"type":"SCALAR"}}"#,
            values.len()
        ))
    }

    pub(super) fn u32s(&mut self, values: &[u32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            values.len()
        ))
    }

    /// The glTF JSON; `uri` is the buffer's uri (None for a GLB), `rest`
    /// the remaining top-level members (nodes, meshes, ...).
    pub(super) fn json(&self, uri: Option<&str>, rest: &str) -> String {
        let uri = uri.map(|u| format!(r#","uri":"{u}""#)).unwrap_or_default();
        let rest = if rest.is_empty() {
            String::new()
        } else {
            format!(",{rest}")
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}{uri}}}],"bufferViews":[{}],"accessors":[{}]{rest}}}"#,
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        )
    }

    pub(super) fn data_uri(&self) -> String {
        format!(
            "data:application/octet-stream;base64,{}",
            encode_base64(&self.bin)
        )
    }

    pub(super) fn glb(&self, rest: &str) -> Vec<u8> {
        glb_bytes(self.json(None, rest).as_bytes(), Some(&self.bin))
    }

    /// Write `name`.gltf with `name`.bin beside it.
    pub(super) fn write_gltf(&self, dir: &Path, name: &str, rest: &str) -> PathBuf {
        write(dir, &format!("{name}.bin"), &self.bin);
        let json = self.json(Some(&format!("{name}.bin")), rest);
        write(dir, &format!("{name}.gltf"), json.as_bytes())
    }
}

pub(super) fn glb_bytes(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut chunks = Vec::new();
    chunks.extend_from_slice(&(json.len() as u32).to_le_bytes());
    chunks.extend_from_slice(b"JSON");
    chunks.extend_from_slice(&json);
    if let Some(bin) = bin {
        let mut bin = bin.to_vec();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        chunks.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        chunks.extend_from_slice(b"BIN\0");
        chunks.extend_from_slice(&bin);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + chunks.len()) as u32).to_le_bytes());
    out.extend_from_slice(&chunks);
    out
}

pub(super) fn encode_base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

pub(super) const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A builder holding one indexed triangle as mesh 0 (accessors 0 and 1).
pub(super) fn triangle_builder() -> Builder {
    let mut b = Builder::default();
    b.positions(&TRIANGLE);
    b.u16s(&[0, 1, 2]);
    b
}

pub(super) const TRIANGLE_MESH: &str =
    r#""meshes":[{"name":"tri","primitives":[{"attributes":{"POSITION":0},"indices":1}]}]"#;

pub(super) fn load_json(b: &Builder, rest: &str) -> InputResult<LoadedAsset> {
    let dir = temp_dir("json");
    load_gltf(&b.write_gltf(&dir, "scene", rest))
}

/// [`load_json`] with the shared meshes baked: every mesh in file order.
pub(super) fn load_baked(b: &Builder, rest: &str) -> LoadedAsset {
    load_json(b, rest).unwrap().into_baked()
}

fn corners(mesh: &LoadedMesh) -> Vec<[Vec3; 3]> {
    mesh.indices
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect()
}

pub(super) fn assert_close(a: Vec3, b: Vec3) {
    assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
}

pub(super) fn assert_corners(mesh: &LoadedMesh, expected: [[f32; 3]; 3]) {
    let got = corners(mesh);
    assert_eq!(got.len(), 1);
    for k in 0..3 {
        assert_close(got[0][k], Vec3::from(expected[k]));
    }
}
pub(super) fn expect_error(
    result: InputResult<LoadedAsset>,
    file: &str,
    location: &str,
    needle: &str,
) {
    let err = result.expect_err("expected an error");
    let shown = err.to_string();
    assert!(err.file.ends_with(file), "{shown} should name {file}");
    assert_eq!(err.location, location, "{shown}");
    assert!(shown.contains(location), "{shown}");
    assert!(shown.contains(needle), "{shown} should contain '{needle}'");
}
