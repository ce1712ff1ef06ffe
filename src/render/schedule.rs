//! Work is (work item × sample slice): a pass renders one slice of every
//! pixel's samples, and rayon steals work items of [`WORK_ITEM_PIXELS`]
//! consecutive pixels within the pass. Because a slice is a range of
//! indices of each pixel's one stratified set (`sampling::cmj`), splitting
//! work never weakens stratification, and because sums are fixed point
//! (`render::film`), the image does not depend on the thread count or on
//! how slices are split across processes.
//!
//! `Schedule::Regions` is the classic baseline for `strata scaling`: the
//! image cut into one band of rows per thread, no stealing.

use super::adaptive;
use super::aov::AovSum;
use super::film::{Film, Losses, PixelSum};
use super::progress::{Observer, Pass, PassDone};
use super::timeline::{ItemLists, ItemSpan, Phase, Timeline};
use super::warning::Warning;
use super::window::Window;
use super::workers::Workers;
use crate::accel::PACKET_SIZE;
use crate::sampling::{Dim, PixelSampler, SamplerKind};
use crate::scene::settings::RenderSettings;
use crate::scene::Scene;
use crate::shade::{CameraSample, FirstHit, Integrator, PacketMode, RayCounts, SampleContext};
use crate::system::cputime::CpuMeter;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::ops::{ControlFlow, Range};
use std::sync::Arc;
use std::time::Instant;

/// Pixels per work item: small enough that 64 threads stay busy on small images.
pub const WORK_ITEM_PIXELS: usize = 64;
/// Most passes a render is split into by default (each pass is a progress
/// tick and a checkpoint).
pub const DEFAULT_PASSES: u32 = 16;

/// Fewest samples per pixel in a pass when `--passes` is not given.
///
/// Within a pass a pixel's samples go to the integrator in batches of
/// [`PACKET_SIZE`], one after the other, so a pixel's second batch finds
/// the tree nodes and leaves its first one walked still in the caches;
/// the next pass comes back to the pixel only after every other pixel.
/// Passes are also each a barrier for the threads and a loop over the
/// film. Passes of 8, 16, 32 and 64 samples are timed in
/// docs/performance.md, "Passes and lanes".
pub const MIN_PASS_SAMPLES: u32 = 4 * PACKET_SIZE as u32;

/// Passes for `samples` samples per pixel when none are asked for: up to
/// [`DEFAULT_PASSES`], each with at least [`MIN_PASS_SAMPLES`] samples per
/// pixel. A pixel's samples are shaded in batches within a pass; in a
/// thinner pass a batch mixes neighbouring pixels' samples, and each pixel
/// is set up again in every pass (docs/performance.md, "Passes and lanes").
pub fn default_passes(samples: u32) -> u32 {
    (samples / MIN_PASS_SAMPLES).clamp(1, DEFAULT_PASSES)
}

crate::mode::mode_enum! {
    /// How work is split over threads: `slices` (work stealing over work
    /// items × sample slices) or `regions` (one static band of rows per
    /// thread, the classic baseline).
    #[derive(Default)]
    pub enum Schedule("schedule") {
        #[default]
        Slices = "slices",
        Regions = "regions",
    }
}

/// Slice `index` of `count` (0-based): this process renders only its share of every pixel's samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SliceSpec {
    pub index: u32,
    pub count: u32,
}

impl SliceSpec {
    pub const WHOLE: SliceSpec = SliceSpec { index: 0, count: 1 };

    /// The sample indices of this slice out of `spp`.
    pub fn samples(&self, spp: u32) -> Range<u32> {
        let lo = (self.index as u64 * spp as u64 / self.count as u64) as u32;
        let hi = ((self.index as u64 + 1) * spp as u64 / self.count as u64) as u32;
        lo..hi
    }
}

