//! Helpers shared by the integration tests (not every test binary uses
//! every one, hence the allows).
#![allow(dead_code, unused_imports)]

pub mod checked;
pub mod exr;

pub use checked::{check_bvhs, load_mesh_scene, load_scene};

use checked::scene_from_str;
use glam::Vec3;
use std::path::{Path, PathBuf};
use strata::render::{render, RenderOptions};
use strata::scene::{RenderOverrides, Scene};

/// `strata ARGS` run in `dir`, its output kept.
pub fn strata(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A run's standard error, as text.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A run's standard output, as text.
pub fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// Say that `test` was skipped and why, where a user running `cargo test`
/// sees it: written to the terminal's stderr directly, past libtest's
/// capture (which takes `print!` and `eprint!` of passing tests).
pub fn skipped(test: &str, why: &str) {
    use std::io::Write;
    let line = format!("\nSKIPPED {test}: {why}\n");
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

/// The scene of `text`, its BVHs checked (as every loader here does).
pub fn scene(text: &str) -> Scene {
    scene_at(text, Path::new("test.toml"))
}

pub fn scene_at(text: &str, path: &Path) -> Scene {
    scene_from_str(text, path, &RenderOverrides::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Render with `threads` threads and return linear RGB.
pub fn render_rgb(scene: &Scene, threads: usize) -> Vec<Vec3> {
    let opts = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    render(scene, &opts, None, ()).film.to_rgb()
}

/// OBJ text of a bumpy UV sphere of 2 × `nu` × `nv` triangles with shared
/// edges everywhere: radius `radius`, bumps of amplitude `bump`.
pub fn bumpy_sphere_obj(nu: u32, nv: u32, radius: f32, bump: f32) -> String {
    let mut obj = String::new();
    for j in 0..=nv {
        for i in 0..nu {
            let th = std::f32::consts::PI * j as f32 / nv as f32;
            let ph = std::f32::consts::TAU * i as f32 / nu as f32;
            let r = radius + bump * ((5.0 * ph).sin() * (3.0 * th).cos());
            obj += &format!(
                "v {} {} {}\n",
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin()
            );
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let a = j * nu + i + 1;
            let b = j * nu + (i + 1) % nu + 1;
            let (c, d) = (a + nu, b + nu);
            obj += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    obj
}

/// A temporary directory that is removed, with everything in it, when
/// the guard is dropped. It derefs to its `Path`, so `dir.join(..)` and
/// `&dir` work where a `&Path` is wanted; keep the guard itself (not a
/// path derived from it) alive for as long as the directory is needed.
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh, empty temporary directory, unique to this call: tests of one
/// binary run in parallel in one process, so the name and the process id
/// alone would let two of them share (and delete) one directory. Removed
/// when the returned guard is dropped.
pub fn temp_dir(name: &str) -> TempDir {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!(
        "strata-test-{}-{}-{call}",
        name,
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// Tiny deterministic generator for test inputs.
pub use strata::sampling::stream::{seeded, Draw, StreamRng};

/// The cube of side `side` centred on the origin, two triangles a face,
/// wound outwards.
pub fn cube(side: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v = (0..8)
        .map(|i| (Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32) - 0.5) * side)
        .collect();
    let f = vec![
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
    ];
    (v, f)
}
