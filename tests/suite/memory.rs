//! Memory of loading and building: what `strata render --stats` and
//! `strata bench` report, and that the compiler's indexed triangle sources
//! expand to exactly the triangles the file and transforms give.

use crate::common::process::{repo, strata_ok};
use glam::Vec3;
use std::path::Path;
use strata::scene::loaders::load_mesh_file;
use strata::system::memory::resident_bytes;

/// A binary PLY height field of `2 * n * n` triangles on [0, 1]².
fn write_grid(path: &Path, n: u32) {
    let nv = (n + 1) * (n + 1);
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        2 * n * n
    )
    .into_bytes();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            for c in [x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos()] {
                bytes.extend(c.to_le_bytes());
            }
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = (j * (n + 1) + i) as i32;
            let w = v + n as i32 + 1;
            for tri in [[v, v + 1, w + 1], [v, w + 1, w]] {
                bytes.push(3);
                for k in tri {
                    bytes.extend(k.to_le_bytes());
                }
            }
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Where Linux lets a process reset its own peak RSS, the peaks must be known.
fn peak_resettable() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[test]
fn render_stats_and_bench_report_final_and_peak_bytes_per_triangle() {
    let dir = crate::common::temp_dir("memory");
    let mesh = dir.join("grid.ply");
    write_grid(&mesh, 300); // 180,000 triangles
    let scene = dir.join("grid.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0.5, 0.5, 2.0]\nlook_at = [0.5, 0.5, 0.0]\n\n[[lights]]\ntype = \"point\"\nposition = [0.5, 0.5, 2.0]\nintensity = [1.0, 1.0, 1.0]\n\n[[objects]]\nmesh = \"grid.ply\"\n",
    )
    .unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let stats = dir.join("stats.json");
    let summary = strata_ok(
        repo(),
        &[
            "render",
            &s(&scene),
            "-o",
            &s(&dir.join("grid.png")),
            "--width",
            "16",
            "--height",
            "12",
            "--spp",
            "1",
            // One preset for render and bench, so that both report the same
            // tree (`auto` builds a render this short with the fastest one).
            "--bvh-quality",
            "medium",
            "--stats",
            &s(&stats),
        ],
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["triangles"], 180_000);
    assert_eq!(json["bvh_quality"], "medium");
    let memory = &json["memory"];
    let final_bpt = memory["final_bytes_per_triangle"].as_f64().unwrap();
    // At least the leaf triangles and ids; the nodes add a fraction.
    assert!((40.0..100.0).contains(&final_bpt), "{memory}");
    if peak_resettable() {
        let peak = memory["peak_bytes_per_triangle"].as_f64().unwrap();
        // The build holds the BVH builder's arrays beside the inputs, but
        // not several copies of the triangles.
        assert!(peak > final_bpt && peak < 600.0, "{memory}");
        assert!(memory["load_peak_bytes"].as_u64().unwrap() > 0, "{memory}");
        assert!(summary.contains("B/triangle"), "{summary}");
    }

    let csv = dir.join("bench.csv");
    strata_ok(
        repo(),
        &[
            "bench",
            &s(&mesh),
            "--batches",
            "16",
            "--repeats",
            "1",
            "--threads",
            "1",
            "--bvh-quality",
            "medium",
            "--csv",
            &s(&csv),
        ],
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let bpt: f64 = row[column("bytes_per_triangle")].parse().unwrap();
    assert!((bpt - final_bpt).abs() < 0.2, "{bpt} vs {final_bpt}");
    if peak_resettable() {
        let peak: f64 = row[column("peak_load_build_bytes_per_triangle")]
            .parse()
            .unwrap();
        assert!(peak > bpt && peak < 600.0, "{text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mesh_instances_and_loose_triangles_keep_their_vertices() {
    let dir = crate::common::temp_dir("memory-instances");
    let mesh = dir.join("grid.ply");
    write_grid(&mesh, 20);
    let scene = dir.join("two.toml");
    let text = "[[objects]]\ntriangle = { v = [[0, 0, 5], [1, 0, 5], [0, 1, 5]] }\n\n[[objects]]\nmesh = \"grid.ply\"\n\n[[objects]]\nmesh = \"grid.ply\"\ntransform = { translate = [3, 0, 0], scale = 2.0 }\n";
    let compiled = crate::common::scene_at(text, &scene);
    let file = load_mesh_file(&mesh).unwrap();
    let grid = &file.meshes[0];
    let corners = |f: &dyn Fn(Vec3) -> Vec3| -> Vec<[Vec3; 3]> {
        grid.indices
            .iter()
            .map(|idx| idx.map(|i| f(grid.positions[i as usize])))
            .collect()
    };
    let mut expected = vec![[
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::new(1.0, 0.0, 5.0),
        Vec3::new(0.0, 1.0, 5.0),
    ]];
    expected.extend(corners(&|p| p));
    // The compiler applies the object's affine transform to each vertex.
    let m = glam::Affine3A::from_scale_rotation_translation(
        Vec3::splat(2.0),
        glam::Quat::IDENTITY,
        Vec3::new(3.0, 0.0, 0.0),
    );
    let placed = corners(&|p| m.transform_point3(p));
    // The grid, placed twice, is stored once in its own space (a
    // prototype); the loose triangle is the scene's own.
    let g = &compiled.geometry;
    assert_eq!(g.file_order_triangles(), &expected[..1]);
    assert_eq!((g.prototypes().len(), g.instances().len()), (1, 2));
    let own = g.prototypes()[0].file_order_triangles();
    assert_eq!(&own[..], &expected[1..]);
    for (instance, want) in g.instances().iter().zip([&expected[1..], &placed[..]]) {
        let a = instance.affine();
        for (t, e) in own.iter().zip(want) {
            for (p, q) in t.iter().zip(e) {
                let moved = a.transform_point3(*p);
                assert!((moved - *q).length() < 1e-6, "{moved} vs {q}");
            }
        }
    }
    // Every triangle sits in exactly one leaf slot, in each tree.
    for tree in [g, &g.prototypes()[0]] {
        let mut seen = vec![0; tree.triangle_count() as usize];
        for id in tree.leaf_slots() {
            if (id as usize) < seen.len() {
                seen[id as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Memory freed in the middle of glibc's heap stays resident until it
/// is handed back, and is not resident after: 16 MB of small arrays
/// (under any mmap threshold, so on the heap), one kept after them so
/// that the heap's top is not free, freed, then handed back. Run in a
/// process of its own by the test below, so that no other test's
/// allocations move the process's memory between the two reads.
#[test]
#[ignore = "run in a process of its own by freed_memory_goes_back_to_the_system"]
fn freed_memory_goes_back_in_this_process() {
    let chunks: Vec<Vec<u8>> = (0..4096).map(|i| vec![i as u8 | 1; 4000]).collect();
    // Opaque to the optimiser, which would otherwise drop both arrays.
    let chunks = std::hint::black_box(chunks);
    let kept = std::hint::black_box(vec![7u8; 4000]);
    drop(chunks);
    let (Some(before), true) = (resident_bytes(), cfg!(target_env = "gnu")) else {
        return;
    };
    strata::accel::pages::give_back_freed_memory();
    let after = resident_bytes().unwrap();
    assert!(
        before > after + (12 << 20),
        "resident {before} bytes before, {after} after"
    );
    assert_eq!(kept[3999], 7, "what is alive stays");
}

/// [`freed_memory_goes_back_in_this_process`] in a process of its own:
/// this test binary started again on that test alone.
#[test]
fn freed_memory_goes_back_to_the_system() {
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    let name = "memory::freed_memory_goes_back_in_this_process";
    let out = std::process::Command::new(exe)
        .args(["--exact", name, "--ignored", "--test-threads=1"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("1 passed"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
