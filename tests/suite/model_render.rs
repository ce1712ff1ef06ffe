//! `strata render MODEL`: a model file rendered as it comes (issue 46).
//! A glTF's own camera and lights render exactly as the same scene written
//! by hand; a model without a camera is framed whole at any size and
//! place; `--save-scene` writes a scene that renders the same image; and a
//! spot light falls off as glTF's formula says.

use crate::common::exr::read_exr;
use crate::common::{render_rgb, scene_at, stderr, strata, temp_dir};
use glam::Vec3;
use std::path::{Path, PathBuf};
use strata::accel::BuildQuality;
use strata::scene::compile::{compile_model, LoadProgress};
use strata::scene::model::{model_scene, CameraChoice};
use strata::scene::{RenderOverrides, Scene};

/// A glTF file `name`.gltf (with `name`.bin beside it) holding one mesh of
/// `positions` and `triangles` as mesh 0, and `rest`: the file's other
/// top-level members (nodes, cameras, extensions).
fn write_gltf(
    dir: &Path,
    name: &str,
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    rest: &str,
) -> PathBuf {
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let index_offset = bin.len();
    bin.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let lo = (0..3).map(|k| positions.iter().map(|p| p[k]).fold(f32::MAX, f32::min));
    let hi = (0..3).map(|k| positions.iter().map(|p| p[k]).fold(f32::MIN, f32::max));
    let list = |it: &mut dyn Iterator<Item = f32>| {
        it.map(|v| format!("{v:?}")).collect::<Vec<_>>().join(",")
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},
        "buffers":[{{"byteLength":{},"uri":"{name}.bin"}}],
        "bufferViews":[{{"buffer":0,"byteLength":{index_offset}}},
                       {{"buffer":0,"byteOffset":{index_offset},"byteLength":{}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{}],"max":[{}]}},
                     {{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        {rest}}}"#,
        bin.len(),
        bin.len() - index_offset,
        positions.len(),
        list(&mut { lo }),
        list(&mut { hi }),
        triangles.len() * 3,
    );
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, json).unwrap();
    path
}

/// The scene `strata render MODEL` makes, compiled as it compiles it.
fn model(path: &Path, cli: &RenderOverrides, camera: Option<usize>) -> Scene {
    let camera = camera.map(CameraChoice::Index);
    let made = model_scene(path, cli, &[], camera).unwrap_or_else(|e| panic!("{e}"));
    let start = std::time::Instant::now();
    compile_model(
        made,
        cli,
        BuildQuality::Auto,
        start,
        &LoadProgress::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .0
}

fn bits(image: &[Vec3]) -> Vec<[u32; 3]> {
    image
        .iter()
        .map(|v| v.to_array().map(f32::to_bits))
        .collect()
}

/// A floor (two triangles, y = 0) and a wall facing +Z at z = −4.
fn floor_and_wall() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let positions = vec![
        [-8.0, 0.0, -8.0],
        [8.0, 0.0, -8.0],
        [8.0, 0.0, 4.0],
        [-8.0, 0.0, 4.0],
        [-8.0, 0.0, -4.0],
        [8.0, 0.0, -4.0],
        [8.0, 6.0, -4.0],
        [-8.0, 6.0, -4.0],
    ];
    let triangles = vec![[0, 3, 2], [0, 2, 1], [4, 5, 6], [4, 6, 7]];
    (positions, triangles)
}

/// A camera looking along −Z from (0, 2, 6); a point light (candela
/// 13660, colour [1, 0.5, 0.25]: 20, 10, 5 W/sr), a spot light pointing
/// straight down (its node's matrix takes −Z to −Y; 20490 cd: 30 W/sr;
/// cones 0.3 and 0.5 rad) and a directional light along −Z (1366 lux:
/// 2 W/m²). A second, orthographic camera.
const LIT_SCENE: &str = r#""scene":0,"scenes":[{"nodes":[0,1,2,3,4,5]}],
    "cameras":[{"type":"perspective","perspective":{"yfov":0.7,"aspectRatio":1.5,"znear":0.1,"zfar":50}},
               {"type":"orthographic","orthographic":{"xmag":3,"ymag":2,"znear":0.1,"zfar":50}}],
    "extensions":{"KHR_lights_punctual":{"lights":[
        {"type":"point","color":[1,0.5,0.25],"intensity":13660},
        {"type":"spot","intensity":20490,"spot":{"innerConeAngle":0.3,"outerConeAngle":0.5}},
        {"type":"directional","intensity":1366}]}},
    "extensionsUsed":["KHR_lights_punctual"],
    "nodes":[{"mesh":0},
             {"camera":0,"translation":[0,2,6]},
             {"extensions":{"KHR_lights_punctual":{"light":0}},"translation":[-1,3,0]},
             {"extensions":{"KHR_lights_punctual":{"light":1}},"matrix":[1,0,0,0, 0,0,-1,0, 0,1,0,0, 2,4,-2,1]},
             {"extensions":{"KHR_lights_punctual":{"light":2}}},
             {"camera":1,"translation":[0,3,8]}]"#;

