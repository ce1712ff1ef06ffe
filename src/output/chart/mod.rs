//! SVG line charts (plotters), for `strata converge` and `strata scaling`.
//!
//! A chart is panels side by side. What a reader needs from it, and where
//! it is decided (each decision is a pure function with its own tests):
//!
//! - **One look per series.** [`styles`] gives every label one colour,
//!   marker and dash in all panels, in order of first appearance; colours
//!   are distinct, and reference lines ([`Series::reference`], such as
//!   "ideal") are grey, dashed and unmarked.
//! - **A legend that covers nothing.** Each panel's legend sits in a strip
//!   below its plot, laid out by [`legend_layout`] to fit its entries; the
//!   SVG is taller than `height` by the tallest strip.
//! - **Ticks that suit the data.** [`ticks`] chooses the tick values and
//!   their labels: integers only on an integer axis ([`Panel::integer_x`]),
//!   powers (of 2 on an integer log axis, else of 10) on a log axis, and no
//!   trailing ".0" where the values are whole.
//! - **Coinciding lines, shown and said.** Where a series equals an earlier
//!   one of its panel ([`same_as`]: every point within [`SAME_TOLERANCE`]),
//!   its legend entry says so, and it is drawn dashed with hollow, larger
//!   markers so the line beneath shows through.
//! - **What was not measured looks it.** A series that extends another
//!   ([`Series::extending`], such as a prediction past the measured
//!   threads) is drawn in that series' colour, dashed, with hollow markers.

mod legend;
mod style;
mod ticks;

pub use legend::{legend_layout, text_width, LegendLayout};
pub use style::{coincide, colour, legend_text, same_as, styles, Marker, Style, SAME_TOLERANCE};
pub use ticks::{axis_range, number_labels, ticks, Ticks};

use legend::{GAP, LEGEND_FONT, LINE_HEIGHT, SAMPLE};
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;
use style::{plotted, style_of};

/// One line of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// A line to compare against (such as ideal scaling), not a measurement:
    /// drawn grey and dashed, without markers.
    pub reference: bool,
    /// Not measured but derived (a prediction): drawn dashed, with
    /// hollow markers.
    pub extension: bool,
    /// The label of the series it extends, whose colour and marker it
    /// takes (if that series is in the chart).
    pub extends: Option<String>,
}

impl Series {
    /// A measured series.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            reference: false,
            extension: false,
            extends: None,
        }
    }

    /// A series that extends the one labelled `of`, or with `None` (or a
    /// label not in the chart) one not measured beside anything: dashed
    /// either way, in its own colour in the second case.
    pub fn extending(label: impl Into<String>, of: Option<&str>, points: Vec<(f64, f64)>) -> Self {
        Self {
            extension: true,
            extends: of.map(str::to_string),
            ..Self::new(label, points)
        }
    }

    /// A reference line.
    pub fn reference(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            reference: true,
            ..Self::new(label, points)
        }
    }
}

/// One panel: axes, scales and its lines.
#[derive(Debug, Clone)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// The x values are counts (threads, processes, samples): ticks only at
    /// integers.
    pub integer_x: bool,
    pub series: Vec<Series>,
}

type DrawResult = Result<(), String>;

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// A line through pixel points, solid or dashed.
fn draw_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    pts: &[(i32, i32)],
    style: &Style,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let stroke = style.colour.stroke_width(2);
    match style.dash {
        None => area.draw(&PathElement::new(pts.to_vec(), stroke)),
        Some((on, off)) => area.draw(&DashedPathElement::new(
            pts.iter().copied(),
            on as i32,
            off as i32,
            stroke,
        )),
    }
    .map_err(err)
}