impl std::str::FromStr for SliceSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, p) = s
            .split_once('/')
            .ok_or_else(|| format!("slice '{s}' is not of the form k/P"))?;
        let index: u32 = k
            .trim()
            .parse()
            .map_err(|_| format!("slice index '{k}' is not a number"))?;
        let count: u32 = p
            .trim()
            .parse()
            .map_err(|_| format!("slice count '{p}' is not a number"))?;
        if count == 0 || index >= count {
            return Err(format!("slice {index}/{count}: need 0 ≤ k < P"));
        }
        Ok(Self { index, count })
    }
}

#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Worker threads; 0 = all cores.
    pub threads: usize,
    pub slice: SliceSpec,
    pub schedule: Schedule,
    /// Passes to split this process's samples into (capped by the sample
    /// count); `None` for [`default_passes`].
    pub passes: Option<u32>,
    /// Sample indices already rendered (from a checkpoint), skipped.
    pub resume_from: Option<u32>,
    /// Trace a batch's camera rays, and its shadow rays towards one light
    /// sample, as packets; the image is bit-identical for every mode.
    pub packets: PacketMode,
    /// The pixels to render (`--crop`); `None` for the whole image.
    pub window: Option<Window>,
    /// Also accumulate what each camera ray hit first (`--aov`).
    pub aovs: bool,
    /// Record every work item and pass here (`--timeline`); the image does
    /// not depend on it.
    pub timeline: Option<Arc<Timeline>>,
    /// Seconds the passes may take (`--time`): no pass starts that the
    /// last one's pace says would end past them (the first always runs).
    /// The image then depends on the machine's speed.
    pub budget: Option<f64>,
    /// Also measure the workers' CPU time (`RenderOutcome::cpu`, which
    /// `strata scaling` reads): a broadcast to the pool before the first
    /// pass and after each, 75 µs of a small render's 3.2 ms, so only
    /// where something reads it.
    pub cpu_times: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            threads: 0,
            slice: SliceSpec::WHOLE,
            schedule: Schedule::Slices,
            passes: None,
            resume_from: None,
            packets: PacketMode::Auto,
            window: None,
            aovs: false,
            timeline: None,
            budget: None,
            cpu_times: false,
        }
    }
}

#[derive(Debug, Clone)]
pub struct RenderOutcome {
    pub film: Film,
    pub counts: RayCounts,
    pub seconds: f64,
    pub threads: usize,
    pub samples: Range<u32>,
    /// CPU time spent, where asked for (`RenderOptions::cpu_times`) and
    /// the system reports it (Linux).
    pub cpu: Option<crate::system::cputime::CpuTimes>,
    /// Per pixel of the window, the sums of the first hits, with
    /// [`RenderOptions::aovs`].
    pub aov: Option<Vec<AovSum>>,
    /// What the front end should say, in the order found.
    pub warnings: Vec<Warning>,
    /// The observer (or the time budget) ended the render after a pass:
    /// the film holds fewer samples than `samples`.
    pub stopped: bool,
    /// The end of the last pass rendered: the most samples a pixel has
    /// (`samples.end` unless stopped, or every pixel met the noise target).
    pub done: u32,
}

/// The pass boundaries that split `range` into at most `passes` parts.
pub fn pass_ranges(range: Range<u32>, passes: u32) -> Vec<Range<u32>> {
    let n = range.end - range.start;
    let passes = passes.clamp(1, n.max(1));
    (0..passes)
        .map(|i| {
            let lo = range.start + (i as u64 * n as u64 / passes as u64) as u32;
            let hi = range.start + ((i as u64 + 1) * n as u64 / passes as u64) as u32;
            lo..hi
        })
        .filter(|r| !r.is_empty())
        .collect()
}

