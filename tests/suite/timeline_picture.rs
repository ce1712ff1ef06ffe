//! tools/timeline_png.py, the still picture of a `--timeline` trace: its
//! colour scale tells work items apart however their costs are spread.
//! Run with the system's python3 (the scale needs no Pillow; drawing
//! does, and is checked by eye: docs/scaling.md, "The timeline").

use crate::common::process::repo;
use std::process::Command;

/// Issue 62: the tool painted most items dark red. Its scale was anchored
/// at the median item (pale there, dark red at 10x and more), so where
/// most of the time went to items ten times the cheap ones (the matte
/// pixels of scenes/unbalanced.toml against its glass), they all came out
/// alike. Here 600 cheap items and 75 costly ones of 5 to 75 ms: the
/// costly ones must take many colours, and no colour may paint most of
/// the picture (the boxes' time).
#[test]
fn the_timeline_picture_tells_work_items_apart() {
    let check = r#"
import sys
sys.path.insert(0, sys.argv[1])
import timeline_png as t
cheap = [100.0 + i % 7 for i in range(600)]
costly = [5000.0 + 1000.0 * i for i in range(75)]
durations = cheap + costly
scale = t.ItemScale(durations)
colours = [scale.colour(d) for d in durations]
costly_colours = set(colours[600:])
time = {}
for d, c in zip(durations, colours):
    time[c] = time.get(c, 0.0) + d
largest = max(time.values()) / sum(durations)
assert len(costly_colours) >= 20, f"{len(costly_colours)} colours for 75 costly items"
assert largest < 0.1, f"one colour paints {largest:.0%} of the picture"
# Longer is darker: the ramp runs one way.
light = [sum(c) for c in (scale.colour(d) for d in sorted(costly))]
assert light == sorted(light, reverse=True), light
print("ok")
"#;
    let out = match Command::new("python3")
        .arg("-c")
        .arg(check)
        .arg(repo().join("tools"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            crate::common::skipped(
                "the_timeline_picture_tells_work_items_apart",
                &format!("no python3: {e}"),
            );
            return;
        }
    };
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
