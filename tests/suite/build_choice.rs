//! The build that fits the render: `auto` chooses from the whole render's
//! settings (never a slice or the thread count), so every split builds the
//! same tree and merges to the one image; a named preset wins; the choice
//! and its reason (with the pages the tree goes on) are in `--stats` and
//! the summary line.

use crate::common::meshes::bumpy_sphere_obj;
use crate::common::process::{repo, run, strata_command, strata_ok};
use crate::common::temp_dir;
use std::path::Path;
use strata::accel::choice::MODEL_MIN_PRIMS;
use strata::accel::pages::Pages;
use strata::accel::BuildQuality;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// 2 × 320 × 200 = 128,000 triangles: over `MODEL_MIN_PRIMS`, so `auto`
/// weighs the rays; one point light, so two rays a sample.
const TRIANGLES: usize = 128_000;
const SCENE: &str = "[camera]\nposition = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\n\
    [[lights]]\ntype = \"point\"\nposition = [2.0, 3.0, 4.0]\nintensity = [30.0, 30.0, 30.0]\n\
    [[objects]]\nmesh = \"ball.obj\"\n";

fn stats(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn pixel_bits(path: &Path) -> Vec<[u32; 3]> {
    let (pixels, _, _) = strata::output::image::read_image(path).unwrap();
    pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// A preview and a long render of the same scene choose different presets,
/// each the one the model names for the whole render's rays; each slice
/// (of the preview) on each thread count chooses the same as the whole,
/// and the slices merge to the whole image bit for bit. A crop renders a
/// few pixels of the long render cheaply and leaves the choice alone. The
/// preview's tree stays on small pages, the long render's goes on huge
/// ones, and the reason says so (with `STRATA_HUGE_PAGES=off`: the rays'
/// choice alone). Where every large allocation goes on huge pages
/// (`STRATA_HUGE_PAGES=on`), the preview's tree does too, and its image is
/// the same bit for bit.
#[test]
fn auto_chooses_from_the_whole_render_for_every_slice_and_thread_count() {
    let dir = temp_dir("build-choice");
    std::fs::write(dir.join("ball.obj"), bumpy_sphere_obj(320, 200, 1.0, 0.05)).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    const { assert!(TRIANGLES >= MODEL_MIN_PRIMS) };
    let mut chosen = Vec::new();
    for (width, height, spp, crop) in [(24u32, 16u32, 2u32, false), (320, 240, 4096, true)] {
        let rays = u64::from(width * height * spp) * 2;
        let choice = BuildQuality::Auto.choose(TRIANGLES, Some(rays));
        let want = choice.quality;
        let mut settings = vec![
            "--width".to_string(),
            width.to_string(),
            "--height".into(),
            height.to_string(),
            "--spp".into(),
            spp.to_string(),
        ];
        if crop {
            settings.extend(["--crop".into(), "150,110,152,112".into()]);
        }
        // The render `name` with `extra` flags and `STRATA_HUGE_PAGES` set
        // to `pages`: its output, its stats and its summary line.
        let render_with = |name: &str, extra: &[&str], pages: &str| {
            let out = dir.join(name);
            let json = dir.join(format!("{name}.json"));
            let mut args = vec!["render", s(&scene), "-o", s(&out), "--stats", s(&json)];
            args.extend(settings.iter().map(String::as_str));
            args.extend(extra);
            let summary = run(
                strata_command(repo())
                    .args(&args)
                    .env("STRATA_HUGE_PAGES", pages),
                "strata",
            );
            (out, stats(&json), summary)
        };
        let render = |name: &str, extra: &[&str]| {
            let (out, st, summary) = render_with(name, extra, "off");
            assert_eq!(st["triangles"], TRIANGLES);
            assert_eq!(st["memory"]["huge_pages"], false);
            assert_eq!(st["bvh_quality"], want.name(), "{name}: {st}");
            let why = st["bvh_why"].as_str().unwrap().to_string();
            assert!(why.starts_with("auto: "), "{why}");
            let huge = choice.pages == Pages::Huge;
            assert_eq!(why.ends_with("; huge pages"), huge, "{why}");
            assert!(summary.contains(&format!("BVH {want} ")), "{summary}");
            assert!(summary.contains(&why), "{summary}");
            (out, why)
        };
        let (whole, why) = render("whole.exr", &["--threads", "2"]);
        let (one, why_one) = render("one.exr", &["--threads", "1"]);
        assert_eq!(why_one, why);
        let bits = pixel_bits(&whole);
        assert_eq!(pixel_bits(&one), bits, "{spp} spp: 1 and 2 threads");
        if !crop {
            let (p0, why0) = render("p0.strata", &["--slice", "0/2", "--threads", "1"]);
            let (p1, why1) = render("p1.strata", &["--slice", "1/2", "--threads", "2"]);
            assert_eq!([&why0, &why1], [&why; 2]);
            let merged = dir.join("merged.exr");
            strata_ok(repo(), &["merge", s(&p0), s(&p1), "-o", s(&merged)]);
            assert_eq!(pixel_bits(&merged), bits, "{spp} spp: merged slices");
            // Every large allocation on huge pages: the tree too.
            let (out, st, _) = render_with("huge.exr", &[], "on");
            let why_huge = st["bvh_why"].as_str().unwrap().to_string();
            assert_eq!(why_huge, format!("{why}; huge pages"));
            assert_eq!(st["memory"]["huge_pages"], true);
            assert_eq!(pixel_bits(&out), bits, "{spp} spp: on huge pages");
        }
        chosen.push((want, choice.pages));
    }
    assert_eq!(
        chosen[0],
        (BuildQuality::Preview, Pages::Small),
        "a preview builds the preview tree, on small pages"
    );
    assert!(
        !matches!(chosen[1].0, BuildQuality::Preview | BuildQuality::Fastest),
        "a long render builds more: {:?}",
        chosen[1]
    );
    assert_eq!(
        chosen[1].1,
        Pages::Huge,
        "a long render's tree on huge pages"
    );
}

/// `--bvh-quality` names the preset whatever the rays, and says so.
#[test]
fn a_named_preset_overrides_auto() {
    let dir = temp_dir("build-choice-named");
    std::fs::write(dir.join("ball.obj"), bumpy_sphere_obj(320, 200, 1.0, 0.05)).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    for q in ["high", "fastest", "preview"] {
        let json = dir.join("s.json");
        let out = dir.join("o.png");
        // On the rays' choice of pages alone: small for 8 × 8 pixels.
        let summary = run(
            strata_command(repo())
                .args([
                    "render",
                    s(&scene),
                    "-o",
                    s(&out),
                    "--width",
                    "8",
                    "--height",
                    "8",
                    "--spp",
                    "1",
                    "--bvh-quality",
                    q,
                    "--stats",
                    s(&json),
                ])
                .env("STRATA_HUGE_PAGES", "off"),
            "strata",
        );
        let st = stats(&json);
        assert_eq!(
            (st["bvh_quality"].as_str(), st["bvh_why"].as_str()),
            (Some(q), Some("as asked"))
        );
        assert!(summary.contains(&format!("BVH {q} ")), "{summary}");
    }
}

/// `STRATA_HUGE_PAGES` other than auto, on or off is an input error
/// naming the variable and the values it takes, before any work.
#[test]
fn a_huge_pages_setting_it_does_not_know_is_refused() {
    let dir = temp_dir("huge-pages-bad");
    let out = dir.join("seed.png");
    let o = strata_command(repo())
        .args(["render", "scenes/seed.toml", "-o"])
        .arg(&out)
        .env("STRATA_HUGE_PAGES", "always")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with(
            "error: <environment>: STRATA_HUGE_PAGES: 'always': expected auto, on or off"
        ),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
}
