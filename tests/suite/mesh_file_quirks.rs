//! Mesh files as other tools write and read them (issue 46): each case the
//! sweep over assimp's test models found, as a small file written here.
//! Lenient cases load, with one warning naming the file and line, and the
//! binary exits 0 printing it; refusals name the unsupported feature and
//! exit 2.

use super::common::meshes::base64;
use super::common::{stderr, strata, temp_dir};
use glam::Vec3;
use std::path::Path;
use strata::scene::asset::LoadedAsset;
use strata::scene::loaders::load_mesh_file;

/// The unit square as two triangles, CRLF line ends as Windows tools
/// write them.
const SQUARE: &str = "v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n";

fn load(dir: &Path, name: &str, bytes: &[u8]) -> LoadedAsset {
    std::fs::write(dir.join(name), bytes).unwrap();
    load_mesh_file(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// `strata render` of a scene holding only `mesh` (and a light), its exit
/// code and stderr.
fn render(dir: &Path, mesh: &str) -> (i32, String) {
    let scene = format!(
        "[render]\nwidth = 8\nheight = 6\nspp = 1\n\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 5.0]\nintensity = [1.0, 1.0, 1.0]\n\n\
         [[objects]]\nmesh = \"{mesh}\"\n"
    );
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let out = strata(dir, &["render", "scene.toml", "-o", "out.png", "--quiet"]);
    (out.status.code().unwrap_or(-1), stderr(&out))
}

fn warning_lines(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect()
}

fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
    let mut out = if big_endian {
        vec![0xfe, 0xff]
    } else {
        vec![0xff, 0xfe]
    };
    for unit in text.encode_utf16() {
        out.extend(if big_endian {
            unit.to_be_bytes()
        } else {
            unit.to_le_bytes()
        });
    }
    out
}

#[test]
fn utf16_obj_reads_as_its_utf8_twin() {
    let dir = temp_dir("real-utf16");
    let text = format!("# Erzeugt von einem Exporter \u{00e9}\r\n{SQUARE}f 1 2 3 4\r\n");
    let plain = load(&dir, "plain.obj", text.as_bytes());
    assert_eq!(plain.triangle_count(), 2);
    for big_endian in [true, false] {
        let asset = load(&dir, "wide.obj", &utf16(&text, big_endian));
        assert_eq!(asset.meshes, plain.meshes, "big endian: {big_endian}");
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    }
    let (code, err) = render(&dir, "wide.obj");
    assert_eq!((code, err.as_str()), (0, ""));
}

#[test]
fn latin1_mtl_names_and_comments_are_read() {
    let dir = temp_dir("real-latin1");
    // Latin-1: © (0xa9) in a comment, ä (0xe4) in a material's name.
    std::fs::write(
        dir.join("box.mtl"),
        b"# \xa9 Hersteller\r\nnewmtl Gel\xe4nder\r\nKd 0.25 0.5 0.75\r\n",
    )
    .unwrap();
    // The OBJ names the material in the same encoding.
    let mut obj = b"mtllib box.mtl\r\n".to_vec();
    obj.extend_from_slice(SQUARE.as_bytes());
    obj.extend_from_slice(b"usemtl Gel\xe4nder\r\nf 1 2 3\r\n");
    let asset = load(&dir, "box.obj", &obj);
    assert_eq!(asset.materials.len(), 1);
    assert_eq!(asset.materials[0].0, "Geländer");
    assert_eq!(asset.materials[0].1.diffuse, Vec3::new(0.25, 0.5, 0.75));
    assert_eq!(asset.meshes[0].material, Some(0));
    assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
}

#[test]
fn windows_texture_paths_resolve() {
    let dir = temp_dir("real-backslash");
    std::fs::create_dir(dir.join("maps")).unwrap();
    let texels: &[u8] = &[200, 100, 50];
    let image = image::RgbImage::from_raw(1, 1, texels.to_vec()).unwrap();
    image.save(dir.join("maps").join("SpiderTex.png")).unwrap();
    std::fs::write(
        dir.join("spider.mtl"),
        "newmtl Skin\r\nKd 1 1 1\r\nmap_Kd .\\maps\\SpiderTex.png\r\n",
    )
    .unwrap();
    let obj = format!("mtllib spider.mtl\r\n{SQUARE}vt 0 0\r\nusemtl Skin\r\nf 1/1 2/1 3/1\r\n");
    let asset = load(&dir, "spider.obj", obj.as_bytes());
    assert_eq!(asset.materials[0].1.diffuse_texture, Some(0));
    assert_eq!(asset.textures.images[0].texels(), [[200, 100, 50]]);
    assert!(asset.meshes[0].uvs.is_some());
    let (code, err) = render(&dir, "spider.obj");
    assert_eq!((code, err.as_str()), (0, ""));
}

#[test]
fn undefined_and_missing_materials_get_the_default_and_one_warning_each() {
    let dir = temp_dir("real-materials");
    std::fs::write(
        dir.join("some.mtl"),
        "newmtl known\nKd 1 0 0\nnewmtl \nKd 0 1 0\n",
    )
    .unwrap();
    let obj = format!(
        "mtllib some.mtl\nmtllib gone.mtl\n{SQUARE}\
         usemtl nowhere\nf 1 2 3\nusemtl known\nf 1 3 4\nusemtl nowhere\nf 2 3 4\n"
    );
    std::fs::write(dir.join("cube.obj"), &obj).unwrap();
    let asset = load_mesh_file(&dir.join("cube.obj")).unwrap();
    assert_eq!(asset.triangle_count(), 3);
    let materials: Vec<_> = asset.meshes.iter().map(|m| m.material).collect();
    assert_eq!(materials, [None, Some(0), None], "None: the default");
    let names: Vec<&str> = asset.materials.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["known"]);
    // The unnamed newmtl, and the missing library at its mtllib line; the
    // usemtl of a name the missing library may have held says no more.
    let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(said.len(), 2, "{said:?}");
    assert!(said[0].contains("some.mtl: line 3: newmtl without a material name"));
    assert!(said[1].contains("cube.obj: line 2: cannot read material library"));
    assert!(said[1].contains("gone.mtl"));

    let (code, err) = render(&dir, "cube.obj");
    assert_eq!(code, 0, "{err}");
    assert_eq!(warning_lines(&err).len(), 2, "{err}");

    // With every library there, an undefined name is one warning at the
    // first usemtl naming it.
    let obj = obj.replace("mtllib gone.mtl\n", "\n");
    std::fs::write(dir.join("cube.obj"), &obj).unwrap();
    let (code, err) = render(&dir, "cube.obj");
    assert_eq!(code, 0, "{err}");
    let lines = warning_lines(&err);
    assert_eq!(lines.len(), 2, "{err}");
    assert!(lines[1].starts_with("warning: "), "{err}");
    assert!(
        lines[1].contains("cube.obj: line 7: material 'nowhere' is not defined"),
        "{err}"
    );
}

