//! Criterion benches of BVH traversal on a real mesh: closest hit and
//! occlusion, coherent and incoherent rays, single rays and 8-ray packets.
//!
//! `cargo bench --bench traversal` (add `-- --quick` for a fast look).
//!
//! The mesh is assets/bunny.obj when `tools/fetch-assets` has fetched it,
//! else a generated icosphere of 81,920 triangles. Rays are the seeded sets
//! of `strata bench` (`strata::experiment::bench::rays`): coherent = the 8 lens samples
//! of one pixel of a camera looking at the mesh, incoherent = chords of the
//! bounding sphere. Traced through the `Scene` API, as the renderer does.
//!
//! `mesh_queries` measures the mesh queries on the dragon
//! (assets/dragon.ply, else the same mesh as above): every crossing and
//! their count beside the closest hit on the same random rays, and the
//! nearest point of random points, one thread.

mod common;

use common::Draw;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use strata::accel::{BuildQuality, PACKET_SIZE};
use strata::experiment::bench::{rays, RayKind};
use strata::math::Ray;
use strata::scene::load_mesh_scene;

fn traversal(c: &mut Criterion) {
    let (scene, name) = common::mesh_scene(BuildQuality::Auto);
    for kind in [RayKind::Camera, RayKind::Random] {
        let batches = rays(&scene, kind, 512, 1);
        let mut g = c.benchmark_group(format!("traversal_{name}_{}", kind.name()));
        g.throughput(Throughput::Elements((batches.len() * PACKET_SIZE) as u64));
        g.bench_function(BenchmarkId::new("closest", "single"), |b| {
            b.iter(|| {
                let mut n = 0;
                for batch in &batches {
                    for r in batch {
                        n += scene.geometry.intersect(r).is_some() as u32;
                    }
                }
                black_box(n)
            })
        });
        g.bench_function(BenchmarkId::new("closest", "packet"), |b| {
            b.iter(|| {
                let mut out = [None; PACKET_SIZE];
                let mut n = 0;
                for batch in &batches {
                    scene.geometry.intersect_packet(batch, &mut out);
                    n += out.iter().filter(|h| h.is_some()).count();
                }
                black_box(n)
            })
        });
        g.bench_function(BenchmarkId::new("occlusion", "single"), |b| {
            b.iter(|| {
                let mut n = 0;
                for batch in &batches {
                    for r in batch {
                        n += scene.geometry.occluded(r) as u32;
                    }
                }
                black_box(n)
            })
        });
        g.bench_function(BenchmarkId::new("occlusion", "packet"), |b| {
            b.iter(|| {
                let mut out = [false; PACKET_SIZE];
                let mut n = 0;
                for batch in &batches {
                    scene.geometry.occluded_packet(batch, u32::MAX, &mut out);
                    n += out.iter().filter(|&&o| o).count();
                }
                black_box(n)
            })
        });
        g.finish();
    }
}

fn mesh_queries(c: &mut Criterion) {
    let dragon = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/dragon.ply");
    let (scene, name) = if dragon.exists() {
        let (scene, _) = load_mesh_scene(&dragon, BuildQuality::Auto).unwrap();
        (scene, "dragon".to_string())
    } else {
        common::mesh_scene(BuildQuality::Auto)
    };
    let g = &scene.geometry;
    // Chords of the bounding sphere, made whole rays: the same crossings.
    let rays: Vec<Ray> = rays(&scene, RayKind::Random, 1024, 2)
        .into_iter()
        .flatten()
        .map(|r| Ray {
            tmax: f32::INFINITY,
            ..r
        })
        .collect();
    let mut group = c.benchmark_group(format!("mesh_queries_{name}"));
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("closest", |b| {
        b.iter(|| rays.iter().filter(|r| g.intersect(r).is_some()).count())
    });
    group.bench_function("crossings", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            let mut n = 0;
            for r in &rays {
                out.clear();
                g.crossings(r, &mut out);
                n += out.len();
            }
            black_box(n)
        })
    });
    group.bench_function("count_crossings", |b| {
        b.iter(|| rays.iter().map(|r| g.count_crossings(r)).sum::<u32>())
    });
    // Points of the bounding box grown by a tenth on each side.
    let (lo, hi) = (g.bvh().bounds.min, g.bvh().bounds.max);
    let mut rng = common::seeded(3);
    let points: Vec<Vec3> = (0..rays.len())
        .map(|_| {
            let f = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 1.2 - 0.1;
            lo + (hi - lo) * f
        })
        .collect();
    // And points near the surface: triangle centroids moved by up to a
    // hundredth of the box's diagonal.
    let tris = g.file_order_triangles();
    let reach = (hi - lo).length() * 0.01;
    let near: Vec<Vec3> = (0..rays.len())
        .map(|i| {
            let t = tris[i * 104_729 % tris.len()];
            (t[0] + t[1] + t[2]) / 3.0 + rng.cube(2.0 * reach)
        })
        .collect();
    for (name, points) in [("nearest_box", &points), ("nearest_surface", &near)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                points
                    .iter()
                    .map(|&p| g.nearest(p, f32::INFINITY).map_or(0.0, |n| n.distance))
                    .sum::<f32>()
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = traversal, mesh_queries
}
criterion_main!(benches);
