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
use crate::output::chart::{Panel, Series};
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
                cpu_speedup: cpu_base.zip(cpu_path_s).map(|(b, m)| b / m),
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

/// What each column of [`table`] means (`strata scaling --help`).
pub const TABLE_COLUMNS: [(&str, &str); 8] = [
    (
        "schedule",
        "slices (work stealing), regions (a band of rows per thread) or processes",
    ),
    ("threads", "threads, or single-threaded processes"),
    ("seconds", "median wall time of the render"),
    (
        "speedup",
        "the same schedule's 1-thread (or 1-process) time over this one",
    ),
    (
        "efficiency",
        "speedup over the thread count: 100% is perfect",
    ),
    ("Mrays/s", "rays traced per second of wall time"),
    (
        "cpu-path",
        "CPU seconds along the critical path (Linux): the wall time with a core to each thread",
    ),
    (
        "cpu-speedup",
        "the 1-thread CPU time over cpu-path: the speedup load balance allows",
    ),
];

/// What each column of [`prediction_table`] means, printed under it and
/// by `strata scaling --help`.
pub const PREDICTION_COLUMNS: [(&str, &str); 10] = [
    ("threads", "simulated threads (or processes)"),
    (
        "slices, regions, processes",
        "predicted speedup of each schedule over one thread (process)",
    ),
    (
        "end-to-end",
        "predicted speedup of the whole run, load to output, under slices",
    ),
    (
        "imbalance",
        "under slices, the share of the threads' time in passes spent waiting",
    ),
    (
        "serial",
        "the share of the whole run that load, build, setup and output take",
    ),
    ("measured", "the measured slices speedup at this count"),
    ("error", "after measured: predicted / measured - 1"),
    (
        "item-cost",
        "the mean work item's time at this count over its time on one thread (measured);",
    ),
    (
        "",
        "above 1, items ran slower with more threads busy, which the model leaves out",
    ),
    (
        "adjusted, error",
        "the prediction over item-cost, and its error: what is left is the schedule's model",
    ),
];

/// The prediction table `strata scaling --predict` prints.
pub fn prediction_table(predictions: &[PredictionRow]) -> String {
    let mut s = format!(
        "{:>7} {:>8} {:>8} {:>9} {:>10} {:>9} {:>7} {:>8} {:>7} {:>9} {:>8} {:>7}\n",
        "threads",
        "slices",
        "regions",
        "processes",
        "end-to-end",
        "imbalance",
        "serial",
        "measured",
        "error",
        "item-cost",
        "adjusted",
        "error"
    );
    let x = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}x"));
    let pct = |v: Option<f64>| v.map_or("-".into(), |e| format!("{:+.1}%", 100.0 * e));
    for p in predictions {
        s += &format!(
            "{:>7} {:>7.2}x {:>7.2}x {:>9} {:>9.2}x {:>8.1}% {:>6.1}% {:>8} {:>7} {:>9} {:>8} {:>7}\n",
            p.threads,
            p.slices,
            p.regions,
            x(p.processes),
            p.end_to_end,
            100.0 * p.imbalance,
            100.0 * p.serial_share,
            x(p.measured),
            pct(p.error),
            x(p.item_slowdown),
            x(p.adjusted),
            pct(p.adjusted_error),
        );
    }
    s
}

