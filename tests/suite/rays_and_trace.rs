//! `strata rays` and `strata trace` through the real binary: reproducible
//! files, the renderer's own answers, and one-line errors with exit code 2.

use crate::common::load_mesh_scene;
use crate::common::process::{repo, strata, strata_ok};
use std::path::{Path, PathBuf};
use strata::accel::BuildQuality;
use strata::rays::file::{encode_rays, parse_hits, read_rays, HitRecord};

const ICOSPHERE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/icosphere.obj");

fn ok(args: &[&str]) {
    strata_ok(repo(), args);
}

/// The command fails with exit code 2 and one line naming `names`.
fn rejected(args: &[&str], names: &[&str]) {
    let out = strata(repo(), args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in names {
        assert!(stderr.contains(n), "'{n}' missing from: {stderr}");
    }
}

fn path(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

#[test]
fn ray_files_are_reproducible_and_traces_do_not_depend_on_threads() {
    let dir = crate::common::temp_dir("rays-trace");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    let (a, b, c) = (
        path(&dir, "a.rays"),
        path(&dir, "b.rays"),
        path(&dir, "c.rays"),
    );
    ok(&[
        "rays",
        "all",
        ICOSPHERE,
        "-n",
        "2000",
        "--seed",
        "5",
        "-o",
        &s(&a),
        "--quiet",
    ]);
    ok(&[
        "rays",
        "all",
        ICOSPHERE,
        "-n",
        "2000",
        "--seed",
        "5",
        "-o",
        &s(&b),
        "--quiet",
    ]);
    ok(&[
        "rays",
        "all",
        ICOSPHERE,
        "-n",
        "2000",
        "--seed",
        "6",
        "-o",
        &s(&c),
        "--quiet",
    ]);
    let bytes = std::fs::read(&a).unwrap();
    assert_eq!(bytes.len(), 5 * 2000 * 32);
    assert_eq!(bytes, std::fs::read(&b).unwrap(), "same seed, same file");
    assert_ne!(
        bytes,
        std::fs::read(&c).unwrap(),
        "another seed, other rays"
    );
    let description: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("a.rays.json")).unwrap()).unwrap();
    assert_eq!(description["closed"], true, "{description}");
    let kinds: Vec<&str> = description["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["random", "camera", "grazing", "edges", "inside"]);

    let (h1, h2, occ) = (
        path(&dir, "1.hits"),
        path(&dir, "2.hits"),
        path(&dir, "occ.hits"),
    );
    // `strata trace` of the rays of `a` into `hits`, with `extra` flags:
    // its standard output once it has succeeded.
    let trace = |hits: &PathBuf, extra: &[&str]| {
        let (rays, hits) = (s(&a), s(hits));
        let mut args = vec!["trace", ICOSPHERE, "--rays", &rays, "--hits", &hits];
        args.extend_from_slice(extra);
        let out = strata(repo(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {stderr}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let summary = trace(&h1, &["--threads", "1"]);
    assert!(summary.contains("on 1 thread ("), "{summary}");
    let tree = trace(&h2, &["--threads", "2", "--quiet", "--tree"]);
    trace(&occ, &["--occlusion", "--quiet"]);
    let hits = parse_hits(&h1, &std::fs::read(&h1).unwrap()).unwrap();
    assert_eq!(std::fs::read(&h1).unwrap(), std::fs::read(&h2).unwrap());

    // The records are the renderer's own answers, and occlusion agrees.
    let (scene, _) = load_mesh_scene(Path::new(ICOSPHERE), BuildQuality::Auto).unwrap();
    // `--tree` prints the statistics of the tree it traced, and only them.
    assert_eq!(
        tree.trim_end(),
        format!("tree: {}", scene.geometry.bvh().stats())
    );
    let rays = read_rays(&a).unwrap();
    let occluded = parse_hits(&occ, &std::fs::read(&occ).unwrap()).unwrap();
    for (i, ray) in rays.iter().enumerate() {
        assert_eq!(
            hits[i],
            HitRecord::from_hit(scene.geometry.intersect(ray)),
            "ray {i}"
        );
        let expected = if hits[i].is_hit() {
            HitRecord::OCCLUDED
        } else {
            HitRecord::MISS
        };
        assert_eq!(occluded[i], expected, "ray {i}");
    }
    // Every inside ray hits the closed icosphere, every edge ray at its target.
    for (k, kind) in kinds.iter().enumerate() {
        let range = k * 2000..(k + 1) * 2000;
        if *kind == "inside" {
            assert!(hits[range.clone()].iter().all(HitRecord::is_hit));
        }
        if *kind == "edges" {
            assert!(hits[range].iter().all(|h| (h.t - 1.0).abs() < 1e-4));
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_names_the_file_and_exits_with_2() {
    let dir = crate::common::temp_dir("rays-trace-bad");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    let rays = path(&dir, "rays.bin");
    let hits = path(&dir, "hits.bin");
    let good = encode_rays(&[strata::math::Ray::new(
        glam::Vec3::new(0.0, 0.0, 5.0),
        -glam::Vec3::Z,
    )]);

    std::fs::write(&rays, &good[..good.len() - 3]).unwrap();
    rejected(
        &["trace", ICOSPHERE, "--rays", &s(&rays), "--hits", &s(&hits)],
        &["rays.bin", "truncated"],
    );
    assert!(!hits.exists(), "no hit file after an error");

    let zero = encode_rays(&[strata::math::Ray::new(glam::Vec3::ZERO, glam::Vec3::ZERO)]);
    std::fs::write(&rays, [good.clone(), zero].concat()).unwrap();
    rejected(
        &["trace", ICOSPHERE, "--rays", &s(&rays), "--hits", &s(&hits)],
        &["rays.bin", "ray 1", "direction is zero"],
    );

    let missing = path(&dir, "missing.obj");
    std::fs::write(&rays, &good).unwrap();
    rejected(
        &[
            "trace",
            &s(&missing),
            "--rays",
            &s(&rays),
            "--hits",
            &s(&hits),
        ],
        &["missing.obj"],
    );
    rejected(
        &[
            "trace",
            ICOSPHERE,
            "--rays",
            &s(&path(&dir, "none.bin")),
            "--hits",
            &s(&hits),
        ],
        &["none.bin", "cannot read"],
    );
    rejected(
        &["rays", "edges", &s(&missing), "-o", &s(&rays)],
        &["missing.obj"],
    );

    let flat = path(&dir, "flat.obj");
    std::fs::write(&flat, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    rejected(
        &["rays", "inside", &s(&flat), "-o", &s(&path(&dir, "x.bin"))],
        &["flat.obj", "inside", "flat"],
    );
    rejected(
        &["rays", "edges", &s(&flat), "-o", &s(&path(&dir, "x.bin"))],
        &["flat.obj", "shared edges"],
    );
    let out = strata(repo(), &["rays", "sideways", ICOSPHERE, "-o", &s(&rays)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown ray kind 'sideways'"));
    std::fs::remove_dir_all(&dir).ok();
}
