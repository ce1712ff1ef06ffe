//! What `strata scaling` shows of its measurements: the tables it prints
//! and the key to their columns, the CSV it writes, and the chart.

use super::{PredictionRow, ScalingRow};
use crate::output::chart::{Panel, Series};

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

#[cfg(test)]
mod tests {
    use super::super::{rows, thread_counts, Mode, Timing};
    use super::*;
    use crate::output::chart::{legend_text, same_as};
    use crate::render::Schedule;

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
