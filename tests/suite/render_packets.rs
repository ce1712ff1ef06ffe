//! Packets in the renderer: `--packets on`, `off` and `auto` render the
//! same film bit for bit (sums, counts, dropped samples), whatever the
//! batch sizes, passes, threads and slices; and, ignored by default, the
//! measurement behind the `auto` threshold.

use crate::common::{bumpy_sphere_obj, scene_at, temp_dir};
use glam::Vec2;
use strata::accel::{Packet, PACKET_SIZE};
use strata::math::offset::spawn_origin;
use strata::math::Ray;
use strata::render::film::Film;
use strata::render::{render, RenderOptions, SliceSpec};
use strata::sampling::{Dim, PixelSampler};
use strata::scene::Scene;
use strata::shade::{BatchRays, PacketMode, CAMERA_PACKET_MIN};

const MODES: [PacketMode; 3] = [PacketMode::Off, PacketMode::On, PacketMode::Auto];

/// The bumpy sphere of `crate::common::bumpy_sphere_obj` (radius 0.5) as a file.
fn write_bumpy(path: &std::path::Path, nu: u32, nv: u32) {
    std::fs::write(path, bumpy_sphere_obj(nu, nv, 0.5, 0.04)).unwrap();
}

/// Thin-lens depth of field, three kinds of area light (rect, disk,
/// sphere) and a point light, two meshes, a glossy floor and Fresnel
/// glass. 37 × 23 pixels, so batches break at row ends and at odd tails.
/// `tag` names the scene's temporary directory: tests run in parallel,
/// and two sharing one would delete each other's files.
fn busy_scene(tag: &str) -> Scene {
    let dir = temp_dir(&format!("render-packets-{tag}"));
    // 14,400 triangles: a BVH deep enough for packets to share traversal.
    write_bumpy(&dir.join("bumpy.obj"), 120, 60);
    let icosphere = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/icosphere.obj");
    let text = format!(
        r#"
[render]
width = 37
height = 23
spp = 12
shadow_samples = 5
reflection_samples = 3
max_depth = 4

[camera]
type = "thin_lens"
position = [0.0, 1.2, 5.0]
look_at = [0.0, 0.5, 0.0]
fov = 40.0
aperture = 0.2
focus_distance = 5.0

[materials.floor]
diffuse = [0.5, 0.5, 0.5]
reflectivity = 0.3
glossiness = 40.0

[materials.glass]
diffuse = [0.0, 0.0, 0.0]
transparency = 1.0
fresnel = true

[materials.shiny]
diffuse = [0.6, 0.3, 0.2]
specular = [0.3, 0.3, 0.3]
shininess = 30.0

[[lights]]
type = "rect"
corner = [-0.6, 3.0, -0.6]
edge_u = [1.2, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.2]
radiance = [6.0, 6.0, 6.0]

[[lights]]
type = "disk"
center = [2.5, 2.0, 1.0]
normal = [-1.0, -1.0, 0.0]
radius = 0.4
radiance = [4.0, 3.0, 2.0]

[[lights]]
type = "sphere"
center = [-2.5, 1.5, 1.5]
radius = 0.3
radiance = [3.0, 4.0, 5.0]

[[lights]]
type = "point"
position = [0.0, 4.0, 4.0]
intensity = [10.0, 10.0, 10.0]

[[objects]]
plane = {{ normal = [0.0, 1.0, 0.0] }}
material = "floor"

[[objects]]
mesh = "bumpy.obj"
material = "shiny"
transform = {{ translate = [-0.8, 0.55, 0.0] }}

[[objects]]
mesh = "{icosphere}"
transform = {{ translate = [0.9, 0.5, -0.8], scale = 0.5 }}

[[objects]]
sphere = {{ center = [0.2, 0.35, 1.3], radius = 0.35 }}
material = "glass"
"#
    );
    scene_at(&text, &dir.join("scene.toml"))
}

fn film(scene: &Scene, packets: PacketMode, threads: usize, passes: u32, slice: SliceSpec) -> Film {
    let opts = RenderOptions {
        threads,
        passes: Some(passes),
        slice,
        packets,
        ..RenderOptions::default()
    };
    render(scene, &opts, None, |_, _| {}).film
}

