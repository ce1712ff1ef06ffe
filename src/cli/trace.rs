//! `strata trace MESH --rays RAYS.bin --hits HITS.bin [--occlusion] [--threads T]`:
//! trace a ray file against one mesh with the renderer's own queries
//! (`Geometry::intersect_stream` and `occluded_stream`, which send
//! spans of alike rays as bundles and eight consecutive rays narrow
//! enough as packets, or one ray at a time through `intersect` and
//! `occluded`) and write one hit record per ray (see
//! [`strata::rays::file`]).

use super::CliError;
use clap::Args;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;
use strata::accel::prefetch::Prefetch;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::rays::file::{encode_hits, read_rays, write_file, HitRecord};
use strata::scene::{load_mesh_scene, load_scene_for_tracing, Scene};

#[derive(Debug, Args, Clone)]
pub struct TraceArgs {
    /// Mesh file (.obj, .ply, .gltf, .glb, .off or .stl), used as it is: triangle i of
    /// the file is primitive i. Or a scene file (.toml), with its
    /// instances: instance k's triangle j is numbered as if every instance
    /// were a copy, after the scene's own primitives and the earlier
    /// instances' triangles (docs/scene-format.md, "Instances").
    pub mesh: PathBuf,
    /// Ray file: records of 8 little-endian f32 (ox oy oz dx dy dz tmin tmax).
    #[arg(long)]
    pub rays: PathBuf,
    /// Hit file to write: per ray t (f32, +inf on a miss), prim (u32, u32::MAX on a miss), u, v (f32).
    #[arg(long)]
    pub hits: PathBuf,
    /// Answer occlusion queries instead: each record is t = 0, prim = 0 if
    /// anything lies in (tmin, tmax], else the miss record.
    #[arg(long)]
    pub occlusion: bool,
    /// Worker threads (default: all cores). The hits are identical for any count.
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// BVH build effort; auto builds medium whatever the mesh (the tree does
    /// not depend on how many rays are timed).
    #[arg(long, default_value = "auto")]
    pub bvh_quality: BuildQuality,
    /// Trace the rays this many times and report the median time, with
    /// caches and branch predictors as warm as in a benchmark loop (every
    /// pass gives the same hits). The timing covers the tracing alone, not
    /// the start of the threads or the buffer the hits are written to.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Software prefetching of deferred BVH children: auto | on | off. Auto
    /// turns it on for trees of 8 MiB and more (nodes and leaf blocks).
    /// It changes no hit, only the time: compare `on` with `off` to measure it.
    /// Where it is on, each thread keeps several rays in flight at once.
    #[arg(long, default_value = "auto")]
    pub prefetch: Prefetch,
    /// Trace one ray at a time, as the renderer traces a lone ray, instead
    /// of spans of alike rays (close origins or close directions) in
    /// bundles of 64, eight consecutive rays narrow enough as packets and the rest
    /// several in flight at once on each thread. The hits are the same;
    /// compare the two to measure them.
    #[arg(long)]
    pub one_at_a_time: bool,
    /// Also print the tree's shape and how many of its nodes and leaves a
    /// random line through its box enters on average (the node figure is
    /// the `sah` Embree prints for its nodes), to compare trees; for a
    /// scene file, the scene's own tree.
    #[arg(long)]
    pub tree: bool,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Rays a thread takes at a time: many interleaved walks' worth, few
/// enough that threads balance.
const CHUNK: usize = 256;

/// Trace every ray with `threads` threads (0: all cores) into `hits`,
/// one record per ray, written in place; returns the thread count used and
/// the seconds the tracing took. Neither the thread pool's start nor the
/// answers' buffer is timed: embreex's timing does not count Embree's
/// start, and the native harness (`tools/embree`) writes into a buffer it
/// allocated before its clock started, so a pass here must not pay for
/// allocating, growing and first touching 16 bytes a ray either (what
/// timing them cost: docs/embree.md, "The harness").
pub fn trace(
    scene: &Scene,
    rays: &[strata::math::Ray],
    hits: &mut [HitRecord],
    occlusion: bool,
    one_at_a_time: bool,
    threads: usize,
) -> Result<(usize, f64), CliError> {
    assert_eq!(rays.len(), hits.len(), "one record per ray");
    // An instance's hit is written as the triangle's id in the scene with
    // every instance copied (`Geometry::flat_prim`).
    let g = &scene.geometry;
    let offsets = g.flat_offsets();
    let record = |found: Option<strata::accel::PrimHit>| match found {
        Some(h) if !g.instances().is_empty() => HitRecord::from_hit(Some(strata::accel::PrimHit {
            prim: g.flat_prim(&h, &offsets) as u32,
            ..h
        })),
        found => HitRecord::from_hit(found),
    };
    let pool = super::thread_pool(threads)?;
    let seconds = pool.install(|| {
        let start = Instant::now();
        let chunks = rays.par_chunks(CHUNK).zip(hits.par_chunks_mut(CHUNK));
        chunks.for_each(|(rays, hits)| {
            if one_at_a_time {
                for (hit, ray) in hits.iter_mut().zip(rays) {
                    *hit = if occlusion {
                        HitRecord::occluded(scene.geometry.occluded(ray))
                    } else {
                        record(scene.geometry.intersect(ray))
                    };
                }
            } else if occlusion {
                let mut out = [false; CHUNK];
                let out = &mut out[..rays.len()];
                scene.geometry.occluded_stream(rays, u32::MAX, out);
                for (hit, &blocked) in hits.iter_mut().zip(out.iter()) {
                    *hit = HitRecord::occluded(blocked);
                }
            } else {
                let mut out = [None; CHUNK];
                let out = &mut out[..rays.len()];
                scene.geometry.intersect_stream(rays, out);
                for (hit, &found) in hits.iter_mut().zip(out.iter()) {
                    *hit = record(found);
                }
            }
        });
        start.elapsed().as_secs_f64()
    });
    Ok((pool.current_num_threads(), seconds))
}

pub fn run(args: TraceArgs) -> Result<(), CliError> {
    super::writable(&args.hits, "--hits", &[])?;
    let is_scene = args
        .mesh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let (mut scene, timings) = if is_scene {
        load_scene_for_tracing(&args.mesh, args.bvh_quality)?
    } else {
        load_mesh_scene(&args.mesh, args.bvh_quality)?
    };
    let ids = scene.geometry.flat_offsets();
    let last = ids.last().copied().unwrap_or(0);
    if last > u64::from(u32::MAX) - scene.geometry.planes().len() as u64 {
        return Err(InputError::file(
            &args.mesh,
            format!(
                "places {last} triangles: more than a hit file's 32-bit primitive ids can number"
            ),
        )
        .into());
    }
    super::warn(&scene.warnings);
    let prefetch = args.prefetch.enabled(scene.geometry.traversal_bytes());
    scene.geometry.set_prefetch(prefetch);
    let rays = read_rays(&args.rays)?;
    if args.hits == args.rays {
        return Err(InputError::new(
            "<command line>",
            "--hits",
            "must not be the ray file it reads",
        )
        .into());
    }
    // Written once, before any pass is timed (see `trace`); every pass
    // writes the same records.
    let mut hits = vec![HitRecord::MISS; rays.len()];
    let mut threads = 0;
    let mut times = Vec::new();
    for _ in 0..args.repeats {
        let (used, seconds) = trace(
            &scene,
            &rays,
            &mut hits,
            args.occlusion,
            args.one_at_a_time,
            args.threads,
        )?;
        threads = used;
        times.push(seconds);
    }
    times.sort_by(f64::total_cmp);
    let seconds = times[times.len() / 2];
    write_file(&args.hits, &encode_hits(&hits))?;
    if !args.quiet {
        let found = hits.iter().filter(|h| h.is_hit()).count();
        // An instanced scene's placed triangles count as its own (its
        // tree holds each instance, not its triangles).
        let placed = scene.geometry.instanced_triangles();
        let own = u64::from(scene.geometry.triangle_count());
        let against = match placed {
            0 => format!("{own} triangles"),
            _ => format!(
                "{} triangles ({placed} placed by {})",
                own + placed,
                super::count(scene.geometry.instances().len(), "instance", "instances")
            ),
        };
        println!(
            "traced {} rays ({}) against {}: {} {} in {:.3} s = {:.2} Mrays/s on {} (load {:.2} s, BVH {:.2} s, kernel {}) -> {}",
            rays.len(),
            if args.occlusion { "occlusion" } else { "closest hit" },
            against,
            found,
            if args.occlusion { "occluded" } else { "hits" },
            seconds,
            rays.len() as f64 / seconds.max(1e-9) / 1e6,
            super::count(threads, "thread", "threads"),
            timings.load.as_secs_f64(),
            timings.bvh_build.as_secs_f64(),
            strata::accel::Kernel::selected().name(),
            args.hits.display()
        );
    }
    if args.tree {
        println!("tree: {}", scene.geometry.bvh().stats());
    }
    Ok(())
}