/// Render this process's slice, telling `observer` how it goes (each
/// pass's end is where checkpoints are written); `film` starts from
/// `initial` when resuming.
///
/// A crop under a noise target is rendered with a margin around it (a
/// pixel's decisions read its neighbours: `adaptive::crop_margin`), which
/// is cut off again, so that it equals the same window of the whole
/// render; `observer` sees the crop alone.
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    initial: Option<Film>,
    observer: impl Observer,
) -> RenderOutcome {
    let s = &scene.settings;
    let noise = adaptive::NoiseTarget::of(s).is_some() && opts.slice.count == 1;
    let crop = opts.window.clone().filter(|_| noise && initial.is_none());
    let Some(crop) = crop else {
        return render_window(scene, opts, initial, observer);
    };
    let grown = crop.grown(adaptive::crop_margin(s.spp), s.height);
    let inner = RenderOptions {
        window: Some(grown.clone()),
        ..opts.clone()
    };
    let cut = CutTo {
        observer,
        outer: &grown,
        inner: &crop,
    };
    let mut outcome = render_window(scene, &inner, None, cut);
    outcome.film = outcome.film.cut(&grown, &crop);
    outcome.aov = outcome.aov.map(|a| grown.cut(&crop, &a));
    outcome
}

/// An observer shown a film of window `outer` that passes on only its
/// window `inner`.
struct CutTo<'w, O> {
    observer: O,
    outer: &'w Window,
    inner: &'w Window,
}

impl<O: Observer> Observer for CutTo<'_, O> {
    fn started(&mut self, work_items: u64) {
        self.observer.started(work_items);
    }
    fn pass_started(&mut self, pass: &Pass) {
        self.observer.pass_started(pass);
    }
    fn item_done(&self) {
        self.observer.item_done();
    }
    fn pass_done(&mut self, film: &Film, done: &PassDone) -> ControlFlow<()> {
        self.observer
            .pass_done(&film.cut(self.outer, self.inner), done)
    }
    fn finished(&mut self) {
        self.observer.finished();
    }
}

