//! The environment light: a constant environment on a diffuse sphere's top
//! gives the analytic radiance × albedo; missed rays see it; the image is
//! the same bits for any split, thread count and packet mode; a map with
//! one bright texel lights a scene as a directional light of the same
//! irradiance does, and a glossy surface reflects it by the lobe's
//! analytic weight; importance sampling a map with a sun has less variance
//! than uniform sampling (measured across seeds); bad maps and keys are
//! refused with one line naming the file and the key.

use crate::common::{scene_at, stderr, strata, temp_dir};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::path::Path;
use strata::light::environment::uv_to_direction;
use strata::partial::format::{read_partial_from, write_partial_to, PartialHeader};
use strata::partial::merge::{merge_partials, MergeRules};
use strata::render::film::Film;
use strata::render::{render, RenderOptions, SliceSpec};
use strata::scene::Scene;
use strata::shade::PacketMode;

/// Write `texels` (row-major, top row first) as an EXR.
fn write_exr(path: &Path, w: usize, h: usize, texels: &[[f32; 3]]) {
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let t = texels[y * w + x];
        (t[0], t[1], t[2])
    })
    .unwrap();
}

/// Write `texels` as a Radiance HDR file: flat (uncompressed) RGBE
/// scanlines, which every reader takes.
fn write_hdr(path: &Path, w: usize, h: usize, texels: &[[f32; 3]]) {
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    for t in texels {
        let max = t[0].max(t[1]).max(t[2]);
        if max < 1e-32 {
            bytes.extend([0, 0, 0, 0]);
        } else {
            // max = m · 2^e with m in [0.5, 1): bytes c / 2^e · 256.
            let e = max.log2().floor() as i32 + 1;
            let f = 256.0 / 2f32.powi(e);
            bytes.extend(t.map(|c| (c * f) as u8));
            bytes.push((e + 128) as u8);
        }
    }
    std::fs::write(path, bytes).unwrap();
}

fn film(scene: &Scene, threads: usize, slice: SliceSpec, packets: PacketMode) -> Film {
    let opts = RenderOptions {
        threads,
        slice,
        packets,
        ..RenderOptions::default()
    };
    render(scene, &opts, None, ()).film
}

fn rgb(scene: &Scene) -> Vec<Vec3> {
    film(scene, 2, SliceSpec::WHOLE, PacketMode::Auto).to_rgb()
}

/// Mean and standard error of the mean of the red channel.
fn mean_and_error(values: &[Vec3]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|v| v.x as f64).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|v| (v.x as f64 - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A unit sphere resting on a plane, both with albedo 0.6, under a
/// constant environment of radiance 2: seen from straight above through
/// an orthographic camera 0.05 wide, every pixel is within 0.025 of the
/// sphere's top, whose tangent plane is horizontal, so nothing (not the
/// plane below, nor the sphere itself) hides any of its upper hemisphere
/// (the pixels' normals tilt by at most 0.025 rad, hiding a fraction of
/// the cosine-weighted hemisphere below 1e-3). Radiance there: ρ L = 1.2.
fn sphere_top(sampler: &str, light_sampling: &str, seed: u32) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
spp = 16
shadow_samples = 4
sampler = "{sampler}"
light_sampling = "{light_sampling}"
seed = {seed}
[camera]
type = "orthographic"
position = [0.0, 5.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.05
[materials.grey]
diffuse = 0.6
[[lights]]
type = "environment"
radiance = 2.0
[[objects]]
plane = {{ normal = [0.0, 1.0, 0.0] }}
material = "grey"
[[objects]]
sphere = {{ center = [0.0, 1.0, 0.0], radius = 1.0 }}
material = "grey"
"#
    )
}

#[test]
fn a_constant_environment_on_a_sphere_top_gives_radiance_times_albedo() {
    let dir = temp_dir("env-top");
    for sampler in ["stratified", "random"] {
        for light_sampling in ["solid_angle", "area"] {
            let s = scene_at(&sphere_top(sampler, light_sampling, 3), &dir.join("s.toml"));
            let (mean, error) = mean_and_error(&rgb(&s));
            let exact = 1.2;
            // Cosine sampling of a constant environment has no variance on
            // an unhidden diffuse point: only rounding and the 1e-3 tilt.
            let tolerance = if light_sampling == "solid_angle" {
                2e-3
            } else {
                4.0 * error + 2e-3
            };
            assert!(
                (mean - exact).abs() < tolerance,
                "{sampler}, {light_sampling}: {mean} ± {error}, expected {exact}"
            );
            if light_sampling == "area" {
                assert!(error > 0.0 && error < 0.05, "{error}");
            }
        }
    }
}