/// A marker centred on a pixel.
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    style: &Style,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let r = style.marker_size;
    let shape = if style.hollow {
        style.colour.stroke_width(2)
    } else {
        style.colour.filled()
    };
    let outline = |pts: Vec<(i32, i32)>| {
        if style.hollow {
            let mut closed = pts.clone();
            closed.push(pts[0]);
            area.draw(&PathElement::new(closed, shape))
        } else {
            area.draw(&Polygon::new(pts, shape))
        }
    };
    match style.marker {
        Marker::None => Ok(()),
        Marker::Circle => area.draw(&Circle::new((x, y), r, shape)),
        Marker::Square => area.draw(&Rectangle::new([(x - r, y - r), (x + r, y + r)], shape)),
        Marker::Triangle => outline(vec![(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)]),
        Marker::Diamond => outline(vec![
            (x, y - r - 1),
            (x + r + 1, y),
            (x, y + r + 1),
            (x - r - 1, y),
        ]),
    }
    .map_err(err)
}

/// One axis as plotters sees it: the drawn range, its scale and our ticks
/// (plotters' own choice of ticks is what put 1.1 … 1.9 on a thread axis).
struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
    ticks: Ticks,
}

impl Axis {
    fn new(values: impl Iterator<Item = f64>, log: bool, integer: bool) -> Self {
        let (lo, hi) = axis_range(values, log);
        let ticks = ticks(lo, hi, log, integer);
        Self { lo, hi, log, ticks }
    }
}

impl Ranged for Axis {
    type ValueType = f64;
    type FormatOption = NoDefaultFormatting;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let f = |x: f64| if self.log { x.ln() } else { x };
        let t = (f(*v) - f(self.lo)) / (f(self.hi) - f(self.lo));
        limit.0 + (t * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.ticks.light.clone()
        } else {
            self.ticks.values.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format_ext(&self, v: &f64) -> String {
        self.ticks.label(*v)
    }
}

fn draw_plot<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    styles: &[(String, Style)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let xs = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0));
    let ys = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1));
    let (x, y) = (
        Axis::new(xs, p.log_x, p.integer_x),
        Axis::new(ys, p.log_y, false),
    );
    let y_labels = y
        .ticks
        .labels
        .iter()
        .map(|l| text_width(l, 10.0))
        .fold(0.0, f64::max);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size((y_labels + 34.0).max(48.0) as u32)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .light_line_style(BLACK.mix(0.05))
        .draw()
        .map_err(err)?;
    let plot = chart.plotting_area();
    let screen = plot.use_screen_coord();
    for s in &p.series {
        let style = style_of(styles, &s.label);
        let px: Vec<(i32, i32)> = plotted(s, p)
            .iter()
            .map(|q| plot.map_coordinate(q))
            .collect();
        draw_line(&screen, &px, &style)?;
        for &q in &px {
            draw_marker(&screen, q, &style)?;
        }
    }
    Ok(())
}

/// A panel's legend texts, one per series.
fn legend_texts(p: &Panel) -> Vec<String> {
    let same = same_as(p);
    (0..p.series.len())
        .map(|i| legend_text(p, i, &same))
        .collect()
}

/// A legend box, centred at the top of `area`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    styles: &[(String, Style)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    if p.series.is_empty() {
        return Ok(());
    }
    let (w, _) = area.dim_in_pixel();
    let layout = legend_layout(&legend_texts(p), w);
    let x0 = ((w as i32 - layout.size.0) / 2).max(0);
    let frame = [(x0, 0), (x0 + layout.size.0, layout.size.1)];
    area.draw(&Rectangle::new(frame, BLACK.mix(0.35).stroke_width(1)))
        .map_err(err)?;
    let font = ("sans-serif", LEGEND_FONT).into_font().color(&BLACK);
    for (((x, y), lines), s) in layout.entries.iter().zip(&p.series) {
        let style = style_of(styles, &s.label);
        let (x, mid) = (x0 + x, y + LINE_HEIGHT / 2);
        draw_line(area, &[(x, mid), (x + SAMPLE, mid)], &style)?;
        let sample = Style {
            marker_size: style.marker_size.min(5),
            ..style
        };
        draw_marker(area, (x + SAMPLE / 2, mid), &sample)?;
        for (k, line) in lines.iter().enumerate() {
            let at = (x + SAMPLE + GAP, y + 2 + k as i32 * LINE_HEIGHT);
            area.draw(&Text::new(line.clone(), at, font.clone()))
                .map_err(err)?;
        }
    }
    Ok(())
}

