//! Subcommands. Each file holds one command's arguments and its run function.

pub mod bench;
pub mod converge;
pub mod cpu;
pub mod flags;
pub mod merge;
pub mod progress;
pub mod rays;
pub mod render;
pub mod scaling;
pub mod trace;

use clap::{Parser, Subcommand};
use strata::accel::allocator::HugePages;
use strata::accel::Kernel;
use strata::error::InputError;

/// strata: a Monte Carlo distribution ray tracer.
///
/// With no command, renders the built-in seed scene to render.png. Every
/// command has its own --help: `strata render --help`.
#[derive(Debug, Parser)]
#[command(
    name = "strata",
    version = strata::VERSION,
    about,
    long_about = None,
    after_help = "With no command, strata renders the built-in seed scene to render.png.\nEvery command has its own help: strata render --help. Documentation: docs/cli.md.\nSTRATA_SIMD=auto|avx2|avx512 picks the instruction set rays are walked in (default auto: the build's own; avx512, where the CPU has it, for measuring).\nSTRATA_HUGE_PAGES=auto|on|off puts large allocations on huge pages (default auto: where the kernel has handed no memory back to a host, so that they are cheap to write first)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

// Parsed once per run, then moved into its command: the size of the
// largest arguments costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene file, or a model file as it comes, to PNG or EXR (or
    /// to a .strata part with --slice).
    Render(render::RenderArgs),
    /// Combine the .strata parts of a sliced render into the image one process would make.
    Merge(merge::MergeArgs),
    /// Measure speedup and efficiency against threads (and processes); writes CSV and SVG.
    Scaling(scaling::ScalingArgs),
    /// Error against time: RMSE per sampling method at spp 1, 2, 4, …; CSV and SVG chart.
    Converge(converge::ConvergeArgs),
    /// Write a ray set for testing intersection against a mesh (RAYS.bin).
    Rays(rays::RaysArgs),
    /// Trace a ray file against a mesh with the renderer's own code (HITS.bin).
    Trace(trace::TraceArgs),
    /// Ray throughput suite: build time, bytes/triangle, Mrays/s single vs packet; CSV.
    Bench(bench::BenchArgs),
}

pub enum CliError {
    /// Bad input: exit code 2.
    Input(InputError),
    /// A bug or an environment failure: exit code 1.
    Internal(String),
}

impl From<InputError> for CliError {
    fn from(e: InputError) -> Self {
        CliError::Input(e)
    }
}

/// Check, before any work, that `path` (given with `flag`) can be written
/// and has one of `extensions`.
pub fn writable(path: &std::path::Path, flag: &str, extensions: &[&str]) -> Result<(), CliError> {
    strata::output::atomic::check_target(path, extensions)
        .map_err(|e| InputError::new("<command line>", flag, e).into())
}

/// Whether two paths name one file, whether or not it exists yet: each
/// resolved through its folder (links and `..` followed), so that
/// `out.json` and `./out.json` are the same.
pub fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    use std::path::{Path, PathBuf};
    let resolve = |p: &Path| -> Option<PathBuf> {
        if let Ok(path) = std::fs::canonicalize(p) {
            return Some(path);
        }
        let folder = match p.parent() {
            Some(f) if !f.as_os_str().is_empty() => f,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(folder).ok()?.join(p.file_name()?))
    };
    match (resolve(a), resolve(b)) {
        (Some(a), Some(b)) => a == b,
        _ => a == b,
    }
}

/// The first of `files` (each a flag and the path it names, if given)
/// that names a file an earlier one names too: the second would overwrite
/// the first's output (or its input) without a word.
pub fn distinct_files(files: &[(&str, Option<&std::path::Path>)]) -> Result<(), CliError> {
    let given: Vec<(&str, &std::path::Path)> =
        files.iter().filter_map(|&(f, p)| Some((f, p?))).collect();
    for (i, &(flag, path)) in given.iter().enumerate() {
        if let Some((earlier, _)) = given[..i].iter().find(|(_, p)| same_file(p, path)) {
            let why = format!(
                "'{}' is also the {earlier} file: give each its own",
                path.display()
            );
            return Err(InputError::new("<command line>", flag, why).into());
        }
    }
    Ok(())
}

/// `--threads N`: 0 (one thread per core) to
/// [`strata::system::budget::MAX_THREADS`]. clap calls it, so a count past
/// that is the usual one-line usage error (exit 2) before anything starts.
pub fn parse_threads(text: &str) -> Result<usize, String> {
    let max = strata::system::budget::MAX_THREADS;
    match text.parse::<usize>() {
        Ok(n) if n <= max => Ok(n),
        Ok(n) => Err(format!(
            "{n} threads is more than any machine has cores: at most {max} (0 for one per core)"
        )),
        Err(_) => Err(format!(
            "expected a whole number of threads from 0 (one per core) to {max}"
        )),
    }
}

/// A pool of `threads` threads (0: one per core).
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, CliError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::Internal(format!("cannot start threads: {e}")))
}

/// Each of `warnings` (the mesh loaders', a render's, a merge's) as one
/// `warning:` line on stderr: the one place the CLI words a warning.
pub fn warn<W: std::fmt::Display>(warnings: impl IntoIterator<Item = W>) {
    for warning in warnings {
        eprintln!("warning: {warning}");
    }
}

/// "1 part", "2 parts".
pub fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

pub fn run(cli: Cli) -> Result<(), CliError> {
    choose_kernel()?;
    choose_huge_pages()?;
    match cli.command {
        Some(Command::Render(args)) => render::run(args),
        Some(Command::Merge(args)) => merge::run(args),
        Some(Command::Scaling(args)) => scaling::run(args),
        Some(Command::Converge(args)) => converge::run(args),
        Some(Command::Rays(args)) => rays::run(args),
        Some(Command::Trace(args)) => trace::run(args),
        Some(Command::Bench(args)) => bench::run(args),
        None => render::run(render::RenderArgs::default()),
    }
}

/// `STRATA_HUGE_PAGES` (auto, on or off): whether large allocations go
/// on huge pages; unset, `auto` (where they are cheap to write first:
/// `strata::accel::allocator`).
fn choose_huge_pages() -> Result<(), CliError> {
    from_env("STRATA_HUGE_PAGES", HugePages::parse)?
        .unwrap_or_default()
        .apply();
    Ok(())
}

/// `STRATA_SIMD` (auto, avx2 or avx512): the instruction set the hot
/// walks run in, for measuring one against the other; unset, the build's
/// own (`strata::accel::Kernel::detect`).
fn choose_kernel() -> Result<(), CliError> {
    if let Some(kernel) = from_env("STRATA_SIMD", Kernel::parse)? {
        kernel.set();
    }
    Ok(())
}

/// Environment variable `var` read by `parse` (trimmed); `None` where it
/// is unset. A value `parse` refuses is an error naming the variable.
fn from_env<T>(
    var: &str,
    parse: impl FnOnce(&str) -> Result<T, String>,
) -> Result<Option<T>, CliError> {
    let Some(value) = std::env::var_os(var) else {
        return Ok(None);
    };
    let parsed = parse(value.to_string_lossy().trim())
        .map_err(|e| InputError::new("<environment>", var, e))?;
    Ok(Some(parsed))
}