/// The same scene written by hand: the camera, the three lights in W/sr
/// and W/m², the angles in degrees, and the path integrator a model file
/// renders with.
fn by_hand(mesh: &str) -> String {
    format!(
        "[render]\nwidth = 120\nheight = 80\nspp = 2\nintegrator = \"path\"\n\
         [camera]\nposition = [0.0, 2.0, 6.0]\nlook_at = [0.0, 2.0, 0.0]\nfov = {:?}\n\
         [[lights]]\ntype = \"point\"\nposition = [-1.0, 3.0, 0.0]\nintensity = [20.0, 10.0, 5.0]\n\
         [[lights]]\ntype = \"spot\"\nposition = [2.0, 4.0, -2.0]\ndirection = [0.0, -1.0, 0.0]\n\
         intensity = 30.0\ninner_angle = {:?}\nouter_angle = {:?}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, 0.0, -1.0]\nirradiance = 2.0\n\
         [[objects]]\nmesh = \"{mesh}\"\nlights = false\n",
        0.7f32.to_degrees(),
        0.3f32.to_degrees(),
        0.5f32.to_degrees(),
    )
}

#[test]
fn a_gltfs_camera_and_lights_render_as_the_same_scene_written_by_hand() {
    let dir = temp_dir("model-lit");
    let (positions, triangles) = floor_and_wall();
    let path = write_gltf(&dir, "lit", &positions, &triangles, LIT_SCENE);
    // Only the width given: the camera's aspect ratio, 1.5, sets the height.
    let cli = RenderOverrides {
        width: Some(120),
        spp: Some(2),
        ..Default::default()
    };
    let made = model(&path, &cli, None);
    assert_eq!((made.settings.width, made.settings.height), (120, 80));
    assert_eq!(made.lights.len(), 3);
    let hand = scene_at(&by_hand("lit.gltf"), &dir.join("hand.toml"));
    let image = render_rgb(&made, 0);
    assert!(
        bits(&image) == bits(&render_rgb(&hand, 0)),
        "the model's render differs from the hand-written scene's"
    );
    // A scene file that imports the file's camera and lights renders the same.
    let imported = scene_at(
        "[render]\nwidth = 120\nheight = 80\nspp = 2\nintegrator = \"path\"\n\
         [[objects]]\nmesh = \"lit.gltf\"\ncamera = 0\n",
        &dir.join("import.toml"),
    );
    assert!(
        bits(&image) == bits(&render_rgb(&imported, 0)),
        "importing differs"
    );
    // Each light is there: without any one of them, the image changes.
    for without in 0..3 {
        let mut fewer = made.clone();
        fewer.lights.remove(without);
        assert_ne!(
            bits(&render_rgb(&fewer, 0)),
            bits(&image),
            "light {without} did nothing"
        );
    }
    // Camera 1 is the orthographic one: its aspect xmag / ymag = 1.5 too.
    let second = model(
        &path,
        &RenderOverrides {
            height: Some(40),
            ..Default::default()
        },
        Some(1),
    );
    assert!(matches!(
        second.camera,
        strata::camera::Camera::Orthographic(_)
    ));
    assert_eq!((second.settings.width, second.settings.height), (60, 40));
}