#[test]
fn packets_on_off_and_auto_render_the_same_film() {
    let base = busy_scene("films");
    // One to eleven shadow samples per hit; one sample per pixel per pass,
    // three, and all twelve at once. The passes change which hits are lit
    // together in SIMD lanes, and so which shadow rays travel together
    // (eight pixels' samples, two pixels' and a third's, or one pixel's
    // eight and then four), which must not change the film either.
    for shadow_samples in [1, 3, 5, 8, 11] {
        let mut scene = base.clone();
        scene.settings.shadow_samples = shadow_samples;
        let mut first_off: Option<Film> = None;
        for passes in [12, 4, 1] {
            let off = film(&scene, PacketMode::Off, 2, passes, SliceSpec::WHOLE);
            match &first_off {
                None => first_off = Some(off.clone()),
                Some(f) => assert!(
                    *f == off,
                    "M = {shadow_samples}: {passes} passes differ from 12"
                ),
            }
            assert!(off.counts.iter().all(|&c| c == 12));
            assert!(off.sums.iter().any(|s| s[0] > 0), "the scene is lit");
            for mode in [PacketMode::On, PacketMode::Auto] {
                assert!(
                    off == film(&scene, mode, 2, passes, SliceSpec::WHOLE),
                    "{mode:?}, M = {shadow_samples}, {passes} passes"
                );
            }
        }
    }
}

#[test]
fn packets_render_the_same_film_on_any_thread_count_and_slicing() {
    let scene = busy_scene("threads");
    let whole = film(&scene, PacketMode::On, 1, 16, SliceSpec::WHOLE);
    for threads in [2, 3, 8] {
        assert!(
            whole == film(&scene, PacketMode::On, threads, 16, SliceSpec::WHOLE),
            "{threads} threads"
        );
    }
    // Slices rendered with different modes and thread counts, then summed.
    for p in [2u32, 5] {
        let mut merged = Film::new(whole.width, whole.height);
        for k in 0..p {
            let mode = MODES[k as usize % 3];
            merged.merge(&film(
                &scene,
                mode,
                1 + k as usize % 3,
                3,
                SliceSpec { index: k, count: p },
            ));
        }
        assert!(merged == whole, "P = {p}");
    }
}

#[test]
fn packet_modes_parse() {
    assert_eq!("auto".parse::<PacketMode>(), Ok(PacketMode::Auto));
    assert_eq!("on".parse::<PacketMode>(), Ok(PacketMode::On));
    assert_eq!("off".parse::<PacketMode>(), Ok(PacketMode::Off));
    assert!("yes".parse::<PacketMode>().is_err());
    assert_eq!(PacketMode::default(), PacketMode::Auto);
    let camera = BatchRays::Camera;
    assert!(!PacketMode::Auto.use_packet(camera, CAMERA_PACKET_MIN - 1));
    assert!(PacketMode::Auto.use_packet(camera, CAMERA_PACKET_MIN));
    assert!(!PacketMode::Auto.use_packet(BatchRays::Shadow, PACKET_SIZE));
    assert!(PacketMode::On.use_packet(BatchRays::Shadow, 1));
    assert!(!PacketMode::Off.use_packet(camera, PACKET_SIZE));
}

