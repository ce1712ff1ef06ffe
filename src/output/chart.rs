//! SVG charts (plotters, SVG backend only).

use crate::render::scaling::ScalingRow;
use plotters::prelude::*;
use std::path::Path;

const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Speedup and efficiency against threads, one line per schedule, with the
/// ideal (linear) speedup dashed. Written atomically.
pub fn write_scaling_svg(path: &Path, title: &str, rows: &[ScalingRow]) -> Result<(), String> {
    let mut svg = String::new();
    draw_scaling(&mut svg, title, rows).map_err(|e| e.to_string())?;
    super::atomic::write_bytes_atomic(path, svg.as_bytes())
        .map_err(|e| format!("cannot write: {e}"))
}

fn draw_scaling(
    svg: &mut String,
    title: &str,
    rows: &[ScalingRow],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut modes: Vec<&str> = Vec::new();
    for r in rows {
        if !modes.contains(&r.mode.as_str()) {
            modes.push(&r.mode);
        }
    }
    let max_threads = rows.iter().map(|r| r.threads).max().unwrap_or(1).max(2) as u32;
    let max_speedup = rows
        .iter()
        .map(|r| r.speedup)
        .filter(|s| s.is_finite())
        .fold(max_threads as f64, f64::max);

    let root = SVGBackend::with_string(svg, (960, 420)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));

    // Speedup.
    let mut chart = ChartBuilder::on(&panels[0])
        .caption("speedup", ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(1..max_threads, 0.0..max_speedup * 1.05)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_labels(max_threads as usize)
        .x_desc("threads (or processes)")
        .y_desc("speedup over 1")
        .draw()?;
    chart
        .draw_series(DashedLineSeries::new(
            [(1, 1.0), (max_threads, max_threads as f64)],
            6,
            4,
            BLACK.mix(0.5).stroke_width(1),
        ))?
        .label("ideal")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
    for (i, mode) in modes.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let points: Vec<(u32, f64)> = rows
            .iter()
            .filter(|r| r.mode == *mode)
            .map(|r| (r.threads as u32, r.speedup))
            .collect();
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
            .label(*mode)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()?;

    // Efficiency.
    let mut chart = ChartBuilder::on(&panels[1])
        .caption("efficiency", ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(1..max_threads, 0.0..110.0)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_labels(max_threads as usize)
        .x_desc("threads (or processes)")
        .y_desc("efficiency (%)")
        .draw()?;
    for (i, mode) in modes.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let points: Vec<(u32, f64)> = rows
            .iter()
            .filter(|r| r.mode == *mode)
            .map(|r| (r.threads as u32, 100.0 * r.efficiency))
            .collect();
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
            .label(*mode)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()?;
    root.present()?;
    Ok(())
}
