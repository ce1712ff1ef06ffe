//! The terminal progress bar: hidden with `--quiet` or when stderr is not a terminal.

use crate::scene::compile::{LoadPhase, LoadProgress};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::{Duration, Instant};

pub fn bar(total: u64, quiet: bool, what: &str) -> ProgressBar {
    let bar = if quiet {
        ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden())
    } else {
        ProgressBar::new(total)
    };
    bar.set_style(
        ProgressStyle::with_template("{prefix} [{bar:40.cyan/blue}] {percent:>3}% {msg} ETA {eta}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_prefix(what.to_string());
    bar
}

/// A load that has not ended after this long shows what it is doing.
const LOAD_QUIET_FOR: Duration = Duration::from_secs(1);

/// Shows what the load reporting to `progress` is doing (reading the
/// scene and its meshes, building the BVH), with the time so far, once
/// it has taken [`LOAD_QUIET_FOR`], until it is finished; then clears the
/// line. Run on a thread of its own, which the loader unparks when it
/// finishes the progress, so that waiting for this ends at once. Hidden
/// when stderr is not a terminal, as the render's bar is; a `--quiet` run
/// does not call it.
pub fn show_load(progress: &LoadProgress) {
    let start = Instant::now();
    let mut spinner: Option<ProgressBar> = None;
    loop {
        let phase = progress.phase();
        let message = match phase {
            LoadPhase::Done => break,
            LoadPhase::Loading => "loading the scene and its meshes".to_string(),
            LoadPhase::Building { triangles } => {
                format!("building the BVH over {triangles} triangles")
            }
        };
        let wait = LOAD_QUIET_FOR.saturating_sub(start.elapsed());
        if !wait.is_zero() {
            std::thread::park_timeout(wait);
            continue;
        }
        let spinner = spinner.get_or_insert_with(|| {
            let s = ProgressBar::new_spinner().with_elapsed(start.elapsed());
            s.set_style(
                ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                    .expect("static template"),
            );
            s.enable_steady_tick(Duration::from_millis(100));
            s
        });
        spinner.set_message(message);
        std::thread::park_timeout(Duration::from_millis(100));
    }
    if let Some(spinner) = spinner {
        spinner.finish_and_clear();
    }
}
