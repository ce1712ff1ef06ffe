//! `strata bench`: the throughput suite on the meshes in assets/ (or the
//! ones named), printed as a table and saved as CSV.

use super::CliError;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::experiment::bench::{rays, trace, Query, RayKind};
use strata::scene::{compile, parse, RenderOverrides};
use strata::system::memory::peak_rss_bytes;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Meshes (OBJ, glTF, GLB or PLY); default: every mesh in assets/.
    pub meshes: Vec<PathBuf>,
    /// Batches of 8 rays per ray set.
    #[arg(long, default_value_t = 50_000)]
    pub batches: usize,
    /// Timed runs per row; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// The "all threads" column (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// BVH build effort; auto picks by primitive count.
    #[arg(long, default_value = "auto")]
    pub bvh_quality: BuildQuality,
    /// Where to save the CSV.
    #[arg(long, default_value = "bench.csv")]
    pub csv: PathBuf,
}

fn meshes(args: &BenchArgs) -> Result<Vec<PathBuf>, CliError> {
    if !args.meshes.is_empty() {
        return Ok(args.meshes.clone());
    }
    let dir = PathBuf::from("assets");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| InputError::file(&dir, format!("cannot list: {e} (run tools/fetch-assets)")))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("obj" | "ply" | "gltf" | "glb")
            )
        })
        .collect();
    out.sort();
    Ok(out)
}

pub fn run(args: BenchArgs) -> Result<(), CliError> {
    super::writable(&args.csv, "--csv", &["csv"])?;
    let all = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pools: Vec<(usize, rayon::ThreadPool)> = [1, all]
        .into_iter()
        .enumerate()
        .filter(|&(i, n)| i == 0 || n != 1)
        .map(|(_, n)| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| CliError::Internal(e.to_string()))?;
            Ok((n, pool))
        })
        .collect::<Result<_, CliError>>()?;
    let mut csv = String::from(
        "mesh,triangles,load_s,build_s,bytes_per_triangle,peak_load_build_bytes_per_triangle,peak_rss_mb,query,rays,mode,threads,mrays_per_s\n",
    );
    println!(
        "{:<22} {:>9} {:>8} {:>7} {:>8} {:>9} {:>10} {:>6} {:>3} {:>9}",
        "mesh", "tris", "build s", "B/tri", "peak/tri", "query", "rays", "mode", "thr", "Mrays/s"
    );
    for mesh in meshes(&args)? {
        let abs = std::fs::canonicalize(&mesh)
            .map_err(|e| InputError::file(&mesh, format!("cannot open: {e}")))?;
        let text = format!("[[objects]]\nmesh = {:?}\n", abs.display().to_string());
        let scene_path = PathBuf::from("bench.toml");
        let desc = parse::parse_description(&scene_path, &text)?;
        let (scene, timings) = compile::compile(
            &desc,
            &scene_path,
            &RenderOverrides::default(),
            args.bvh_quality,
            Instant::now(),
        )?;
        let rss = peak_rss_bytes().unwrap_or(0) as f64 / (1 << 20) as f64;
        let tris = scene.geometry.triangle_count as usize;
        let bpt = scene.geometry.accel_bytes() as f64 / tris.max(1) as f64;
        // Peak memory of load + build above the level before, per triangle.
        let peak = timings.peak_bytes().map(|b| b as f64 / tris.max(1) as f64);
        let peak_text = peak.map_or("-".to_string(), |p| format!("{p:.0}"));
        let load = timings.load.as_secs_f64();
        let name = mesh
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let build = timings.bvh_build.as_secs_f64();
        let mb =
            |b: Option<u64>| b.map_or("-".to_string(), |b| format!("{:.0} MB", b as f64 / 1e6));
        println!(
            "# {name}: load {load:.3} s (peak +{}), BVH build {build:.3} s (peak +{}); final {bpt:.1} B/tri, peak {peak_text} B/tri",
            mb(timings.load_peak_bytes),
            mb(timings.build_peak_bytes),
        );
        println!(
            "# {name}: tree {}; prefetch {} ({:.1} MB of nodes and leaf blocks)",
            scene.geometry.bvh.stats(),
            if scene.geometry.bvh.prefetch {
                "on"
            } else {
                "off"
            },
            scene.geometry.traversal_bytes() as f64 / 1e6
        );
        for kind in [RayKind::Camera, RayKind::Random] {
            let batches = rays(&scene, kind, args.batches, 1);
            for query in [Query::Closest, Query::Occlusion] {
                for (threads, pool) in &pools {
                    for packet in [false, true] {
                        let mut times: Vec<f64> = (0..args.repeats.max(1))
                            .map(|_| trace(&scene, &batches, query, packet, pool).0)
                            .collect();
                        times.sort_by(f64::total_cmp);
                        let t = times[times.len() / 2];
                        let mrays = (batches.len() * 8) as f64 / t / 1e6;
                        let q = match query {
                            Query::Closest => "closest",
                            Query::Occlusion => "occlusion",
                        };
                        let mode = if packet { "packet" } else { "single" };
                        println!(
                            "{name:<22} {tris:>9} {build:>8.3} {bpt:>7.1} {peak_text:>8} {q:>9} {:>10} {mode:>6} {threads:>3} {mrays:>9.2}",
                            kind.name()
                        );
                        csv += &format!(
                            "{name},{tris},{load:.4},{build:.4},{bpt:.1},{},{rss:.0},{q},{},{mode},{threads},{mrays:.3}\n",
                            peak.map_or(String::new(), |p| format!("{p:.1}")),
                            kind.name()
                        );
                    }
                }
            }
        }
    }
    strata::output::atomic::write_bytes_atomic(&args.csv, csv.as_bytes())
        .map_err(|e| InputError::file(&args.csv, format!("cannot write: {e}")))?;
    println!("-> {}", args.csv.display());
    Ok(())
}
