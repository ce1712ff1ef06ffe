//! The flags of `strata render` that pipelines reach for, through the real
//! binary: `--set` equals editing the file (and with no value removes a
//! key), `--crop` equals the window of
//! a full render, EXR headers carry the camera and the render's settings,
//! `--aov` adds the first hits' albedo, normal and depth as EXR channels,
//! and a killed `--progressive` render leaves a readable image.

use crate::common::exr::read_exr;
use crate::common::process::{repo, strata, strata_command, strata_ok};
use exr::prelude::{AttributeValue, Text};

fn scene(name: &str) -> String {
    format!("{}/scenes/{name}", repo().display())
}

#[test]
fn set_equals_editing_the_file_bit_for_bit() {
    let dir = crate::common::temp_dir("set");
    let text = std::fs::read_to_string(scene("soft-shadow.toml")).unwrap();
    let edited = text
        .replace("fov = 40.0", "fov = 30.0")
        .replace("radiance = [6.0, 6.0, 6.0]", "radiance = [3.0, 4.0, 5.0]")
        .replace("spp = 4", "spp = 2");
    assert_ne!(edited, text);
    std::fs::write(dir.join("edited.toml"), edited).unwrap();
    std::fs::write(dir.join("original.toml"), &text).unwrap();
    strata_ok(
        &dir,
        &["render", "edited.toml", "-q", "-o", "edited.strata"],
    );
    strata_ok(
        &dir,
        &[
            "render",
            "original.toml",
            "-q",
            "-o",
            "set.strata",
            "--set",
            "camera.fov=30",
            "--set",
            "lights[0].radiance=[3, 4, 5]",
            "--set",
            "render.spp=2",
        ],
    );
    // Parts hold the scene's fingerprint and the film's exact sums.
    let a = std::fs::read(dir.join("edited.strata")).unwrap();
    let b = std::fs::read(dir.join("set.strata")).unwrap();
    assert!(a == b, "--set and the edited file differ");
    // An unknown key, or an element the scene lacks, is named.
    for (set, needle) in [
        ("render.spq=3", "--set render.spq: unknown key 'spq'"),
        ("lights[4].radiance=[1,1,1]", "lights has 1 entry"),
    ] {
        let o = strata(
            &dir,
            &["render", "original.toml", "-q", "-o", "x.png", "--set", set],
        );
        assert_eq!(o.status.code(), Some(2));
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(needle), "{set}: {e}");
        assert!(!dir.join("x.png").exists());
    }
}

/// Issue 62: `--set KEY=` removes a key, so that a value another
/// excludes can take its place: the sky strata gives a model turned
/// into a sky map. A key that is not there is named.
#[test]
fn set_with_no_value_removes_a_key() {
    let dir = crate::common::temp_dir("unset");
    let ball = crate::common::bumpy_sphere_obj(12, 6, 1.0, 0.0);
    std::fs::write(dir.join("ball.obj"), ball).unwrap();
    std::fs::copy(scene("sky.hdr"), dir.join("sky.hdr")).unwrap();
    let mut args = vec![
        "render",
        "ball.obj",
        "--width",
        "24",
        "--height",
        "18",
        "-q",
        "-o",
        "sky.png",
        "--set",
        "lights[0].map=\"sky.hdr\"",
    ];
    let o = strata(&dir, &args);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("give radiance or map, not both"), "{e}");
    args.extend(["--set", "lights[0].radiance=", "--save-scene", "saved.toml"]);
    strata_ok(&dir, &args);
    assert!(dir.join("sky.png").is_file());
    let saved = std::fs::read_to_string(dir.join("saved.toml")).unwrap();
    assert!(saved.contains("map = \"sky.hdr\""), "{saved}");
    let table: toml::Value = toml::from_str(&saved).unwrap();
    let sky = &table["lights"][0];
    assert!(sky.get("radiance").is_none(), "{saved}");
    let o = strata(
        &dir,
        &[
            "render",
            "ball.obj",
            "-q",
            "-o",
            "x.png",
            "--set",
            "lights[0].radiace=",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--set lights[0].radiace: lights[0] has no key 'radiace' to remove"),
        "{e}"
    );
}

