//! Legend layout: entries in columns under a plot, sized to their text.

/// Legend text size as handed to plotters (which writes size / 1.24 into
/// the SVG: 12 px).
pub(super) const LEGEND_FONT: f64 = 14.88;
pub(super) const LINE_HEIGHT: i32 = 16;
pub(super) const SAMPLE: i32 = 34;
pub(super) const GAP: i32 = 6;
const COLUMN_GAP: i32 = 18;
const PAD: i32 = 8;

/// Estimated width in pixels of `text` in a sans-serif font of `px`
/// pixels, from per-character widths a little above DejaVu Sans' (the
/// widest of the common sans-serif fonts), so estimates err wide.
pub fn text_width(text: &str, px: f64) -> f64 {
    let em: f64 = text
        .chars()
        .map(|c| match c {
            'i' | 'j' | 'l' | '.' | ',' | ':' | ';' | '\'' | '|' | '!' => 0.3,
            'f' | 't' | 'r' | '(' | ')' | '[' | ']' | ' ' | '/' | '-' => 0.42,
            'm' | 'w' | 'M' | 'W' | '%' => 0.98,
            c if c.is_ascii_uppercase() => 0.75,
            c if c.is_ascii_digit() => 0.65,
            '+' | '=' | '<' | '>' => 0.85,
            _ => 0.64,
        })
        .sum();
    em * px
}

/// Where each legend entry goes, relative to the legend box's top left.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendLayout {
    /// Per entry: its top-left corner and its text, one string per line.
    pub entries: Vec<((i32, i32), Vec<String>)>,
    /// The box around the entries.
    pub size: (i32, i32),
}

/// Greedy word wrap to `width` pixels (a word longer than that stays whole).
fn wrap(text: &str, width: f64, px: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), px) <= width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Lay legend entries out in as many columns as fit `width` pixels, down
/// each column in turn, wrapping any entry too wide for a single column.
/// Each entry is a line sample, a gap, then its text.
pub fn legend_layout(texts: &[String], width: u32) -> LegendLayout {
    if texts.is_empty() {
        return LegendLayout {
            entries: Vec::new(),
            size: (0, 0),
        };
    }
    let px = LEGEND_FONT / 1.24;
    let room = (width as i32 - 2 * PAD).max(SAMPLE + GAP + 40);
    let text_room = (room - SAMPLE - GAP) as f64;
    let entry = |t: &String| SAMPLE + GAP + text_width(t, px).min(text_room).ceil() as i32;
    // Column by column, so the entries read down in their order; as many
    // columns as fit, each as wide as its widest entry.
    let n = texts.len();
    let (per_column, widths) = (1..=n)
        .rev()
        .map(|c| {
            let per = n.div_ceil(c);
            let widths: Vec<i32> = texts
                .chunks(per)
                .map(|col| col.iter().map(entry).max().unwrap_or(0))
                .collect();
            (per, widths)
        })
        .find(|(_, w)| w.iter().sum::<i32>() + COLUMN_GAP * (w.len() as i32 - 1) <= room)
        .expect("one column fits: entries wrap to the room");
    let mut entries = Vec::new();
    let (mut x, mut bottom) = (PAD, PAD);
    for (column, w) in texts.chunks(per_column).zip(&widths) {
        let mut y = PAD;
        for t in column {
            let lines = wrap(t, text_room, px);
            let height = LINE_HEIGHT * lines.len() as i32;
            entries.push(((x, y), lines));
            y += height;
        }
        bottom = bottom.max(y);
        x += w + COLUMN_GAP;
    }
    LegendLayout {
        entries,
        size: (x - COLUMN_GAP + PAD, bottom + PAD - 2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(labels: &[&str]) -> Vec<String> {
        labels.iter().map(|s| s.to_string()).collect()
    }

    /// Each entry's box: sample, gap and its widest line, by its lines.
    fn boxes(layout: &LegendLayout) -> Vec<(i32, i32, i32, i32)> {
        let px = LEGEND_FONT / 1.24;
        layout
            .entries
            .iter()
            .map(|((x, y), lines)| {
                let w = lines.iter().map(|l| text_width(l, px)).fold(0.0, f64::max);
                let w = SAMPLE + GAP + w.ceil() as i32;
                (*x, *y, x + w, y + LINE_HEIGHT * lines.len() as i32)
            })
            .collect()
    }

    fn check(layout: &LegendLayout, width: u32) {
        let (w, h) = layout.size;
        assert!(w <= width as i32, "legend {w} px wide in {width}");
        let b = boxes(layout);
        for (i, r) in b.iter().enumerate() {
            assert!(
                r.0 >= 0 && r.1 >= 0 && r.2 <= w && r.3 <= h,
                "entry {i} leaves the box"
            );
            for (j, q) in b[..i].iter().enumerate() {
                let apart = r.2 <= q.0 || q.2 <= r.0 || r.3 <= q.1 || q.3 <= r.1;
                assert!(apart, "entries {j} and {i} overlap: {q:?} {r:?}");
            }
        }
    }

    #[test]
    fn short_entries_share_rows_and_read_down_the_columns() {
        let t = texts(&["ideal", "slices", "regions", "processes", "a", "b", "c"]);
        let layout = legend_layout(&t, 520);
        check(&layout, 520);
        let xs: Vec<i32> = layout.entries.iter().map(|e| e.0 .0).collect();
        assert!(xs.iter().any(|&x| x != xs[0]), "several columns");
        assert!(
            xs.windows(2).all(|w| w[0] <= w[1]),
            "down each column first"
        );
        assert!(
            layout.size.1 < 4 * LINE_HEIGHT + 2 * PAD,
            "sized to its rows"
        );
    }

    #[test]
    fn long_entries_take_one_column_and_wrap_when_too_wide() {
        let long = "stratified+is/area-lights (slope -0.87) (same as stratified (slope -0.87))";
        let t = texts(&["random (slope -0.48)", long]);
        let layout = legend_layout(&t, 400);
        check(&layout, 400);
        assert_eq!(layout.entries[1].0 .0, layout.entries[0].0 .0, "one column");
        assert!(layout.entries[1].1.len() > 1, "the long entry wraps");
        assert_eq!(
            layout.entries[1].1.join(" "),
            long,
            "wrapping keeps every word"
        );
        assert_eq!(legend_layout(&[], 400).size, (0, 0));
    }
}