/// [`render`] of `opts.window` as it is.
fn render_window(
    scene: &Scene,
    opts: &RenderOptions,
    initial: Option<Film>,
    mut observer: impl Observer,
) -> RenderOutcome {
    let setup_start = opts.timeline.as_deref().map(Timeline::now);
    let s = &scene.settings;
    let (pool, threads) = Workers::for_threads(opts.threads);
    let window = opts
        .window
        .clone()
        .unwrap_or_else(|| Window::whole(s.width, s.height));
    let mut film = initial.unwrap_or_else(|| Film::new(window.width(), window.height()));
    let full = opts.slice.samples(s.spp);
    let start_sample = opts
        .resume_from
        .unwrap_or(full.start)
        .clamp(full.start, full.end);
    let asked = opts
        .passes
        .unwrap_or_else(|| default_passes(full.end - full.start));
    // A noise target needs every sample of a pixel so far: a slice's
    // process has only its own, so slices render without one.
    let target = adaptive::NoiseTarget::of(s).filter(|_| opts.slice.count == 1);
    // A noise target judges, and a time budget stops, at the same points.
    if target.is_some() {
        film.track_squares();
    }
    let passes = if target.is_some() || opts.budget.is_some() {
        adaptive::passes(start_sample, full.end)
    } else {
        pass_ranges(start_sample..full.end, asked)
    };
    let mut warnings: Vec<Warning> = Warning::unlit(scene).into_iter().collect();
    if target.is_none()
        && opts.budget.is_none()
        && opts.passes.is_some()
        && (passes.len() as u32) < asked
        && !passes.is_empty()
    {
        warnings.push(Warning::FewerPasses {
            asked,
            made: passes.len() as u32,
        });
    }
    let n = film.pixel_count();
    let mut counts = RayCounts::default();
    let mut aov = opts.aovs.then(|| vec![AovSum::default(); n]);
    let mut cpu = opts
        .cpu_times
        .then(|| CpuMeter::start(pool.cpu_ns(), pool.caller()));
    let start = Instant::now();
    let chunk = match opts.schedule {
        Schedule::Slices => WORK_ITEM_PIXELS,
        Schedule::Regions => n.div_ceil(threads),
    };
    // A chunk is cut into work items of WORK_ITEM_PIXELS, the last shorter.
    let items_per_pass: u64 = (0..n)
        .step_by(chunk.max(1))
        .map(|first| (n - first).min(chunk).div_ceil(WORK_ITEM_PIXELS) as u64)
        .sum();
    observer.started(items_per_pass * passes.len() as u64);
    let timeline = opts.timeline.as_deref();
    let item_lists = timeline.map(|_| ItemLists::new(threads));
    if let (Some(t), Some(setup_start)) = (timeline, setup_start) {
        t.phase(Phase::Setup, setup_start, t.at(start));
    }
    let mut stopped = false;
    let mut done = start_sample;
    // Which pixels take this pass's samples, under a noise target.
    let mut decisions = adaptive::Decisions::default();
    // The last pass's seconds per pixel sample, for the time budget.
    let mut pace: Option<f64> = None;
    for (pass_index, samples) in passes.iter().enumerate() {
        if let Some(t) = target {
            pool.install(|| decisions.update(&film, t));
        }
        let active = decisions.active();
        let live = match target {
            Some(_) => active.iter().filter(|&&a| a).count(),
            None => n,
        };
        if live == 0 {
            break;
        }
        let work = live as f64 * samples.len() as f64;
        if let (Some(budget), Some(pace)) = (opts.budget, pace) {
            if start.elapsed().as_secs_f64() + pace * work > budget {
                stopped = true;
                break;
            }
        }
        let pass_clock = Instant::now();
        let pass_start = timeline.map(Timeline::now);
        let pass = Pass {
            index: pass_index,
            count: passes.len(),
            samples: samples.clone(),
            spp: s.spp,
        };
        observer.pass_started(&pass);
        // Each worker owns its chunk's AOV sums for the pass; they carry
        // over between passes, added to in sample order.
        let aov_chunks: Vec<Option<&mut [AovSum]>> = match &mut aov {
            Some(a) => a.chunks_mut(chunk).map(Some).collect(),
            None => (0..n.div_ceil(chunk)).map(|_| None).collect(),
        };
        let watching = &observer;
        let active = (!active.is_empty()).then_some(active);
        let set = SampleSet::of(s, target.is_some() || opts.budget.is_some(), samples);
        // Each chunk adds its pixels to its own run of the film as each
        // work item ends, while the item's sums are in the caches: added
        // after the pass on one thread, they took 20 ns a pixel (1.5 ms of
        // each 320 × 240 pass), and a pass held a record a pixel beside
        // the film (seed-mc at 1080p peaked at 304 MB, now 145 MB). Its
        // rays are counted by its own integrator; the pass sums the counts
        // and the losses.
        let runs = film.runs_mut(chunk);
        let (pass_counts, losses) = pool.install(|| {
            runs.into_par_iter()
                .zip(aov_chunks.into_par_iter())
                .enumerate()
                .with_max_len(1)
                .map(|(b, (mut run, mut aov_pixels))| {
                    // A clock read where the chunk starts (its integrator's
                    // setup counted in its first work item) and one where
                    // each work item ends, the next one's start.
                    let mut item_start = timeline.map(Timeline::now);
                    let mut integrator = Integrator::with_packets(scene, opts.packets);
                    let mut sums = [PixelSum::default(); WORK_ITEM_PIXELS];
                    let len = run.len();
                    for at in (0..len).step_by(WORK_ITEM_PIXELS) {
                        let accs = &mut sums[..(len - at).min(WORK_ITEM_PIXELS)];
                        accs.fill(PixelSum::default());
                        let first = b * chunk + at;
                        let aov = aov_pixels
                            .as_deref_mut()
                            .map(|a| &mut a[at..at + accs.len()]);
                        let active = active.map(|a| &a[first..first + accs.len()]);
                        let pixels = PixelRun {
                            window: &window,
                            first,
                            active,
                            set,
                        };
                        let rays_before = integrator.counts.total();
                        render_pixels(&mut integrator, scene, pixels, accs, aov, samples.clone());
                        // A pixel that took no samples has nothing to add.
                        for (i, acc) in accs.iter().enumerate() {
                            if active.is_none_or(|a| a[i]) {
                                run.add_pixel(at + i, acc);
                            }
                        }
                        if let (Some(t), Some(lists), Some(start_ns)) =
                            (timeline, &item_lists, item_start)
                        {
                            let end_ns = t.now();
                            lists.push(ItemSpan {
                                thread: rayon::current_thread_index().unwrap_or(0),
                                pass: pass_index,
                                pixels: first as u32..(first + accs.len()) as u32,
                                samples: samples.clone(),
                                start_ns,
                                end_ns,
                                rays: integrator.counts.total() - rays_before,
                            });
                            item_start = Some(end_ns);
                        }
                        watching.item_done();
                    }
                    (integrator.counts, run.losses)
                })
                .reduce(
                    || (RayCounts::default(), Losses::default()),
                    |a, b| (a.0 + b.0, a.1.merge(b.1)),
                )
        });
        counts += pass_counts;
        let film_start = timeline.map(Timeline::now);
        film.add_losses(losses);
        if let Some(cpu) = &mut cpu {
            cpu.pass(pool.cpu_ns());
        }
        done = samples.end;
        pace = Some(pass_clock.elapsed().as_secs_f64() / work);
        let after_start = timeline.map(Timeline::now);
        let done = PassDone {
            pass,
            rays: counts.total(),
            seconds: start.elapsed().as_secs_f64(),
        };
        stopped = observer.pass_done(&film, &done).is_break();
        if let (Some(t), Some(pass_start), Some(film_start), Some(after_start)) =
            (timeline, pass_start, film_start, after_start)
        {
            let of_pass = || Some((pass_index, samples.clone()));
            t.phase_of_pass(Phase::Pass, of_pass(), pass_start, film_start);
            t.phase_of_pass(Phase::Film, of_pass(), film_start, after_start);
            t.phase_of_pass(Phase::AfterPass, of_pass(), after_start, t.now());
        }
        if stopped {
            break;
        }
    }
    if let (Some(t), Some(lists)) = (timeline, item_lists) {
        t.add_items(&window, threads, lists.into_items());
    }
    observer.finished();
    let seconds = start.elapsed().as_secs_f64();
    warnings.extend(Warning::dropped(&film));
    RenderOutcome {
        film,
        counts,
        seconds,
        threads,
        samples: full,
        cpu: cpu.and_then(CpuMeter::finish),
        aov,
        warnings,
        stopped,
        done,
    }
}

