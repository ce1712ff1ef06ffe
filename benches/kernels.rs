//! Criterion benches of the innermost kernels: the 8-wide ray–box node
//! test and the watertight ray–triangle test.
//!
//! `cargo bench --bench kernels` (add `-- --quick` for a fast look).
//!
//! The node test (`RayBoxes`, `Packet::test_node`/`test_lanes`) and
//! the packet setup are crate-private, so the node test is measured
//! through the nearest public API: `Bvh8::closest_hit` / `Bvh8::occluded` /
//! `Bvh8::walk_packet` on a BVH of one node whose eight children are
//! one-primitive leaves (`Bvh8::one_node`), with a primitive test that
//! never hits. Per ray that is one 8-wide slab test, the child sort and a visit
//! of each entered leaf.
//!
//! Ray–triangle: the scalar watertight test; the 8-wide leaf test (one ray
//! against a block of eight triangles, `triangle_lanes::intersect`); the packet
//! test (one triangle against eight rays in lanes, `ShearedRays`); and
//! `Scene::intersect` on 8 rays against `Scene::intersect_packet` on a
//! one-triangle scene, the packet path's fixed cost.
//!
//! Sampling: a pixel's 2D draws one at a time (`DimSampler::get_2d`)
//! against eight at once (`DimSampler::get_2d_lanes`), for CMJ sets of a
//! square, a partial grid and a prepared size, and for the random sampler.

mod common;

use strata::shape::triangle_lanes::{self, ShearedRays, TriangleBlock};

use common::{seeded, Draw, StreamRng as Rng};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use strata::accel::{BuildQuality, Bvh8, Packet, PACKET_SIZE};
use strata::accel::{ClosestHitPacket, OcclusionPacket, PrimHit};
use strata::math::lanes::LANES;
use strata::math::{Aabb, Ray};
use strata::sampling::{Dim, PixelSampler, SamplerKind};
use strata::scene::{scene_from_str, RenderOverrides};
use strata::shape::triangle::{intersect, ShearedRay};

/// One node, eight leaf children with random boxes in [-1, 1]³.
fn one_node_bvh(rng: &mut Rng) -> Bvh8 {
    let boxes: [Aabb; 8] = std::array::from_fn(|_| {
        let c = Vec3::new(
            rng.range(-0.7, 0.7),
            rng.range(-0.7, 0.7),
            rng.range(-0.7, 0.7),
        );
        let h = Vec3::new(
            rng.range(0.1, 0.3),
            rng.range(0.1, 0.3),
            rng.range(0.1, 0.3),
        );
        Aabb::new(c - h, c + h)
    });
    // The node test alone: one node, nothing to fetch ahead.
    Bvh8::one_node(&boxes)
}

/// `batches` batches of 8 rays: each batch from one point on a sphere of
/// radius 4, towards nearby points of the box cluster (so batches are
/// coherent, and some rays enter several boxes while others miss).
fn node_rays(rng: &mut Rng, batches: usize) -> Vec<[Ray; PACKET_SIZE]> {
    (0..batches)
        .map(|_| {
            let origin = rng.unit_vector() * 4.0;
            let aim = Vec3::new(
                rng.range(-0.8, 0.8),
                rng.range(-0.8, 0.8),
                rng.range(-0.8, 0.8),
            );
            std::array::from_fn(|_| {
                let jitter = Vec3::new(
                    rng.range(-0.1, 0.1),
                    rng.range(-0.1, 0.1),
                    rng.range(-0.1, 0.1),
                );
                Ray::new(origin, aim + jitter - origin)
            })
        })
        .collect()
}

