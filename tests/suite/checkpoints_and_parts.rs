//! Checkpoints and parts through the real binary: an existing checkpoint
//! is never discarded silently and can be previewed, one of another spp
//! says what to do instead (and the plan it gives runs), parts of
//! another build are refused unless forced, and a merged PNG shows the
//! film as `strata render` would (the scene's exposure and tone curve).

use crate::common::scenes::{LIT_SPHERE, SPHERE_ON_PLANE};
use crate::common::{load_scene, stderr, stdout, strata};
use strata::partial::format::{read_partial, write_partial, PartialHeader};
use strata::render::{each_pass, render, RenderOptions, SliceSpec};

#[test]
fn an_existing_checkpoint_is_never_discarded_and_can_be_previewed() {
    let dir = crate::common::temp_dir("checkpoint");
    std::fs::write(dir.join("s.toml"), SPHERE_ON_PLANE).unwrap();
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
fn a_checkpoint_of_another_spp_says_what_to_do_instead() {
    let dir = crate::common::temp_dir("words-resume");
    std::fs::write(dir.join("scene.toml"), LIT_SPHERE).unwrap();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", "scene.toml", "-q", "-o", "x.png"];
        args.extend_from_slice(extra);
        strata(&dir, &args)
    };
    let o = render(&["--checkpoint", "ck.strata"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = render(&["--spp", "8", "--checkpoint", "ck.strata", "--resume"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    for needle in [
        "ck.strata: the checkpoint is of a 4-spp render and this one asks for 8, which is a new render",
        "stratified set",
        "strata merge on it writes its 4-spp image",
        "--spp 8 --slice 0/2 -o part_0.strata",
    ] {
        assert!(e.contains(needle), "'{needle}' missing from: {e}");
    }
    // The plan it gives runs: the first slice now, a preview of it, the
    // rest later, and the merge is the 8-spp render.
    for args in [
        &[
            "render",
            "scene.toml",
            "-q",
            "--spp",
            "8",
            "--slice",
            "0/2",
            "-o",
            "part_0.strata",
        ][..],
        &[
            "merge",
            "-q",
            "--partial",
            "part_0.strata",
            "-o",
            "preview.png",
        ],
        &[
            "render",
            "scene.toml",
            "-q",
            "--spp",
            "8",
            "--slice",
            "1/2",
            "-o",
            "part_1.strata",
        ],
        &[
            "merge",
            "-q",
            "part_0.strata",
            "part_1.strata",
            "-o",
            "merged.strata",
        ],
        &[
            "render",
            "scene.toml",
            "-q",
            "--spp",
            "8",
            "-o",
            "whole.strata",
        ],
        &["merge", "-q", "merged.strata", "-o", "merged.exr"],
        &["merge", "-q", "whole.strata", "-o", "whole.exr"],
    ] {
        let o = strata(&dir, args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
    }
    let (merged, whole) = (
        crate::common::exr::read_exr(&dir.join("merged.exr")),
        crate::common::exr::read_exr(&dir.join("whole.exr")),
    );
    for c in ["R", "G", "B"] {
        assert_eq!(merged.channel(c), whole.channel(c), "{c}");
    }
}

#[test]
fn parts_of_another_build_are_refused_unless_forced() {
    let dir = crate::common::temp_dir("builds");
    std::fs::write(dir.join("s.toml"), SPHERE_ON_PLANE).unwrap();
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

/// A merge never writes over one of its own parts (it would then hold
/// every slice, and the next merge of the same parts would fail on a
/// duplicate), named however the path is written; nor does a render write
/// its stats and its timeline to one file. A slice's part may still be
/// its own checkpoint.
#[test]
fn no_output_overwrites_an_input_or_another_output() {
    let dir = crate::common::temp_dir("overwrite");
    std::fs::write(dir.join("s.toml"), SPHERE_ON_PLANE).unwrap();
    for k in 0..2 {
        let (slice, out) = (format!("{k}/2"), format!("p{k}.strata"));
        let args = [
            "render",
            "s.toml",
            "-q",
            "--slice",
            &slice,
            "-o",
            &out,
            "--checkpoint",
            &out,
            "--resume",
        ];
        let o = strata(&dir, &args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let before = std::fs::read(dir.join("p0.strata")).unwrap();
    let name = dir.file_name().unwrap().to_string_lossy();
    let round_about = format!("../{name}/p1.strata");
    for output in ["p0.strata", "./p0.strata", &round_about] {
        let o = strata(&dir, &["merge", "p0.strata", "p1.strata", "-o", output]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{output}: {err}");
        assert!(
            err.contains("--output") && err.contains("is one of the parts it merges"),
            "{err}"
        );
    }
    assert_eq!(std::fs::read(dir.join("p0.strata")).unwrap(), before);
    let o = strata(
        &dir,
        &["merge", "p0.strata", "p1.strata", "-o", "all.strata"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let args = [
        "render",
        "s.toml",
        "-q",
        "-o",
        "a.png",
        "--stats",
        "r.json",
        "--timeline",
        "./r.json",
    ];
    let o = strata(&dir, &args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--timeline: './r.json' is also the --stats file"),
        "{err}"
    );
    assert!(!dir.join("a.png").exists() && !dir.join("r.json").exists());
}

/// A sliced render of a scene with its own exposure and tone curve merges
/// into the PNG that one process writes; parts of different curves are
/// refused with the way out, and the merge's flags choose another display.
#[test]
fn a_merged_png_shows_the_film_as_the_render_does() {
    let dir = crate::common::temp_dir("display");
    let scene = LIT_SPHERE.replacen(
        "[render]",
        "[render]\nexposure = 3.0\ntonemap = \"filmic\"",
        1,
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let ok = |args: &[&str]| {
        let o = strata(&dir, args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
    };
    ok(&["render", "s.toml", "-q", "-o", "whole.png"]);
    ok(&[
        "render",
        "s.toml",
        "-q",
        "-o",
        "clamp.png",
        "--tonemap",
        "clamp",
    ]);
    for k in 0..2 {
        let (slice, out) = (format!("{k}/2"), format!("p{k}.strata"));
        ok(&["render", "s.toml", "-q", "--slice", &slice, "-o", &out]);
    }
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
    ok(&["merge", "-q", "p0.strata", "p1.strata", "-o", "merged.png"]);
    assert_eq!(read("merged.png"), read("whole.png"));
    // The display changes the PNG (the scene is bright enough to tell).
    assert_ne!(read("clamp.png"), read("whole.png"));
    ok(&[
        "merge",
        "-q",
        "--tonemap",
        "clamp",
        "p0.strata",
        "p1.strata",
        "-o",
        "c.png",
    ]);
    assert_eq!(read("c.png"), read("clamp.png"));
    // A merged part keeps the display too.
    ok(&["merge", "-q", "p0.strata", "-o", "half.strata"]);
    assert_eq!(
        read_partial(&dir.join("half.strata"))
            .unwrap()
            .header
            .exposure,
        3.0
    );

    let p1 = dir.join("p1.strata");
    let mut part = read_partial(&p1).unwrap();
    part.header.tonemap = strata::output::tonemap::Tonemap::Clamp;
    write_partial(&p1, &part.header, &part.film).unwrap();
    let o = strata(&dir, &["merge", "p0.strata", "p1.strata", "-o", "m.png"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("tone curve") && e.contains("--tonemap"), "{e}");
    assert!(!dir.join("m.png").exists());
    ok(&[
        "merge",
        "-q",
        "--tonemap",
        "filmic",
        "p0.strata",
        "p1.strata",
        "-o",
        "m.png",
    ]);
    assert_eq!(read("m.png"), read("whole.png"));
    // An EXR shows neither the curve nor the exposure: such parts merge.
    ok(&["merge", "-q", "p0.strata", "p1.strata", "-o", "m.exr"]);
    // Another exposure is refused for a PNG as another curve is.
    part.header.tonemap = strata::output::tonemap::Tonemap::Filmic;
    part.header.exposure = 1.0;
    write_partial(&p1, &part.header, &part.film).unwrap();
    let o = strata(&dir, &["merge", "p0.strata", "p1.strata", "-o", "e.png"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("exposure: 1 vs 3 stops") && e.contains("--exposure"),
        "{e}"
    );
    ok(&[
        "merge",
        "-q",
        "--exposure",
        "3",
        "p0.strata",
        "p1.strata",
        "-o",
        "e.png",
    ]);
    assert_eq!(read("e.png"), read("whole.png"));
    // A part of another size is told its size, not the scene's fingerprint.
    let wider = (part.header.width + 1).to_string();
    let args = [
        "render", "s.toml", "-q", "--slice", "1/2", "--width", &wider, "-o", "w.strata",
    ];
    ok(&args);
    let o = strata(&dir, &["merge", "p0.strata", "w.strata", "-o", "s.exr"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("resolution: ") && !e.contains("fingerprint"),
        "{e}"
    );
}
