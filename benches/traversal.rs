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

mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;
use strata::accel::{BuildQuality, PACKET_SIZE};
use strata::experiment::bench::{rays, RayKind};

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

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = traversal
}
criterion_main!(benches);
