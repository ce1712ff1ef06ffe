//! How `strata` reads its command line, through the real binary: a bare
//! `strata` renders the built-in scene in any directory, every output path
//! is checked before the scene is loaded, and mistyped commands and
//! misplaced flags get a suggestion.

use crate::common::scenes::SPHERE_ON_PLANE;
use crate::common::{stderr, stdout, strata};

#[test]
fn a_bare_strata_renders_the_built_in_scene_in_any_directory() {
    let dir = crate::common::temp_dir("bare");
    let o = strata(&dir, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(dir.join("render.png").is_file());
    assert!(stdout(&o).contains("-> render.png"), "{}", stdout(&o));
}

/// Flags whose mistakes were found only after the work they spoil (a
/// whole render, a reference, a mesh's benchmark) are refused before it:
/// with the scene or first mesh missing, their error must come first, and
/// nothing is printed to standard output.
#[test]
fn mistaken_flags_are_refused_before_any_work() {
    let dir = crate::common::temp_dir("flags-first");
    for (args, said) in [
        (
            &[
                "render",
                "missing.toml",
                "-o",
                "x.exr",
                "--aov",
                "normal,depth,normal",
            ][..],
            "--aov: normal is named twice",
        ),
        (
            &["converge", "missing.toml", "--noise", "0.1,-1"],
            "--noise -1: must be relative errors above 0",
        ),
        (
            &["bench", "missing.obj", "--no-embree", "--csv", "b.csv"],
            "missing.obj: cannot open",
        ),
        (
            &["bench", "missing.toml", "--no-embree", "--csv", "b.csv"],
            "missing.toml: cannot load '.toml' files as a mesh",
        ),
    ] {
        let o = strata(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(said), "{args:?}: {}", stderr(&o));
        assert_eq!(stdout(&o), "", "{args:?}: work began before the refusal");
    }
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
    std::fs::write(dir.join("s.toml"), SPHERE_ON_PLANE).unwrap();
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

/// Issue 62: a flag far from every real one gets no suggestion (clap's
/// Jaro similarity offered `--resume` for `--exposure`, `--timeline` for
/// `--time`, before both were flags), a slip gets one, and a negative count says its least value
/// instead of advising `-- -4`.
#[test]
fn suggestions_are_near_misses_and_negative_counts_name_their_least_value() {
    let dir = crate::common::temp_dir("flag-words");
    for (args, far) in [
        (&["render", "--resolve", "2"][..], "--resume"),
        (&["render", "--timelapse", "2"][..], "--timeline"),
    ] {
        let o = strata(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = stderr(&o);
        assert!(e.contains(&format!("'{}'", args[1])), "{args:?}: {e}");
        assert!(!e.contains(far) && !e.contains("tip:"), "{args:?}: {e}");
    }
    let o = strata(&dir, &["render", "--shadow-sample", "2"]);
    assert!(
        stderr(&o).contains("a similar argument exists: '--shadow-samples'"),
        "{}",
        stderr(&o)
    );
    for (args, least) in [
        (&["render", "--spp", "-4"][..], 1),
        (&["render", "--width", "-100"][..], 1),
        (&["render", "model.glb", "--camera", "-1"][..], 0),
        (&["render", "--passes", "0"][..], 1),
        (&["converge", "s.toml", "--max-spp", "-2"][..], 1),
    ] {
        let o = strata(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = stderr(&o);
        assert!(
            e.contains(&format!("for '{}", args[args.len() - 2]))
                && e.contains(&format!("must be at least {least}")),
            "{args:?}: {e}"
        );
        assert!(!e.contains("-- -"), "{args:?}: {e}");
    }
}
