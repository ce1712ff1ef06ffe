//! The native Embree harness (tools/embree/embree_trace, the anchor of
//! `strata bench` and tools/bench_embree.py; docs/embree.md) answers the
//! same rays as `strata trace`: the same triangle and t, u, v within
//! float tolerance on closest hit, the same occlusion, in Embree's default
//! and robust modes and with packets of 8. A harness that traced other
//! triangles or other rays would make every speed ratio meaningless.
//!
//! It needs a C compiler and libembree-dev (`.ci/run` installs it). Without
//! them the test prints one line and passes, except under CI, where it
//! fails.

use crate::common::load_mesh_scene;
use crate::common::process::{repo, run, strata_command};
use std::path::{Path, PathBuf};
use std::process::Command;
use strata::accel::BuildQuality;
use strata::rays::file::{encode_triangles, parse_hits, read_rays, HitRecord};

/// Rays of each kind.
const PER_KIND: usize = 600;

pub fn harness() -> Option<PathBuf> {
    let root = repo();
    let out = root.join("target").join("embree");
    let made = Command::new("make")
        .arg("-s")
        .arg("-C")
        .arg(root.join("tools").join("embree"))
        .arg(format!("OUT={}", out.display()))
        .output();
    match made {
        Ok(o) if o.status.success() => Some(out.join("embree_trace")),
        other => {
            // Name what is actually missing: make itself, or Embree's
            // headers and library, or else say what the build said.
            let why = match other {
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    "make is not installed (apt-get install make)".to_string()
                }
                Err(e) => format!("make did not start: {e}"),
                Ok(o) => {
                    let said = String::from_utf8_lossy(&o.stderr).trim().to_string();
                    if said.contains("embree")
                        && (said.contains("No such file") || said.contains("cannot find"))
                    {
                        format!("libembree-dev is not installed (apt-get install libembree-dev): {said}")
                    } else {
                        format!("tools/embree does not build: {said}")
                    }
                }
            };
            assert!(std::env::var_os("CI").is_none(), "CI: {why}");
            crate::common::skipped("embree_native", &why);
            None
        }
    }
}

pub fn hits(path: &Path) -> Vec<HitRecord> {
    parse_hits(path, &std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn the_native_harness_answers_as_strata_does() {
    let Some(exe) = harness() else { return };
    let dir = crate::common::temp_dir("embree-native");
    let mesh = dir.join("sphere.obj");
    std::fs::write(&mesh, crate::common::bumpy_sphere_obj(48, 24, 1.0, 0.1)).unwrap();
    // MESH.tris in strata's file order, unindexed, as `strata bench` writes it.
    let (scene, _) = load_mesh_scene(&mesh, BuildQuality::Auto).unwrap();
    let tris = scene.geometry.file_order_triangles();
    let tris_path = dir.join("sphere.tris");
    std::fs::write(&tris_path, encode_triangles(&tris)).unwrap();

    let rays = dir.join("rays.bin");
    let strata = |args: &[&Path]| {
        let mut c = strata_command(repo());
        c.args(args);
        c
    };
    run(
        strata(&[
            Path::new("rays"),
            Path::new("all"),
            &mesh,
            Path::new("-o"),
            &rays,
        ])
        .args(["-n", "600", "--seed", "3", "--quiet"]),
        "strata rays",
    );
    // Closest hits, then occlusion, from `strata trace`.
    let [ours, ours_occ] = [&[][..], &["--occlusion"]].map(|flags| {
        let out = dir.join("strata.hits");
        run(
            strata(&[
                Path::new("trace"),
                &mesh,
                Path::new("--rays"),
                &rays,
                Path::new("--hits"),
                &out,
            ])
            .arg("-q")
            .args(flags),
            "strata trace",
        );
        hits(&out)
    });
    let ray_list = read_rays(&rays).unwrap();
    let n = ours.len();
    assert_eq!(n, 5 * PER_KIND);
    let found = ours.iter().filter(|h| h.is_hit()).count();
    assert!(found > n / 4 && found < n, "{found} hits of {n}");

    for flags in [
        &[][..],
        &["--robust"],
        &["--packet"],
        &["--robust", "--packet"],
    ] {
        let [theirs, theirs_occ] = [&[][..], &["--occlusion"]].map(|query| {
            let out = dir.join("embree.hits");
            run(
                Command::new(&exe)
                    .arg(&tris_path)
                    .arg(&rays)
                    .arg("--hits")
                    .arg(&out)
                    .args(query)
                    .args(flags),
                "embree_trace",
            );
            hits(&out)
        });
        assert_eq!(theirs.len(), n);
        // Two answers agree if they name the same triangle, or triangles
        // hit at the same t: rays aimed at a shared edge or vertex may
        // name either neighbour.
        let agree = |a: &HitRecord, b: &HitRecord| {
            a.prim == b.prim || (a.is_hit() && b.is_hit() && (a.t - b.t).abs() <= 1e-4 * a.t.abs())
        };
        // Embree's default mode (Möller–Trumbore, not watertight) lets some
        // `edges` rays (the fourth 600, `strata rays all`'s order) through
        // the vertex or edge they aim at, to a farther hit: counted apart.
        let edges = 3 * PER_KIND..4 * PER_KIND;
        let cracks = edges
            .clone()
            .filter(|&i| {
                !agree(&ours[i], &theirs[i]) && ours[i].is_hit() && theirs[i].t > ours[i].t
            })
            .count();
        let other = (0..n).filter(|&i| !agree(&ours[i], &theirs[i])).count() - cracks;
        let other_occ = (0..n)
            .filter(|&i| ours_occ[i] != theirs_occ[i] && !edges.contains(&i))
            .count();
        assert!(
            other <= n / 100,
            "{flags:?}: {other} of {n} rays answered otherwise"
        );
        assert!(
            other_occ <= n / 100,
            "{flags:?}: {other_occ} of {n} occlusion answers differ"
        );
        if flags.contains(&"--robust") {
            assert!(
                cracks <= PER_KIND / 100,
                "{flags:?}: {cracks} edges rays went through"
            );
        }
        // Where both name one triangle, t is compared by how far off the
        // triangle's plane the difference puts the hit point, and u, v by
        // how far across the ray they put it, over the distance from the
        // origin (along a grazing ray both are ill-conditioned; this is
        // tools/validate_embree.py's rule, with 1e-4 for two float answers
        // instead of its 1e-5 for one answer against the exact one).
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            if a.is_hit() && a.prim == b.prim {
                let [v0, v1, v2] = tris[a.prim as usize];
                let normal = (v1 - v0).cross(v2 - v0).normalize();
                let ray = &ray_list[i];
                let off = (a.t - b.t).abs() * ray.direction.dot(normal).abs();
                let scale = (v0 - ray.origin).length().max(1e-3);
                assert!(
                    off < 1e-4 * scale,
                    "{flags:?} ray {i}: t {} vs {}",
                    a.t,
                    b.t
                );
                let at = |h: &HitRecord| v0 + h.u * (v1 - v0) + h.v * (v2 - v0);
                let gap = at(a) - at(b);
                let d = ray.direction.normalize();
                let across = (gap - gap.dot(d) * d).length();
                // Embree's robust (Plücker) u, v stray further on grazing
                // rays (the third 600): there only t is compared.
                let grazing = (2 * PER_KIND..3 * PER_KIND).contains(&i);
                assert!(
                    grazing || across < 1e-4 * scale,
                    "{flags:?} ray {i}: {a:?} vs {b:?}"
                );
            }
        }
        println!("{flags:?}: of {n} rays, {other} answered otherwise, {cracks} edges rays went through, {other_occ} occlusion answers differ");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