/// The chart `strata scaling` draws: speedup and efficiency against the
/// measured thread counts, each with the ideal as a reference line, a line
/// per schedule from wall time and, where measured, one from the CPU
/// critical path. Predictions (`--predict`, rows whose mode ends in
/// `(predicted)`) are the dashed extensions of the schedules they
/// predict: over the measured counts in those two panels, so that the
/// measured points keep their scale, and past them in a third panel of
/// speedup, log-log, out to the largest count predicted.
pub fn chart_panels(title: &str, rows: &[ScalingRow]) -> Vec<Panel> {
    const PREDICTED: &str = " (predicted)";
    let (predicted, measured): (Vec<&ScalingRow>, Vec<&ScalingRow>) =
        rows.iter().partition(|r| r.mode.ends_with(PREDICTED));
    let modes = |rows: &[&ScalingRow]| {
        let mut modes: Vec<String> = Vec::new();
        for r in rows {
            if !modes.contains(&r.mode) {
                modes.push(r.mode.clone());
            }
        }
        modes
    };
    let counts = |rows: &[&ScalingRow]| {
        let mut counts: Vec<usize> = rows.iter().map(|r| r.threads).collect();
        counts.sort_unstable();
        counts.dedup();
        counts
    };
    let measured_counts = counts(&measured);
    let most = measured_counts.last().copied().unwrap_or(0);
    // The ideal at every count drawn, so that a line on it is seen to be.
    let ideal = |counts: &[usize], value: &dyn Fn(f64) -> f64| {
        let points = counts.iter().map(|&t| (t as f64, value(t as f64)));
        Series::reference("ideal", points.collect())
    };
    let points = |mode: &str,
                  within: &dyn Fn(usize) -> bool,
                  value: &dyn Fn(&ScalingRow, f64) -> f64,
                  pick: &dyn Fn(&ScalingRow) -> Option<f64>| {
        rows.iter()
            .filter(|r| r.mode == mode && within(r.threads))
            .filter_map(|r| Some((r.threads as f64, value(r, pick(r)?))))
            .collect::<Vec<_>>()
    };
    // A prediction extends the wall-time line of the schedule it
    // predicts, where that was measured.
    let wall = |mode: &str| format!("{mode} (wall)");
    let extended = |mode: &str| {
        let of = wall(mode.trim_end_matches(PREDICTED));
        measured.iter().any(|r| wall(&r.mode) == of).then_some(of)
    };
    let speedup = |r: &ScalingRow| Some(r.speedup);
    let lines =
        |within: &dyn Fn(usize) -> bool, value: &dyn Fn(&ScalingRow, f64) -> f64, cpu: bool| {
            let mut series = Vec::new();
            for mode in modes(&measured) {
                series.push(Series::new(
                    wall(&mode),
                    points(&mode, within, value, &speedup),
                ));
                let path = points(&mode, within, value, &|r| r.cpu_speedup);
                if cpu && !path.is_empty() {
                    series.push(Series::new(format!("{mode} (CPU critical path)"), path));
                }
            }
            for mode in modes(&predicted) {
                let pts = points(&mode, within, value, &speedup);
                if !pts.is_empty() {
                    series.push(Series::extending(
                        mode.clone(),
                        extended(&mode).as_deref(),
                        pts,
                    ));
                }
            }
            series
        };
    let panel = |title: String, y_label: &str, counts: &[usize], log_y: bool, series| Panel {
        title,
        x_label: "threads (or processes)".into(),
        y_label: y_label.into(),
        // Many counts: doublings spaced alike.
        log_x: counts.last().is_some_and(|&t| t > 16),
        log_y,
        integer_x: true,
        series,
    };
    let measured_only = |t: usize| t <= most;
    let mut speedups = vec![ideal(&measured_counts, &|t| t)];
    speedups.extend(lines(&measured_only, &|_, s| s, true));
    let mut efficiency = vec![ideal(&measured_counts, &|_| 100.0)];
    efficiency.extend(lines(
        &measured_only,
        &|r, s| 100.0 * s / r.threads as f64,
        true,
    ));
    let mut panels = vec![
        panel(
            format!("speedup: {title}"),
            "speedup over 1",
            &measured_counts,
            false,
            speedups,
        ),
        panel(
            "efficiency".into(),
            "efficiency (%)",
            &measured_counts,
            false,
            efficiency,
        ),
    ];
    let all_counts = counts(&rows.iter().collect::<Vec<_>>());
    if all_counts.last().is_some_and(|&t| t > most) {
        let mut past = vec![ideal(&all_counts, &|t| t)];
        // The measured lines as they are, each prediction from the
        // largest measured count on.
        for mode in modes(&measured) {
            past.push(Series::new(
                wall(&mode),
                points(&mode, &|_| true, &|_, s| s, &speedup),
            ));
        }
        for mode in modes(&predicted) {
            let pts = points(&mode, &|t| t >= most, &|_, s| s, &speedup);
            past.push(Series::extending(
                mode.clone(),
                extended(&mode).as_deref(),
                pts,
            ));
        }
        let mut p = panel(
            format!("predicted past {most} threads"),
            "speedup over 1",
            &all_counts,
            true,
            past,
        );
        p.log_x = true;
        panels.push(p);
    }
    panels
}