#[test]
fn ply_header_with_a_bare_comment_line() {
    let dir = temp_dir("real-ply");
    let header =
        "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: \n\
                  element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                  element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let ascii = format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    let asset = load(&dir, "wuson.ply", ascii.as_bytes());
    assert_eq!(asset.triangle_count(), 1);
    assert_eq!(asset.meshes[0].positions[1], Vec3::X);
    let said: Vec<String> = asset.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(
        said[0].contains("wuson.ply: line 3: 'Created by Blender3D 247"),
        "{said:?}"
    );

    // The binary body after the same header.
    let header = header.replace("ascii", "binary_little_endian");
    let mut binary = header.into_bytes();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        binary.extend(v.to_le_bytes());
    }
    binary.push(3);
    for i in [0i32, 1, 2] {
        binary.extend(i.to_le_bytes());
    }
    let asset = load(&dir, "wuson_bin.ply", &binary);
    assert_eq!(asset.triangle_count(), 1);
    assert_eq!(asset.meshes[0].positions[2], Vec3::Y);
    assert_eq!(asset.warnings.len(), 1);

    // An ASCII body error still names the right line: the skipped line counts.
    let broken = ascii.replace("1 0 0\n0 1 0", "1 0 0\n0 x 0");
    std::fs::write(dir.join("broken.ply"), broken).unwrap();
    let err = load_mesh_file(&dir.join("broken.ply")).unwrap_err();
    assert!(err.to_string().contains("line 13"), "{err}");

    let (code, err) = render(&dir, "wuson.ply");
    assert_eq!(code, 0, "{err}");
    assert_eq!(warning_lines(&err).len(), 1, "{err}");
}

