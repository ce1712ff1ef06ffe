//! `strata bench`: the throughput suite on the meshes in assets/ (or the
//! ones named), printed as a table and saved as CSV.
//!
//! The Embree column comes from tools/embree/embree_trace, a C program on
//! Embree 3's own API (docs/embree.md), compiled here on demand with
//! `make -C tools/embree` into target/embree/. It builds the same
//! triangles once at high quality and then traces the same rays on request
//! (`--serve`): rtcIntersect1 / rtcOccluded1 ray by ray, rtcIntersect8 /
//! rtcOccluded8 on the same packets of 8 for the packet rows. Its passes and
//! strata's alternate, so a change in the machine's load falls on both.
//! Without a C compiler or libembree-dev, one line says so and the column
//! stays empty.

use super::CliError;
use clap::Args;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::experiment::bench::{rays, trace, Question, RayKind};
use strata::geometry::Geometry;
use strata::math::Ray;
use strata::rays::file::{encode_rays, encode_triangles};
use strata::scene::load_mesh_scene;
use strata::system::memory::peak_rss_bytes;

/// The columns of the table `strata bench` prints.
const COLUMNS: [(&str, &str); 12] = [
    ("mesh", "the mesh file"),
    ("tris", "its triangles"),
    ("build s", "seconds to build strata's BVH"),
    ("B/tri", "bytes per triangle that tracing reads: nodes and leaf blocks"),
    ("peak/tri", "how far memory rose while loading and building, per triangle"),
    ("query", "closest: the nearest hit; occlusion: any hit"),
    (
        "rays",
        "coherent: a pixel's 8 lens samples of a camera facing the mesh; incoherent: random chords of its bounding sphere",
    ),
    ("mode", "single: one ray at a time; packet: packets of 8"),
    ("thr", "threads"),
    ("Mrays/s", "strata's millions of rays per second (median of --repeats)"),
    ("Embree", "Embree's on the same rays (docs/embree.md); - without it"),
    ("ratio", "strata's Mrays/s over Embree's"),
];

#[derive(Debug, Args)]
#[command(after_help = "Every column of the table: strata bench --help.")]
#[command(after_long_help = format!("The table's columns:\n{}", strata::experiment::column_key(&COLUMNS)))]
pub struct BenchArgs {
    /// Meshes (OBJ, glTF, GLB, PLY, OFF or STL); default: every mesh in assets/.
    pub meshes: Vec<PathBuf>,
    /// Packets of 8 rays per ray set (the single rows trace them ray by ray).
    #[arg(long = "batches", value_name = "N", default_value_t = 50_000, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub packets: usize,
    /// Timed runs per row; the median is reported.
    #[arg(long, default_value_t = 3, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub repeats: usize,
    /// The "all threads" column (default: every core).
    #[arg(long, value_parser = super::parse_threads)]
    pub threads: Option<usize>,
    /// BVH build effort; auto builds medium whatever the mesh (the tree does
    /// not depend on how many rays are timed).
    #[arg(long, default_value = "auto")]
    pub bvh_quality: BuildQuality,
    /// Where to save the CSV.
    #[arg(long, default_value = "bench.csv")]
    pub csv: PathBuf,
    /// No Embree column (it needs a C compiler and libembree-dev).
    #[arg(long)]
    pub no_embree: bool,
}

/// The compiled Embree harness, or `None` after one line saying why not.
fn embree_harness() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = root.join("target").join("embree");
    let made = Command::new("make")
        .arg("-s")
        .arg("-C")
        .arg(root.join("tools").join("embree"))
        .arg(format!("OUT={}", out.display()))
        .output();
    let why = match made {
        Ok(o) if o.status.success() => return Some(out.join("embree_trace")),
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stderr).to_string();
            let line = text
                .lines()
                .find(|l| l.to_lowercase().contains("error") && !l.starts_with("make"))
                .or_else(|| text.lines().next())
                .unwrap_or("make failed")
                .trim()
                .to_string();
            line
        }
        Err(e) => format!("cannot run make: {e}"),
    };
    println!(
        "# Embree column skipped: tools/embree/embree_trace does not build (apt-get install libembree-dev): {why}"
    );
    None
}

/// One `embree_trace --serve` process: the scene built once at high
/// quality, then one pass per request.
struct Embree {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    build_s: f64,
    bytes: f64,
}