#[test]
fn camera_out_of_range_and_flags_without_a_model_are_clear_errors() {
    let dir = temp_dir("model-errors");
    let (positions, triangles) = floor_and_wall();
    write_gltf(&dir, "lit", &positions, &triangles, LIT_SCENE);
    write_gltf(
        &dir,
        "bare",
        &positions,
        &triangles,
        r#""nodes":[{"mesh":0}]"#,
    );
    std::fs::write(dir.join("s.toml"), "").unwrap();
    for (args, needles) in [
        (
            &["render", "lit.gltf", "--camera", "2"][..],
            &[
                "--camera",
                "lit.gltf has 2 cameras, 0 to 1, so there is no camera 2",
            ][..],
        ),
        (
            &["render", "bare.gltf", "--camera", "0"],
            &["bare.gltf has no cameras"],
        ),
        (
            &["render", "s.toml", "--camera", "0"],
            &["--camera", "applies to a model file"],
        ),
        (
            &["render", "s.toml", "--save-scene", "x.toml"],
            &["--save-scene", "applies to a model file"],
        ),
        (
            &["render", "lit.gltf", "--save-scene", "x.png"],
            &["--save-scene", ".toml"],
        ),
    ] {
        let out = strata(&dir, args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        let text = stderr(&out);
        assert_eq!(text.lines().count(), 1, "{args:?}: one line: {text}");
        for needle in needles {
            assert!(text.contains(needle), "{args:?}: {text}");
        }
    }
}

/// `--save-scene` writes the scene it rendered, every flag and `--set`
/// included, naming the model relative to where it is saved: rendering
/// that file gives the same image, bit for bit. A model without camera or
/// lights says so, one line each.
#[test]
fn a_saved_scene_renders_the_same_image() {
    let dir = temp_dir("model-save");
    let obj = crate::common::bumpy_sphere_obj(24, 12, 1.0, 0.1);
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::write(dir.join("models/ball.obj"), obj).unwrap();
    let (positions, triangles) = floor_and_wall();
    write_gltf(
        &dir.join("models"),
        "lit",
        &positions,
        &triangles,
        LIT_SCENE,
    );
    for (model, extra) in [
        (
            "models/ball.obj",
            &["--set", "camera.fov=30", "--seed", "7"][..],
        ),
        (
            "models/lit.gltf",
            &["--camera", "1", "--set", "lights[1].intensity=[5, 5, 5]"][..],
        ),
    ] {
        let mut args = vec![
            "render",
            model,
            "--width",
            "48",
            "--height",
            "36",
            "--spp",
            "3",
            "-o",
            "a.exr",
            "--save-scene",
            "saved/s.toml",
        ];
        args.extend(extra);
        std::fs::create_dir_all(dir.join("saved")).unwrap();
        let out = strata(&dir, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        if model.ends_with(".obj") {
            let notes = stderr(&out);
            assert!(
                notes.contains("has no lights") && notes.contains("has no camera"),
                "{notes}"
            );
            assert!(
                notes.contains("framed its bounds [-"),
                "the bounds are said: {notes}"
            );
        }
        let saved = std::fs::read_to_string(dir.join("saved/s.toml")).unwrap();
        assert!(saved.contains("mesh = \"../models/"), "{saved}");
        let out = strata(&dir, &["render", "saved/s.toml", "-o", "b.exr", "--quiet"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let (a, b) = (read_exr(&dir.join("a.exr")), read_exr(&dir.join("b.exr")));
        assert_eq!(a.size, (48, 36));
        for c in ["R", "G", "B"] {
            let same = a
                .channel(c)
                .iter()
                .zip(b.channel(c))
                .all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same, "{model}: channel {c} differs\n{saved}");
        }
    }
}

/// A bumpy ball stretched along x, scaled by `size` and moved well off
/// the origin, as a PLY (or OBJ) file.
fn ball(size: f32, at: Vec3, ply: bool) -> (String, String) {
    let obj = crate::common::bumpy_sphere_obj(32, 16, 1.0, 0.15);
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for line in obj.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let v: Vec<f32> = words.map(|w| w.parse().unwrap()).collect();
                vertices.push(at + size * Vec3::new(2.5 * v[0], v[1], 0.7 * v[2]));
            }
            Some("f") => faces.push(words.map(|w| w.parse::<u32>().unwrap()).collect::<Vec<_>>()),
            _ => {}
        }
    }
    if !ply {
        let mut text = String::new();
        for v in &vertices {
            text += &format!("v {:?} {:?} {:?}\n", v.x, v.y, v.z);
        }
        for f in &faces {
            text += &format!("f {} {} {}\n", f[0], f[1], f[2]);
        }
        return ("ball.obj".into(), text);
    }
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    );
    for v in &vertices {
        text += &format!("{:?} {:?} {:?}\n", v.x, v.y, v.z);
    }
    for f in &faces {
        text += &format!("3 {} {} {}\n", f[0] - 1, f[1] - 1, f[2] - 1);
    }
    ("ball.ply".into(), text)
}

