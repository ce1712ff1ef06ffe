//! `strata scaling`: speedup and efficiency against threads (and processes).

use super::CliError;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::experiment::scaling::{
    chart_panels, csv, rows, table, thread_counts, time_processes, time_threads, Mode, ScratchDir,
    SliceJob, Timing,
};
use strata::output::chart::write_svg;
use strata::render::Schedule;
use strata::scene::RenderOverrides;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScheduleChoice {
    Slices,
    Regions,
    Both,
}

#[derive(Debug, Args, Clone)]
pub struct ScalingArgs {
    /// Scene file (TOML), rendered with its own settings. Default: the
    /// built-in seed scene.
    pub scene: Option<PathBuf>,
    /// Largest thread count; the run measures 1, 2, 4, … and this. Default: all cores.
    #[arg(long)]
    pub max_threads: Option<usize>,
    /// Renders per configuration; the median is reported.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Which in-process scheduler(s) to measure: slices (work stealing over
    /// work items × sample slices), regions (one static band per thread,
    /// the classic baseline), or both.
    #[arg(long, value_enum, default_value = "both")]
    pub schedule: ScheduleChoice,
    /// Also run P single-threaded processes (`render --slice k/P`) and merge
    /// their parts, for each count P; timed from spawn to merged film.
    #[arg(long)]
    pub processes: bool,
    /// Override the scene's samples per pixel.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Override the scene's image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the scene's image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Where to write the table as CSV.
    #[arg(long, default_value = "scaling.csv")]
    pub csv: PathBuf,
    /// Where to write the SVG chart (speedup and efficiency).
    #[arg(long, default_value = "scaling.svg")]
    pub chart: PathBuf,
    /// Print only the table.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: ScalingArgs) -> Result<(), CliError> {
    super::writable(&args.csv, "--csv", &["csv"])?;
    super::writable(&args.chart, "--chart", &["svg"])?;
    let scene_name = super::render::scene_name(args.scene.as_deref());
    let overrides = RenderOverrides {
        spp: args.spp,
        width: args.width,
        height: args.height,
        ..RenderOverrides::default()
    };
    let (scene, _) =
        super::render::load_or_seed(args.scene.as_deref(), &[], &overrides, BuildQuality::Auto)?;
    let max = match args.max_threads {
        Some(0) => {
            return Err(
                InputError::new("<command line>", "--max-threads", "must be at least 1").into(),
            )
        }
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let counts = thread_counts(max);
    let mut modes = match args.schedule {
        ScheduleChoice::Slices => vec![Mode::Threads(Schedule::Slices)],
        ScheduleChoice::Regions => vec![Mode::Threads(Schedule::Regions)],
        ScheduleChoice::Both => vec![
            Mode::Threads(Schedule::Slices),
            Mode::Threads(Schedule::Regions),
        ],
    };
    let scratch = if args.processes {
        modes.push(Mode::Processes);
        Some(ScratchDir::new("scaling").map_err(|e| CliError::Internal(e.to_string()))?)
    } else {
        None
    };
    // Each child renders its slice with this executable's own `render`, on
    // one thread, with the same setting overrides as this run.
    let mut overrides = Vec::new();
    for (flag, v) in [
        ("--spp", args.spp),
        ("--width", args.width),
        ("--height", args.height),
    ] {
        if let Some(v) = v {
            overrides.extend([flag.to_string(), v.to_string()]);
        }
    }
    let exe = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("strata"));
    let spawn_slice = |job: &SliceJob| {
        Command::new(&exe)
            .arg("render")
            .args(&args.scene)
            .args(["--threads", "1", "--quiet", "--slice"])
            .arg(format!("{}/{}", job.slice.index, job.slice.count))
            .arg("-o")
            .arg(&job.part)
            .arg("--stats")
            .arg(&job.stats)
            .args(&overrides)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", exe.display()))
    };

    let s = &scene.settings;
    if !args.quiet {
        eprintln!(
            "{scene_name}: {}x{} {} spp; threads {:?}; {} repeats",
            s.width, s.height, s.spp, counts, args.repeats
        );
    }
    // Warm up caches and the allocator once, untimed.
    time_threads(&scene, Schedule::Slices, max);

    // Interleave repeats so that drifting machine load hits every configuration alike.
    let mut timings: Vec<Vec<Vec<Timing>>> = vec![vec![Vec::new(); counts.len()]; modes.len()];
    for rep in 0..args.repeats {
        for (m, mode) in modes.iter().enumerate() {
            for (i, &n) in counts.iter().enumerate() {
                let t = match mode {
                    Mode::Threads(schedule) => time_threads(&scene, *schedule, n),
                    Mode::Processes => {
                        let dir = scratch.as_ref().expect("scratch dir").path();
                        time_processes(n, dir, &spawn_slice)
                    }
                    .map_err(CliError::Internal)?,
                };
                if !args.quiet {
                    eprintln!(
                        "  {:<9} {:>11}, run {}/{}: {:.3} s",
                        mode.name(),
                        super::count(n, "thread", "threads"),
                        rep + 1,
                        args.repeats,
                        t.seconds
                    );
                }
                timings[m][i].push(t);
            }
        }
    }
    let all: Vec<_> = modes
        .iter()
        .zip(&timings)
        .flat_map(|(mode, t)| rows(*mode, &counts, t))
        .collect();
    print!("{}", table(&all));
    strata::output::atomic::write_bytes_atomic(&args.csv, csv(&all).as_bytes())
        .map_err(|e| InputError::file(&args.csv, format!("cannot write: {e}")))?;
    let short_name = args.scene.as_deref().and_then(|p| p.file_name());
    let title = format!(
        "{} ({}x{}, {} spp)",
        short_name.map_or("seed.toml".into(), |n| n.to_string_lossy()),
        s.width,
        s.height,
        s.spp
    );
    write_svg(&args.chart, &chart_panels(&title, &all), 520, 420)
        .map_err(|e| InputError::file(&args.chart, e))?;
    if !args.quiet {
        eprintln!("wrote {} and {}", args.csv.display(), args.chart.display());
    }
    Ok(())
}