#[test]
fn a_crop_equals_its_window_of_the_full_render() {
    let dir = crate::common::temp_dir("crop");
    let s = scene("seed-mc.toml");
    strata_ok(&dir, &["render", &s, "-q", "-o", "full.exr"]);
    strata_ok(
        &dir,
        &[
            "render",
            &s,
            "-q",
            "--crop",
            "37,21,101,70",
            "-o",
            "crop.exr",
        ],
    );
    let (full, crop) = (
        read_exr(&dir.join("full.exr")),
        read_exr(&dir.join("crop.exr")),
    );
    assert_eq!(crop.origin, (37, 21));
    assert_eq!(crop.size, (64, 49));
    assert_eq!(crop.display, full.size);
    for ((name, whole), (crop_name, part)) in full.channels.iter().zip(&crop.channels) {
        assert_eq!(name, crop_name);
        for y in 0..49 {
            for x in 0..64 {
                let a = whole[(21 + y) * full.size.0 + 37 + x];
                let b = part[y * 64 + x];
                assert_eq!(a.to_bits(), b.to_bits(), "{name} at ({x}, {y}) of the crop");
            }
        }
    }
    // The PNG of a crop is the window's size.
    strata_ok(
        &dir,
        &["render", &s, "-q", "--crop", "0,0,10,5", "-o", "crop.png"],
    );
    let (_, w, h) = strata::output::image::read_image(&dir.join("crop.png")).unwrap();
    assert_eq!((w, h), (10, 5));
}

#[test]
fn exr_headers_carry_the_camera_and_the_settings() {
    let dir = crate::common::temp_dir("meta");
    let s = scene("soft-shadow.toml");
    strata_ok(
        &dir,
        &[
            "render", &s, "-q", "--seed", "7", "--spp", "3", "-o", "m.exr",
        ],
    );
    let exr = read_exr(&dir.join("m.exr"));
    let other = |name: &str| exr.layer.other.get(&Text::from(name)).cloned();
    assert_eq!(other("spp"), Some(AttributeValue::I32(3)));
    assert_eq!(other("seed"), Some(AttributeValue::F64(7.0)));
    assert_eq!(
        other("sampler"),
        Some(AttributeValue::Text(Text::from("stratified")))
    );
    assert_eq!(
        other("strataVersion"),
        Some(AttributeValue::Text(Text::from(strata::VERSION)))
    );
    assert!(matches!(other("renderTimeSeconds"), Some(AttributeValue::F32(t)) if t > 0.0));
    // The scene's camera sits at [0, 3, 5] looking at [0, 0.3, 0]: the
    // matrices (row vectors) map it to the camera origin and the point it
    // looks at to the middle of the image, in front of the camera.
    let row_vector = |m: [f32; 16], p: [f32; 3]| -> [f32; 4] {
        std::array::from_fn(|c| p[0] * m[c] + p[1] * m[4 + c] + p[2] * m[8 + c] + m[12 + c])
    };
    let to_camera = exr.layer.world_to_camera.expect("worldToCamera");
    let origin = row_vector(to_camera, [0.0, 3.0, 5.0]);
    assert!(origin[..3].iter().all(|c| c.abs() < 1e-5), "{origin:?}");
    assert!(
        row_vector(to_camera, [0.0, 0.3, 0.0])[2] > 0.0,
        "+z looks forward"
    );
    let to_ndc = exr.layer.world_to_normalized_device.expect("worldToNDC");
    let h = row_vector(to_ndc, [0.0, 0.3, 0.0]);
    assert!(
        (h[0] / h[3] - 0.5).abs() < 1e-5 && (h[1] / h[3] - 0.5).abs() < 1e-5,
        "{h:?}"
    );
}