/// All samples of `samples` for one pixel, of a render's one set.
#[inline]
pub fn render_pixel(
    integrator: &mut Integrator,
    scene: &Scene,
    index: usize,
    samples: Range<u32>,
    acc: &mut PixelSum,
) {
    let set = SampleSet::whole(scene.settings.seed, scene.settings.spp);
    render_pixel_of(integrator, scene, index, samples, set, acc);
}

/// All samples of `samples` for one pixel, drawn from `set`.
pub fn render_pixel_of(
    integrator: &mut Integrator,
    scene: &Scene,
    index: usize,
    samples: Range<u32>,
    set: SampleSet,
    acc: &mut PixelSum,
) {
    let whole = Window::whole(scene.settings.width, scene.settings.height);
    let pixels = PixelRun {
        window: &whole,
        first: index,
        active: None,
        set,
    };
    render_pixels(
        integrator,
        scene,
        pixels,
        std::slice::from_mut(acc),
        None,
        samples,
    );
}

/// Pixels `first..` of `window` (row-major); with `active`, only those
/// whose entry is true (a noise target's pixels still sampling); their
/// samples drawn from `set`.
#[derive(Debug, Clone, Copy)]
pub struct PixelRun<'w> {
    pub window: &'w Window,
    pub first: usize,
    pub active: Option<&'w [bool]>,
    pub set: SampleSet,
}

/// The stratified set that samples are drawn from: sample `i` is index
/// `i − first` of each pixel's set of `count`, whose scrambling `seed`
/// chooses. A render's samples are one set of spp (`first` 0, the
/// render's seed); a noise target's passes are each a set of their own
/// (`render::adaptive`), so that a pixel stopped after any pass has used
/// whole stratified sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleSet {
    pub first: u32,
    pub count: u32,
    pub seed: u32,
}