fn ray_box(c: &mut Criterion) {
    let mut rng = seeded(7);
    let bvh = one_node_bvh(&mut rng);
    let mut batches = node_rays(&mut rng, 160);
    // Packets need one direction sign per axis: keep the batches that have it.
    batches.retain(|b| Packet::new(b).is_some());
    batches.truncate(128);
    let rays = (batches.len() * PACKET_SIZE) as u64;
    let mut g = c.benchmark_group("ray_box");
    g.throughput(Throughput::Elements(rays));
    g.bench_function("node8_closest_single", |b| {
        b.iter(|| {
            let mut n = 0;
            for batch in &batches {
                for r in batch {
                    n += bvh.closest_hit(r, &[] as &[()], |_, _, _| None).is_some() as u32;
                }
            }
            black_box(n)
        })
    });
    g.bench_function("node8_occlusion_single", |b| {
        b.iter(|| {
            let mut n = 0;
            for batch in &batches {
                for r in batch {
                    n += bvh.occluded(r, &[] as &[()], |_, _, _| false) as u32;
                }
            }
            black_box(n)
        })
    });
    // Packets built once, outside the timed loop: the node tests alone.
    let packets: Vec<Packet> = batches.iter().filter_map(|b| Packet::new(b)).collect();
    g.bench_function("node8_closest_packet", |b| {
        b.iter(|| {
            let mut out = [None::<PrimHit>; PACKET_SIZE];
            let mut n = 0;
            for p in &packets {
                let mut query = ClosestHitPacket(|_, _, _, _: &mut [Option<PrimHit>]| false);
                bvh.walk_packet(p, &mut out, &[] as &[()], &mut query);
                n += out.iter().filter(|h| h.is_some()).count();
            }
            black_box(n)
        })
    });
    g.bench_function("node8_occlusion_packet", |b| {
        b.iter(|| {
            let mut out = [false; PACKET_SIZE];
            let mut n = 0;
            for p in &packets {
                bvh.walk_packet(p, &mut out, &[] as &[()], &mut OcclusionPacket(|_, _, _| 0));
                n += out.iter().filter(|&&o| o).count();
            }
            black_box(n)
        })
    });
    g.bench_function("packet_setup", |b| {
        b.iter(|| {
            let mut n = 0;
            for batch in &batches {
                n += black_box(Packet::new(batch)).is_some() as u32;
            }
            black_box(n)
        })
    });
    g.finish();
}

