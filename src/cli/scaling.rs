//! `strata scaling`: speedup and efficiency against threads (and processes).

use super::CliError;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::Instant;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::experiment::column_key;
use strata::experiment::predict::{ProcessCosts, RunCosts};
use strata::experiment::scaling::{
    chart_panels, csv, predict_rows, predicted_scaling_rows, prediction_table, rows, table,
    thread_counts, time_processes, time_threads, time_threads_with, Mode, ScratchDir, SliceJob,
    Timing, PREDICTION_COLUMNS, TABLE_COLUMNS,
};
use strata::output::chart::write_svg;
use strata::render::timeline::Timeline;
use strata::render::Schedule;
use strata::render::{Film, SliceSpec};
use strata::scene::RenderOverrides;
use strata::scene::{LoadTimings, Scene};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScheduleChoice {
    Slices,
    Regions,
    Both,
}

#[derive(Debug, Args, Clone)]
#[command(after_help = "Every column of the tables: strata scaling --help.")]
#[command(after_long_help = columns_help())]
pub struct ScalingArgs {
    /// Scene file (TOML), rendered with its own settings. Default: the
    /// built-in seed scene.
    pub scene: Option<PathBuf>,
    /// Largest thread count; the run measures 1, 2, 4, … and this. Default: all cores.
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=strata::system::budget::MAX_THREADS as u64))]
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
    /// Also predict the speedup at 1, 2, 4, … up to --predict-max threads
    /// (and processes) from the work items of the measured 1-thread run,
    /// drawn beside the measured speedup. See docs/scaling.md, "Past this
    /// machine's cores".
    #[arg(long)]
    pub predict: bool,
    /// Largest thread count --predict simulates.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub predict_max: u32,
    /// Print only the tables, without the progress and the key to the
    /// --predict table's columns.
    #[arg(short, long)]
    pub quiet: bool,
}

/// What `strata scaling --help` says under the flags: every column of
/// both tables.
fn columns_help() -> String {
    format!(
        "The table's columns:\n{}\nThe --predict table's columns (docs/scaling.md, \"Past this machine's cores\"):\n{}",
        column_key(&TABLE_COLUMNS),
        column_key(&PREDICTION_COLUMNS)
    )
}