/// The table `strata scaling` prints.
pub fn table(rows: &[ScalingRow]) -> String {
    let mut s = format!(
        "{:<10} {:>7} {:>9} {:>8} {:>10} {:>8} {:>12} {:>11}\n",
        "schedule",
        "threads",
        "seconds",
        "speedup",
        "efficiency",
        "Mrays/s",
        "cpu-path",
        "cpu-speedup"
    );
    for r in rows {
        let path = r.cpu_path_s.map_or("-".into(), |x| format!("{x:.3}"));
        let cpu = r.cpu_speedup.map_or("-".into(), |x| format!("{x:.2}x"));
        s += &format!(
            "{:<10} {:>7} {:>9.3} {:>7.2}x {:>9.1}% {:>8.2} {:>12} {:>11}\n",
            r.mode,
            r.threads,
            r.seconds,
            r.speedup,
            100.0 * r.efficiency,
            r.mrays_per_s,
            path,
            cpu
        );
    }
    s
}

/// The CSV `strata scaling` writes: one line per (schedule, threads).
pub fn csv(rows: &[ScalingRow]) -> String {
    let mut s = String::from(
        "schedule,threads,seconds,speedup,efficiency,mrays_per_s,cpu_path_s,cpu_speedup,runs\n",
    );
    let opt = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6}"));
    for r in rows {
        let runs: Vec<String> = r.runs.iter().map(|x| format!("{x:.6}")).collect();
        s += &format!(
            "{},{},{:.6},{:.4},{:.4},{:.4},{},{},{}\n",
            r.mode,
            r.threads,
            r.seconds,
            r.speedup,
            r.efficiency,
            r.mrays_per_s,
            opt(r.cpu_path_s),
            opt(r.cpu_speedup),
            runs.join(" ")
        );
    }
    s
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
    use crate::output::chart::{legend_text, same_as};

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
    }

    #[test]
    fn the_chart_names_schedules_that_scale_alike() {
        let t = |s: f64| Timing {
            seconds: s,
            rays: 1000,
            cpu: None,
        };
        let timings = [vec![t(4.0)], vec![t(2.5)], vec![t(1.6)]];
        let mut r = rows(Mode::Threads(Schedule::Slices), &[1, 2, 4], &timings);
        r.extend(rows(Mode::Threads(Schedule::Regions), &[1, 2, 4], &timings));
        let panels = chart_panels("t", &r);
        for p in &panels {
            assert!(p.integer_x && p.series[0].reference);
            let ideal: Vec<f64> = p.series[0].points.iter().map(|q| q.0).collect();
            assert_eq!(ideal, [1.0, 2.0, 4.0], "the ideal at every count");
            let same = same_as(p);
            assert_eq!(same, [None, None, Some(1)], "{}", p.title);
            assert_eq!(
                legend_text(p, 2, &same),
                "regions (wall) (same as slices (wall))"
            );
        }
    }

    /// Issue 62: predictions out to 64 threads swamped the measured 1 and
    /// 2. The measured panels keep the measured counts' scale, the
    /// prediction in them dashed; a third panel carries each prediction
    /// on past the largest measured count, as the dashed extension of the
    /// line it predicts.
    #[test]
    fn predictions_extend_the_measured_lines_without_swamping_them() {
        let t = |s: f64| Timing {
            seconds: s,
            rays: 1000,
            cpu: None,
        };
        let mut r = rows(
            Mode::Threads(Schedule::Slices),
            &[1, 2],
            &[vec![t(2.0)], vec![t(1.1)]],
        );
        let predicted = |mode: &str, threads: usize| ScalingRow {
            mode: format!("{mode} (predicted)"),
            threads,
            seconds: f64::NAN,
            speedup: threads as f64 * 0.9,
            efficiency: 0.9,
            mrays_per_s: f64::NAN,
            cpu_path_s: None,
            cpu_speedup: None,
            runs: Vec::new(),
        };
        for mode in ["slices", "slices end to end"] {
            r.extend(thread_counts(64).into_iter().map(|n| predicted(mode, n)));
        }
        let panels = chart_panels("t", &r);
        assert_eq!(panels.len(), 3);
        for p in &panels[..2] {
            let xs = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0));
            assert!(
                xs.fold(0.0, f64::max) <= 2.0,
                "{}: past the measured",
                p.title
            );
            let ext = p
                .series
                .iter()
                .find(|s| s.label == "slices (predicted)")
                .unwrap();
            assert_eq!(ext.extends.as_deref(), Some("slices (wall)"));
        }
        let past = &panels[2];
        assert!(past.log_x && past.log_y, "doublings to 64");
        let of = |label: &str| past.series.iter().find(|s| s.label == label).unwrap();
        let measured: Vec<f64> = of("slices (wall)").points.iter().map(|q| q.0).collect();
        assert_eq!(measured, [1.0, 2.0]);
        let predicted: Vec<f64> = of("slices (predicted)")
            .points
            .iter()
            .map(|q| q.0)
            .collect();
        assert_eq!(
            predicted,
            [2.0, 4.0, 8.0, 16.0, 32.0, 64.0],
            "from the last measured on"
        );
        let end_to_end = of("slices end to end (predicted)");
        assert!(end_to_end.extension && end_to_end.extends.is_none());
        // Drawn: the prediction in the colour of what it extends, dashed.
        let styles = crate::output::chart::styles(&panels);
        let style = |l: &str| styles.iter().find(|(x, _)| x == l).unwrap().1;
        assert_eq!(
            style("slices (predicted)").colour,
            style("slices (wall)").colour
        );
        assert!(
            style("slices (predicted)").dash.is_some() && style("slices (wall)").dash.is_none()
        );
        // Without predictions past what was measured, two panels.
        assert_eq!(chart_panels("t", &r[..2]).len(), 2);
    }

    /// Issue 62: every column the tables print is explained (in `--help`
    /// and, for the prediction, under the table).
    #[test]
    fn every_column_of_the_tables_is_explained() {
        let names = |columns: &[(&str, &str)]| -> Vec<String> {
            let names = columns.iter().flat_map(|(n, _)| n.split(", "));
            names.map(str::to_string).collect()
        };
        let r = rows(
            Mode::Threads(Schedule::Slices),
            &[1],
            &[vec![Timing {
                seconds: 1.0,
                rays: 1,
                cpu: None,
            }]],
        );
        for (header, key) in [
            (table(&r), names(&TABLE_COLUMNS)),
            (prediction_table(&[]), names(&PREDICTION_COLUMNS)),
        ] {
            let header = header.lines().next().unwrap().to_string();
            for column in header.split_whitespace() {
                assert!(key.iter().any(|k| k == column), "{column} unexplained");
            }
        }
        let key = crate::experiment::column_key(&PREDICTION_COLUMNS);
        let line = key
            .lines()
            .find(|l| l.trim_start().starts_with("item-cost"));
        assert!(
            line.is_some_and(|l| l.ends_with("on one thread (measured);")),
            "{key}"
        );
    }
}
