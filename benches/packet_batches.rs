//! Criterion bench of the renderer's own batches traced as one packet
//! against one ray at a time, by rays per batch: the measurement behind
//! the `--packets auto` thresholds (`shade::packets`: `CAMERA_PACKET_MIN`,
//! `SHADOW_PACKET_MIN`; docs/performance.md, "Measurements behind the
//! renderer's defaults").
//!
//! `cargo bench -p strata-benches --bench packet_batches` (add `-- --quick`
//! for a fast look, or a filter such as `-- shadow` for one kind).
//!
//! Batches are built as the renderer builds them: the camera rays of one
//! pixel (its 8 pixel and lens samples, `pixel`), and the batch's shadow
//! rays to a rect light, one from each of those 8 rays' hits where all 8
//! hit and pass the cosine test (`shadow`); for comparison also `row`
//! batches, one sample of each of 8 neighbouring pixels. For n = 1..8,
//! `single/n` traces the first n rays of every batch one by one and
//! `packet/n` as one packet; the throughputs' ratio at each n is what the
//! thresholds were read from. Scenes, 160 × 120 pixels: the benches' mesh
//! (assets/bunny.obj when `tools/fetch-assets` has fetched it, else a
//! generated icosphere) on a floor under a rect light, through a thin lens
//! and a pinhole, and scenes/thin-lens.toml and scenes/mesh.toml. Each
//! group says on standard error how many of its batches form a packet
//! (`Packet::new`; the rest fall back to single rays inside the packet
//! call).

mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec2;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use strata::accel::{Packet, PACKET_SIZE};
use strata::math::offset::spawn_origin;
use strata::math::Ray;
use strata::sampling::{Dim, PixelSampler};
use strata::scene::{load_scene, scene_from_str, RenderOverrides, Scene};

/// The benches' mesh on a floor under a rect light, seen through a thin
/// lens of `aperture` (0: a pinhole), and its name.
fn mesh_scene(aperture: f32) -> (Scene, String) {
    let (mesh, name) = common::mesh_file();
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
mesh = "{}"
"#,
        mesh.display()
    );
    let lens = if aperture > 0.0 {
        "thin_lens"
    } else {
        "pinhole"
    };
    let scene = scene_from_str(&text, &mesh.with_extension("toml"), &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    (scene, format!("{name}_{lens}"))
}

/// A scene of scenes/ at 160 × 120 pixels.
fn scenes_file(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name);
    let overrides = RenderOverrides {
        width: Some(160),
        height: Some(120),
        ..Default::default()
    };
    load_scene(&path, &overrides, Default::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .0
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

fn packet_batches(c: &mut Criterion) {
    let scenes = [
        mesh_scene(0.04),
        mesh_scene(0.0),
        (scenes_file("thin-lens.toml"), "thin_lens_toml".to_string()),
        (scenes_file("mesh.toml"), "mesh_toml".to_string()),
    ];
    for (scene, name) in &scenes {
        let g = &scene.geometry;
        // Shadow rays ignore the light's own primitive, as the renderer's do.
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
            eprintln!(
                "packet_batches_{name}_{kind}: {} primitives, {} batches, {}% form packets",
                g.primitive_count(),
                set.len(),
                100 * coherent / set.len()
            );
            let mut group = c.benchmark_group(format!("packet_batches_{name}_{kind}"));
            for n in 1..=PACKET_SIZE {
                group.throughput(Throughput::Elements((set.len() * n) as u64));
                group.bench_function(BenchmarkId::new("single", n), |b| {
                    b.iter(|| {
                        let mut found = 0usize;
                        for batch in set {
                            for r in &batch[..n] {
                                found += if closest {
                                    g.intersect(r).is_some()
                                } else {
                                    g.occluded_except(r, except)
                                } as usize;
                            }
                        }
                        black_box(found)
                    })
                });
                group.bench_function(BenchmarkId::new("packet", n), |b| {
                    b.iter(|| {
                        let mut found = 0usize;
                        for batch in set {
                            if closest {
                                let mut out = [None; PACKET_SIZE];
                                g.intersect_packet(&batch[..n], &mut out[..n]);
                                found += out.iter().filter(|h| h.is_some()).count();
                            } else {
                                let mut out = [false; PACKET_SIZE];
                                g.occluded_packet(&batch[..n], except, &mut out[..n]);
                                found += out.iter().filter(|&&o| o).count();
                            }
                        }
                        black_box(found)
                    })
                });
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = packet_batches
}
criterion_main!(benches);
