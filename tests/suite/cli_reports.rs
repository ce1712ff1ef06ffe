//! What the binary says about a run: the summary names what was rendered
//! (and `--stats` and `--debug-sample` agree), a scene without light and
//! `--passes` beyond the sample count are warned about, and `strata
//! converge` is quick by default with only its table on standard output.

use crate::common::scenes::{LIT_SPHERE, SPHERE_ON_PLANE};
use crate::common::{stderr, stdout, strata};

#[test]
fn the_summary_says_what_was_rendered() {
    let dir = crate::common::temp_dir("summary");
    std::fs::write(dir.join("s.toml"), SPHERE_ON_PLANE).unwrap();
    let o = strata(
        &dir,
        &[
            "render",
            "s.toml",
            "--threads",
            "1",
            "--slice",
            "1/4",
            "-o",
            "p.strata",
            "--stats",
            "s.json",
        ],
    );
    let out = stdout(&o);
    assert!(out.contains("samples 2..4 of 8 spp"), "{out}");
    assert!(out.contains("on 1 thread "), "{out}");
    assert!(
        !out.contains("B/triangle"),
        "no meshes, no per-triangle figure: {out}"
    );
    let stats = std::fs::read_to_string(dir.join("s.json")).unwrap();
    assert!(
        stats.contains("\"peak_bytes_per_triangle\": null"),
        "{stats}"
    );
    // A replayed sample names what it hit.
    let o = strata(&dir, &["render", "s.toml", "--debug-sample", "8,11,0"]);
    assert!(stdout(&o).contains("hits plane 0"), "{}", stdout(&o));
    assert!(!stdout(&o).contains("4294967295"), "{}", stdout(&o));
}

#[test]
fn a_scene_without_light_is_warned_about() {
    let dir = crate::common::temp_dir("dark");
    std::fs::write(
        dir.join("s.toml"),
        "[render]\nwidth = 8\nheight = 6\n[[objects]]\nsphere = { radius = 1.0 }\n",
    )
    .unwrap();
    let o = strata(&dir, &["render", "s.toml", "-q", "-o", "out.png"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("no lights"), "{}", stderr(&o));
    let o = strata(&dir, &["render", "-q", "-o", "lit.png"]);
    assert!(!stderr(&o).contains("no lights"), "the seed scene is lit");
}

#[test]
fn more_passes_than_samples_warn_and_say_how_many_ran() {
    let dir = crate::common::temp_dir("words-passes");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    let o = strata(
        &dir,
        &[
            "render",
            "scene.toml",
            "-q",
            "-o",
            "x.png",
            "--passes",
            "32",
        ],
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.starts_with("warning: --passes 32:"), "{e}");
    assert!(e.contains("so 4 passes"), "{e}");
    let o = strata(
        &dir,
        &["render", "scene.toml", "-q", "-o", "x.png", "--passes", "4"],
    );
    assert_eq!(stderr(&o), "");
}

/// The default of `flag` that `strata converge --help` shows.
fn converge_default(help: &str, flag: &str) -> u64 {
    let at = help
        .find(&format!("{flag} <"))
        .unwrap_or_else(|| panic!("{flag} in {help}"));
    let rest = &help[at..];
    let value = rest[rest.find("[default: ").expect("a default") + 10..]
        .split(']')
        .next()
        .unwrap();
    value.parse().unwrap()
}

#[test]
fn converge_is_quick_by_default_and_its_standard_output_is_the_table() {
    let dir = crate::common::temp_dir("words-converge");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    let help = strata(&dir, &["converge", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    let (max, reference, repeats) = (
        converge_default(&help, "--max-spp"),
        converge_default(&help, "--reference-spp"),
        converge_default(&help, "--repeats"),
    );
    // The reference keeps docs/converge.md's rule (16 times --max-spp), and
    // the samples per pixel of a default run (every method at 1, 2, …, max,
    // each repeated, and the reference) stay a quick look: the old
    // defaults (256, 4096) traced 10 228 with four methods.
    assert!(reference >= 16 * max, "{reference} vs {max}");
    let methods = strata::experiment::converge::METHODS.len() as u64;
    let work = methods * repeats * (2 * max - 1) + reference;
    assert!(work <= 4096, "{work} samples per pixel");

    let o = strata(
        &dir,
        &[
            "converge",
            "scene.toml",
            "--max-spp",
            "2",
            "--reference-spp",
            "8",
            "--repeats",
            "1",
        ],
    );
    let (out, e) = (String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert_eq!(o.status.code(), Some(0), "{e}");
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[0].starts_with("method"), "{out}");
    // A row per method and spp (1 and 2), and nothing else.
    assert_eq!(lines.len(), 1 + methods as usize * 2, "{out}");
    for row in &lines[1..] {
        let fields: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(fields.len(), 5, "{row}");
        assert!(fields[1].parse::<u32>().is_ok(), "{row}");
    }
    assert!(e.contains("wrote converge.csv and converge.svg"), "{e}");
    assert!(e.contains("no --reference given"), "{e}");
}

/// Issue 62: every column a report prints is explained where it prints or
/// in `--help`: the scaling tables (the prediction's key under it), and
/// those of converge and bench. And the --predict chart keeps the measured
/// counts' scale, its predictions past them in a third panel.
#[test]
fn every_column_of_a_report_is_explained() {
    let dir = crate::common::temp_dir("columns");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    let o = strata(
        &dir,
        &[
            "scaling",
            "scene.toml",
            "--max-threads",
            "2",
            "--repeats",
            "1",
            "--predict",
            "--predict-max",
            "8",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    let help = stdout(&strata(&dir, &["scaling", "--help"]));
    let explained = |help: &str, column: &str| {
        help.lines().any(|l| {
            let l = l.trim_start();
            l.starts_with(column)
                || l.split("  ")
                    .next()
                    .is_some_and(|n| n.split(", ").any(|c| c == column))
        })
    };
    let headers: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("schedule") || l.starts_with("threads"))
        .collect();
    assert_eq!(headers.len(), 2, "{out}");
    for column in headers.iter().flat_map(|h| h.split_whitespace()) {
        assert!(explained(&help, column), "scaling --help: {column}");
    }
    // The prediction's key, under its table.
    let key = &out[out.find("\nthreads ").unwrap()..];
    for column in ["item-cost", "adjusted, error", "imbalance"] {
        assert!(
            key.lines().any(|l| l.trim_start().starts_with(column)),
            "{out}"
        );
    }
    let chart = std::fs::read_to_string(dir.join("scaling.svg")).unwrap();
    assert!(chart.contains("predicted past 2 threads"), "no third panel");
    // converge's and bench's tables, by their headers.
    for (command, header) in [
        ("converge", "method spp seconds RMSE relMSE"),
        (
            "bench",
            "mesh tris B/tri peak/tri query rays mode thr Mrays/s Embree ratio",
        ),
    ] {
        let help = stdout(&strata(&dir, &[command, "--help"]));
        for column in header.split_whitespace() {
            assert!(explained(&help, column), "{command} --help: {column}");
        }
    }
}
