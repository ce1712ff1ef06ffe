//! SVG charts (plotters, SVG backend only).

use crate::render::scaling::ScalingRow;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Speedup and efficiency against threads, one colour per schedule: solid
/// lines from wall time, dashed lines from CPU time along the critical path
/// (what a core per thread would give, apart from the machine's other
/// load), and the ideal speedup in grey. Written atomically.
pub fn write_scaling_svg(
    path: &Path,
    title: &str,
    rows: &[ScalingRow],
) -> std::result::Result<(), String> {
    let mut svg = String::new();
    draw_scaling(&mut svg, title, rows).map_err(|e| e.to_string())?;
    super::atomic::write_bytes_atomic(path, svg.as_bytes())
        .map_err(|e| format!("cannot write: {e}"))
}

fn draw_scaling(svg: &mut String, title: &str, rows: &[ScalingRow]) -> Result<()> {
    let root = SVGBackend::with_string(svg, (960, 420)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));
    let max_threads = rows.iter().map(|r| r.threads).max().unwrap_or(1).max(2) as u32;
    let top = rows
        .iter()
        .flat_map(|r| [Some(r.speedup), r.cpu_speedup])
        .flatten()
        .filter(|s| s.is_finite())
        .fold(max_threads as f64, f64::max);
    panel(
        &panels[0],
        rows,
        "speedup",
        "speedup over 1",
        top * 1.05,
        Some(max_threads),
        |r| Some(r.speedup),
        |r| r.cpu_speedup,
    )?;
    panel(
        &panels[1],
        rows,
        "efficiency",
        "efficiency (%)",
        110.0,
        None,
        |r| Some(100.0 * r.efficiency),
        |r| r.cpu_speedup.map(|s| 100.0 * s / r.threads as f64),
    )?;
    root.present()?;
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn panel(
    area: &DrawingArea<SVGBackend, Shift>,
    rows: &[ScalingRow],
    caption: &str,
    y_desc: &str,
    y_max: f64,
    ideal_up_to: Option<u32>,
    wall: impl Fn(&ScalingRow) -> Option<f64>,
    cpu: impl Fn(&ScalingRow) -> Option<f64>,
) -> Result<()> {
    let max_threads = rows.iter().map(|r| r.threads).max().unwrap_or(1).max(2) as u32;
    let mut modes: Vec<&str> = Vec::new();
    for r in rows {
        if !modes.contains(&r.mode.as_str()) {
            modes.push(&r.mode);
        }
    }
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(1..max_threads, 0.0..y_max)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_labels(max_threads as usize)
        .x_desc("threads (or processes)")
        .y_desc(y_desc)
        .draw()?;
    if let Some(m) = ideal_up_to {
        chart
            .draw_series(LineSeries::new(
                [(1, 1.0), (m, m as f64)],
                RGBColor(160, 160, 160).stroke_width(1),
            ))?
            .label("ideal")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RGBColor(160, 160, 160)));
    }
    for (i, mode) in modes.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let series = |f: &dyn Fn(&ScalingRow) -> Option<f64>| -> Vec<(u32, f64)> {
            rows.iter()
                .filter(|r| r.mode == *mode)
                .filter_map(|r| Some((r.threads as u32, f(r)?)))
                .collect()
        };
        chart
            .draw_series(LineSeries::new(series(&wall), colour.stroke_width(2)))?
            .label(format!("{mode} (wall)"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
            });
        let cpu_points = series(&cpu);
        if !cpu_points.is_empty() {
            chart
                .draw_series(DashedLineSeries::new(
                    cpu_points,
                    6,
                    4,
                    colour.stroke_width(2),
                ))?
                .label(format!("{mode} (CPU critical path)"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 6, y)], colour.stroke_width(2))
                });
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()?;
    Ok(())
}
