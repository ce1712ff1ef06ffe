//! How each series is drawn: one colour, marker and dash per label across a
//! chart's panels, and which series coincide with an earlier one.

use super::{Panel, Series};
use plotters::style::RGBColor;

/// The shape drawn at each point of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    None,
    Circle,
    Square,
    Triangle,
    Diamond,
}

/// How one series is drawn, the same in every panel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    pub colour: RGBColor,
    pub marker: Marker,
    /// Marker outlined rather than filled (over a series it coincides with).
    pub hollow: bool,
    /// Marker half-size in pixels.
    pub marker_size: i32,
    /// Dash and gap lengths in pixels; `None` draws a solid line.
    pub dash: Option<(u32, u32)>,
}

/// Distinct colours for measured series (none of them grey, which marks
/// reference lines); more series get colours spread round the hue circle.
const PALETTE: [RGBColor; 9] = [
    RGBColor(31, 119, 180),  // blue
    RGBColor(255, 127, 14),  // orange
    RGBColor(44, 160, 44),   // green
    RGBColor(214, 39, 40),   // red
    RGBColor(148, 103, 189), // purple
    RGBColor(140, 86, 75),   // brown
    RGBColor(227, 119, 194), // pink
    RGBColor(188, 189, 34),  // olive
    RGBColor(23, 190, 207),  // cyan
];

/// Greys for reference lines, one each.
const GREYS: [u8; 4] = [128, 80, 170, 40];

const MARKERS: [Marker; 4] = [
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
    Marker::Diamond,
];

/// Dash patterns by overlay depth: solid, then patterns whose gaps let the
/// lines beneath show.
const DASHES: [Option<(u32, u32)>; 4] = [None, Some((10, 7)), Some((3, 6)), Some((16, 5))];

const REFERENCE_DASH: (u32, u32) = (7, 5);

/// The dash of a series that extends another (a prediction): longer than
/// a reference line's, in the colour of what it extends.
const EXTENSION_DASH: (u32, u32) = (9, 5);

/// The `i`-th colour of measured series: the palette, then hues a golden
/// angle apart at alternating lightness.
pub fn colour(i: usize) -> RGBColor {
    if let Some(c) = PALETTE.get(i) {
        return *c;
    }
    let k = i - PALETTE.len();
    let hue = (k as f64 * 137.507_764 + 15.0) % 360.0;
    let light = [0.42, 0.32, 0.55][k % 3];
    let sat = 0.7;
    let c = (1.0 - (2.0 * light - 1.0_f64).abs()) * sat;
    let h = hue / 60.0;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = light - c / 2.0;
    let to = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    RGBColor(to(r), to(g), to(b))
}

/// Every label of the chart with its style, in order of first appearance.
/// A label's overlay depth is the most earlier series it coincides with in
/// any one panel: depth 0 is drawn solid with filled markers, deeper ones
/// dashed with hollow, larger markers.
///
/// An extension ([`Series::extension`]) takes the colour and marker of
/// the series it extends, hollow and dashed; one that extends none in the
/// chart takes the next colour.
pub fn styles(panels: &[Panel]) -> Vec<(String, Style)> {
    let mut out: Vec<(String, Style)> = Vec::new();
    let mut depth: Vec<usize> = Vec::new();
    let (mut measured, mut references) = (0, 0);
    for panel in panels {
        for (s, d) in panel.series.iter().zip(overlay_depths(panel)) {
            if s.extension {
                continue;
            }
            if let Some(i) = out.iter().position(|(l, _)| *l == s.label) {
                depth[i] = depth[i].max(d);
                continue;
            }
            let style = if s.reference {
                references += 1;
                let g = GREYS[(references - 1) % GREYS.len()];
                Style {
                    colour: RGBColor(g, g, g),
                    marker: Marker::None,
                    hollow: false,
                    marker_size: 0,
                    dash: Some(REFERENCE_DASH),
                }
            } else {
                next_measured(&mut measured)
            };
            out.push((s.label.clone(), style));
            depth.push(d);
        }
    }
    for ((_, style), d) in out.iter_mut().zip(depth) {
        if d > 0 {
            style.hollow = true;
            let d = d.min(DASHES.len() - 1);
            style.marker_size = 3 + 2 * d as i32;
            style.dash = DASHES[d];
        }
    }
    for s in panels.iter().flat_map(|p| &p.series) {
        if !s.extension || out.iter().any(|(l, _)| *l == s.label) {
            continue;
        }
        let of = |(l, _): &&(String, Style)| s.extends.as_ref() == Some(l);
        let base = out.iter().find(of).map(|(_, st)| *st);
        let base = base.unwrap_or_else(|| next_measured(&mut measured));
        let style = Style {
            hollow: true,
            marker_size: 4,
            dash: Some(EXTENSION_DASH),
            ..base
        };
        out.push((s.label.clone(), style));
    }
    out
}