fn ray_triangle(c: &mut Criterion) {
    // Triangles of the bench mesh (or the icosphere), each with a ray from
    // a random point towards a point of its plane near it: about half hit.
    let (scene, _) = common::mesh_scene(BuildQuality::Fastest);
    let tris = scene.geometry.file_order_triangles();
    let mut rng = seeded(11);
    let cases: Vec<([Vec3; 3], Ray, ShearedRay)> = (0..1024)
        .map(|i| {
            let t = tris[(i * 7919) % tris.len()];
            let (u, v) = (rng.range(-0.3, 1.0), rng.range(-0.3, 1.0));
            let target = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
            let size = (t[1] - t[0]).length().max(1e-6);
            let origin = target + rng.unit_vector() * 50.0 * size;
            let ray = Ray::new(origin, target - origin);
            (t, ray, ShearedRay::new(&ray))
        })
        .collect();
    let mut g = c.benchmark_group("ray_triangle");
    g.throughput(Throughput::Elements(cases.len() as u64));
    g.bench_function("single", |b| {
        b.iter(|| {
            let mut n = 0;
            for (t, r, s) in &cases {
                n += intersect(r, s, t).is_some() as u32;
            }
            black_box(n)
        })
    });
    g.bench_function("single_with_shear", |b| {
        b.iter(|| {
            let mut n = 0;
            for (t, r, _) in &cases {
                n += intersect(r, &ShearedRay::new(r), t).is_some() as u32;
            }
            black_box(n)
        })
    });
    // The same cases eight triangles at a time: one ray against a block
    // (the leaf test), and one triangle against eight rays (the packet
    // leaf test). Throughput counts ray–triangle tests.
    let blocks: Vec<(TriangleBlock, Ray, ShearedRay)> = cases
        .chunks(LANES)
        .map(|chunk| {
            let mut block = TriangleBlock::EMPTY;
            for (lane, (t, _, _)) in chunk.iter().enumerate() {
                block.set(lane, t, lane as u32);
            }
            (block, chunk[0].1, chunk[0].2)
        })
        .collect();
    g.bench_function("block8_one_ray", |b| {
        b.iter(|| {
            let mut n = 0;
            for (block, r, s) in &blocks {
                n += triangle_lanes::intersect(r, s, block, 0xff).0.count_ones();
            }
            black_box(n)
        })
    });
    let ray_lanes: Vec<([Vec3; 3], ShearedRays, [f32; LANES])> = cases
        .chunks(LANES)
        .map(|chunk| {
            let rays: Vec<Ray> = chunk.iter().map(|c| c.1).collect();
            (chunk[0].0, ShearedRays::new(&rays), [f32::INFINITY; LANES])
        })
        .collect();
    g.bench_function("eight_rays_one_triangle", |b| {
        b.iter(|| {
            let mut n = 0;
            for (t, rays, tmax) in &ray_lanes {
                n += rays.intersect(t, (*tmax).into(), 0xff).0.count_ones();
            }
            black_box(n)
        })
    });
    g.finish();

    // One triangle as a scene: 8 coherent rays one by one and as a packet.
    let one = scene_from_str(
        "[[objects]]\ntriangle = { v = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]] }\n",
        Path::new("one.toml"),
        &RenderOverrides::default(),
    )
    .unwrap();
    let batches: Vec<[Ray; PACKET_SIZE]> = (0..128)
        .map(|_| {
            let aim = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0);
            std::array::from_fn(|_| {
                let j = Vec3::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05), 0.0);
                let o = Vec3::new(0.0, 0.0, 3.0);
                Ray::new(o, aim + j - o)
            })
        })
        .collect();
    let mut g = c.benchmark_group("ray_triangle_scene");
    g.throughput(Throughput::Elements((batches.len() * PACKET_SIZE) as u64));
    g.bench_function("single8", |b| {
        b.iter(|| {
            let mut n = 0;
            for batch in &batches {
                for r in batch {
                    n += one.geometry.intersect(r).is_some() as u32;
                }
            }
            black_box(n)
        })
    });
    g.bench_function("packet8", |b| {
        b.iter(|| {
            let mut out = [None; PACKET_SIZE];
            let mut n = 0;
            for batch in &batches {
                one.geometry.intersect_packet(batch, &mut out);
                n += out.iter().filter(|h| h.is_some()).count();
            }
            black_box(n)
        })
    });
    g.finish();
}

fn sampling(c: &mut Criterion) {
    const PIXELS: u32 = 1024;
    let mut g = c.benchmark_group("sampling");
    for (kind, n) in [
        (SamplerKind::Stratified, 16u32),
        (SamplerKind::Stratified, 35),
        (SamplerKind::Random, 16),
    ] {
        g.throughput(Throughput::Elements((PIXELS * n) as u64));
        let sets = PixelSampler::prepare_sets([n, 0]);
        let pixel = |p: u32| {
            PixelSampler::new(kind, 7, p)
                .with_sets(sets)
                .dim_2d(Dim::PIXEL, n)
        };
        g.bench_function(format!("{kind}_{n}_one_at_a_time"), |b| {
            b.iter(|| {
                let mut sum = 0.0;
                for p in 0..PIXELS {
                    let draws = pixel(p);
                    for i in 0..n {
                        sum += draws.get_2d(i).x;
                    }
                }
                black_box(sum)
            })
        });
        g.bench_function(format!("{kind}_{n}_eight_lanes"), |b| {
            b.iter(|| {
                let mut sum = 0.0;
                for p in 0..PIXELS {
                    let draws = pixel(p);
                    for first in (0..n).step_by(8) {
                        let index = std::array::from_fn(|i| (first + i as u32).min(n - 1));
                        let live = (n - first).min(8);
                        let points = draws.get_2d_lanes(index, (1 << live) - 1);
                        sum += points[..live as usize].iter().map(|p| p.x).sum::<f32>();
                    }
                }
                black_box(sum)
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = ray_box, ray_triangle, sampling
}
criterion_main!(benches);
