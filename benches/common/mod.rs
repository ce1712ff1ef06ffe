//! What the criterion benches share: the mesh they trace (the bunny when
//! `tools/fetch-assets` has fetched it, else a generated icosphere, so the
//! benches never fail for a missing asset) and seeded ray sets.
#![allow(dead_code, unused_imports)]

use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use strata::accel::BuildQuality;
use strata::scene::{load_mesh_scene, Scene};

/// An icosahedron subdivided `levels` times onto the unit sphere:
/// 20·4^levels triangles with shared edges everywhere.
pub fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let ab = midpoint(a, b, &mut v);
            let bc = midpoint(b, c, &mut v);
            let ca = midpoint(c, a, &mut v);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// The mesh file to trace and its name: assets/bunny.obj if present, else
/// a level-6 icosphere (81,920 triangles, about the bunny's size) written
/// to Cargo's scratch directory for benches (under target/).
pub fn mesh_file() -> (PathBuf, String) {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/bunny.obj");
    if bunny.exists() {
        return (bunny, "bunny".to_string());
    }
    // Cargo's scratch directory for benches: written once, reused after.
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("strata-bench-icosphere-6.obj");
    if !path.exists() {
        let (v, f) = icosphere(6);
        let mut obj = String::new();
        for p in &v {
            obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        for t in &f {
            obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        // Written beside and renamed, so a concurrent bench never reads half a file.
        let tmp = path.with_extension(format!("{}.tmp", std::process::id()));
        std::fs::write(&tmp, obj).expect("write the generated icosphere");
        std::fs::rename(&tmp, &path).expect("rename the generated icosphere");
    }
    (path, "icosphere".to_string())
}

/// The mesh as the only object of a scene (what `strata trace` and
/// `strata bench` build), and its name.
pub fn mesh_scene(quality: BuildQuality) -> (Scene, String) {
    let (path, name) = mesh_file();
    let (scene, _) = load_mesh_scene(&path, quality).unwrap_or_else(|e| panic!("{e}"));
    (scene, name)
}

/// Tiny deterministic generator for bench inputs.
pub use strata::sampling::stream::{seeded, Draw, StreamRng};