/// The style of the next measured series: the `measured`-th colour and
/// marker, solid with filled markers; counts it.
fn next_measured(measured: &mut usize) -> Style {
    let k = *measured;
    *measured += 1;
    Style {
        colour: colour(k),
        marker: MARKERS[k % MARKERS.len()],
        hollow: false,
        marker_size: 3,
        dash: None,
    }
}

pub(super) fn style_of(styles: &[(String, Style)], label: &str) -> Style {
    styles
        .iter()
        .find(|(l, _)| l == label)
        .map(|(_, s)| *s)
        .expect("every label has a style")
}

// ---------------------------------------------------------- coincidence

/// Two series coincide when they have the same points, each coordinate
/// equal within this relative tolerance: 0.5%, about a pixel on these
/// charts, and less than the noise of a timing (the scaling table's
/// speedups, to two decimals, read the same).
pub const SAME_TOLERANCE: f64 = 5e-3;

/// The points of a series that can be drawn on the panel's scales, by x.
pub(super) fn plotted(s: &Series, p: &Panel) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = s
        .points
        .iter()
        .copied()
        .filter(|(x, y)| {
            x.is_finite() && y.is_finite() && (!p.log_x || *x > 0.0) && (!p.log_y || *y > 0.0)
        })
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts
}

/// Whether two point lists (sorted by x) are the same within
/// [`SAME_TOLERANCE`].
pub fn coincide(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    let close = |u: f64, v: f64| (u - v).abs() <= SAME_TOLERANCE * u.abs().max(v.abs());
    !a.is_empty()
        && a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| close(p.0, q.0) && close(p.1, q.1))
}

/// For each series of a panel, the first earlier series it coincides with.
pub fn same_as(panel: &Panel) -> Vec<Option<usize>> {
    let pts: Vec<_> = panel.series.iter().map(|s| plotted(s, panel)).collect();
    (0..pts.len())
        .map(|i| (0..i).find(|&j| coincide(&pts[j], &pts[i])))
        .collect()
}

/// For each series of a panel, how many earlier series it coincides with.
fn overlay_depths(panel: &Panel) -> Vec<usize> {
    let pts: Vec<_> = panel.series.iter().map(|s| plotted(s, panel)).collect();
    (0..pts.len())
        .map(|i| (0..i).filter(|&j| coincide(&pts[j], &pts[i])).count())
        .collect()
}

