//! Criterion bench of the BVH build (`Bvh8::build`: PLOC in parallel, then the
//! collapse to 8-wide nodes) over the triangle boxes of a real mesh, at
//! three of the `--bvh-quality` levels.
//!
//! `cargo bench --bench build` (add `-- --quick` for a fast look).
//!
//! The mesh is assets/bunny.obj when `tools/fetch-assets` has fetched it,
//! else a generated icosphere of 81,920 triangles.

mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use strata::accel::{BuildQuality, Bvh8};
use strata::math::Aabb;

fn build(c: &mut Criterion) {
    let (scene, name) = common::mesh_scene(BuildQuality::Fastest);
    let boxes: Vec<Aabb> = scene
        .geometry
        .file_order_triangles()
        .iter()
        .map(|t| Aabb::from_points(t))
        .collect();
    let mut g = c.benchmark_group(format!("build_{name}"));
    g.throughput(Throughput::Elements(boxes.len() as u64));
    for (label, quality) in [
        ("fastest", BuildQuality::Fastest),
        ("auto", BuildQuality::Auto),
        ("high", BuildQuality::High),
    ] {
        g.bench_function(BenchmarkId::from_parameter(label), |b| {
            b.iter(|| black_box(Bvh8::build(black_box(&boxes), quality)))
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = build
}
criterion_main!(benches);
