//! Scenes for the tests: read from text (their BVHs checked, as every
//! loader here does), and a render's linear RGB.

use super::checked::scene_from_str;
use glam::Vec3;
use std::path::Path;
use strata::render::{render, RenderOptions};
use strata::scene::{RenderOverrides, Scene};

/// The scene of `text`, its BVHs checked (as every loader here does).
pub fn scene(text: &str) -> Scene {
    scene_at(text, Path::new("test.toml"))
}

/// The scene of `text` as if read from the file `path` (which relative
/// paths in it are resolved against), its BVHs checked.
pub fn scene_at(text: &str, path: &Path) -> Scene {
    scene_from_str(text, path, &RenderOverrides::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Render with `threads` threads and return linear RGB.
pub fn render_rgb(scene: &Scene, threads: usize) -> Vec<Vec3> {
    let opts = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    render(scene, &opts, None, |_, _| {}).film.to_rgb()
}
