//! strata's instances against Embree's: the native harness builds the same
//! two-level scene (one mesh, an Embree instance per line of the same
//! placements file) and both answer every kind of `strata rays` ray,
//! generated on the placed copies, with the same triangle of the same
//! instance (`strata trace SCENE.toml` numbers instance k's triangle j
//! k·T + j, as the harness does from Embree's instID and primID).

use super::embree_native::{harness, hits};
use crate::common::meshes::{placement_row, random_affine};
use crate::common::process::{run, strata_command};
use crate::common::queries::barycentric;
use crate::common::{bumpy_sphere_obj, scene_at, seeded, temp_dir};
use glam::DVec3;
use std::process::Command;
use strata::accel::BuildQuality;
use strata::rays::file::{encode_triangles, read_rays, HitRecord};

/// Rays of each kind.
const PER_KIND: usize = 400;

#[test]
fn embree_instances_answer_as_strata_instances_do() {
    let Some(exe) = harness() else { return };
    let dir = temp_dir("embree-instances");
    std::fs::write(dir.join("m.obj"), bumpy_sphere_obj(32, 16, 1.0, 0.15)).unwrap();
    let mut rng = seeded(45);
    let mut rows = Vec::new();
    for _ in 0..24 {
        rows.push(placement_row(&random_affine(&mut rng, 8.0)));
    }
    std::fs::write(dir.join("places.csv"), rows.join("\n") + "\n").unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "[[objects]]\nmesh = \"m.obj\"\ninstances = \"places.csv\"\n",
    )
    .unwrap();

    // The mesh for the harness, in strata's file order; the placed copies
    // for `strata rays` (its edge and grazing rays aim at their edges).
    let (mesh, _) = crate::common::load_mesh_scene(&dir.join("m.obj"), BuildQuality::Auto).unwrap();
    let tris = mesh.geometry.file_order_triangles();
    std::fs::write(dir.join("m.tris"), encode_triangles(&tris)).unwrap();
    let scene = scene_at(
        &std::fs::read_to_string(dir.join("s.toml")).unwrap(),
        &dir.join("s.toml"),
    );
    let g = &scene.geometry;
    let mut copies = String::new();
    for inst in g.instances() {
        let m = inst.affine();
        for t in &tris {
            for v in t {
                let p = m.transform_point3(*v);
                copies += &format!("v {} {} {}\n", p.x, p.y, p.z);
            }
        }
    }
    for f in 0..tris.len() * g.instances().len() {
        copies += &format!("f {} {} {}\n", 3 * f + 1, 3 * f + 2, 3 * f + 3);
    }
    std::fs::write(dir.join("copies.obj"), copies).unwrap();

    let strata = |args: &[&str]| {
        let mut c = strata_command(&dir);
        c.args(args);
        c
    };
    let n = PER_KIND.to_string();
    run(
        &mut strata(&[
            "rays",
            "all",
            "copies.obj",
            "-o",
            "rays.bin",
            "-n",
            &n,
            "--seed",
            "5",
            "--quiet",
        ]),
        "strata rays",
    );
    let [ours, ours_occ] = [&[][..], &["--occlusion"]].map(|flags| {
        run(
            strata(&[
                "trace", "s.toml", "--rays", "rays.bin", "--hits", "s.hits", "-q",
            ])
            .args(flags),
            "strata trace",
        );
        hits(&dir.join("s.hits"))
    });
    // The summary counts the triangles the instances place.
    let said = run(
        &mut strata(&["trace", "s.toml", "--rays", "rays.bin", "--hits", "s.hits"]),
        "strata trace",
    );
    let (placed, n) = (tris.len() * g.instances().len(), g.instances().len());
    let against = format!("against {placed} triangles ({placed} placed by {n} instances)");
    assert!(said.contains(&against), "{said}");
    let total = ours.len();
    assert_eq!(total, 5 * PER_KIND);
    let found = ours.iter().filter(|h| h.is_hit()).count();
    assert!(found > total / 4, "{found} hits of {total}");
    assert!(
        ours.iter()
            .filter(|h| h.is_hit())
            .all(|h| (h.prim as usize) < tris.len() * g.instances().len()),
        "every hit names an instanced triangle"
    );

    // The placed triangles in f64, each instance's map the exact inverse
    // of the world-to-object map strata walks with: the exact answer.
    let exact_tris: Vec<[DVec3; 3]> = g
        .instances()
        .iter()
        .flat_map(|inst| {
            let m = inst.affine_f64();
            tris.iter()
                .map(move |t| t.map(|v| m.transform_point3(v.as_dvec3())))
        })
        .collect();
    let rays = read_rays(&dir.join("rays.bin")).unwrap();
    // A real mismatch: an answer other than the exact closest hit where
    // that hit is not within 1e-6 (barycentric) of an edge, and a hit
    // where the exact answer is a miss not that close to the triangle.
    let real = |i: usize, a: &HitRecord| -> bool {
        let ray = &rays[i];
        let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
        let exact = closest_exact(&exact_tris, o, d, f64::from(ray.tmin), f64::from(ray.tmax));
        match (exact, a.is_hit()) {
            (None, false) => false,
            (Some((_, _, edge)), false) => edge > 1e-6,
            (None, true) => barycentric(&exact_tris[a.prim as usize], o, d).1 < -1e-6,
            (Some((t, prim, edge)), true) => {
                a.prim as usize != prim && (f64::from(a.t) - t).abs() > 1e-4 * t && edge > 1e-6
            }
        }
    };
    let ours_real: Vec<usize> = (0..total).filter(|&i| real(i, &ours[i])).collect();
    assert!(
        ours_real.is_empty(),
        "strata: real mismatches at rays {ours_real:?}"
    );

    for flags in [&["--robust"][..], &[], &["--robust", "--packet"]] {
        let [theirs, theirs_occ] = [&[][..], &["--occlusion"]].map(|query| {
            let out = dir.join("e.hits");
            run(
                Command::new(&exe)
                    .arg(dir.join("m.tris"))
                    .arg(dir.join("rays.bin"))
                    .arg("--instances")
                    .arg(dir.join("places.csv"))
                    .arg("--hits")
                    .arg(&out)
                    .args(query)
                    .args(flags),
                "embree_trace",
            );
            hits(&out)
        });
        // The same triangle of the same instance, or hits at the same t
        // (a ray aimed at a shared edge or vertex may name either side).
        let agree = |a: &HitRecord, b: &HitRecord| {
            a.prim == b.prim || (a.is_hit() && b.is_hit() && (a.t - b.t).abs() <= 1e-4 * a.t.abs())
        };
        let mut per_kind = [0usize; 5];
        let mut real_kind = [0usize; 5];
        let mut t_off = 0;
        for i in 0..total {
            let (a, b) = (&ours[i], &theirs[i]);
            if !agree(a, b) {
                per_kind[i / PER_KIND] += 1;
                if real(i, b) {
                    real_kind[i / PER_KIND] += 1;
                }
            }
            if a.is_hit() && a.prim == b.prim {
                // t off the triangle's plane, over the distance (as
                // embree_native compares it: along a grazing ray t is
                // ill-conditioned).
                let [v0, v1, v2] = exact_tris[a.prim as usize];
                let n = (v1 - v0).cross(v2 - v0).normalize();
                let ray = &rays[i];
                let off = f64::from((a.t - b.t).abs()) * ray.direction.as_dvec3().dot(n).abs();
                if off > 1e-4 * (v0 - ray.origin.as_dvec3()).length().max(1e-3) {
                    t_off += 1;
                }
            }
        }
        let occ = (0..total).filter(|&i| ours_occ[i] != theirs_occ[i]).count();
        println!(
            "{flags:?}: of {total} rays (random, camera, grazing, edges, inside) answered otherwise \
             {per_kind:?}, of which Embree's real mismatches {real_kind:?}; t off {t_off}; \
             occlusion differs {occ}"
        );
        assert_eq!(t_off, 0, "{flags:?}: the same triangle at another t");
        // Every disagreement is Embree's, or a ray through an edge: strata
        // has none (checked above). Embree moves rays into instance space
        // with its own rounding, so a grazing ray may go its other way.
        assert!(
            per_kind.iter().sum::<usize>() <= total / 100,
            "{flags:?}: {per_kind:?} answered otherwise"
        );
        if flags.contains(&"--robust") {
            assert!(
                occ <= total / 200,
                "{flags:?}: {occ} occlusion answers differ"
            );
        }
    }
}

/// The exact closest hit in (tmin, tmax): t, triangle, and how far inside
/// its triangle (the least barycentric), by Möller–Trumbore in f64 over
/// every triangle.
fn closest_exact(
    tris: &[[DVec3; 3]],
    o: DVec3,
    d: DVec3,
    tmin: f64,
    tmax: f64,
) -> Option<(f64, usize, f64)> {
    let mut best: Option<(f64, usize, f64)> = None;
    for (k, tri) in tris.iter().enumerate() {
        let (t, inside) = barycentric(tri, o, d);
        if inside >= 0.0 && t > tmin && t < tmax && best.is_none_or(|b| t < b.0) {
            best = Some((t, k, inside));
        }
    }
    best
}