impl SampleSet {
    /// Every sample of a render of `spp`: one set.
    pub fn whole(seed: u32, spp: u32) -> Self {
        Self {
            first: 0,
            count: spp,
            seed,
        }
    }

    /// The set that a render of `settings` draws the samples of `pass`
    /// from. `may_stop`: a pixel may stop after any pass (a noise target, a
    /// time budget), so each pass is a stratified set of its own, except
    /// under the Sobol sampler, whose one sequence is stratified at every
    /// power-of-two prefix and so serves as one set.
    pub fn of(settings: &RenderSettings, may_stop: bool, pass: &Range<u32>) -> Self {
        match may_stop && settings.sampler != SamplerKind::Sobol {
            true => Self::of_pass(settings.seed, pass),
            false => Self::whole(settings.seed, settings.spp),
        }
    }

    /// The samples of one pass of a noise target: a set of their own,
    /// scrambled apart from every other pass's (the first keeps the
    /// render's seed).
    pub fn of_pass(seed: u32, pass: &Range<u32>) -> Self {
        let seed = match pass.start {
            0 => seed,
            start => crate::sampling::hash::hash_words(&[seed, start]),
        };
        Self {
            first: pass.start,
            count: pass.end - pass.start,
            seed,
        }
    }
}

/// All samples of `samples` for the pixels `run.first..run.first +
/// accs.len()` of its window, into `accs`, and with `aov`, what their camera
/// rays hit first into it.
///
/// The pixels' samples form one sequence, pixel by pixel and in index order
/// within each, and go to the integrator a batch of [`PACKET_SIZE`] at a time: with
/// eight or more samples per pixel a batch is mostly the pixel and lens
/// samples of one pixel, whose rays start close together and point nearly
/// the same way; with fewer (or a pixel's last few) it takes the next
/// pixels' samples too, so that its SIMD lanes (its camera packet, its
/// light samples) are full and a one-sample pass does not shade one ray
/// at a time; such batches' camera rays still gain from travelling as a
/// packet (the timings against batches of one pixel's samples and against
/// `--packets off` are in docs/performance.md, "Passes and lanes", and
/// "Measurements behind the renderer's defaults"). Each sample is still
/// computed from its own index alone and added to its own pixel in index
/// order, so the sums are those of sample-by-sample rendering.
pub fn render_pixels(
    integrator: &mut Integrator,
    scene: &Scene,
    run: PixelRun,
    accs: &mut [PixelSum],
    mut aov: Option<&mut [AovSum]>,
    samples: Range<u32>,
) {
    let s = &scene.settings;
    if samples.is_empty() || accs.is_empty() {
        return;
    }
    // The next pixel from `j` on that takes samples.
    let live = |mut j: usize| {
        while run.active.is_some_and(|a| j < a.len() && !a[j]) {
            j += 1;
        }
        j
    };
    let (mut j, mut next) = (live(0), samples.start);
    if j == accs.len() {
        return;
    }
    let mut out = [Vec3::ZERO; PACKET_SIZE];
    let mut first_hits = [FirstHit::MISS; PACKET_SIZE];
    // The common set sizes, prepared once for all these pixels: camera
    // samples, and first-hit light samples.
    let set = run.set;
    let sets = PixelSampler::prepare_sets([set.count, set.count.saturating_mul(s.shadow_samples)]);
    // The pixel the sequence is in (`j`), what it shares among its
    // samples, and its next sample; kept across batches, so that each pixel
    // is set up once and the sequence needs no divisions.
    let setup = |j: usize| {
        let (x, y, index) = run.window.pixel(run.first + j);
        let sampler = PixelSampler::new(s.sampler, set.seed, index).with_sets(sets);
        let jitter = sampler.dim_2d(Dim::PIXEL, set.count);
        (Vec2::new(x as f32, y as f32), sampler, jitter)
    };
    let (mut corner, mut sampler, mut jitter) = setup(j);
    let mut batch = [CameraSample {
        ctx: SampleContext::new(sampler, 0, set.count),
        film: Vec2::ZERO,
    }; PACKET_SIZE];
    // Each lane's pixel: a lane that stays with its pixel from one batch
    // to the next keeps its sample context and changes only the index.
    // (Written whole per sample, the 168-byte contexts were copied through
    // the stack with wide loads that stalled on narrower stores; see
    // docs/mitsuba.md, "What was tried for the render".)
    let mut pixel_of = [usize::MAX; PACKET_SIZE];
    while j < accs.len() {
        // The batch's samples, one pixel's at a time.
        let mut n = 0;
        while n < PACKET_SIZE && j < accs.len() {
            let end = samples.end.min(next + (PACKET_SIZE - n) as u32);
            let len = (end - next) as usize;
            // This pixel's share of the batch: its pixel samples in SIMD
            // lanes (unused lanes repeat the last sample).
            let index = std::array::from_fn(|i| (next + i as u32).min(end - 1) - set.first);
            let offsets = jitter.get_2d_lanes(index, (1 << len) - 1);
            let lanes = batch[n..n + len].iter_mut().zip(&mut pixel_of[n..n + len]);
            for ((camera, pixel), (sample, offset)) in lanes.zip((next..end).zip(offsets)) {
                let sample = sample - set.first;
                if *pixel == j {
                    camera.ctx.sample = sample;
                } else {
                    camera.ctx = SampleContext::new(sampler, sample, set.count);
                    *pixel = j;
                }
                camera.film = corner + offset;
            }
            n += len;
            next = end;
            if next == samples.end {
                j = live(j + 1);
                next = samples.start;
                if j < accs.len() {
                    (corner, sampler, jitter) = setup(j);
                }
            }
        }
        let first = aov.is_some().then_some(&mut first_hits[..]);
        integrator.camera_batch(&batch[..n], &mut out, first);
        for ((v, camera), &pixel) in out.iter().zip(&batch[..n]).zip(&pixel_of) {
            accs[pixel].add(*v, camera.ctx.sample + set.first);
        }
        if let Some(aov) = aov.as_deref_mut() {
            for (hit, &j) in first_hits[..n].iter().zip(&pixel_of) {
                aov[j].add(hit);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_partition_the_samples() {
        for spp in [1u32, 2, 7, 16, 1000] {
            for p in 1..=6u32 {
                let mut covered = Vec::new();
                for k in 0..p {
                    covered.extend(SliceSpec { index: k, count: p }.samples(spp));
                }
                assert_eq!(covered, (0..spp).collect::<Vec<_>>());
            }
        }
        assert!("3/3".parse::<SliceSpec>().is_err());
        assert!("a/3".parse::<SliceSpec>().is_err());
        assert_eq!(
            "1/4".parse::<SliceSpec>(),
            Ok(SliceSpec { index: 1, count: 4 })
        );
    }

    #[test]
    fn default_passes_are_thick_and_few() {
        for spp in [1u32, 7, 31, 32, 64, 100, 1024, 100_000] {
            let passes = pass_ranges(0..spp, default_passes(spp));
            assert!(passes.len() as u32 <= DEFAULT_PASSES);
            // Thinner passes only where the sample count allows no more.
            let thinnest = passes.iter().map(|p| p.len() as u32).min().unwrap();
            assert!(
                thinnest >= MIN_PASS_SAMPLES.min(spp),
                "{spp} spp: {passes:?}"
            );
        }
        assert_eq!(default_passes(16), 1);
        assert_eq!(default_passes(1024), DEFAULT_PASSES);
    }

    #[test]
    fn passes_cover_the_range_in_order() {
        let r = pass_ranges(3..40, 16);
        assert_eq!(r.first().unwrap().start, 3);
        assert_eq!(r.last().unwrap().end, 40);
        assert!(r.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(pass_ranges(0..1, 16), vec![0..1]);
    }
}
