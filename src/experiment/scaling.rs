//! Measuring how rendering scales with threads and processes (`strata scaling`).
//!
//! Each configuration is rendered `repeats` times and the median kept: on a
//! shared machine single timings are noisy, and ratios measured in one run,
//! interleaved, are what compare. Speedup is against the same schedule's
//! 1-thread (or 1-process) median; efficiency is speedup / threads.
//!
//! Wall time on a machine shared with other work measures the neighbours as
//! much as the scheduler. So in-process runs also record CPU time
//! (`system::cputime`) along the critical path: per pass, the busiest
//! worker's CPU time, plus the serial work between passes. That is the wall
//! time the render would take with a core per thread, and the 1-thread CPU
//! time over it (`cpu_speedup`) is the speedup that load balance and
//! parallel overheads allow. A static schedule that leaves a thread idle
//! shows up there whatever the machine's load; contention for shared
//! caches, memory bandwidth or a hyperthread's sibling still counts.
//!
//! In-process timings cover rendering only (the scene is loaded and the BVH
//! built once). Process timings are wall time from spawning P children (one
//! single-threaded slice k/P each, started by a closure the caller hands
//! in: `strata scaling` runs its own executable's `render --slice`) until
//! their parts are read back and merged, so they include each child's
//! start, scene load, BVH build and part write: the real cost of splitting a
//! render across processes.

use super::predict::{predict_processes, predict_threads, ProcessCosts, RunCosts, Split};
use crate::partial::merge::{merge_partials, MergeRules};
use crate::partial::read_partial;
use crate::render::timeline::Timeline;
use crate::render::{render, Film, RenderOptions, Schedule, SliceSpec};
use crate::scene::Scene;
use crate::system::cputime::{thread_cpu_ns, waited_children_cpu_seconds};
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::Arc;
use std::time::Instant;

mod report;
pub use report::{chart_panels, csv, prediction_table, table, PREDICTION_COLUMNS, TABLE_COLUMNS};

/// 1, 2, 4, … up to `max`, and `max` itself.
pub fn thread_counts(max: usize) -> Vec<usize> {
    let max = max.max(1);
    let mut v: Vec<usize> = std::iter::successors(Some(1usize), |&t| Some(t * 2))
        .take_while(|&t| t < max)
        .collect();
    v.push(max);
    v
}

/// The median (mean of the middle two for an even count).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// What a scaling run compares: one of the in-process schedules, or P processes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Threads(Schedule),
    Processes,
}

impl Mode {
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Threads(Schedule::Slices) => "slices",
            Mode::Threads(Schedule::Regions) => "regions",
            Mode::Processes => "processes",
        }
    }
}

/// One timed run.
#[derive(Debug, Clone, Copy)]
pub struct Timing {
    pub seconds: f64,
    pub rays: u64,
    /// CPU seconds of all threads together, and along the critical path
    /// (see [`CpuTimes`](crate::system::cputime::CpuTimes); for processes, the
    /// slowest child plus the merge, in 10 ms ticks). Linux only.
    pub cpu: Option<(f64, f64)>,
}

/// Render `scene` once in this process.
pub fn time_threads(scene: &Scene, schedule: Schedule, threads: usize) -> Timing {
    time_threads_with(scene, schedule, threads, None).0
}

/// [`time_threads`], recording its work items into `timeline`; also
/// returns the film.
pub fn time_threads_with(
    scene: &Scene,
    schedule: Schedule,
    threads: usize,
    timeline: Option<Arc<Timeline>>,
) -> (Timing, Film) {
    let opts = RenderOptions {
        threads,
        schedule,
        timeline,
        cpu_times: true,
        ..RenderOptions::default()
    };
    let outcome = render(scene, &opts, None, ());
    let timing = Timing {
        seconds: outcome.seconds,
        rays: outcome.counts.total(),
        cpu: outcome.cpu.map(|c| (c.total, c.critical_path)),
    };
    (timing, outcome.film)
}

/// One child render of [`time_processes`]: the slice it renders, on one
/// thread, and where it writes its part and its statistics JSON.
#[derive(Debug, Clone)]
pub struct SliceJob {
    pub slice: SliceSpec,
    pub part: PathBuf,
    pub stats: PathBuf,
}

