//! Packets in the renderer: `--packets on`, `off` and `auto` render the
//! same film bit for bit (sums, counts, dropped samples), whatever the
//! batch sizes, passes, threads and slices. (The measurement behind the
//! `auto` thresholds is the bench `benches/packet_batches.rs`.)

use crate::common::process::{repo, strata, strata_command};
use crate::common::{bumpy_sphere_obj, scene_at, temp_dir};
use strata::accel::PACKET_SIZE;
use strata::render::film::Film;
use strata::render::{render, RenderOptions, SliceSpec};
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
    render(scene, &opts, None, ()).film
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
        let status = strata_command(repo())
            .args(["render", scene, "-q", "--width", "40", "--height", "30"])
            .args(["--spp", "4", "--packets", mode, "-o"])
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success());
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(outputs[0], outputs[1]);
    let bad = strata(repo(), &["render", scene, "--packets", "sometimes"]);
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}
