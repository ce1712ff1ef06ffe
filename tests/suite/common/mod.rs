//! Helpers shared by the suite's modules, one concept a file:
//!
//! | file | holds |
//! |---|---|
//! | `checked.rs` | the library's scene loaders, every BVH checked before a test sees it |
//! | `process.rs` | the repository's root, the `strata` binary run (one runner), a run's output, a refused render |
//! | `scenes.rs` | scenes from text, small lit scenes, a render's linear RGB |
//! | `meshes.rs` | generated meshes (a cube, a bumpy sphere as OBJ), random placements, base64 for glTF buffers |
//! | `queries.rs` | brute-force answers of the mesh queries (crossings, nearest point) and the nearest-point check |
//! | `exr.rs` | reading back the EXR files the binary writes |
//!
//! Here too: temporary directories, and a skipped test said where the user
//! sees it.

pub mod checked;
pub mod exr;
pub mod films;
pub mod meshes;
pub mod process;
pub mod queries;
pub mod scenes;

pub use checked::{load_mesh_scene, load_scene};
pub use meshes::{bumpy_sphere_obj, cube};
pub use process::{stderr, stdout, strata};
pub use scenes::{render_rgb, scene, scene_at};

use std::path::{Path, PathBuf};

/// Say that `test` was skipped and why, where a user running `cargo test`
/// sees it: written to the terminal's stderr directly, past libtest's
/// capture (which takes `print!` and `eprint!` of passing tests).
pub fn skipped(test: &str, why: &str) {
    use std::io::Write;
    let line = format!("\nSKIPPED {test}: {why}\n");
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
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