pub fn run(args: ScalingArgs) -> Result<(), CliError> {
    super::writable(&args.csv, "--csv", &["csv"])?;
    super::writable(&args.chart, "--chart", &["svg"])?;
    let scene_name = super::render::scene_name(args.scene.as_deref());
    let (scene, load_timings) = super::render::load_or_seed(
        args.scene.as_deref(),
        &[],
        &overrides(&args),
        BuildQuality::Auto,
    )?;
    let max = args
        .max_threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
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
    // The slices runs keep their timelines (two clock reads per work
    // item), for the summary and for --predict.
    let mut recorded: Vec<Recorded> = Vec::new();
    for rep in 0..args.repeats {
        for (m, mode) in modes.iter().enumerate() {
            for (i, &n) in counts.iter().enumerate() {
                let record = *mode == Mode::Threads(Schedule::Slices);
                let t = match mode {
                    Mode::Threads(schedule) if record => {
                        let timeline = Arc::new(Timeline::new(Instant::now()));
                        let (t, film) =
                            time_threads_with(&scene, *schedule, n, Some(timeline.clone()));
                        recorded.push(Recorded {
                            threads: n,
                            seconds: t.seconds,
                            timeline,
                            // Only --predict's 1-thread run writes its image.
                            film: (n == 1 && args.predict).then_some(film),
                        });
                        t
                    }
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
    let mut all: Vec<_> = modes
        .iter()
        .zip(&timings)
        .flat_map(|(mode, t)| rows(*mode, &counts, t))
        .collect();
    print!("{}", table(&all));
    if args.predict {
        let predictions = predict(&scene, &load_timings, &recorded, &all, &counts, &args)?;
        all.extend(predicted_scaling_rows(&predictions));
    }
    let most = counts.last().copied().unwrap_or(1);
    if let Some(summary) = median_run(&recorded, most).and_then(|r| r.timeline.summary()) {
        if !args.quiet {
            println!("\nthe median {most}-thread slices run at a glance:");
            print!("{}", summary.text());
        }
    }
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

/// One slices run with its timeline (`--predict`).
struct Recorded {
    threads: usize,
    seconds: f64,
    timeline: Arc<Timeline>,
    film: Option<Film>,
}

/// The run of `recorded` at `threads` with the median time.
fn median_run(recorded: &[Recorded], threads: usize) -> Option<&Recorded> {
    let mut runs: Vec<&Recorded> = recorded.iter().filter(|r| r.threads == threads).collect();
    runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    runs.get(runs.len() / 2).copied()
}

/// `--predict`: the costs of the median 1-thread run, the serial phases
/// around it (the scene's load and build as this run timed them, an image
/// and with `--processes` a part written and read back, timed here), every
/// count up to `--predict-max` simulated, printed beside what was measured.
fn predict(
    scene: &Scene,
    load: &LoadTimings,
    recorded: &[Recorded],
    measured: &[strata::experiment::scaling::ScalingRow],
    counts: &[usize],
    args: &ScalingArgs,
) -> Result<Vec<strata::experiment::scaling::PredictionRow>, CliError> {
    let internal = |e: String| CliError::Internal(e);
    let base = median_run(recorded, 1).ok_or_else(|| internal("no 1-thread run".into()))?;
    let s = &scene.settings;
    let mut costs = RunCosts::from_timeline(&base.timeline, s.width * s.height);
    costs.load_s = load.load.as_secs_f64();
    costs.build_s = load.bvh_build.as_secs_f64();
    let scratch = ScratchDir::new("predict").map_err(|e| internal(e.to_string()))?;
    let timed = |work: &mut dyn FnMut() -> Result<(), String>| -> Result<f64, CliError> {
        let start = Instant::now();
        work().map_err(internal)?;
        Ok(start.elapsed().as_secs_f64())
    };
    let png = scratch.path().join("image.png");
    let film = base
        .film
        .as_ref()
        .ok_or_else(|| internal("no 1-thread film".into()))?;
    let pixels = film.to_rgb();
    costs.output_s =
        timed(&mut || strata::output::image::write_image(&png, &pixels, s.width, s.height))?;
    let parts = match args.processes {
        false => None,
        true => {
            use strata::partial::format::{read_partial, write_partial, PartialHeader};
            let part = scratch.path().join("part.strata");
            let spp = s.spp;
            let write_s = timed(&mut || {
                let header = PartialHeader::for_scene(scene, SliceSpec::WHOLE, 0..spp);
                write_partial(&part, &header, film).map_err(|e| e.to_string())
            })?;
            let read_s = timed(&mut || read_partial(&part).map(|_| ()).map_err(|e| e.to_string()))?;
            // A child loads and builds on its one thread.
            let one = super::thread_pool(1)?;
            let (_, child) = one.install(|| {
                super::render::load_or_seed(
                    args.scene.as_deref(),
                    &[],
                    &overrides(args),
                    BuildQuality::Auto,
                )
            })?;
            let start_s = timed(&mut || {
                let exe = std::env::current_exe().map_err(|e| e.to_string())?;
                let status = Command::new(exe)
                    .arg("--version")
                    .stdout(Stdio::null())
                    .status();
                status.map(|_| ()).map_err(|e| e.to_string())
            })?;
            Some(ProcessCosts {
                start_s,
                load_s: child.load.as_secs_f64(),
                build_s: child.bvh_build.as_secs_f64(),
                write_s,
                read_s,
            })
        }
    };
    let mut predicted_counts = thread_counts(args.predict_max as usize);
    predicted_counts.extend_from_slice(counts);
    predicted_counts.sort_unstable();
    predicted_counts.dedup();
    // Each measured count's mean work item against the 1-thread run's.
    let mean_item = |r: &Recorded| r.timeline.summary().map(|s| s.mean_item_s);
    let slowdowns: Vec<(usize, f64)> = counts
        .iter()
        .filter_map(|&t| Some((t, mean_item(median_run(recorded, t)?)? / mean_item(base)?)))
        .collect();
    let predictions = predict_rows(&costs, &predicted_counts, measured, &slowdowns, parts);
    if !args.quiet {
        let items: usize = costs.passes.iter().map(|p| p.items.len()).sum();
        println!(
            "\npredicted from the median 1-thread run's {items} work items ({:.3} s of work; load {:.3} s, build {:.3} s, setup {:.3} s, output {:.3} s):",
            costs.work_s(),
            costs.load_s,
            costs.build_s,
            costs.setup_s,
            costs.output_s
        );
    }
    print!("{}", prediction_table(&predictions));
    if !args.quiet {
        print!("\n{}", column_key(&PREDICTION_COLUMNS));
    }
    Ok(predictions)
}

/// The scene's settings as the command line overrides them.
fn overrides(args: &ScalingArgs) -> RenderOverrides {
    RenderOverrides {
        spp: args.spp,
        width: args.width,
        height: args.height,
        ..RenderOverrides::default()
    }
}
