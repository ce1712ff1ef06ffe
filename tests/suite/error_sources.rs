//! An error names where its value came from (issue 62, point 2): a flag
//! (`--spp 0`), a `--set` edit (`--set render.spp=0`), the scene file at
//! its line, or, for a model file, strata's own scene, which has no lines:
//! `strata render bunny.obj --spp 0` is the flag's fault, never
//! `bunny.obj: line 7`.

use crate::common::meshes::base64;
use crate::common::{stderr, strata, temp_dir};
use std::path::Path;

/// `strata render ARGS` in `dir`: exit 2 and its one line of error.
fn refused(dir: &Path, args: &[&str]) -> String {
    let mut all = vec!["render", "-q", "-o", "out.png"];
    all.extend(args);
    let out = strata(dir, &all);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(!dir.join("out.png").exists());
    err.trim_end().to_string()
}

const MODEL: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn a_flag_on_a_model_file_is_the_flags_fault() {
    let dir = temp_dir("sources-model");
    std::fs::write(dir.join("bunny.obj"), MODEL).unwrap();
    for (args, said) in [
        (
            &["bunny.obj", "--spp", "0"][..],
            "error: <command line>: --spp 0: must be at least 1",
        ),
        (
            &["bunny.obj", "--width", "100000"],
            "error: <command line>: --width 100000: image larger than 32768 pixels on a side",
        ),
        (
            &["bunny.obj", "--set", "render.spp=0"],
            "error: <command line>: --set render.spp=0: must be at least 1",
        ),
    ] {
        let err = refused(&dir, args);
        assert_eq!(err, said, "{args:?}");
    }
}

/// A model without lights is lit by strata's environment: a background
/// names the flag or edit that gave it and says how to colour that light,
/// never to drop a light the user never wrote.
#[test]
fn a_background_on_a_model_lit_by_strata_names_the_light_as_strata_s() {
    let dir = temp_dir("sources-background");
    std::fs::write(dir.join("bunny.obj"), MODEL).unwrap();
    for (args, place) in [
        (
            &["bunny.obj", "--background", "0.1"][..],
            "--background 0.1:",
        ),
        (
            &["bunny.obj", "--set", "render.background=[0.1, 0.2, 0.3]"],
            "--set render.background=",
        ),
    ] {
        let err = refused(&dir, args);
        assert!(err.contains(place), "{args:?}: {err}");
        assert!(
            err.contains("strata lights it") && err.contains("lights[0].radiance"),
            "{err}"
        );
        assert!(!err.contains("drop the background or the light"), "{err}");
        assert!(!err.contains("line "), "{err}");
    }
}

/// In a scene file the same values are the file's at their line, the
/// edit's, or the flag's; a flag's background against the file's own
/// environment light names the flag, not `render.background`.
#[test]
fn a_scene_files_values_name_the_line_the_edit_or_the_flag() {
    let dir = temp_dir("sources-scene");
    std::fs::write(dir.join("s.toml"), "[render]\nwidth = 8\nspp = 0\n").unwrap();
    std::fs::write(dir.join("ok.toml"), "[render]\nwidth = 8\nheight = 8\n").unwrap();
    let camera = |position: &str| {
        format!("[camera]\nposition = {position}\nlook_at = [0, 1, 0]\n[render]\nwidth = 8\nheight = 8\n")
    };
    std::fs::write(dir.join("cam.toml"), camera("[0, 1, 5]")).unwrap();
    std::fs::write(dir.join("top.toml"), camera("[0, 5, 0]")).unwrap();
    std::fs::write(dir.join("far.toml"), camera("[0, 1, 1e20]")).unwrap();
    std::fs::write(
        dir.join("env.toml"),
        "[render]\nwidth = 8\nheight = 8\n[[lights]]\ntype = \"environment\"\nradiance = 1.0\n",
    )
    .unwrap();
    for (args, said) in [
        (
            &["s.toml"][..],
            "error: s.toml: line 3: render.spp: must be at least 1",
        ),
        (
            &["ok.toml", "--set", "render.spp=0"],
            "error: <command line>: --set render.spp=0: must be at least 1",
        ),
        (
            &["ok.toml", "--shadow-samples", "0"],
            "error: <command line>: --shadow-samples 0: must be at least 1",
        ),
        // A value the compiler checks: the edited key is named once, and
        // a key inside an edited table after it.
        (
            &["ok.toml", "--set", "camera.fov=500"],
            "error: <command line>: --set camera.fov: must be between 0 and 180 degrees, got 500",
        ),
        (
            &["ok.toml", "--set", "camera={fov = 500}"],
            "error: <command line>: --set camera: camera.fov: must be between 0 and 180 degrees, got 500",
        ),
        (
            &["ok.toml", "--background", "1,0,-1"],
            "error: <command line>: --background 1,0,-1: must be finite and not negative",
        ),
        // A relation between two keys, one of them edited: the edit is
        // named, not the file's line of the key the user left alone.
        (
            &["cam.toml", "--set", "camera.position=[0, 1, 0]"],
            "error: <command line>: --set camera.position: camera.look_at: equals camera.position, so there is no view direction",
        ),
        (
            &["cam.toml", "--set", "camera.position=[0, 5, 0]"],
            "error: <command line>: --set camera.position: camera.up: is not given, and its default [0, 1, 0] is parallel to the view direction from camera.position to camera.look_at: give camera.up across it",
        ),
        (
            &["cam.toml", "--set", "camera.up=[0, 0, 3]"],
            "error: <command line>: --set camera.up: is zero or parallel to the view direction",
        ),
        // Both ends in the file: its line of `up`'s table (up not written).
        (
            &["top.toml"],
            "error: top.toml: line 1: camera.up: is not given, and its default [0, 1, 0] is parallel to the view direction from camera.position to camera.look_at: give camera.up across it",
        ),
        (
            &["far.toml"],
            "error: far.toml: line 3: camera.look_at: lies too far from camera.position for 32-bit floats (their distance must stay below about 1e19)",
        ),
    ] {
        assert_eq!(refused(&dir, args), said, "{args:?}");
    }
    let err = refused(&dir, &["env.toml", "--background", "0.2"]);
    assert!(
        err.starts_with("error: <command line>: --background 0.2: rays that hit nothing see env.toml's environment light"),
        "{err}"
    );
}

/// A glTF camera whose aspect ratio makes the image too large names the
/// file's camera, not a `[render]` key strata wrote.
#[test]
fn a_models_camera_aspect_is_named_as_the_files() {
    let dir = temp_dir("sources-aspect");
    let bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":0.7,"aspectRatio":0.0001,"znear":0.1}}}}],
        "nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,5]}}],
        "scenes":[{{"nodes":[0,1]}}],"scene":0}}"#,
        base64(&bin)
    );
    std::fs::write(dir.join("tall.gltf"), gltf).unwrap();
    let err = refused(&dir, &["tall.gltf"]);
    assert!(
        err.starts_with(
            "error: tall.gltf: camera 0: its aspect ratio 0.0001 makes the image 640×6400000"
        ),
        "{err}"
    );
    assert!(err.ends_with("give --width and --height"), "{err}");
}