/// Without a camera, the model's silhouette fills the image (reaching
/// close to an edge) without touching any edge, for models from 1e-3 to
/// 1e4 across, far from the origin, in wide and tall images.
#[test]
fn auto_framing_fills_the_image_without_cutting_the_model() {
    let dir = temp_dir("model-frame");
    for (k, (size, at, (w, h))) in [
        (1e-3, Vec3::new(2e-3, -5e-3, 1e-3), (80, 60)),
        (1e-3, Vec3::new(0.5, 0.25, -0.5), (60, 80)),
        (1.0, Vec3::new(3.0, -2.0, 7.0), (80, 60)),
        (30.0, Vec3::ZERO, (64, 64)),
        (1e4, Vec3::new(-3e4, 1e4, 2e4), (60, 80)),
    ]
    .into_iter()
    .enumerate()
    {
        let (name, text) = ball(size, at, k % 2 == 0);
        std::fs::write(dir.join(&name), text).unwrap();
        let (ws, hs) = (w.to_string(), h.to_string());
        let out = strata(
            &dir,
            &[
                "render",
                &name,
                "--width",
                &ws,
                "--height",
                &hs,
                "--aov",
                "depth,normal",
                "-o",
                "f.exr",
                "--spp",
                "1",
                "--quiet",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let exr = read_exr(&dir.join("f.exr"));
        let normal = |axis: &str| exr.channel(&format!("normal.{axis}")).to_vec();
        let (nx, ny, nz) = (normal("X"), normal("Y"), normal("Z"));
        // The model: hit, and not the studio's ground (normal exactly up).
        let depth: Vec<f32> = exr
            .channel("depth.Z")
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                let ground = (nx[i], ny[i], nz[i]) == (0.0, 1.0, 0.0);
                if ground {
                    f32::INFINITY
                } else {
                    d
                }
            })
            .collect();
        let hit = |x: usize, y: usize| depth[y * w + x].is_finite();
        let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
        for y in 0..h {
            for x in 0..w {
                if hit(x, y) {
                    (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                }
            }
        }
        let case = format!("size {size} at {at}, {w}x{h}: x {x0}..{x1}, y {y0}..{y1}");
        assert!(x1 >= x0 && y1 >= y0, "nothing seen: {case}");
        // Not cut: no silhouette pixel on any edge of the image.
        assert!(x0 > 0 && y0 > 0 && x1 < w - 1 && y1 < h - 1, "cut: {case}");
        // Fills: in one direction it reaches within an eighth of the edges.
        let reach_x = (w / 2 - x0).max(x1 + 1 - w / 2) as f32 / (w / 2) as f32;
        let reach_y = (h / 2 - y0).max(y1 + 1 - h / 2) as f32 / (h / 2) as f32;
        assert!(reach_x.max(reach_y) > 0.875, "does not fill: {case}");
        // And it is the model, not a speck: a good part of the image.
        let covered = depth.iter().filter(|d| d.is_finite()).count() as f32 / (w * h) as f32;
        assert!(covered > 0.15, "covers {covered}: {case}");
    }
}

/// A spot light pointing straight down at a diffuse floor: the radiance
/// at distance r from its foot is ρ/π · I · falloff(cosθ) · cosθ / d²,
/// with falloff 1 inside the inner cone, 0 outside the outer one and
/// glTF's ((cosθ − cos θo) / (cos θi − cos θo))² between.
#[test]
fn a_spot_light_falls_off_on_a_diffuse_plane_as_gltf_says() {
    let (h, intensity, inner, outer) = (2.0f32, 6.0f32, 15f32, 35f32);
    let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
    let mut seen = [0; 3];
    for i in 0..60 {
        let r = i as f32 * 0.03;
        let text = format!(
            "[render]\nwidth = 1\nheight = 1\n[camera]\ntype = \"orthographic\"\nposition = [{r:?}, 5.0, 0.0]\nlook_at = [{r:?}, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nheight = 0.0001\n\
             [materials.white]\ndiffuse = 0.5\n[[lights]]\ntype = \"spot\"\nposition = [0.0, {h:?}, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nintensity = {intensity:?}\ninner_angle = {inner:?}\nouter_angle = {outer:?}\n\
             [[objects]]\nplane = {{ normal = [0.0, 1.0, 0.0] }}\nmaterial = \"white\"\n"
        );
        let l = render_rgb(&crate::common::scene(&text), 1)[0].x;
        let d2 = r * r + h * h;
        let cos = h / d2.sqrt();
        let (falloff, region) = if cos >= ci {
            (1.0, 0)
        } else if cos <= co {
            (0.0, 2)
        } else {
            (((cos - co) / (ci - co)).powi(2), 1)
        };
        seen[region] += 1;
        let expected = 0.5 / std::f32::consts::PI * intensity * falloff * cos / d2;
        if falloff == 0.0 {
            assert_eq!(l, 0.0, "r {r}: outside the outer cone");
        } else {
            // Near the outer cone the ramp is steep relative to its value:
            // rounding of cosθ in f32 moves it by ~1e-6 of the peak.
            let peak = 0.5 / std::f32::consts::PI * intensity / (h * h);
            assert!(
                (l - expected).abs() <= 1e-3 * expected + 1e-5 * peak,
                "r {r}: {l} vs {expected}"
            );
        }
    }
    assert!(
        seen.iter().all(|&n| n >= 5),
        "every region sampled: {seen:?}"
    );
}