/// A perspective view of the sphere on the plane, with a glossy floor and
/// a mirror ball, under `light` (TOML of one `[[lights]]` entry).
fn busy(light: &str, extra: &str) -> String {
    format!(
        r#"
[render]
width = 29
height = 19
spp = 6
shadow_samples = 3
reflection_samples = 2
max_depth = 3
{extra}
[camera]
position = [0.0, 1.5, 5.0]
look_at = [0.0, 0.7, 0.0]
fov = 50.0
[materials.grey]
diffuse = 0.6
[materials.floor]
diffuse = 0.4
reflectivity = 0.4
glossiness = 30.0
[materials.mirror]
diffuse = 0.0
reflectivity = 0.9
{light}
[[objects]]
plane = {{ normal = [0.0, 1.0, 0.0] }}
material = "floor"
[[objects]]
sphere = {{ center = [-0.7, 0.6, 0.0], radius = 0.6 }}
material = "grey"
[[objects]]
sphere = {{ center = [0.8, 0.5, 0.5], radius = 0.5 }}
material = "mirror"
"#
    )
}

/// A 64 × 32 sky: a gradient, a ground, and a sun of 2 × 2 bright texels.
fn sky_texels() -> (usize, usize, Vec<[f32; 3]>) {
    let (w, h) = (64, 32);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if (9..11).contains(&y) && (40..42).contains(&x) {
                [3000.0, 2800.0, 2500.0]
            } else if y >= h / 2 {
                [0.2, 0.18, 0.15]
            } else {
                [0.3 + 0.01 * y as f32, 0.5, 0.9 - 0.01 * x as f32]
            }
        })
        .collect();
    (w, h, texels)
}

const SKY_LIGHT: &str = "[[lights]]\ntype = \"environment\"\nmap = \"sky.exr\"\n\
    scale = [0.5, 0.6, 0.7]\nrotate = [0.0, 1.0, 0.0, 30.0]\n";

#[test]
fn the_image_is_the_same_bits_for_any_split_thread_count_and_packet_mode() {
    let dir = temp_dir("env-split");
    let (w, h, texels) = sky_texels();
    write_exr(&dir.join("sky.exr"), w, h, &texels);
    let constant = "[[lights]]\ntype = \"environment\"\nradiance = [0.4, 0.5, 0.6]\n";
    for (light, extra) in [
        (SKY_LIGHT, ""),
        (constant, ""),
        (SKY_LIGHT, "sampler = \"random\""),
    ] {
        let s = scene_at(&busy(light, extra), &dir.join("s.toml"));
        let whole = film(&s, 1, SliceSpec::WHOLE, PacketMode::Off);
        // Missed camera rays see the environment: the image's top row.
        assert!(whole.to_rgb()[..29].iter().all(|p| p.min_element() > 0.0));
        for (threads, packets) in [(3, PacketMode::On), (2, PacketMode::Auto)] {
            assert!(
                whole == film(&s, threads, SliceSpec::WHOLE, packets),
                "{threads} {packets:?}"
            );
        }
        for p in [2u32, 3] {
            let parts = (0..p)
                .map(|k| {
                    let slice = SliceSpec { index: k, count: p };
                    let f = film(&s, 1 + k as usize, slice, PacketMode::Auto);
                    let header = PartialHeader::for_scene(&s, slice, slice.samples(s.settings.spp));
                    let mut bytes = Vec::new();
                    write_partial_to(&mut bytes, &header, &f).unwrap();
                    let back = read_partial_from(bytes.as_slice(), bytes.len() as u64).unwrap();
                    (std::path::PathBuf::from(format!("part_{k}.strata")), back)
                })
                .collect();
            let rules = MergeRules {
                require_all: true,
                preview: false,
                force: false,
            };
            let merged = merge_partials(parts, rules).unwrap();
            assert!(merged.film == whole, "--slice k/{p} merged");
        }
    }
}

/// A diffuse sphere on a plane, seen from the front, lit by `light`.
fn lit_by(light: &str, light_sampling: &str) -> String {
    format!(
        r#"
[render]
width = 24
height = 16
spp = 16
shadow_samples = 2
light_sampling = "{light_sampling}"
[camera]
position = [0.0, 2.0, 5.0]
look_at = [0.0, 0.5, 0.0]
fov = 45.0
[materials.grey]
diffuse = 0.7
[[objects]]
plane = {{ normal = [0.0, 1.0, 0.0] }}
material = "grey"
[[objects]]
sphere = {{ center = [0.0, 0.7, 0.0], radius = 0.7 }}
material = "grey"
{light}
"#
    )
}