/// A series' legend text: its label, and what it coincides with.
pub fn legend_text(panel: &Panel, i: usize, same: &[Option<usize>]) -> String {
    let label = &panel.series[i].label;
    match same[i] {
        Some(j) => format!("{label} (same as {})", panel.series[j].label),
        None => label.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panel(series: Vec<Series>) -> Panel {
        Panel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: false,
            log_y: false,
            integer_x: true,
            series,
        }
    }

    fn line(label: &str, slope: f64) -> Series {
        Series::new(
            label,
            (1..=4).map(|t| (t as f64, slope * t as f64)).collect(),
        )
    }

    #[test]
    fn a_label_keeps_its_style_in_every_panel_and_colours_are_distinct() {
        // The second panel lists the series in another order, without "ideal".
        let ideal = Series::reference("ideal", vec![(1.0, 1.0), (4.0, 4.0)]);
        let first = panel(vec![ideal, line("a", 0.9), line("b", 0.8), line("c", 0.7)]);
        let second = panel(vec![line("c", 7.0), line("a", 9.0), line("d", 6.0)]);
        let styles = styles(&[first, second]);
        let labels: Vec<&str> = styles.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels, ["ideal", "a", "b", "c", "d"], "one style per label");
        let ideal = styles[0].1;
        let RGBColor(r, g, b) = ideal.colour;
        assert!(r == g && g == b, "the reference line is grey");
        assert!(ideal.dash.is_some() && ideal.marker == Marker::None);
        for (i, (l, s)) in styles.iter().enumerate() {
            for (m, t) in &styles[..i] {
                assert_ne!(s.colour, t.colour, "{l} and {m} share a colour");
            }
            if l != "ideal" {
                assert!(
                    s.dash.is_none() && !s.hollow && s.marker != Marker::None,
                    "{l}"
                );
            }
        }
    }

    /// Issue 62: a prediction is drawn as the dashed extension of what
    /// it predicts, in its colour; one with nothing measured beside it
    /// gets a colour of its own, dashed too.
    #[test]
    fn an_extension_is_its_series_dashed() {
        let extension = |label: &str, of: Option<&str>| {
            Series::extending(label, of, vec![(4.0, 3.0), (64.0, 40.0)])
        };
        let first = panel(vec![
            extension("a (predicted)", Some("a")),
            line("a", 0.9),
            line("b", 0.8),
        ]);
        let second = panel(vec![extension("e (predicted)", None)]);
        let styles = styles(&[first, second]);
        let of = |label: &str| styles.iter().find(|(l, _)| l == label).unwrap().1;
        let (a, predicted) = (of("a"), of("a (predicted)"));
        assert_eq!((predicted.colour, predicted.marker), (a.colour, a.marker));
        assert!(predicted.dash.is_some() && predicted.hollow && a.dash.is_none());
        let orphan = of("e (predicted)");
        assert!(orphan.dash.is_some());
        assert!(![a.colour, of("b").colour].contains(&orphan.colour));
    }

    #[test]
    fn colours_past_the_palette_stay_distinct_and_never_grey() {
        let colours: Vec<RGBColor> = (0..40).map(colour).collect();
        for (i, c) in colours.iter().enumerate() {
            assert!(!(c.0 == c.1 && c.1 == c.2), "colour {i} is grey");
            assert!(!colours[..i].contains(c), "colour {i} repeats");
        }
    }

    #[test]
    fn coinciding_series_are_named_and_drawn_apart() {
        let a = line("slices", 0.9);
        let mut b = line("regions", 0.9);
        b.points[2].1 *= 1.0 + SAME_TOLERANCE / 2.0;
        let mut c = line("processes", 0.9);
        c.points[3].1 *= 1.0 + 2.0 * SAME_TOLERANCE; // off at one point: another line
        let d = line("twin", 0.9);
        let p = panel(vec![a, b, c, d]);
        assert_eq!(same_as(&p), [None, Some(0), None, Some(0)]);
        let same = same_as(&p);
        assert_eq!(legend_text(&p, 1, &same), "regions (same as slices)");
        assert_eq!(legend_text(&p, 2, &same), "processes");
        let styles = styles(&[p]);
        let (a, b, c, d) = (styles[0].1, styles[1].1, styles[2].1, styles[3].1);
        assert!(a.dash.is_none() && !a.hollow && c.dash.is_none());
        // Over a solid line, a dashed one with hollow, larger markers; a
        // third copy with yet another dash and larger markers still.
        assert!(b.dash.is_some() && b.hollow && b.marker_size > a.marker_size);
        assert!(d.dash.is_some() && d.dash != b.dash && d.marker_size > b.marker_size);
    }

    #[test]
    fn coincidence_needs_every_point() {
        let pts = [(1.0, 1.0), (2.0, 2.0)];
        let off = |k: f64| [(1.0, 1.0), (2.0, 2.0 * (1.0 + k * SAME_TOLERANCE))];
        assert!(coincide(&pts, &off(0.9)));
        assert!(!coincide(&pts, &off(1.1)));
        assert!(!coincide(&pts, &pts[..1]));
        assert!(!coincide(&[], &[]), "empty series are not said to coincide");
    }
}