/// Render panels side by side into an SVG document: each panel's plot is
/// `panel_width` × `height`, and its legend lies in a strip below it (so
/// the document is [`legend_strip_height`] taller than `height`).
pub fn svg(panels: &[Panel], panel_width: u32, height: u32) -> Result<String, String> {
    let styles = styles(panels);
    let strip = legend_strip_height(panels, panel_width);
    let columns = panels.len().max(1);
    let mut out = String::new();
    {
        let size = (panel_width * columns as u32, height + strip);
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (plots, legends) = root.split_vertically(height);
        let cells = plots.split_evenly((1, columns));
        let strips = legends.split_evenly((1, columns));
        for ((p, cell), strip) in panels.iter().zip(&cells).zip(&strips) {
            draw_plot(cell, p, &styles)?;
            draw_legend(strip, p, &styles)?;
        }
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// Height of the strip under the plots: the tallest legend, plus a margin.
pub fn legend_strip_height(panels: &[Panel], panel_width: u32) -> u32 {
    panels
        .iter()
        .map(|p| legend_layout(&legend_texts(p), panel_width).size.1)
        .filter(|&h| h > 0)
        .max()
        .map_or(0, |h| h as u32 + 10)
}

/// Write the SVG atomically.
pub fn write_svg(
    path: &Path,
    panels: &[Panel],
    panel_width: u32,
    height: u32,
) -> Result<(), String> {
    let doc = svg(panels, panel_width, height)?;
    super::atomic::write_bytes_atomic(path, doc.as_bytes())
        .map_err(|e| format!("cannot write: {e}"))
}

/// Least-squares slope of log y against log x.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One SVG element as plotters writes it: tag, attributes, text.
    #[derive(Debug)]
    struct El {
        tag: String,
        attrs: Vec<(String, String)>,
        text: String,
    }

    impl El {
        fn get(&self, name: &str) -> &str {
            self.attrs
                .iter()
                .find(|(k, _)| k == name)
                .map_or("", |(_, v)| v.as_str())
        }

        fn num(&self, name: &str) -> f64 {
            self.get(name).parse().unwrap_or(f64::NAN)
        }

        /// The points of a polyline or polygon.
        fn points(&self) -> Vec<(f64, f64)> {
            self.get("points")
                .split_whitespace()
                .filter_map(|p| p.split_once(','))
                .map(|(x, y)| (x.parse().unwrap(), y.parse().unwrap()))
                .collect()
        }
    }

    fn unescape(s: &str) -> String {
        s.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&amp;", "&")
    }

    /// The elements of an SVG document, in order.
    fn elements(doc: &str) -> Vec<El> {
        let mut out = Vec::new();
        let mut rest = doc;
        while let Some(i) = rest.find('<') {
            rest = &rest[i + 1..];
            if rest.starts_with('/') {
                continue;
            }
            let end = rest.find('>').unwrap();
            let head = &rest[..end];
            let tag: String = head.chars().take_while(|c| c.is_alphanumeric()).collect();
            let mut attrs = Vec::new();
            let mut a = &head[tag.len()..];
            while let Some(eq) = a.find("=\"") {
                let name = a[..eq].trim().to_string();
                let close = a[eq + 2..].find('"').unwrap();
                attrs.push((name, unescape(&a[eq + 2..eq + 2 + close])));
                a = &a[eq + 3 + close..];
            }
            let text = match rest[end + 1..].find("</text>") {
                Some(t) if tag == "text" => unescape(rest[end + 1..end + 1 + t].trim()),
                _ => String::new(),
            };
            out.push(El { tag, attrs, text });
            rest = &rest[end + 1..];
        }
        out
    }

    fn hex(c: RGBColor) -> String {
        format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
    }

    fn panel(log: bool, integer_x: bool, series: Vec<Series>) -> Panel {
        Panel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: log,
            log_y: log,
            integer_x,
            series,
        }
    }

    /// `n` lines across the whole plot, the last reaching its top right
    /// corner (where plotters' legend used to sit).
    fn fan(labels: &[&str]) -> Vec<Series> {
        let n = labels.len() as f64;
        let line = |(i, l): (usize, &&str)| {
            let k = (i + 1) as f64 / n;
            Series::new(*l, (1..=8).map(|t| (t as f64, k * t as f64)).collect())
        };
        labels.iter().enumerate().map(line).collect()
    }

    /// The legend entries of a document: (panel, text, colour of the
    /// sample line drawn just before the text).
    fn legend(els: &[El], height: f64, width: f64) -> Vec<(usize, String, String)> {
        let mut last_stroke = String::new();
        let mut out = Vec::new();
        for e in els {
            if e.tag == "polyline" {
                last_stroke = e.get("stroke").to_string();
            }
            if e.tag == "text" && e.num("y") >= height {
                out.push((
                    (e.num("x") / width) as usize,
                    e.text.clone(),
                    last_stroke.clone(),
                ));
            }
        }
        out
    }

    #[test]
    fn the_legend_lies_below_the_plots_and_covers_no_data() {
        let labels = ["ideal", "slices", "regions", "processes", "a", "b"];
        let panels = [
            panel(false, true, fan(&labels)),
            panel(false, true, fan(&labels[1..])),
        ];
        let doc = svg(&panels, 400, 300).unwrap();
        let els = elements(&doc);
        let strip = legend_strip_height(&panels, 400);
        assert!(strip > 0 && els[0].num("height") == (300 + strip) as f64);
        let boxes: Vec<&El> = els
            .iter()
            .filter(|e| e.tag == "rect" && e.get("fill") == "none")
            .collect();
        assert_eq!(boxes.len(), 2, "a legend box per panel");
        let inside = |b: &El, (x, y): (f64, f64)| {
            let (bx, by) = (b.num("x"), b.num("y"));
            x >= bx && x <= bx + b.num("width") && y >= by && y <= by + b.num("height")
        };
        for b in &boxes {
            assert!(b.num("y") >= 300.0, "a legend box reaches into the plots");
        }
        for e in els
            .iter()
            .filter(|e| e.tag == "text" && labels.contains(&e.text.as_str()))
        {
            let at = (e.num("x"), e.num("y"));
            assert!(
                boxes.iter().any(|b| inside(b, at)),
                "{} outside its box",
                e.text
            );
        }
        let data: Vec<(f64, f64)> = els
            .iter()
            .filter(|e| e.tag == "polyline" && e.get("stroke") != "#000000")
            .flat_map(|e| e.points())
            .chain(
                els.iter()
                    .filter(|e| e.tag == "circle")
                    .map(|e| (e.num("cx"), e.num("cy"))),
            )
            .filter(|p| p.1 < 300.0)
            .collect();
        assert!(data.len() > 50);
        for p in data {
            assert!(
                boxes.iter().all(|b| !inside(b, p)),
                "data at {p:?} under the legend"
            );
        }
    }

    #[test]
    fn a_label_has_one_colour_in_every_panel_and_no_two_share_one() {
        let ideal = Series::reference("ideal", vec![(1.0, 1.0), (8.0, 8.0)]);
        let mut first = fan(&["slices", "regions", "processes"]);
        first.insert(0, ideal);
        let second = fan(&["processes", "slices", "regions"]);
        let panels = [panel(false, true, first), panel(false, true, second)];
        let els = elements(&svg(&panels, 400, 300).unwrap());
        let entries = legend(&els, 300.0, 400.0);
        assert_eq!(entries.len(), 7);
        for (p, label, colour) in &entries {
            for (q, other, c) in &entries {
                assert_eq!(
                    label == other,
                    colour == c,
                    "{label} in {p} and {other} in {q}"
                );
            }
            // The panel's own lines are drawn in that colour.
            let drawn = els.iter().any(|e| {
                e.tag == "polyline"
                    && e.get("stroke") == colour
                    && e.points()
                        .iter()
                        .all(|&(x, y)| y < 300.0 && (x / 400.0) as usize == *p)
            });
            assert!(
                drawn,
                "{label} is not drawn in its legend colour in panel {p}"
            );
        }
        let ideal = &entries.iter().find(|e| e.1 == "ideal").unwrap().2;
        assert_eq!(ideal, "#808080", "the reference line is grey");
    }

    #[test]
    fn axes_of_counts_tick_at_integers_and_log_axes_at_plain_powers() {
        let speedup = vec![Series::new("slices", vec![(1.0, 1.0), (2.0, 1.03)])];
        let rmse: Vec<(f64, f64)> = (0..5)
            .map(|i| (2f64.powi(i), 0.09 * 2f64.powi(i).powf(-0.8)))
            .collect();
        let panels = [
            panel(false, true, speedup),
            panel(true, true, vec![Series::new("random", rmse)]),
        ];
        let els = elements(&svg(&panels, 400, 300).unwrap());
        let ticks = |panel: usize, anchor: &str| -> Vec<String> {
            els.iter()
                .filter(|e| e.tag == "text" && e.get("text-anchor") == anchor)
                .filter(|e| e.num("y") < 300.0 && (e.num("x") / 400.0) as usize == panel)
                .filter(|e| e.text.parse::<f64>().is_ok())
                .map(|e| e.text.clone())
                .collect()
        };
        assert_eq!(ticks(0, "middle"), ["1", "2"], "threads are whole");
        assert_eq!(ticks(1, "middle"), ["1", "2", "4", "8", "16"]);
        let y = ticks(1, "end");
        assert!(y.len() >= 3, "{y:?}");
        assert!(y.iter().all(|l| !l.ends_with(".0")), "{y:?}");
    }

    #[test]
    fn coinciding_lines_are_said_and_both_show() {
        let mut series = fan(&["slices", "regions", "processes"]);
        series[1].points = series[0].points.clone();
        let panels = [panel(false, true, series)];
        let styles = styles(&panels);
        let els = elements(&svg(&panels, 400, 300).unwrap());
        let texts: Vec<String> = legend(&els, 300.0, 400.0)
            .into_iter()
            .map(|e| e.1)
            .collect();
        assert_eq!(texts, ["slices", "regions (same as slices)", "processes"]);
        let (under, over) = (hex(styles[0].1.colour), hex(styles[1].1.colour));
        let in_plot = |colour: &str, tag: &str| -> Vec<&El> {
            els.iter()
                .filter(|e| e.tag == tag && e.get("stroke") == colour)
                .filter(|e| e.points().iter().all(|p| p.1 < 300.0))
                .collect()
        };
        assert_eq!(in_plot(&under, "polyline").len(), 1, "the first is solid");
        assert!(in_plot(&over, "polyline").len() > 5, "the second is dashed");
        let filled = |colour: &str| {
            els.iter()
                .filter(|e| e.tag == "circle" && e.num("cy") < 300.0)
                .any(|e| e.get("fill") == colour)
        };
        assert!(filled(&under), "the first has filled markers");
        assert!(
            !filled(&over),
            "the second's markers are outlines over them"
        );
    }

    #[test]
    fn slope_of_a_power_law_and_the_slope_in_the_legend() {
        let pts: Vec<(f64, f64)> = (0..6)
            .map(|i| (2f64.powi(i), 3.0 * 2f64.powi(i).powf(-0.5)))
            .collect();
        assert!((log_log_slope(&pts).unwrap() + 0.5).abs() < 1e-9);
        let p = panel(true, true, vec![Series::new("random (slope -0.50)", pts)]);
        let doc = svg(&[p.clone(), p], 400, 300).unwrap();
        assert!(doc.starts_with("<svg") && doc.contains("random (slope -0.50)"));
    }
}
