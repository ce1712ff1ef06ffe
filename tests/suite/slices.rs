//! Sample slices across threads, processes and interruptions: the image is
//! bit-identical however the work is split, bad parts are refused, and
//! slicing keeps each pixel's one stratified set.

use crate::common::films::{film_of, part};
use crate::common::process::{repo, strata, strata_command};
use crate::common::{scene, temp_dir};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use strata::partial::format::read_partial;
use strata::partial::merge::{merge_partials, MergeRules};

/// An image's pixels as bits: exact, and blind to EXR header attributes
/// such as the render time.
fn pixel_bits(path: &std::path::Path) -> Vec<[u32; 3]> {
    let (pixels, _, _) = strata::output::image::read_image(path).unwrap();
    pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// Rules for merging every slice into an image.
const ALL: MergeRules = MergeRules {
    require_all: true,
    preview: false,
    force: false,
};
use strata::render::film::{Film, PixelSum};
use strata::render::{render, RenderOptions, SliceSpec};
use strata::sampling::hash::hash_words;
use strata::sampling::{Dim, PixelSampler};
use strata::scene::Scene;
use strata::shade::{Integrator, SampleContext};

/// Mirrors, Fresnel glass and a point light: every kind of ray.
const BUSY: &str = "[render]\nwidth = 40\nheight = 30\nspp = 10\nmax_depth = 6\n\
    [camera]\nposition = [0.0, 1.0, 6.0]\nlook_at = [0.0, 0.5, 0.0]\n\
    [materials.glass]\ndiffuse = [0.0, 0.0, 0.0]\ntransparency = 1.0\nfresnel = true\n\
    [materials.mirror]\ndiffuse = [0.0, 0.0, 0.0]\nreflectivity = 0.9\n\
    [[lights]]\ntype = \"point\"\nposition = [2.0, 5.0, 4.0]\nintensity = [40.0, 40.0, 40.0]\n\
    [[objects]]\nplane = { normal = [0.0, 1.0, 0.0] }\n\
    [[objects]]\nsphere = { center = [-0.8, 0.6, 0.0], radius = 0.6 }\nmaterial = \"glass\"\n\
    [[objects]]\nsphere = { center = [0.8, 0.6, -0.5], radius = 0.6 }\nmaterial = \"mirror\"\n";

#[test]
fn slices_merged_equal_one_render_for_any_split_and_thread_count() {
    let s = scene(BUSY);
    let whole = film_of(&s, SliceSpec::WHOLE, 1);
    assert!(whole.counts.iter().all(|&c| c == 10));
    for threads in [2, 3, 8] {
        assert_eq!(
            whole,
            film_of(&s, SliceSpec::WHOLE, threads),
            "{threads} threads"
        );
    }
    for p in [1u32, 2, 3, 5] {
        // Each slice on a different thread count, merged in reverse order.
        let mut parts: Vec<_> = (0..p)
            .map(|k| part(&s, SliceSpec { index: k, count: p }, 1 + k as usize % 3))
            .collect();
        parts.reverse();
        let merged = merge_partials(parts, ALL).unwrap();
        assert_eq!(merged.header.samples, 0..10);
        assert_eq!(merged.film, whole, "P = {p}");
        assert_eq!(merged.film.to_rgb(), whole.to_rgb());
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Wait until `path` exists (or fail after a generous timeout).
fn wait_for(path: &Path, child: &mut std::process::Child) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render ended before writing {}",
            path.display()
        );
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// True if this process ignores SIGINT (bit 1 of `SigIgn` in
/// /proc/self/status); children inherit that.
fn sigint_ignored() -> bool {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("SigIgn:"))
        .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .is_some_and(|mask| mask & (1 << 1) != 0)
}

fn unfinished(ck: &Path) -> u32 {
    let p = read_partial(ck).unwrap();
    assert!(
        !p.header.is_complete(),
        "the render finished before it was killed: the test proves nothing"
    );
    p.header.samples.end
}

#[test]
fn a_killed_render_resumes_to_the_same_bits() {
    let dir = temp_dir("resume");
    let scene_path = dir.join("scene.toml");
    // About a second of work in 96 passes, so a kill lands mid-render.
    let text = BUSY
        .replace("width = 40", "width = 48")
        .replace("height = 30", "height = 36")
        .replace("spp = 10", "spp = 384");
    std::fs::write(&scene_path, text).unwrap();
    let full = dir.join("full.exr");
    let out = dir.join("resumed.exr");
    let ck = dir.join("ck.strata");
    let o = strata(
        repo(),
        &["render", s(&scene_path), "-o", s(&full), "--quiet"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let start_render = || {
        strata_command(repo())
            .args(["render", s(&scene_path), "-o", s(&out), "--quiet"])
            .args(["--threads", "1", "--passes", "96", "--checkpoint", s(&ck)])
            .arg("--resume")
            .spawn()
            .unwrap()
    };
    // SIGINT after the first checkpoint: the default action ends the process.
    // A job started in the background by a non-interactive shell (as CI may
    // run us) inherits SIGINT as ignored, and so would the render: then send
    // SIGTERM, whose default action is the same.
    let signal = if sigint_ignored() { "TERM" } else { "INT" };
    let mut child = start_render();
    wait_for(&ck, &mut child);
    let sent = Command::new("sh")
        .args(["-c", &format!("kill -{signal} {}", child.id())])
        .status()
        .unwrap();
    assert!(sent.success());
    assert!(!child.wait().unwrap().success());
    let first = unfinished(&ck);

    // Resume, then SIGKILL once the checkpoint has moved on.
    let mut child = start_render();
    let start = Instant::now();
    loop {
        if read_partial(&ck).is_ok_and(|p| p.header.samples.end > first) {
            break;
        }
        assert!(child.try_wait().unwrap().is_none(), "finished too soon");
        assert!(start.elapsed() < Duration::from_secs(120));
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let second = unfinished(&ck);
    assert!(second > first);
    assert!(!out.exists(), "a killed render wrote no image");

    // Finish, on a different thread count.
    let o = strata(
        repo(),
        &[
            "render",
            s(&scene_path),
            "-o",
            s(&out),
            "--quiet",
            "--threads",
            "2",
            "--checkpoint",
            s(&ck),
            "--resume",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        pixel_bits(&full),
        pixel_bits(&out),
        "resumed image differs from the uninterrupted one"
    );
    assert!(read_partial(&ck).unwrap().header.is_complete());

    // A checkpoint of other settings is refused, naming the file.
    let o = strata(
        repo(),
        &[
            "render",
            s(&scene_path),
            "-o",
            s(&out),
            "--spp",
            "7",
            "--checkpoint",
            s(&ck),
            "--resume",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("ck.strata") && err.contains("spp"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The parts of a 3-way split of a small scene, and the whole as EXR.
struct Parts {
    dir: crate::common::TempDir,
    scene: PathBuf,
}

impl Parts {
    fn new(name: &str) -> Self {
        let dir = temp_dir(name);
        let scene = dir.join("scene.toml");
        let text = BUSY
            .replace("width = 40", "width = 16")
            .replace("height = 30", "height = 12")
            .replace("spp = 10", "spp = 5");
        std::fs::write(&scene, text).unwrap();
        Self { dir, scene }
    }

    fn render(&self, name: &str, extra: &[&str]) -> PathBuf {
        let out = self.dir.join(name);
        let o = strata(
            repo(),
            &[&["render", s(&self.scene), "-o", s(&out), "--quiet"], extra].concat(),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    }

    fn slice(&self, k: u32) -> PathBuf {
        self.render(&format!("part_{k}.strata"), &["--slice", &format!("{k}/3")])
    }
}

/// Run `strata merge`, expect exit 2 with one line naming `blame`, and no output.
fn refused(dir: &Path, parts: &[&Path], blame: &Path, what: &str) {
    let out = dir.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| s(p)));
    args.extend(["-o", s(&out)]);
    let o = strata(repo(), &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: one line: {err}");
    assert!(
        err.contains(s(blame)),
        "{what}: names {}: {err}",
        blame.display()
    );
    assert!(!err.contains("panicked"), "{what}: {err}");
    let leftovers = std::fs::read_dir(dir).unwrap().any(|e| {
        let n = e.unwrap().file_name().to_string_lossy().to_string();
        n.starts_with("merged") || n.contains(".tmp-")
    });
    assert!(!leftovers, "{what}: output left behind");
}

#[test]
fn merge_writes_the_one_process_image_and_refuses_bad_parts() {
    let t = Parts::new("merge");
    let whole = t.render("whole.exr", &[]);
    let [p0, p1, p2] = [0, 1, 2].map(|k| t.slice(k));

    // The good case, parts in any order, and a staged merge through .strata.
    let merged = t.dir.join("good.exr");
    let o = strata(
        repo(),
        &["merge", s(&p2), s(&p0), s(&p1), "-o", s(&merged), "-q"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(pixel_bits(&whole), pixel_bits(&merged));
    let first_two = t.dir.join("p01.strata");
    assert!(strata(
        repo(),
        &["merge", s(&p0), s(&p1), "-o", s(&first_two), "-q"]
    )
    .status
    .success());
    let staged = t.dir.join("staged.exr");
    assert!(strata(
        repo(),
        &["merge", s(&first_two), s(&p2), "-o", s(&staged), "-q"]
    )
    .status
    .success());
    assert_eq!(pixel_bits(&whole), pixel_bits(&staged));

    // Another scene: the glass sphere moved.
    let other_scene = t.dir.join("other.toml");
    let text = std::fs::read_to_string(&t.scene)
        .unwrap()
        .replace("[-0.8, 0.6, 0.0]", "[-0.8, 0.6, 0.1]");
    std::fs::write(&other_scene, text).unwrap();
    let other = t.dir.join("other_1.strata");
    let o = strata(
        repo(),
        &[
            "render",
            s(&other_scene),
            "--slice",
            "1/3",
            "-o",
            s(&other),
            "-q",
        ],
    );
    assert!(o.status.success());
    refused(&t.dir, &[&p0, &other, &p2], &other, "different scene");

    // Other settings: seed; and a different P.
    let seeded = t.render("seed_1.strata", &["--slice", "1/3", "--seed", "7"]);
    refused(&t.dir, &[&p0, &seeded, &p2], &seeded, "different seed");
    let fourths = t.render("q_1.strata", &["--slice", "1/4"]);
    refused(&t.dir, &[&p0, &fourths, &p2], &fourths, "different P");

    // Duplicate and missing slices.
    let copy = t.dir.join("copy_of_1.strata");
    std::fs::copy(&p1, &copy).unwrap();
    refused(&t.dir, &[&p0, &p1, &copy, &p2], &copy, "duplicate");
    refused(&t.dir, &[&p0, &p2], &p2, "missing middle");
    refused(&t.dir, &[&p0, &p1], &p1, "missing last");

    // Truncated, corrupt and garbage files.
    let bytes = std::fs::read(&p1).unwrap();
    let cut = t.dir.join("cut_1.strata");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    refused(&t.dir, &[&p0, &cut, &p2], &cut, "truncated");
    let flipped = t.dir.join("flipped_1.strata");
    let mut f = bytes.clone();
    f[bytes.len() / 2] ^= 1;
    std::fs::write(&flipped, f).unwrap();
    refused(&t.dir, &[&p0, &flipped, &p2], &flipped, "corrupt");
    let mut ck = read_partial(&p1).unwrap();
    ck.header.samples.end -= 1;
    let unfinished = t.dir.join("unfinished_1.strata");
    strata::partial::format::write_partial(&unfinished, &ck.header, &ck.film).unwrap();
    refused(
        &t.dir,
        &[&p0, &unfinished, &p2],
        &unfinished,
        "unfinished checkpoint",
    );
    let garbage = t.dir.join("garbage.strata");
    std::fs::write(&garbage, b"this is not a partial render at all\n").unwrap();
    refused(&t.dir, &[&p0, &garbage, &p2], &garbage, "garbage");
    let missing_file = t.dir.join("nowhere.strata");
    refused(&t.dir, &[&p0, &missing_file], &missing_file, "no such file");
    std::fs::remove_dir_all(&t.dir).ok();
}

#[test]
fn bad_slices_and_outputs_are_refused_on_one_line() {
    let t = Parts::new("badslice");
    for (args, mention) in [
        (vec!["--slice", "3/3"], "3/3"),
        (vec!["--slice", "x/3"], "x"),
        (vec!["--slice", "1/0"], "1/0"),
        (vec!["--slice", "1/3", "-o", "part.png"], "--slice"),
        (vec!["-o", "out.jpg"], "--output"),
        (vec!["--checkpoint", "ck.png"], "--checkpoint"),
        (vec!["--timeline", "trace.txt"], "--timeline"),
        (vec!["--timeline", "no/such/dir/trace.json"], "--timeline"),
    ] {
        let o = strata(
            repo(),
            &[&["render", s(&t.scene), "-q"], args.as_slice()].concat(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{args:?}: one line: {err}"
        );
        assert!(err.contains(mention), "{args:?}: {err}");
    }
    assert!(!Path::new("part.png").exists());
    // More slices than samples: a slice without samples renders (its part
    // merges as nothing) but says so, with how many slices would do.
    let part = t.dir.join("empty.strata");
    let args = [
        "render",
        s(&t.scene),
        "-q",
        "--spp",
        "4",
        "--slice",
        "4/8",
        "-o",
        s(&part),
    ];
    let o = strata(repo(), &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: slice 4/8 of 4 spp holds no samples: split into at most 4 slices"),
        "{err}"
    );
    std::fs::remove_dir_all(&t.dir).ok();
}

/// Recording a timeline changes no bit of the film, and it holds every
/// work item once: each pass's items cover every pixel exactly once, and
/// their rays add up to the render's.
#[test]
fn a_timeline_holds_every_work_item_and_changes_no_bit() {
    use strata::render::timeline::Timeline;
    use strata::render::Schedule;
    let scene = scene(BUSY);
    let pixels = scene.settings.width * scene.settings.height;
    for schedule in [Schedule::Slices, Schedule::Regions] {
        for threads in [1, 3] {
            let opts = |timeline| RenderOptions {
                threads,
                schedule,
                passes: Some(3),
                timeline,
                ..RenderOptions::default()
            };
            let plain = render(&scene, &opts(None), None, ());
            let timeline = std::sync::Arc::new(Timeline::new(Instant::now()));
            let traced = render(&scene, &opts(Some(timeline.clone())), None, ());
            let case = format!("{schedule:?}, {threads} threads");
            assert!(plain.film == traced.film, "{case}: the film changed");
            let items = timeline.items();
            let rays: u64 = items.iter().map(|i| i.rays).sum();
            assert_eq!(rays, traced.counts.total(), "{case}");
            for pass in 0..3 {
                let mut covered: Vec<_> = items
                    .iter()
                    .filter(|i| i.pass == pass)
                    .map(|i| i.pixels.clone())
                    .collect();
                covered.sort_by_key(|r| r.start);
                let joined = covered.windows(2).all(|w| w[0].end == w[1].start);
                assert!(joined && covered[0].start == 0, "{case}: {covered:?}");
                assert_eq!(covered.last().unwrap().end, pixels, "{case}");
            }
            assert!(items
                .iter()
                .all(|i| i.thread < threads && i.end_ns >= i.start_ns));
        }
    }
}

/// `strata render --timeline`: Chrome's trace event format with the six
/// fields on every event, a track per thread used, spans that never
/// overlap on a track, and work items whose rays are the render's.
#[test]
fn the_timeline_is_a_trace_perfetto_opens() {
    let t = Parts::new("timeline");
    let (trace, stats) = (t.dir.join("trace.json"), t.dir.join("stats.json"));
    let out = t.dir.join("out.png");
    let o = strata(
        repo(),
        &[
            "render",
            s(&t.scene),
            "-q",
            "--threads",
            "3",
            "--passes",
            "2",
            "--timeline",
            s(&trace),
            "--stats",
            s(&stats),
            "-o",
            s(&out),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let events = json["traceEvents"].as_array().unwrap();
    for e in events {
        for field in ["ph", "ts", "dur", "pid", "tid", "name"] {
            assert!(e.get(field).is_some(), "no {field}: {e}");
        }
    }
    let spans: Vec<&serde_json::Value> = events.iter().filter(|e| e["ph"] == "X").collect();
    let tracks: std::collections::BTreeSet<u64> =
        spans.iter().map(|e| e["tid"].as_u64().unwrap()).collect();
    let workers: std::collections::BTreeSet<u64> = spans
        .iter()
        .filter(|e| e["name"] == "work item")
        .map(|e| e["tid"].as_u64().unwrap())
        .collect();
    assert!(!workers.contains(&0) && workers.len() <= 3 && !workers.is_empty());
    assert!(tracks.contains(&0), "the main track");
    let named: std::collections::BTreeSet<u64> = events
        .iter()
        .filter(|e| e["name"] == "thread_name")
        .map(|e| e["tid"].as_u64().unwrap())
        .collect();
    assert!(workers.is_subset(&named), "every track used is named");
    for tid in &tracks {
        let mut on_track: Vec<(f64, f64)> = spans
            .iter()
            .filter(|e| e["tid"].as_u64() == Some(*tid))
            .map(|e| {
                let ts = e["ts"].as_f64().unwrap();
                (ts, ts + e["dur"].as_f64().unwrap())
            })
            .collect();
        on_track.sort_by(|a, b| a.0.total_cmp(&b.0));
        for w in on_track.windows(2) {
            // Times are printed in µs to the nanosecond.
            assert!(w[0].1 <= w[1].0 + 1e-3, "track {tid}: {w:?} overlap");
        }
    }
    let names: Vec<&str> = spans.iter().filter_map(|e| e["name"].as_str()).collect();
    for phase in ["load", "BVH build", "pass 1", "pass 2", "output"] {
        assert!(names.contains(&phase), "no {phase} span");
    }
    let rays: u64 = spans
        .iter()
        .filter(|e| e["name"] == "work item")
        .map(|e| e["args"]["rays"].as_u64().unwrap())
        .sum();
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(rays, stats["rays_total"].as_u64().unwrap());
    let summary = &stats["timeline"];
    let busy: f64 = summary["threads"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["busy_s"].as_f64().unwrap())
        .sum();
    assert!(busy > 0.0 && summary["longest_item_s"].as_f64() >= summary["mean_item_s"].as_f64());
    std::fs::remove_dir_all(&t.dir).ok();
}

/// A hard, oblique edge of an emitter: each pixel on it averages a step
/// over its area (antialiasing jitter), where stratification pays most.
const HARD_EDGE: &str = "[render]\nwidth = 12\nheight = 8\nspp = 16\n\
    [camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 10.0\n\
    [materials.glow]\ndiffuse = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\n\
    [[objects]]\ntriangle = { v = [[-0.4, -0.8, 0.0], [40.0, 0.0, 0.0], [0.4, 0.8, 0.0]] }\nmaterial = \"glow\"\n";

/// The mistake slicing must not make: each slice a fresh, separately
/// stratified set of its own N/P samples. Built here, for this test only.
fn render_with_fresh_sets_per_slice(scene: &Scene, slices: u32) -> Vec<Vec3> {
    let st = &scene.settings;
    let mut integrator = Integrator::new(scene);
    (0..st.width * st.height)
        .map(|index| {
            let (x, y) = (index % st.width, index / st.width);
            let mut acc = PixelSum::default();
            for k in 0..slices {
                let range = SliceSpec {
                    index: k,
                    count: slices,
                }
                .samples(st.spp);
                let n = range.len() as u32;
                let seed = hash_words(&[st.seed, k, 0x5eed]);
                let sampler = PixelSampler::new(st.sampler, seed, index);
                for i in 0..n {
                    let ctx = SampleContext::new(sampler, i, n);
                    let film = Vec2::new(x as f32, y as f32) + sampler.get_2d(Dim::PIXEL, i, n);
                    acc.add(integrator.camera_sample(&ctx, film), i);
                }
            }
            let mut f = Film::new(1, 1);
            f.add_pixel(0, &acc);
            f.mean(0)
        })
        .collect()
}

/// Mean over pixels of the per-pixel variance over seeds (red channel).
fn mean_variance(images: &[Vec<Vec3>]) -> f64 {
    let n = images.len() as f64;
    let pixels = images[0].len();
    (0..pixels)
        .map(|i| {
            let mean = images.iter().map(|im| im[i].x as f64).sum::<f64>() / n;
            images
                .iter()
                .map(|im| (im[i].x as f64 - mean).powi(2))
                .sum::<f64>()
                / (n - 1.0)
        })
        .sum::<f64>()
        / pixels as f64
}

#[test]
fn slicing_keeps_the_stratification_of_the_whole_set() {
    let base = scene(HARD_EDGE);
    let p = 4;
    let (mut whole, mut sliced, mut fresh) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..64 {
        let mut sc = base.clone();
        sc.settings.seed = seed;
        whole.push(film_of(&sc, SliceSpec::WHOLE, 1).to_rgb());
        let parts = (0..p)
            .map(|k| part(&sc, SliceSpec { index: k, count: p }, 1))
            .collect();
        sliced.push(merge_partials(parts, ALL).unwrap().film.to_rgb());
        fresh.push(render_with_fresh_sets_per_slice(&sc, p));
    }
    let (vw, vs, vf) = (
        mean_variance(&whole),
        mean_variance(&sliced),
        mean_variance(&fresh),
    );
    eprintln!("variance over seeds: whole {vw:.3e}, sliced {vs:.3e}, fresh per slice {vf:.3e}");
    assert!(vw > 1e-6, "the scene must be noisy: variance {vw}");
    assert_eq!(vs, vw, "sliced variance must equal unsliced variance");
    assert!(
        vf > 1.4 * vw,
        "fresh per-slice sets should be measurably worse: {vf:.3e} vs {vw:.3e}"
    );
}
