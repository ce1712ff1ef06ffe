//! A new user's first hour, through the real binary: a bare `strata`
//! works anywhere, every output path is checked before any work, no
//! checkpoint is discarded silently, mistyped commands get a suggestion,
//! parts of different builds do not mix, and the figures printed say what
//! was done.

use crate::common::{load_scene, stderr, stdout, strata};
use strata::partial::format::{read_partial, write_partial, PartialHeader};
use strata::render::{each_pass, render, RenderOptions, SliceSpec};

/// A small scene with one light and one triangle-free sphere.
const SMALL: &str = r#"
[render]
width = 16
height = 12
spp = 8
[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = [10.0, 10.0, 10.0]
[[objects]]
sphere = { center = [0.0, 0.5, 0.0], radius = 0.5 }
[[objects]]
plane = { normal = [0.0, 1.0, 0.0] }
"#;

#[test]
fn a_bare_strata_renders_the_built_in_scene_in_any_directory() {
    let dir = crate::common::temp_dir("bare");
    let o = strata(&dir, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(dir.join("render.png").is_file());
    assert!(stdout(&o).contains("-> render.png"), "{}", stdout(&o));
}

#[test]
fn every_output_path_is_checked_before_the_scene_is_loaded() {
    let dir = crate::common::temp_dir("paths");
    // A scene that does not exist: an output error must come first.
    for (args, flag) in [
        (
            vec!["render", "missing.toml", "-o", "nodir/x.png"],
            "--output",
        ),
        (
            vec!["render", "missing.toml", "--stats", "nodir/s.json"],
            "--stats",
        ),
        (
            vec!["render", "missing.toml", "--checkpoint", "nodir/c.strata"],
            "--checkpoint",
        ),
        (vec!["render", "missing.toml", "-o", "x.jpg"], "--output"),
        (
            vec!["converge", "missing.toml", "--csv", "nodir/c.csv"],
            "--csv",
        ),
        (
            vec!["scaling", "missing.toml", "--chart", "nodir/s.svg"],
            "--chart",
        ),
        (
            vec!["merge", "missing.strata", "-o", "nodir/m.exr"],
            "--output",
        ),
    ] {
        let o = strata(&dir, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(flag), "{args:?}: {}", stderr(&o));
        assert!(
            !stderr(&o).contains("missing"),
            "{args:?}: the scene was read first"
        );
    }
    // Nothing was written: not the image beside a bad --stats path either.
    std::fs::write(dir.join("s.toml"), SMALL).unwrap();
    let o = strata(
        &dir,
        &[
            "render",
            "s.toml",
            "-o",
            "out.png",
            "--stats",
            "nodir/s.json",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(!dir.join("out.png").exists());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "only s.toml");
}

#[test]
fn an_existing_checkpoint_is_never_discarded_and_can_be_previewed() {
    let dir = crate::common::temp_dir("checkpoint");
    std::fs::write(dir.join("s.toml"), SMALL).unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "s.toml",
            "-q",
            "--checkpoint",
            "ck.strata",
            "-o",
            "out.png",
        ];
        args.extend_from_slice(extra);
        strata(&dir, &args)
    };
    // An unfinished checkpoint: the render stopped after its first pass.
    let ck = dir.join("ck.strata");
    let (scene, _) =
        load_scene(&dir.join("s.toml"), &Default::default(), Default::default()).unwrap();
    let full = SliceSpec::WHOLE.samples(scene.settings.spp);
    let header = PartialHeader::for_scene(&scene, SliceSpec::WHOLE, full.clone());
    let opts = RenderOptions {
        passes: Some(2),
        ..RenderOptions::default()
    };
    render(
        &scene,
        &opts,
        None,
        each_pass(|film, done| {
            if done == 4 {
                let h = PartialHeader {
                    samples: full.start..done,
                    ..header.clone()
                };
                write_partial(&ck, &h, film).unwrap();
            }
        }),
    );
    let before = std::fs::read(&ck).unwrap();

    let o = run(&[]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("--resume") && e.contains("delete"), "{e}");
    assert_eq!(
        std::fs::read(&ck).unwrap(),
        before,
        "the checkpoint is untouched"
    );

    // An unfinished checkpoint does not merge into an image, but previews.
    let o = strata(&dir, &["merge", "ck.strata", "-o", "m.png"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--partial"), "{}", stderr(&o));
    let o = strata(
        &dir,
        &["merge", "--partial", "ck.strata", "-o", "preview.png"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(dir.join("preview.png").is_file());
    assert!(stdout(&o).contains("preview of 1 part"), "{}", stdout(&o));
    let o = strata(&dir, &["merge", "--partial", "ck.strata", "-o", "p.strata"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "a preview is an image, not a part"
    );

    // With --resume it continues.
    let o = run(&["--resume"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(read_partial(&ck).unwrap().header.is_complete());
}

#[test]
fn parts_of_another_build_are_refused_unless_forced() {
    let dir = crate::common::temp_dir("builds");
    std::fs::write(dir.join("s.toml"), SMALL).unwrap();
    for k in 0..2 {
        let (slice, out) = (format!("{k}/2"), format!("p{k}.strata"));
        let o = strata(
            &dir,
            &["render", "s.toml", "-q", "--slice", &slice, "-o", &out],
        );
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let p1 = dir.join("p1.strata");
    let mut part = read_partial(&p1).unwrap();
    assert_eq!(part.header.strata_version, strata::VERSION);
    part.header.strata_version = "0.0.1+git.0123456789ab".into();
    write_partial(&p1, &part.header, &part.film).unwrap();
    let o = strata(&dir, &["merge", "p0.strata", "p1.strata", "-o", "m.exr"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("0.0.1+git.0123456789ab") && stderr(&o).contains("--force"));
    let o = strata(
        &dir,
        &["merge", "--force", "p0.strata", "p1.strata", "-o", "m.exr"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The version names the build.
    let o = strata(&dir, &["--version"]);
    assert_eq!(stdout(&o).trim(), format!("strata {}", strata::VERSION));
}

#[test]
fn mistyped_commands_and_misplaced_flags_get_a_suggestion() {
    let dir = crate::common::temp_dir("typos");
    let o = strata(&dir, &["rendr", "scene.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("'render'"), "{}", stderr(&o));
    let o = strata(&dir, &["--threads", "1", "render", "scene.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("render --threads"), "{}", stderr(&o));
    let help = stdout(&strata(&dir, &["render", "--help"]));
    assert!(!help.contains("1000+"), "stale --packets help");
    assert!(help.contains("[possible values: auto, on, off]"), "{help}");
}

#[test]
fn the_summary_says_what_was_rendered() {
    let dir = crate::common::temp_dir("summary");
    std::fs::write(dir.join("s.toml"), SMALL).unwrap();
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