fn harness_error(what: impl std::fmt::Display) -> CliError {
    CliError::Internal(format!("embree_trace: {what}"))
}

impl Embree {
    /// Write the triangles (unindexed, in file order) and the rays where
    /// the harness reads them, start it and wait for its build.
    fn start(
        exe: &Path,
        dir: &Path,
        geometry: &Geometry,
        rays: &[Ray],
        threads: usize,
    ) -> Result<Self, CliError> {
        let bytes = encode_triangles(&geometry.file_order_triangles());
        let (mesh_path, rays_path) = (dir.join("mesh.tris"), dir.join("rays.bin"));
        std::fs::write(&mesh_path, bytes).map_err(harness_error)?;
        std::fs::write(&rays_path, encode_rays(rays)).map_err(harness_error)?;
        let mut child = Command::new(exe)
            .arg(&mesh_path)
            .arg(&rays_path)
            .args(["--serve", "--threads", &threads.to_string()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(harness_error)?;
        let stdin = child.stdin.take().unwrap();
        let stdout = BufReader::new(child.stdout.take().unwrap());
        let mut embree = Embree {
            child,
            stdin,
            stdout,
            build_s: 0.0,
            bytes: 0.0,
        };
        // "ready TRIANGLES BUILD_SECONDS EMBREE_BYTES PEAK_BYTES"
        let ready = embree.line()?;
        let f: Vec<&str> = ready.split_whitespace().collect();
        if f.len() != 5 || f[0] != "ready" {
            return Err(harness_error(format!("did not start: {ready:?}")));
        }
        embree.build_s = f[2].parse().map_err(harness_error)?;
        embree.bytes = f[3].parse().map_err(harness_error)?;
        Ok(embree)
    }

    fn line(&mut self) -> Result<String, CliError> {
        let mut line = String::new();
        self.stdout.read_line(&mut line).map_err(harness_error)?;
        Ok(line)
    }

    /// Seconds of one pass over rays `first..first + count`.
    fn pass(
        &mut self,
        first: usize,
        count: usize,
        question: Question,
        packet: bool,
        threads: usize,
    ) -> Result<f64, CliError> {
        let q = question.name();
        let mode = if packet { "packet" } else { "single" };
        writeln!(self.stdin, "{first} {count} {q} {mode} {threads}").map_err(harness_error)?;
        self.stdin.flush().map_err(harness_error)?;
        let reply = self.line()?;
        reply
            .split_whitespace()
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| harness_error(format!("unexpected reply {reply:?}")))
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[xs.len() / 2]
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
    // Every mesh found and of a format strata reads before the first is
    // measured: a typo in the last one should not cost the others' run.
    let mut meshes = meshes(&args)?;
    for mesh in &mut meshes {
        let given = mesh.clone();
        strata::scene::loaders::check_extension(&given).map_err(|e| InputError::file(&given, e))?;
        *mesh = std::fs::canonicalize(&given)
            .map_err(|e| InputError::file(&given, format!("cannot open: {e}")))?;
    }
    let all = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pools: Vec<(usize, rayon::ThreadPool)> = [1, all]
        .into_iter()
        .enumerate()
        .filter(|&(i, n)| i == 0 || n != 1)
        .map(|(_, n)| Ok((n, super::thread_pool(n)?)))
        .collect::<Result<_, CliError>>()?;
    let mut csv = String::from(
        "mesh,triangles,load_s,build_s,bytes_per_triangle,peak_load_build_bytes_per_triangle,peak_rss_mb,query,rays,mode,threads,mrays_per_s,embree_build_s,embree_bytes_per_triangle,embree_mrays_per_s,strata_over_embree\n",
    );
    let harness = if args.no_embree {
        None
    } else {
        embree_harness()
    };
    let work = std::env::temp_dir().join(format!("strata-bench-{}", std::process::id()));
    if harness.is_some() {
        std::fs::create_dir_all(&work).map_err(harness_error)?;
    }
    println!(
        "# strata walks rays with its {} kernel (STRATA_SIMD picks another); large allocations on {} pages (STRATA_HUGE_PAGES)",
        strata::accel::Kernel::selected().name(),
        if strata::accel::allocator::large_allocations_on_huge_pages() {
            "huge"
        } else {
            "small"
        }
    );
    println!(
        "{:<22} {:>9} {:>8} {:>7} {:>8} {:>9} {:>10} {:>6} {:>3} {:>9} {:>9} {:>6}",
        "mesh",
        "tris",
        "build s",
        "B/tri",
        "peak/tri",
        "query",
        "rays",
        "mode",
        "thr",
        "Mrays/s",
        "Embree",
        "ratio"
    );
    let result = bench_meshes(&args, &meshes, &pools, harness.as_deref(), &work, &mut csv);
    let _ = std::fs::remove_dir_all(&work);
    result?;
    strata::output::atomic::write_bytes_atomic(&args.csv, csv.as_bytes())
        .map_err(|e| InputError::file(&args.csv, format!("cannot write: {e}")))?;
    println!("-> {}", args.csv.display());
    Ok(())
}

fn bench_meshes(
    args: &BenchArgs,
    meshes: &[PathBuf],
    pools: &[(usize, rayon::ThreadPool)],
    harness: Option<&Path>,
    work: &Path,
    csv: &mut String,
) -> Result<(), CliError> {
    for mesh in meshes {
        let (scene, timings) = load_mesh_scene(mesh, args.bvh_quality)?;
        let rss = peak_rss_bytes().unwrap_or(0) as f64 / (1 << 20) as f64;
        let tris = scene.geometry.triangle_count() as usize;
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
            scene.geometry.bvh().stats(),
            if scene.geometry.bvh().prefetch {
                "on"
            } else {
                "off"
            },
            scene.geometry.traversal_bytes() as f64 / 1e6
        );
        let sets =
            [RayKind::Camera, RayKind::Random].map(|k| (k, rays(&scene, k, args.packets, 1)));
        let mut embree = match harness {
            Some(exe) => {
                let flat: Vec<Ray> = sets
                    .iter()
                    .flat_map(|(_, b)| b.iter().flatten().copied())
                    .collect();
                let e = Embree::start(exe, work, &scene.geometry, &flat, pools.last().unwrap().0)?;
                println!(
                    "# {name}: Embree (native, high quality, default mode) BVH build {:.3} s on {}, {:.1} B/tri",
                    e.build_s,
                    super::count(pools.last().unwrap().0, "thread", "threads"),
                    e.bytes / tris.max(1) as f64
                );
                Some(e)
            }
            None => None,
        };
        let mut first = 0;
        for (kind, packets) in &sets {
            let (kind, count) = (*kind, packets.len() * 8);
            for question in [Question::ClosestHit, Question::Occlusion] {
                for (threads, pool) in pools {
                    for packet in [false, true] {
                        // strata's passes and Embree's alternate.
                        let (mut times, mut theirs) = (vec![], vec![]);
                        for _ in 0..args.repeats.max(1) {
                            times.push(trace(&scene, packets, question, packet, pool).0);
                            if let Some(e) = embree.as_mut() {
                                theirs.push(e.pass(first, count, question, packet, *threads)?);
                            }
                        }
                        let t = median(times);
                        let mrays = count as f64 / t / 1e6;
                        let their =
                            (!theirs.is_empty()).then(|| count as f64 / median(theirs) / 1e6);
                        let (their_text, ratio_text) = their
                            .map_or(("-".into(), "-".into()), |e| {
                                (format!("{e:.2}"), format!("{:.2}", mrays / e))
                            });
                        let embree_csv = match (&embree, their) {
                            (Some(e), Some(m)) => format!(
                                "{:.4},{:.1},{m:.3},{:.4}",
                                e.build_s,
                                e.bytes / tris.max(1) as f64,
                                mrays / m
                            ),
                            _ => ",,,".into(),
                        };
                        let q = question.name();
                        let mode = if packet { "packet" } else { "single" };
                        println!(
                            "{name:<22} {tris:>9} {build:>8.3} {bpt:>7.1} {peak_text:>8} {q:>9} {:>10} {mode:>6} {threads:>3} {mrays:>9.2} {their_text:>9} {ratio_text:>6}",
                            kind.name()
                        );
                        *csv += &format!(
                            "{name},{tris},{load:.4},{build:.4},{bpt:.1},{},{rss:.0},{q},{},{mode},{threads},{mrays:.3},{embree_csv}\n",
                            peak.map_or(String::new(), |p| format!("{p:.1}")),
                            kind.name()
                        );
                    }
                }
            }
            first += count;
        }
    }
    Ok(())
}
