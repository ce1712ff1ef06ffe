//! A scene given as TOML text instead of a file (the Python package's
//! `render(scene=...)` with a dict or a string): compiled exactly as the
//! same text read from `path` would be, relative paths resolved against
//! `path`'s folder and errors named by it.

use super::{compile_for, LoadProgress, LoadTimings, Purpose};
use crate::error::InputResult;
use crate::scene::edit::Edit;
use crate::scene::settings::RenderOverrides;
use crate::scene::{BuildQuality, Scene};
use std::path::Path;
use std::time::Instant;

/// [`super::load_edited_scene`] of `text`, as if read from `path`.
pub fn load_edited_text(
    text: &str,
    path: &Path,
    edits: &[Edit],
    overrides: &RenderOverrides,
    quality: BuildQuality,
) -> InputResult<(Scene, LoadTimings)> {
    let progress = LoadProgress::default();
    compile_text(
        text,
        path,
        edits,
        overrides,
        quality,
        Instant::now(),
        &progress,
    )
}

/// A render's scene from `text` read from `path` (or as if), edited,
/// loading since `start`: what both entry points share.
pub(super) fn compile_text(
    text: &str,
    path: &Path,
    edits: &[Edit],
    overrides: &RenderOverrides,
    quality: BuildQuality,
    start: Instant,
    progress: &LoadProgress,
) -> InputResult<(Scene, LoadTimings)> {
    let desc = crate::scene::parse::parse_edited(path, text, edits)?;
    let purpose = Purpose::Render;
    compile_for(
        &desc, path, overrides, quality, purpose, start, progress, None,
    )
}
