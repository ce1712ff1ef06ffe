//! Helpers shared by the integration tests.
#![allow(dead_code)]

use glam::Vec3;
use std::path::{Path, PathBuf};
use strata::render::{render, RenderOptions};
use strata::scene::{scene_from_str, RenderOverrides, Scene};

pub fn scene(text: &str) -> Scene {
    scene_from_str(text, Path::new("test.toml"), &RenderOverrides::default())
        .unwrap_or_else(|e| panic!("{e}"))
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
    render(scene, &opts, None, |_, _| {}).film.to_rgb()
}

/// A fresh, empty temporary directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strata-test-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Tiny deterministic generator for test inputs.
pub struct Rng(pub u32);

impl Rng {
    pub fn next(&mut self) -> f32 {
        self.0 = strata::sampling::hash::hash_u32(self.0.wrapping_add(0x9e37_79b9));
        strata::sampling::hash::unit_float(self.0)
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }

    pub fn unit_vector(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}