/// Render with `processes` single-threaded children, one slice each, and
/// merge their parts. `spawn` starts the child for a job (the caller knows
/// how its renderer is invoked; piping the child's stderr makes a failure's
/// message part of the error). Parts and statistics go to `work_dir`.
pub fn time_processes(
    processes: usize,
    work_dir: &Path,
    spawn: &dyn Fn(&SliceJob) -> Result<Child, String>,
) -> Result<Timing, String> {
    std::fs::create_dir_all(work_dir).map_err(|e| format!("{}: {e}", work_dir.display()))?;
    let jobs: Vec<SliceJob> = (0..processes)
        .map(|k| SliceJob {
            slice: SliceSpec {
                index: k as u32,
                count: processes as u32,
            },
            part: work_dir.join(format!("part_{k}.strata")),
            stats: work_dir.join(format!("stats_{k}.json")),
        })
        .collect();
    let start = Instant::now();
    let children: Vec<Child> = jobs.iter().map(spawn).collect::<Result<_, _>>()?;
    // Each child's CPU time: the growth of this process's waited-for
    // children's time as each one is reaped.
    let mut failures = Vec::new();
    let mut child_cpu = Vec::new();
    let mut reaped = waited_children_cpu_seconds();
    for child in children {
        let out = child.wait_with_output().map_err(|e| e.to_string())?;
        if !out.status.success() {
            failures.push(String::from_utf8_lossy(&out.stderr).trim().to_string());
        }
        let now = waited_children_cpu_seconds();
        child_cpu.push(reaped.zip(now).map(|(a, b)| b - a));
        reaped = now;
    }
    if let Some(f) = failures.first() {
        return Err(format!("a child render failed: {f}"));
    }
    let merge_cpu_start = thread_cpu_ns();
    let parts = jobs
        .iter()
        .map(|job| {
            read_partial(&job.part)
                .map(|p| (job.part.clone(), p))
                .map_err(|e| format!("{}: {e}", job.part.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let rules = MergeRules {
        require_all: true,
        ..MergeRules::default()
    };
    merge_partials(parts, rules).map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    let merge_cpu = merge_cpu_start
        .zip(thread_cpu_ns())
        .map(|(a, b)| b.saturating_sub(a) as f64 * 1e-9);
    // Children run in parallel, then the merge: the critical path is the
    // slowest child plus the merge (reading the parts included).
    let cpu = child_cpu
        .into_iter()
        .collect::<Option<Vec<f64>>>()
        .zip(merge_cpu)
        .map(|(c, m)| {
            (
                c.iter().sum::<f64>() + m,
                c.iter().copied().fold(0.0, f64::max) + m,
            )
        });
    let mut rays = 0;
    for job in &jobs {
        let text = std::fs::read_to_string(&job.stats).map_err(|e| e.to_string())?;
        let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        rays += json["rays_total"].as_u64().unwrap_or(0);
    }
    Ok(Timing { seconds, rays, cpu })
}

/// One line of the scaling table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ScalingRow {
    pub mode: String,
    /// Threads, or processes of one thread each.
    pub threads: usize,
    /// Median wall time of the render.
    pub seconds: f64,
    pub speedup: f64,
    pub efficiency: f64,
    pub mrays_per_s: f64,
    /// Median CPU time along the critical path: the wall time if every
    /// thread (or process) had a core of its own (Linux).
    pub cpu_path_s: Option<f64>,
    /// The 1-thread run's CPU time over `cpu_path_s`: the speedup that
    /// load balance and parallel overheads allow, whatever else the machine
    /// is running.
    pub cpu_speedup: Option<f64>,
    /// Every repeat's time, for the CSV.
    pub runs: Vec<f64>,
}

/// Rows for one mode from its timings (`timings[i]` are the repeats at
/// `counts[i]`). Speedup is against the first count's median.
pub fn rows(mode: Mode, counts: &[usize], timings: &[Vec<Timing>]) -> Vec<ScalingRow> {
    let medians: Vec<f64> = timings
        .iter()
        .map(|t| median(&t.iter().map(|x| x.seconds).collect::<Vec<_>>()))
        .collect();
    let base =
        medians.first().copied().unwrap_or(f64::NAN) * counts.first().copied().unwrap_or(1) as f64;
    let cpu_median = |t: &Vec<Timing>, pick: fn((f64, f64)) -> f64| {
        let v: Option<Vec<f64>> = t.iter().map(|x| x.cpu.map(pick)).collect();
        v.map(|v| median(&v))
    };
    let cpu_base = timings.first().and_then(|t| cpu_median(t, |c| c.0));
    counts
        .iter()
        .zip(timings)
        .zip(&medians)
        .map(|((&threads, t), &seconds)| {
            let rays = t.first().map_or(0, |x| x.rays);
            let speedup = base / seconds;
            let cpu_path_s = cpu_median(t, |c| c.1);
            ScalingRow {
                mode: mode.name().to_string(),
                threads,
                seconds,
                speedup,
                efficiency: speedup / threads as f64,
                mrays_per_s: rays as f64 / seconds / 1e6,
                cpu_path_s,
                // A process's CPU time comes in clock ticks: a render
                // shorter than one reads 0, and 0/0 is no speedup.
                cpu_speedup: cpu_base
                    .zip(cpu_path_s)
                    .filter(|&(b, m)| b > 0.0 && m > 0.0)
                    .map(|(b, m)| b / m),
                runs: t.iter().map(|x| x.seconds).collect(),
            }
        })
        .collect()
}

/// One thread (or process) count of a prediction (`strata scaling --predict`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct PredictionRow {
    pub threads: usize,
    /// Predicted speedups of the in-process render over one thread.
    pub slices: f64,
    pub regions: f64,
    /// P processes against one, start to merged film (with `--processes`).
    pub processes: Option<f64>,
    /// The slices render with the load, build, setup and output around
    /// it: the whole run's speedup, which those serial phases bound (Amdahl).
    pub end_to_end: f64,
    /// Of the threads' time in passes under slices, the share left idle.
    pub imbalance: f64,
    /// Of the whole run at this count, the share of the serial phases.
    pub serial_share: f64,
    /// The measured slices speedup at this count, where it was measured,
    /// and the prediction's error against it (predicted / measured − 1).
    pub measured: Option<f64>,
    pub error: Option<f64>,
    /// Where measured: the mean work item's time at this count over its
    /// time on one thread. Above 1, each item ran slower with more threads
    /// busy (shared caches and memory bandwidth, lower turbo clocks), which
    /// the schedule's simulation leaves out.
    pub item_slowdown: Option<f64>,
    /// The simulated speedup over the measured item slowdown, and its
    /// error against the measured speedup: what remains is the model of the
    /// schedule itself.
    pub adjusted: Option<f64>,
    pub adjusted_error: Option<f64>,
}

/// Predict every count of `counts` from `costs` (one run's work items),
/// against the measured `rows` where they have the count, with the item
/// slowdown measured at each count in `slowdowns`; processes too with the
/// costs of their parts (`--processes`).
pub fn predict_rows(
    costs: &RunCosts,
    counts: &[usize],
    rows: &[ScalingRow],
    slowdowns: &[(usize, f64)],
    parts: Option<ProcessCosts>,
) -> Vec<PredictionRow> {
    let threads = |split, t| predict_threads(costs, split, t);
    let (slices_1, regions_1) = (threads(Split::Slices, 1), threads(Split::Regions, 1));
    let processes_1 = parts.map(|p| predict_processes(costs, 1, p).seconds);
    counts
        .iter()
        .map(|&t| {
            let slices = threads(Split::Slices, t);
            let measured = rows
                .iter()
                .find(|r| r.mode == Mode::Threads(Schedule::Slices).name() && r.threads == t)
                .map(|r| r.speedup);
            let predicted = slices_1.seconds / slices.seconds;
            let item_slowdown = slowdowns.iter().find(|s| s.0 == t).map(|s| s.1);
            let adjusted = item_slowdown.map(|k| predicted / k);
            PredictionRow {
                threads: t,
                slices: predicted,
                regions: regions_1.seconds / threads(Split::Regions, t).seconds,
                processes: processes_1
                    .zip(parts)
                    .map(|(one, p)| one / predict_processes(costs, t, p).seconds),
                end_to_end: slices_1.end_to_end_s / slices.end_to_end_s,
                imbalance: slices.imbalance,
                serial_share: costs.around_s() / slices.end_to_end_s,
                measured,
                error: measured.map(|m| predicted / m - 1.0),
                item_slowdown,
                adjusted,
                adjusted_error: measured.zip(adjusted).map(|(m, a)| a / m - 1.0),
            }
        })
        .collect()
}

/// The predictions as rows of the scaling table's CSV and chart, each
/// mode named `... (predicted)`.
pub fn predicted_scaling_rows(predictions: &[PredictionRow]) -> Vec<ScalingRow> {
    let row = |mode: &str, threads: usize, speedup: f64| ScalingRow {
        mode: format!("{mode} (predicted)"),
        threads,
        seconds: f64::NAN,
        speedup,
        efficiency: speedup / threads as f64,
        mrays_per_s: f64::NAN,
        cpu_path_s: None,
        cpu_speedup: None,
        runs: Vec::new(),
    };
    let mut out: Vec<ScalingRow> = Vec::new();
    out.extend(
        predictions
            .iter()
            .map(|p| row("slices", p.threads, p.slices)),
    );
    out.extend(
        predictions
            .iter()
            .map(|p| row("regions", p.threads, p.regions)),
    );
    out.extend(
        predictions
            .iter()
            .filter_map(|p| Some(row("processes", p.threads, p.processes?))),
    );
    out.extend(
        predictions
            .iter()
            .map(|p| row("slices end to end", p.threads, p.end_to_end)),
    );
    out
}

/// A scratch directory for process runs, removed on drop.
pub struct ScratchDir(pub PathBuf);

impl ScratchDir {
    pub fn new(tag: &str) -> std::io::Result<Self> {
        let dir = std::env::temp_dir().join(format!("strata-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        Ok(Self(dir))
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A timed render measures its workers' CPU time where the system
    /// reports a thread's (Linux): some, and the critical path within the
    /// total; a plain render measures none.
    #[test]
    fn timed_renders_measure_cpu_time_and_plain_ones_do_not() {
        let text = "[render]\nwidth = 32\nheight = 24\nspp = 4\n\
                    [[objects]]\nsphere = { center = [0, 0, -3], radius = 1 }\n";
        let (scene, _) = crate::scene::compile::load_edited_text(
            text,
            Path::new("timed.toml"),
            &[],
            &Default::default(),
            Default::default(),
        )
        .unwrap();
        let plain = crate::render::render(&scene, &RenderOptions::default(), None, ());
        assert!(plain.cpu.is_none());
        let timing = time_threads(&scene, Schedule::Slices, 2);
        if crate::system::cputime::thread_cpu_ns().is_some() {
            let (total, path) = timing.cpu.expect("CPU time measured");
            assert!(total > 0.0 && path > 0.0 && path <= total, "{total} {path}");
        }
    }

    #[test]
    fn thread_counts_double_up_to_the_maximum() {
        assert_eq!(thread_counts(1), vec![1]);
        assert_eq!(thread_counts(2), vec![1, 2]);
        assert_eq!(thread_counts(8), vec![1, 2, 4, 8]);
        assert_eq!(thread_counts(6), vec![1, 2, 4, 6]);
    }

    #[test]
    fn rows_compute_speedup_and_efficiency_from_medians() {
        let t = |s: f64| Timing {
            seconds: s,
            rays: 1_000_000,
            cpu: Some((s, s / 2.0)),
        };
        let r = rows(
            Mode::Threads(Schedule::Slices),
            &[1, 2],
            &[vec![t(2.0), t(9.0), t(1.9)], vec![t(1.0), t(1.1), t(0.5)]],
        );
        assert_eq!(r[0].seconds, 2.0);
        assert_eq!(r[1].seconds, 1.0);
        assert_eq!(r[1].speedup, 2.0);
        assert_eq!(r[1].efficiency, 1.0);
        assert_eq!(r[1].mrays_per_s, 1.0);
        // 1-thread CPU 2.0 s in total (median); critical path at two threads 0.5 s.
        assert_eq!(r[1].cpu_path_s, Some(0.5));
        assert_eq!(r[1].cpu_speedup, Some(4.0));
        assert!(csv(&r).lines().count() == 3);
        assert!(table(&r).contains("slices"));
        let panels = chart_panels("t", &r);
        assert_eq!(panels[0].series.len(), 3, "ideal, wall, CPU");
        assert!(panels[0].series[0].reference && panels.iter().all(|p| p.integer_x));
        assert_eq!(panels[1].series[0].points, vec![(1.0, 100.0), (2.0, 100.0)]);
        assert_eq!(panels[1].series[1].points, vec![(1.0, 100.0), (2.0, 100.0)]);
        // CPU times below the clock's tick read 0: no speedup, not NaN.
        let zero = |s: f64| Timing {
            seconds: s,
            rays: 1,
            cpu: Some((0.0, 0.0)),
        };
        let r = rows(
            Mode::Processes,
            &[1, 2],
            &[vec![zero(0.004)], vec![zero(0.005)]],
        );
        assert_eq!(r[1].cpu_speedup, None);
        assert!(
            !csv(&r).contains("NaN") && !table(&r).contains("NaN"),
            "{}",
            table(&r)
        );
    }
}