#[test]
fn a_killed_progressive_render_leaves_a_readable_image() {
    let dir = crate::common::temp_dir("progressive");
    let out = dir.join("p.png");
    let mut child = strata_command(&dir)
        .args([
            "render",
            &scene("seed-mc.toml"),
            "-q",
            "--progressive",
            "--passes",
            "64",
            "--spp",
            "4096",
            "--threads",
            "1",
            "-o",
        ])
        .arg(&out)
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(
            start.elapsed().as_secs() < 120,
            "no image after two minutes"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render ended early"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // Let it rewrite the image a few times, then kill it mid-render.
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "still rendering");
    child.kill().unwrap();
    child.wait().unwrap();
    let (pixels, w, h) = strata::output::image::read_image(&out).unwrap();
    assert_eq!((w, h), (200, 150));
    assert!(pixels.iter().any(|p| p.max_element() > 0.0), "a lit image");
}

/// An orthographic camera 5 units in front of a square (two triangles
/// wound towards the camera) that fills the middle of the view.
const QUAD: &str = r#"
[render]
width = 32
height = 32
spp = 4
[camera]
type = "orthographic"
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
height = 4.0
[materials.paint]
diffuse = [0.2, 0.4, 0.6]
[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = [1.0, 1.0, 1.0]
[[objects]]
material = "paint"
group = [
  { triangle = { v = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0]] } },
  { triangle = { v = [[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]] } },
]
"#;

#[test]
fn aovs_hold_the_first_hits_albedo_normal_and_depth() {
    let dir = crate::common::temp_dir("aov");
    std::fs::write(dir.join("quad.toml"), QUAD).unwrap();
    let render = |threads: &str, out: &str| {
        strata_ok(
            &dir,
            &[
                "render",
                "quad.toml",
                "-q",
                "--aov",
                "albedo,normal,depth",
                "--threads",
                threads,
                "-o",
                out,
            ],
        );
        read_exr(&dir.join(out))
    };
    let exr = render("2", "a.exr");
    let channel = |name: &str| &exr.channels.iter().find(|(n, _)| n == name).unwrap().1;
    // The quad spans pixels 8..24 both ways (4 world units over 32 pixels).
    let inside = 16 * 32 + 16;
    let outside = 2 * 32 + 2;
    for (name, value) in [
        ("albedo.R", 0.2),
        ("albedo.G", 0.4),
        ("albedo.B", 0.6),
        ("normal.X", 0.0),
        ("normal.Y", 0.0),
        ("normal.Z", 1.0),
        ("depth.Z", 5.0),
    ] {
        let got = channel(name)[inside];
        assert!((got - value).abs() < 1e-6, "{name}: {got} vs {value}");
    }
    assert_eq!(channel("depth.Z")[outside], f32::INFINITY);
    assert_eq!(channel("albedo.G")[outside], 0.0);
    // Every pixel's channels are its own samples' (four samples a pixel,
    // two pixels to a batch of eight): the quad's 16 × 16 pixels exactly.
    for (k, (depth, albedo)) in channel("depth.Z")
        .iter()
        .zip(channel("albedo.G"))
        .enumerate()
    {
        let (x, y) = (k % 32, k / 32);
        let on_quad = (8..24).contains(&x) && (8..24).contains(&y);
        assert_eq!(depth.is_finite(), on_quad, "depth of pixel ({x}, {y})");
        assert_eq!(*albedo > 0.0, on_quad, "albedo of pixel ({x}, {y})");
    }
    // The same bits on one thread.
    let one = render("1", "b.exr");
    for ((name, a), (_, b)) in exr.channels.iter().zip(&one.channels) {
        let bits = |v: &Vec<f32>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b), "{name}");
    }
    // Without --aov, only the beauty pass.
    strata_ok(&dir, &["render", "quad.toml", "-q", "-o", "plain.exr"]);
    let names: Vec<String> = read_exr(&dir.join("plain.exr"))
        .channels
        .into_iter()
        .map(|c| c.0)
        .collect();
    assert_eq!(names, ["B", "G", "R"]);
    // AOVs are EXR channels.
    let o = strata(
        &dir,
        &["render", "quad.toml", "-q", "--aov", "depth", "-o", "x.png"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.join("x.png").exists());
}