#[test]
fn the_cli_renders_identical_images_with_packets_on_and_off() {
    let dir = temp_dir("render-packets-cli");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/seed-mc.toml");
    let mut outputs = Vec::new();
    for mode in ["on", "off"] {
        let out = dir.join(format!("{mode}.strata"));
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
            .args(["render", scene, "-q", "--width", "40", "--height", "30"])
            .args(["--spp", "4", "--packets", mode, "-o"])
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success());
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(outputs[0], outputs[1]);
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", scene, "--packets", "sometimes"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------
// The measurement behind the `auto` thresholds (ignored: it takes a few
// minutes and its numbers depend on the machine):
//
//   cargo test --release --test suite render_packets:: -- --ignored --nocapture
//
// Batches are built as the renderer builds them: the camera rays of one
// pixel (8 pixel and lens samples), and the batch's shadow rays to a rect
// light, one from each of those 8 rays' hits (where all 8 hit and pass
// the cosine test);
// for comparison also "row" batches, one sample of each of 8 neighbouring
// pixels. For n = 1..8 the first n rays of every batch are traced one by
// one and as one packet, alternately, 15 times; the medians of this
// thread's CPU time are reported (a shared machine slows CPU time less
// than wall time). Scenes: the bunny when `tools/fetch-assets` has fetched
// it (else a generated bumpy sphere) through a thin lens and a pinhole,
// and scenes/thin-lens.toml (three spheres and a plane).

/// The bunny (or a bumpy sphere) on a floor under a rect light.
fn mesh_scene(aperture: f32) -> (Scene, String) {
    let dir = temp_dir("render-packets-measure");
    let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bunny.obj");
    let (mesh, name) = if std::path::Path::new(bunny).exists() {
        (bunny.to_string(), "bunny")
    } else {
        write_bumpy(&dir.join("bumpy.obj"), 160, 80);
        ("bumpy.obj".to_string(), "bumpy sphere")
    };
    let text = format!(
        r#"
[render]
width = 160
height = 120
[camera]
type = "thin_lens"
position = [0.0, 0.6, 3.2]
look_at = [0.0, 0.0, 0.0]
aperture = {aperture}
[[lights]]
type = "rect"
corner = [-0.8, 2.5, -0.2]
edge_u = [1.6, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.2]
radiance = [8.0, 8.0, 8.0]
[[objects]]
plane = {{ point = [0.0, -0.992, 0.0], normal = [0.0, 1.0, 0.0] }}
[[objects]]
mesh = "{mesh}"
"#
    );
    let lens = if aperture > 0.0 {
        "thin lens"
    } else {
        "pinhole"
    };
    (
        scene_at(&text, &dir.join("scene.toml")),
        format!("{name}, {lens}"),
    )
}

/// Pixel batches, row batches and (if the first light is an area light)
/// the shadow rays of full batches.
fn batches(scene: &Scene) -> [Vec<Vec<Ray>>; 3] {
    let s = &scene.settings;
    let light = &scene.lights[0];
    let n = PACKET_SIZE as u32;
    let camera_ray = |x: u32, y: u32, i: u32| {
        let sampler = PixelSampler::new(s.sampler, s.seed, y * s.width + x);
        let film = Vec2::new(x as f32, y as f32) + sampler.get_2d(Dim::PIXEL, i, n);
        let lens = sampler.get_2d(Dim::LENS, i, n);
        scene.camera.generate_ray(film, lens)
    };
    let (mut pixel, mut row, mut shadow) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..s.height {
        for x in 0..s.width {
            let rays: Vec<Ray> = (0..n).map(|i| camera_ray(x, y, i)).collect();
            if x % n == 0 && x + n <= s.width {
                row.push((0..n).map(|k| camera_ray(x + k, y, 0)).collect());
            }
            // One shadow ray from each sample's hit, as direct_light makes
            // a batch's shadow rays (one light sample per camera sample).
            if light.is_area() {
                let sampler = PixelSampler::new(s.sampler, s.seed, y * s.width + x);
                let shadow_rays: Vec<Ray> = rays
                    .iter()
                    .enumerate()
                    .filter_map(|(i, ray)| {
                        let hit = scene.geometry.intersect(ray)?;
                        let sf = scene.geometry.surface(ray, &hit);
                        let wo = -ray.direction.normalize();
                        let ng = if sf.geometric_normal.dot(wo) >= 0.0 {
                            sf.geometric_normal
                        } else {
                            -sf.geometric_normal
                        };
                        let u = sampler.get_2d(Dim::light(0, 0), i as u32, n);
                        let ls = light.sample(sf.p, u, s.light_sampling)?;
                        if ng.dot(ls.wi) <= 0.0 {
                            return None;
                        }
                        let o = spawn_origin(sf.p, sf.p_error, ng, ls.wi);
                        Some(Ray::segment(o, ls.wi, ls.distance - (o - sf.p).length()))
                    })
                    .collect();
                if shadow_rays.len() == PACKET_SIZE {
                    shadow.push(shadow_rays);
                }
            }
            pixel.push(rays);
        }
    }
    [pixel, row, shadow]
}

/// Seconds of this thread's CPU time (wall time where that is not known).
fn now() -> f64 {
    match strata::system::cputime::thread_cpu_ns() {
        Some(ns) => ns as f64 * 1e-9,
        None => std::time::UNIX_EPOCH.elapsed().unwrap().as_secs_f64(),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median CPU seconds per ray, single and packet, for the first `n` rays
/// of every batch in `set`.
fn time_batches(
    scene: &Scene,
    set: &[Vec<Ray>],
    n: usize,
    closest: bool,
    except: u32,
) -> (f64, f64) {
    // Enough rays per timed block that the clock's tick does not matter.
    let loops = 400_000usize.div_ceil(set.len() * n);
    let rays = (loops * set.len() * n) as f64;
    let (mut single, mut packet) = (Vec::new(), Vec::new());
    let mut sink = 0usize;
    for _ in 0..15 {
        let t = now();
        for b in set.iter().cycle().take(loops * set.len()) {
            for r in &b[..n] {
                sink += if closest {
                    scene.geometry.intersect(r).is_some() as usize
                } else {
                    scene.geometry.occluded_except(r, except) as usize
                };
            }
        }
        single.push((now() - t) / rays);
        let t = now();
        for b in set.iter().cycle().take(loops * set.len()) {
            if closest {
                let mut out = [None; PACKET_SIZE];
                scene.geometry.intersect_packet(&b[..n], &mut out[..n]);
                sink += out.iter().filter(|h| h.is_some()).count();
            } else {
                let mut out = [false; PACKET_SIZE];
                scene
                    .geometry
                    .occluded_packet(&b[..n], except, &mut out[..n]);
                sink += out.iter().filter(|&&o| o).count();
            }
        }
        packet.push((now() - t) / rays);
    }
    std::hint::black_box(sink);
    (median(single), median(packet))
}

#[test]
#[ignore]
fn measure_packet_against_single_rays_by_batch_size() {
    let thin_lens = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/thin-lens.toml");
    let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/mesh.toml");
    let overrides = strata::scene::RenderOverrides {
        width: Some(160),
        height: Some(120),
        ..Default::default()
    };
    let load = |path: &str| {
        crate::common::load_scene(std::path::Path::new(path), &overrides, Default::default())
            .unwrap()
            .0
    };
    let scenes = [
        mesh_scene(0.04),
        mesh_scene(0.0),
        (load(thin_lens), "scenes/thin-lens.toml".to_string()),
        (load(mesh), "scenes/mesh.toml".to_string()),
    ];
    println!("packet/single throughput (> 1: packets faster), by rays per batch n");
    println!(
        "{:44} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7}   single Mrays/s",
        "scene, batch", 1, 2, 3, 4, 5, 6, 7, 8
    );
    for (scene, name) in &scenes {
        println!(
            "{name}: {} primitives, {} BVH nodes",
            scene.geometry.primitive_count(),
            scene.geometry.bvh().nodes.len()
        );
        let except = scene.lights[0].prim().unwrap_or(u32::MAX);
        let [pixel, row, shadow] = batches(scene);
        for (kind, set, closest) in [
            ("pixel", &pixel, true),
            ("row", &row, true),
            ("shadow", &shadow, false),
        ] {
            if set.is_empty() {
                continue;
            }
            let coherent = set.iter().filter(|r| Packet::new(r).is_some()).count();
            let label = format!(
                "{name}, {kind} ({}% form packets)",
                100 * coherent / set.len()
            );
            print!("{label:44}");
            let mut single_rate = 0.0;
            for n in 1..=PACKET_SIZE {
                let (s, p) = time_batches(scene, set, n, closest, except);
                print!(" {:6.2}x", s / p);
                single_rate = 1e-6 / s;
            }
            println!("   {single_rate:.2}");
        }
    }
}