/// The texel (i, j) of a `w` × `h` map: its centre's direction and its
/// irradiance per unit radiance on a surface facing that direction (its
/// solid angle, to second order in its size).
fn texel(i: usize, j: usize, w: usize, h: usize) -> (Vec3, f32) {
    let uv = Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
    let (d, _) = uv_to_direction(uv);
    let (t0, t1) = (PI * j as f32 / h as f32, PI * (j + 1) as f32 / h as f32);
    (d, 2.0 * PI / w as f32 * (t0.cos() - t1.cos()))
}

#[test]
fn one_bright_texel_lights_like_a_directional_light_of_its_irradiance() {
    let dir = temp_dir("env-texel");
    let (w, h) = (256, 128);
    let (i, j) = (100, 40);
    let radiance = 4096.0;
    let mut texels = vec![[0.0f32; 3]; w * h];
    texels[j * w + i] = [radiance; 3];
    // Radiance HDR this time (4096 is exact in RGBE).
    write_hdr(&dir.join("sun.hdr"), w, h, &texels);
    let (d, omega) = texel(i, j, w, h);
    let e = radiance * omega;
    let env = lit_by(
        "[[lights]]\ntype = \"environment\"\nmap = \"sun.hdr\"\n",
        "solid_angle",
    );
    let directional = lit_by(
        &format!(
            "[[lights]]\ntype = \"directional\"\ndirection = [{}, {}, {}]\nirradiance = {e}\n",
            -d.x, -d.y, -d.z
        ),
        "solid_angle",
    );
    let a = rgb(&scene_at(&env, &dir.join("s.toml")));
    let b = rgb(&scene_at(&directional, &dir.join("s.toml")));
    let mean = |v: &[Vec3]| v.iter().map(|p| p.x as f64).sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(&a), mean(&b));
    // The texel is 0.025 rad across: its cosine varies over it by second
    // order (< 1e-3 relatively), and its soft shadow edge against the hard
    // one moves light between pixels, not in or out of the image. The
    // map's sampling finds the texel with every sample, so what is left
    // of Monte Carlo error is the cosine's variation over it.
    assert!(mb > 0.05, "the directional light lights the scene: {mb}");
    assert!(
        (ma - mb).abs() < 3e-3 * mb,
        "environment {ma} vs directional {mb}"
    );
    // Away from the shadow's edge, pixel by pixel.
    let close = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (p.x - q.x).abs() <= 0.01 * q.x.max(0.05))
        .count();
    assert!(
        close * 10 > a.len() * 8,
        "{close} of {} pixels agree",
        a.len()
    );
}

#[test]
fn a_glossy_surface_reflects_a_bright_texel_by_the_lobe_it_falls_in() {
    // A glossy plane (no diffuse or Phong layer) seen by an orthographic
    // camera: every ray has the same mirror direction, and the reflected
    // radiance is k_r times the lobe-weighted average of the map,
    // k_r · p_lobe(texel) · L · Ω to second order in the texel's size.
    let dir = temp_dir("env-glossy");
    let (w, h) = (256, 128);
    let (i, j) = (96, 44);
    let radiance = 1000.0;
    let mut texels = vec![[0.0f32; 3]; w * h];
    texels[j * w + i] = [radiance; 3];
    write_exr(&dir.join("sun.exr"), w, h, &texels);
    let (d, omega) = texel(i, j, w, h);
    // Camera rays travel along `view`, mirrored about +y to `mirror`,
    // 10° from the texel.
    let tilt = glam::Mat3::from_axis_angle(Vec3::new(d.z, 0.0, -d.x).normalize(), 0.1745);
    let mirror = tilt * d;
    let view = Vec3::new(mirror.x, -mirror.y, mirror.z);
    let (n, kr) = (20.0f32, 0.8f32);
    let cos = mirror.dot(d);
    let exact = kr * (n + 1.0) / (2.0 * PI) * cos.powf(n) * radiance * omega;
    for glossy_sampling in ["lobe", "uniform"] {
        let text = format!(
            r#"
[render]
width = 16
height = 16
spp = 64
reflection_samples = 4
glossy_sampling = "{glossy_sampling}"
[camera]
type = "orthographic"
position = [{}, {}, {}]
look_at = [0.0, 0.0, 0.0]
height = 0.5
[materials.glossy]
diffuse = 0.0
reflectivity = {kr}
glossiness = {n}
[[lights]]
type = "environment"
map = "sun.exr"
[[objects]]
plane = {{ normal = [0.0, 1.0, 0.0] }}
material = "glossy"
"#,
            -3.0 * view.x,
            -3.0 * view.y,
            -3.0 * view.z
        );
        let (mean, error) = mean_and_error(&rgb(&scene_at(&text, &dir.join("s.toml"))));
        assert!(
            (mean - exact as f64).abs() < 4.0 * error + 2e-3 * exact as f64,
            "{glossy_sampling}: {mean} ± {error}, expected {exact}"
        );
    }
    assert!(exact > 0.5, "the texel is well inside the lobe: {exact}");
}

