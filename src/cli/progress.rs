//! What the terminal shows while work runs: the render's progress bar
//! (an observer of `strata::render`) and what a slow load is doing. Both
//! go to stderr, hidden with `--quiet` or when stderr is not a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::ops::ControlFlow;
use std::time::{Duration, Instant};
use strata::render::progress::{Observer, Pass, PassDone};
use strata::render::Film;
use strata::scene::compile::{LoadPhase, LoadProgress};

/// The render's bar: a tick per work item, and in its message the pass,
/// its samples and the previous pass's rate.
pub struct RenderBar {
    bar: ProgressBar,
    quiet: bool,
    /// Rays and seconds at the end of the previous pass, for its rate.
    last: (u64, f64),
    rate: String,
}

impl RenderBar {
    /// A bar drawn nowhere until the render says how many work items it
    /// has ([`Observer::started`]): a bar of length 0 reads as full, and
    /// was shown at 100% before the first item.
    pub fn new(quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix} [{wide_bar:.cyan/blue}] {percent:>3}% {msg} ETA {eta}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        bar.set_prefix("render");
        Self {
            bar,
            quiet,
            last: (0, 0.0),
            rate: String::new(),
        }
    }
}

impl Observer for RenderBar {
    fn started(&mut self, work_items: u64) {
        self.bar.set_length(work_items);
        if !self.quiet {
            // Hidden by indicatif itself when stderr is not a terminal.
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    fn pass_started(&mut self, pass: &Pass) {
        self.bar.set_message(format!(
            "pass {}/{} (samples {}..{} of {}){}",
            pass.index + 1,
            pass.count,
            pass.samples.start,
            pass.samples.end,
            pass.spp,
            self.rate
        ));
    }

    fn item_done(&self) {
        self.bar.inc(1);
    }

    fn pass_done(&mut self, _: &Film, done: &PassDone) -> ControlFlow<()> {
        let (rays, seconds) = self.last;
        let rate = (done.rays - rays) as f64 / (done.seconds - seconds).max(1e-9) / 1e6;
        self.rate = format!(" {rate:.2} Mrays/s");
        self.last = (done.rays, done.seconds);
        ControlFlow::Continue(())
    }

    fn finished(&mut self) {
        self.bar.finish_and_clear();
    }
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
