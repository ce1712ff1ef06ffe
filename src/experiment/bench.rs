//! The throughput suite behind `strata bench`: per mesh, BVH build time,
//! bytes per triangle, and Mrays/s for closest hit and occlusion on
//! coherent rays (the 8 lens samples of one pixel to a packet) and
//! incoherent rays (random chords of the bounding sphere), traced one by
//! one and as packets, at 1 thread and at all threads.
//!
//! Ray sets are seeded `rand` streams, so every run traces the same rays.

use crate::accel::PACKET_SIZE;
use crate::math::Ray;
use crate::sampling::stream::{item_stream, Draw, StreamRng};
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// Coherent or incoherent rays, in packets of [`PACKET_SIZE`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayKind {
    /// A `side`² pixel camera looking at the mesh; each packet is the 8 lens
    /// samples (a lens of 2% of the scene radius) of one pixel.
    Camera,
    /// Chords between two uniform points on the bounding sphere.
    Random,
}

impl RayKind {
    pub fn name(self) -> &'static str {
        match self {
            Self::Camera => "coherent",
            Self::Random => "incoherent",
        }
    }
}

fn sphere_point(rng: &mut StreamRng) -> Vec3 {
    let z = 2.0 * rng.unit() - 1.0;
    let phi = std::f32::consts::TAU * rng.unit();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `packets` packets of 8 rays of `kind` around the scene's BVH bounds;
/// packet `k` draws from its own seeded stream.
pub fn rays(scene: &Scene, kind: RayKind, packets: usize, seed: u32) -> Vec<[Ray; PACKET_SIZE]> {
    let b = scene.geometry.bvh().bounds;
    let center = (b.min + b.max) * 0.5;
    let radius = ((b.max - b.min).length() * 0.5).max(1e-6);
    let side = (packets as f64).sqrt().ceil() as usize;
    (0..packets)
        .map(|k| {
            let mut rng = item_stream(seed, kind as u32, k as u32);
            std::array::from_fn(|_| match kind {
                RayKind::Camera => {
                    let (px, py) = (k % side, k / side);
                    let fx = ((px as f32 + 0.5) / side as f32 * 2.0 - 1.0) * radius;
                    let fy = (1.0 - (py as f32 + 0.5) / side as f32 * 2.0) * radius;
                    let focus = center + Vec3::new(fx, fy, 0.0);
                    let lens = 0.02 * radius;
                    let o = center
                        + Vec3::new(rng.range(-lens, lens), rng.range(-lens, lens), 2.5 * radius);
                    Ray::new(o, focus - o)
                }
                RayKind::Random => {
                    let a = center + sphere_point(&mut rng) * radius;
                    let c = center + sphere_point(&mut rng) * radius;
                    Ray::segment(a, c - a, 1.0)
                }
            })
        })
        .collect()
}

/// What the suite asks of each ray: its closest hit, or whether anything
/// blocks it (not [`crate::accel::Query`], what a walk asks at a leaf).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Question {
    ClosestHit,
    Occlusion,
}

impl Question {
    /// The name the CSV and the Embree harness's protocol use.
    pub fn name(self) -> &'static str {
        match self {
            Self::ClosestHit => "closest",
            Self::Occlusion => "occlusion",
        }
    }
}

/// Trace every packet's rays once; returns (seconds, hits). `packet`
/// traces each packet with [`Geometry::intersect_packet`](crate::geometry::Geometry::intersect_packet) /
/// [`Geometry::occluded_packet`](crate::geometry::Geometry::occluded_packet),
/// else ray by ray.
pub fn trace(
    scene: &Scene,
    packets: &[[Ray; PACKET_SIZE]],
    question: Question,
    packet: bool,
    pool: &rayon::ThreadPool,
) -> (f64, u64) {
    let start = Instant::now();
    let hits: u64 = pool.install(|| {
        packets
            .par_chunks(64)
            .map(|chunk| {
                let mut hits = 0u64;
                for rays in chunk {
                    hits += match (question, packet) {
                        (Question::ClosestHit, false) => rays
                            .iter()
                            .filter(|r| scene.geometry.intersect(r).is_some())
                            .count(),
                        (Question::Occlusion, false) => {
                            rays.iter().filter(|r| scene.geometry.occluded(r)).count()
                        }
                        (Question::ClosestHit, true) => {
                            let mut out = [None; PACKET_SIZE];
                            scene.geometry.intersect_packet(rays, &mut out);
                            out.iter().filter(|h| h.is_some()).count()
                        }
                        (Question::Occlusion, true) => {
                            let mut out = [false; PACKET_SIZE];
                            scene.geometry.occluded_packet(rays, u32::MAX, &mut out);
                            out.iter().filter(|&&b| b).count()
                        }
                    } as u64;
                }
                hits
            })
            .sum()
    });
    (start.elapsed().as_secs_f64(), hits)
}
