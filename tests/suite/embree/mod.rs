//! strata against Intel Embree, through tools/validate_embree.py (embreex).
//!
//! `cargo test --release --test suite embree:: -- --nocapture` prints every
//! validator table and a summary in Markdown (the README's results table).
//! The Python environment and the bunny are set up on first use (see
//! `setup`); the tests fail, never skip, if that is impossible.

mod meshes;
pub mod setup;

use crate::common::process::{repo, strata_ok};
use glam::{DVec3, Vec3};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;
use strata::accel::BuildQuality;

const KINDS: [&str; 5] = ["random", "camera", "grazing", "edges", "inside"];
/// Rays of each kind for each of the 9 meshes: 1,012,500 in all.
const RAYS_PER_KIND: usize = 22_500;

fn work_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Run the validator; returns its exit code, stdout and the JSON report.
fn validate(mesh: &Path, rays: &Path, hits: &Path, occ: Option<&Path>) -> (i32, String, Value) {
    let report = hits.with_extension("report.json");
    let mut cmd = Command::new(setup::python());
    cmd.arg(repo().join("tools/validate_embree.py"))
        .args([mesh, rays, hits])
        .arg("--json")
        .arg(&report);
    if let Some(occ) = occ {
        cmd.arg("--occlusion").arg(occ);
    }
    let output = cmd.output().expect("run tools/validate_embree.py");
    let code = output.status.code().unwrap_or(-1);
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(
        code == 0 || code == 1,
        "validate_embree.py failed ({code}):\n{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json = std::fs::read_to_string(&report).expect("validator report");
    (
        code,
        stdout,
        serde_json::from_str(&json).expect("report JSON"),
    )
}

/// Rays of every kind for `mesh`, traced by strata (closest hit and
/// occlusion) and checked by the validator.
fn check_mesh(mesh: &Path, dir: &Path, name: &str, seed: u32) -> Value {
    // The trees `strata trace` may build over the mesh, checked here: the
    // binary, a release build, does not check them itself.
    for quality in BuildQuality::ALL {
        crate::common::load_mesh_scene(mesh, quality).unwrap_or_else(|e| panic!("{e}"));
    }
    let rays = dir.join(format!("{name}.rays"));
    let hits = dir.join(format!("{name}.hits"));
    let occ = dir.join(format!("{name}.occ"));
    let (m, r, h, o) = (
        mesh.to_str().unwrap(),
        rays.to_str().unwrap(),
        hits.to_str().unwrap(),
        occ.to_str().unwrap(),
    );
    let n = RAYS_PER_KIND.to_string();
    let seed = seed.to_string();
    strata_ok(
        repo(),
        &[
            "rays", "all", m, "-n", &n, "--seed", &seed, "-o", r, "--quiet",
        ],
    );
    print!(
        "{}",
        strata_ok(repo(), &["trace", m, "--rays", r, "--hits", h])
    );
    strata_ok(
        repo(),
        &[
            "trace",
            m,
            "--rays",
            r,
            "--hits",
            o,
            "--occlusion",
            "--quiet",
        ],
    );
    let (_, table, report) = validate(mesh, &rays, &hits, Some(&occ));
    print!("{table}");
    report
}

fn int(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"))
}

/// "a/S/E" of one check in a report row.
fn split(row: &Value, check: &str) -> String {
    let c = &row[check];
    format!(
        "{}/{}/{}",
        int(&c["ambiguous"]),
        int(&c["real_strata"]),
        int(&c["real_embree"])
    )
}

fn pair(row: &Value, a: &str, b: &str) -> String {
    if row.get(a).is_some() {
        format!("{}/{}", int(&row[a]), int(&row[b]))
    } else {
        "–".to_string()
    }
}

#[test]
fn strata_agrees_with_embree_on_a_million_rays_of_every_kind() {
    let start = Instant::now();
    let python = setup::python();
    println!("python: {}", python.display());
    let dir = work_dir("embree-million");

    // The meshes: the bunny, a generated sphere, a box of degenerate
    // triangles, and each translated 1e5 from the origin and scaled to 1e-6.
    let bunny = setup::bunny();
    let sphere = dir.join("sphere.obj");
    meshes::uv_sphere(DVec3::new(0.3, -0.2, 0.1), 1.0, 64, 128).write_obj(
        &sphere,
        "UV sphere, 64 stacks x 128 slices, strata tests/embree",
    );
    let degenerate = dir.join("degenerate.obj");
    meshes::degenerate_box(8).write_obj(
        &degenerate,
        "box with degenerate triangles, strata tests/embree",
    );
    let mut cases: Vec<(String, PathBuf)> = Vec::new();
    for (name, path) in [
        ("bunny", bunny),
        ("sphere", sphere),
        ("degenerate", degenerate),
    ] {
        let far = dir.join(format!("{name}-far.obj"));
        meshes::transformed_copy(&path, &far, |p| p + Vec3::splat(1e5), "translated by 1e5");
        let tiny = dir.join(format!("{name}-tiny.obj"));
        meshes::transformed_copy(&path, &tiny, |p| p * 1e-6, "scaled by 1e-6");
        cases.push((name.to_string(), path));
        cases.push((format!("{name} +1e5"), far));
        cases.push((format!("{name} ×1e-6"), tiny));
    }

    let mut reports = Vec::new();
    for (i, (name, mesh)) in cases.iter().enumerate() {
        let file = name.replace(' ', "_").replace('×', "x");
        reports.push((name.clone(), check_mesh(mesh, &dir, &file, 1 + i as u32)));
    }

    // The summary, as Markdown.
    let mut md = String::new();
    writeln!(md, "| mesh | kind | rays | hit/miss a/S/E | prim a/S/E | occlusion a/S/E | t a/S/E | bary a/S/E | t rel max | t err S/E | edges through S/E | inside escaped S/E |").unwrap();
    writeln!(md, "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|").unwrap();
    let mut total_rays = 0;
    let mut failures = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for (name, report) in &reports {
        for row in report["kinds"].as_array().unwrap() {
            let kind = row["kind"].as_str().unwrap();
            seen.insert(kind.to_string());
            total_rays += int(&row["rays"]);
            writeln!(
                md,
                "| {name} | {kind} | {} | {} | {} | {} | {} | {} | {:.1e} | {:.0e}/{:.0e} | {} | {} |",
                int(&row["rays"]),
                split(row, "hitmiss"),
                split(row, "prim"),
                split(row, "occlusion"),
                split(row, "t"),
                split(row, "bary"),
                row["t_rel_max"].as_f64().unwrap(),
                row["t_err_strata_max"].as_f64().unwrap(),
                row["t_err_embree_max"].as_f64().unwrap(),
                pair(row, "through_strata", "through_embree"),
                pair(row, "escaped_strata", "escaped_embree"),
            )
            .unwrap();
            if int(&row["real"]) != 0 {
                failures.push(format!("{name} {kind}: {} real mismatches where strata is wrong (examples in the report)", row["real"]));
            }
            for (key, what) in [
                ("through_strata", "edge rays went through"),
                ("escaped_strata", "inside rays escaped"),
            ] {
                if row.get(key).is_some_and(|v| int(v) != 0) {
                    failures.push(format!("{name} {kind}: {} {what}", row[key]));
                }
            }
        }
    }
    let summary = dir.join("summary.md");
    std::fs::write(&summary, &md).unwrap();
    println!(
        "\n{md}\n{total_rays} rays in {:.0} s; summary -> {}",
        start.elapsed().as_secs_f64(),
        summary.display()
    );
    assert!(total_rays >= 1_000_000, "only {total_rays} rays");
    assert_eq!(seen.len(), KINDS.len(), "kinds seen: {seen:?}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Change one record of a hit file in place.
fn edit_hit(path: &Path, ray: usize, f: impl FnOnce(&mut [u8; 16])) {
    let mut bytes = std::fs::read(path).unwrap();
    let record: &mut [u8; 16] = (&mut bytes[16 * ray..16 * ray + 16]).try_into().unwrap();
    f(record);
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn the_validator_catches_a_wrong_primitive_and_a_wrong_t() {
    let dir = work_dir("embree-planted");
    let mesh = meshes::uv_sphere(DVec3::ZERO, 1.0, 32, 64);
    let obj = dir.join("sphere.obj");
    mesh.write_obj(&obj, "UV sphere");
    let (rays, hits) = (dir.join("random.rays"), dir.join("random.hits"));
    let (o, r, h) = (
        obj.to_str().unwrap(),
        rays.to_str().unwrap(),
        hits.to_str().unwrap(),
    );
    strata_ok(
        repo(),
        &[
            "rays", "random", o, "-n", "5000", "--seed", "7", "-o", r, "--quiet",
        ],
    );
    strata_ok(repo(), &["trace", o, "--rays", r, "--hits", h, "--quiet"]);
    let (code, table, _) = validate(&obj, &rays, &hits, None);
    assert_eq!(code, 0, "the untouched hits must pass:\n{table}");

    // Two rays that hit a triangle squarely (|cos| > 0.5 to its normal).
    let ray_bytes = std::fs::read(&rays).unwrap();
    let hit_bytes = std::fs::read(&hits).unwrap();
    let f32_at = |b: &[u8], i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    let square_hits: Vec<usize> = (0..5000)
        .filter(|&i| {
            let prim = u32::from_le_bytes(hit_bytes[16 * i + 4..16 * i + 8].try_into().unwrap());
            if prim == u32::MAX {
                return false;
            }
            let [a, b, c] = mesh.faces[prim as usize].map(|k| mesh.positions[k as usize]);
            let n = (b - a).cross(c - a).normalize();
            let d = Vec3::from_array([3, 4, 5].map(|k| f32_at(&ray_bytes, 8 * i + k))).normalize();
            n.dot(d).abs() > 0.5
        })
        .collect();
    assert!(square_hits.len() >= 2);
    let (wrong_prim, wrong_t) = (square_hits[0], square_hits[1]);
    let n_tris = mesh.faces.len() as u32;
    edit_hit(&hits, wrong_prim, |rec| {
        let prim = u32::from_le_bytes(rec[4..8].try_into().unwrap());
        rec[4..8].copy_from_slice(&((prim + n_tris / 2) % n_tris).to_le_bytes());
    });
    edit_hit(&hits, wrong_t, |rec| {
        let t = f32::from_le_bytes(rec[0..4].try_into().unwrap());
        rec[0..4].copy_from_slice(&(t * 1.01).to_le_bytes());
    });

    let (code, table, report) = validate(&obj, &rays, &hits, None);
    print!("{table}");
    assert_eq!(code, 1, "the validator must fail on planted bugs");
    let row = &report["kinds"][0];
    assert_eq!(int(&row["prim"]["real_strata"]), 1, "{row}");
    assert_eq!(int(&row["t"]["real_strata"]), 1, "{row}");
    assert_eq!(int(&row["real"]), 2, "nothing else is flagged: {row}");
    let examples = report["examples"]["random"]["strata_wrong"]
        .as_array()
        .unwrap();
    let flagged: Vec<(u64, String)> = examples
        .iter()
        .map(|e| (int(&e["ray"]), e["checks"].to_string()))
        .collect();
    assert!(
        flagged.contains(&(wrong_prim as u64, "[\"prim\"]".to_string())),
        "{flagged:?}"
    );
    assert!(
        flagged.contains(&(wrong_t as u64, "[\"t\"]".to_string())),
        "{flagged:?}"
    );
}
