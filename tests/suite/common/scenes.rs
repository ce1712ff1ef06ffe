//! Scenes for the tests: read from text (their BVHs checked, as every
//! loader here does), two small lit ones the command-line tests write to
//! files, and a render's linear RGB.

use super::checked::scene_from_str;
use glam::Vec3;
use std::path::Path;
use strata::render::{render, RenderOptions};
use strata::scene::{RenderOverrides, Scene};

/// 16 × 12 pixels at 8 spp: one point light over a sphere (no triangles)
/// on a plane.
pub const SPHERE_ON_PLANE: &str = r#"
[render]
width = 16
height = 12
spp = 8
[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = [10.0, 10.0, 10.0]
[[objects]]
sphere = { center = [0.0, 0.5, 0.0], radius = 0.5 }
[[objects]]
plane = { normal = [0.0, 1.0, 0.0] }
"#;

/// Lit, tiny and quick (8 × 6 pixels at 4 spp, one point light over a
/// sphere): renders in milliseconds.
pub const LIT_SPHERE: &str = r#"[render]
width = 8
height = 6
spp = 4

[[lights]]
type = "point"
position = [0.0, 4.0, 0.0]
intensity = [10.0, 10.0, 10.0]

[[objects]]
sphere = { radius = 1.0 }
"#;

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
    render(scene, &opts, None, ()).film.to_rgb()
}