#[test]
fn importance_sampling_a_map_with_a_sun_has_less_variance_than_uniform() {
    let dir = temp_dir("env-variance");
    let (w, h, texels) = sky_texels();
    write_exr(&dir.join("sky.exr"), w, h, &texels);
    let light = "[[lights]]\ntype = \"environment\"\nmap = \"sky.exr\"\n";
    // Each pixel's variance across seeds, averaged over the image.
    let variance = |light_sampling: &str| {
        let runs: Vec<Vec<Vec3>> = (0..8)
            .map(|seed| {
                let text = lit_by(light, light_sampling)
                    .replace("spp = 16", &format!("spp = 4\nseed = {seed}"));
                rgb(&scene_at(&text, &dir.join("s.toml")))
            })
            .collect();
        let pixels = runs[0].len();
        (0..pixels)
            .map(|p| {
                let m = runs.iter().map(|r| r[p].x as f64).sum::<f64>() / runs.len() as f64;
                runs.iter()
                    .map(|r| (r[p].x as f64 - m).powi(2))
                    .sum::<f64>()
                    / (runs.len() - 1) as f64
            })
            .sum::<f64>()
            / pixels as f64
    };
    let (importance, uniform) = (variance("solid_angle"), variance("area"));
    assert!(
        importance * 4.0 < uniform,
        "importance {importance} vs uniform {uniform}"
    );
}

#[test]
fn bad_maps_and_keys_are_one_line_errors_naming_the_file_and_key() {
    let dir = temp_dir("env-bad");
    std::fs::write(dir.join("not-a-map.exr"), b"hello").unwrap();
    let png = dir.join("sky.png");
    image::RgbImage::from_pixel(4, 2, image::Rgb([9, 9, 9]))
        .save(&png)
        .unwrap();
    write_exr(
        &dir.join("nan.exr"),
        2,
        1,
        &[[1.0, 1.0, 1.0], [f32::NAN, 0.0, 0.0]],
    );
    let env = "[[lights]]\ntype = \"environment\"\n";
    let cases = [
        (format!("{env}map = \"missing.exr\"\n"), "lights[0].map: cannot read"),
        (format!("{env}map = \"not-a-map.exr\"\n"), "not-a-map.exr"),
        (format!("{env}map = \"sky.png\"\n"), "must be EXR or Radiance HDR"),
        (format!("{env}map = \"nan.exr\"\n"), "texel (1, 0)"),
        (format!("{env}radiance = 1.0\nmap = \"nan.exr\"\n"), "give radiance or map, not both"),
        (env.to_string(), "needs `radiance` or `map`"),
        (format!("{env}radiance = -1.0\n"), "lights[0].radiance: must not be negative"),
        (format!("{env}radiance = 1.0\nrotate = [0.0, 0.0, 0.0, 30.0]\n"), "lights[0].rotate"),
        (format!("{env}radiance = 1.0\nscale = [1.0, 2.0]\n"), "lights[0].scale"),
        (format!("{env}radiance = 1.0\nposition = [0.0, 1.0, 0.0]\n"), "does not apply to an environment light"),
        (format!("{env}radiance = 1.0\n{env}radiance = 2.0\n"), "one environment light"),
        (format!("[render]\nbackground = [0.1, 0.1, 0.1]\n{env}radiance = 1.0\n"), "render.background"),
        (
            "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 1.0\nmap = \"sky.exr\"\n".to_string(),
            "lights[0].map: does not apply to a point light",
        ),
    ];
    for (text, expected) in cases {
        std::fs::write(dir.join("scene.toml"), &text).unwrap();
        let out = strata(&dir, &["render", "scene.toml", "-o", "out.png", "-q"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{text}\n{err}");
        assert_eq!(err.trim().lines().count(), 1, "{text}\n{err}");
        assert!(
            err.contains("scene.toml") && err.contains(expected),
            "{text}\n{err}"
        );
        assert!(!dir.join("out.png").exists());
    }
}
