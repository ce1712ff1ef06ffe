//! `strata trace MESH --rays RAYS.bin --hits HITS.bin [--occlusion] [--threads T]`:
//! trace a ray file against one mesh with the renderer's own queries
//! (`Geometry::intersect_stream` and `occluded_stream`, which send narrow
//! groups of eight as packets, or one ray at a time through `intersect`
//! and `occluded`) and write one hit record per
//! ray (see [`strata::rayfile`]).

use super::CliError;
use clap::Args;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;
use strata::accel::prefetch::Prefetch;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::rayfile::{encode_hits, read_rays, write_file, HitRecord};
use strata::scene::{load_mesh_scene, Scene};

#[derive(Debug, Args, Clone)]
pub struct TraceArgs {
    /// Mesh file (.obj, .ply, .gltf or .glb), used as it is: triangle i of the file is primitive i.
    pub mesh: PathBuf,
    /// Ray file: records of 8 little-endian f32 (ox oy oz dx dy dz tmin tmax).
    #[arg(long)]
    pub rays: PathBuf,
    /// Hit file to write: per ray t (f32, +inf on a miss), prim (u32, u32::MAX on a miss), u, v (f32).
    #[arg(long)]
    pub hits: PathBuf,
    /// Answer occlusion queries instead: each record is t = 0, prim = 0 if
    /// anything lies in (tmin, tmax), else the miss record.
    #[arg(long)]
    pub occlusion: bool,
    /// Worker threads (default: all cores). The hits are identical for any count.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// BVH build effort; auto picks by primitive count.
    #[arg(long, default_value = "auto")]
    pub bvh_quality: BuildQuality,
    /// Trace the rays this many times and report the median time, with
    /// caches and branch predictors as warm as in a benchmark loop (the
    /// hits are the same every time; the first pass's are written).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Software prefetching of deferred BVH children: auto | on | off. Auto
    /// turns it on for trees of 8 MiB and more (nodes and leaf blocks).
    /// It changes no hit, only the time: compare `on` with `off` to measure it.
    /// Where it is on, each thread keeps several rays in flight at once.
    #[arg(long, default_value = "auto")]
    pub prefetch: Prefetch,
    /// Trace one ray at a time, as the renderer traces a lone ray, instead
    /// of narrow groups of eight as packets and the rest several in flight
    /// at once on each thread. The hits are the same; compare the two to
    /// measure them.
    #[arg(long)]
    pub one_at_a_time: bool,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Rays a thread takes at a time: many interleaved walks' worth, few
/// enough that threads balance.
const CHUNK: usize = 256;

/// Trace every ray with `threads` threads (0: all cores); returns the
/// records, the thread count used and the seconds the tracing took (the
/// thread pool's start is not counted, as embreex's timing does not count
/// Embree's).
pub fn trace(
    scene: &Scene,
    rays: &[strata::math::Ray],
    occlusion: bool,
    one_at_a_time: bool,
    threads: usize,
) -> Result<(Vec<HitRecord>, usize, f64), CliError> {
    let pool = super::thread_pool(threads)?;
    let (hits, seconds) = pool.install(|| {
        let start = Instant::now();
        let hits: Vec<HitRecord> = if one_at_a_time {
            rays.par_iter()
                .with_min_len(CHUNK)
                .map(|ray| {
                    if occlusion {
                        HitRecord::occluded(scene.geometry.occluded(ray))
                    } else {
                        HitRecord::from_hit(scene.geometry.intersect(ray))
                    }
                })
                .collect()
        } else {
            rays.par_chunks(CHUNK)
                .flat_map_iter(|chunk| {
                    let records: Vec<HitRecord> = if occlusion {
                        let mut out = vec![false; chunk.len()];
                        scene.geometry.occluded_stream(chunk, u32::MAX, &mut out);
                        out.into_iter().map(HitRecord::occluded).collect()
                    } else {
                        let mut out = vec![None; chunk.len()];
                        scene.geometry.intersect_stream(chunk, &mut out);
                        out.into_iter().map(HitRecord::from_hit).collect()
                    };
                    records
                })
                .collect()
        };
        (hits, start.elapsed().as_secs_f64())
    });
    Ok((hits, pool.current_num_threads(), seconds))
}

pub fn run(args: TraceArgs) -> Result<(), CliError> {
    super::writable(&args.hits, "--hits", &[])?;
    let (mut scene, timings) = load_mesh_scene(&args.mesh, args.bvh_quality)?;
    scene.geometry.bvh.prefetch = args.prefetch.enabled(scene.geometry.traversal_bytes());
    let rays = read_rays(&args.rays)?;
    if args.hits == args.rays {
        return Err(InputError::new(
            "<command line>",
            "--hits",
            "must not be the ray file it reads",
        )
        .into());
    }
    let (hits, threads, first) = trace(
        &scene,
        &rays,
        args.occlusion,
        args.one_at_a_time,
        args.threads,
    )?;
    let mut times = vec![first];
    for _ in 1..args.repeats {
        times.push(
            trace(
                &scene,
                &rays,
                args.occlusion,
                args.one_at_a_time,
                args.threads,
            )?
            .2,
        );
    }
    times.sort_by(f64::total_cmp);
    let seconds = times[times.len() / 2];
    write_file(&args.hits, &encode_hits(&hits))?;
    if !args.quiet {
        let found = hits.iter().filter(|h| h.is_hit()).count();
        println!(
            "traced {} rays ({}) against {} triangles: {} {} in {:.3} s = {:.2} Mrays/s on {} (load {:.2} s, BVH {:.2} s) -> {}",
            rays.len(),
            if args.occlusion { "occlusion" } else { "closest hit" },
            scene.geometry.triangle_count,
            found,
            if args.occlusion { "occluded" } else { "hits" },
            seconds,
            rays.len() as f64 / seconds.max(1e-9) / 1e6,
            super::count(threads, "thread", "threads"),
            timings.load.as_secs_f64(),
            timings.bvh_build.as_secs_f64(),
            args.hits.display()
        );
    }
    Ok(())
}