#[test]
fn files_without_triangles_warn_naming_the_file() {
    let dir = temp_dir("real-points");
    std::fs::write(
        dir.join("cloud.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n",
    )
    .unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
               property float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n";
    std::fs::write(dir.join("cloud.ply"), ply).unwrap();
    for name in ["cloud.obj", "cloud.ply"] {
        let asset = load_mesh_file(&dir.join(name)).unwrap();
        assert_eq!(asset.triangle_count(), 0);
        let (code, err) = render(&dir, name);
        assert_eq!(code, 0, "{err}");
        let lines = warning_lines(&err);
        assert_eq!(lines.len(), 1, "{err}");
        assert!(lines[0].contains(&format!("{name}: no faces")), "{err}");
    }
}

/// A glTF file of one triangle: `extra` is spliced into the top level.
fn gltf(extra: &str) -> String {
    // Three vertices, little-endian f32, as a data URI.
    let mut bytes = Vec::new();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bytes.extend(v.to_le_bytes());
    }
    let data = base64(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "nodes":[{{"mesh":0}}]{extra}}}"#
    )
}

#[test]
fn gltf_scene_without_nodes_renders_nothing_and_says_so() {
    let dir = temp_dir("real-gltf-empty");
    assert_eq!(
        load(&dir, "one.gltf", gltf("").as_bytes()).triangle_count(),
        1
    );
    for scenes in [r#","scene":0,"scenes":[{}]"#, r#","scenes":[{"nodes":[]}]"#] {
        let asset = load(&dir, "empty.gltf", gltf(scenes).as_bytes());
        assert_eq!(asset.triangle_count(), 0);
        let (code, err) = render(&dir, "empty.gltf");
        assert_eq!(code, 0, "{err}");
        let lines = warning_lines(&err);
        assert_eq!(lines.len(), 1, "{err}");
        assert!(
            lines[0].contains("empty.gltf: scenes[0]: the scene lists no nodes"),
            "{err}"
        );
    }
}

#[test]
fn refusals_name_the_feature() {
    let dir = temp_dir("real-refusals");
    let v1 = r#"{"asset":{"version":"1.0"},"meshes":{"box":{"primitives":[]}},"scene":"s"}"#;
    std::fs::write(dir.join("old.gltf"), v1).unwrap();
    let mut glb1 = b"glTF".to_vec();
    glb1.extend(1u32.to_le_bytes());
    glb1.extend(20u32.to_le_bytes());
    glb1.extend([0u8; 8]);
    std::fs::write(dir.join("old.glb"), glb1).unwrap();
    let draco = gltf(
        r#","extensionsUsed":["KHR_draco_mesh_compression"],
        "extensionsRequired":["KHR_draco_mesh_compression"]"#,
    )
    .replace(r#""bufferView":0,"#, "");
    std::fs::write(dir.join("draco.gltf"), draco).unwrap();
    let other = gltf(r#","extensionsRequired":["KHR_lights_punctual","EXT_made_up"]"#);
    std::fs::write(dir.join("other.gltf"), other).unwrap();
    let cases = [
        (
            "old.gltf",
            "old.gltf: asset.version: glTF 1.0 is not supported",
        ),
        (
            "old.glb",
            "old.glb: GLB header: binary glTF 1.0 (GLB version 1) is not supported",
        ),
        (
            "draco.gltf",
            "draco.gltf: extensionsRequired[0]: glTF extension KHR_draco_mesh_compression",
        ),
        (
            "other.gltf",
            "other.gltf: extensionsRequired[1]: glTF extension EXT_made_up is not supported",
        ),
    ];
    for (name, needle) in cases {
        let err = load_mesh_file(&dir.join(name)).unwrap_err().to_string();
        assert!(err.contains(needle), "{err}\nshould contain {needle}");
        let (code, err) = render(&dir, name);
        assert_eq!(code, 2, "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
}

#[test]
fn binary_files_posing_as_obj_are_still_refused() {
    let dir = temp_dir("real-binary");
    std::fs::write(dir.join("x.obj"), b"v 0 0 0\n\x89PNG\x00\x01\xff\n").unwrap();
    let err = load_mesh_file(&dir.join("x.obj")).unwrap_err();
    assert_eq!(err.location, "line 2", "{err}");
    assert!(err.to_string().contains("NUL byte"), "{err}");
}
