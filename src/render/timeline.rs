//! The timeline of a render (`strata render --timeline`): when each work
//! item ran and on which thread, when each serial phase ran (load, BVH
//! build, each pass's barrier and film update, output), written in the
//! Chrome trace event format that Perfetto and `chrome://tracing` open.
//!
//! Recording costs two clock reads per work item and one uncontended lock
//! (each thread writes only its own list), not anything per ray: a work
//! item is 64 pixels × a pass's samples, thousands of rays. The cost is
//! measured in docs/scaling.md, "The timeline".
//!
//! [`Timeline::summary`] is what a person reads at a glance: each thread's
//! busy and idle time, the longest work item against the mean, and each
//! phase's share of the wall time. `experiment::predict` replays the work
//! items' costs on other thread counts.

use super::window::Window;
use serde::Serialize;
use std::fmt::Write as _;
use std::ops::Range;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// One work item as it ran: `pixels` of the window (row-major indices),
/// samples `samples` of each, on worker `thread`, traced `rays` rays.
#[derive(Debug, Clone, PartialEq)]
pub struct ItemSpan {
    pub thread: usize,
    pub pass: usize,
    pub pixels: Range<u32>,
    pub samples: Range<u32>,
    pub start_ns: u64,
    pub end_ns: u64,
    pub rays: u64,
}

impl ItemSpan {
    pub fn seconds(&self) -> f64 {
        self.end_ns.saturating_sub(self.start_ns) as f64 * 1e-9
    }

    /// The item's pixels as rectangles of the image, in order: one where
    /// they lie in one row, more where they wrap past the window's edge.
    pub fn rects(&self, window: &Window) -> Vec<PixelRect> {
        pixel_rects(window, &self.pixels)
    }
}

/// A rectangle of pixels in the image's coordinates (from its top-left
/// corner, as `--crop` and `--debug-sample` count them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct PixelRect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl std::fmt::Display for PixelRect {
    /// `64x1 at (128, 40)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}x{} at ({}, {})",
            self.width, self.height, self.x, self.y
        )
    }
}

/// "64x1 at (128, 40)", or "36x1 at (64, 0) and 28x1 at (0, 1)".
pub fn rects_text(rects: &[PixelRect]) -> String {
    let texts: Vec<String> = rects.iter().map(PixelRect::to_string).collect();
    texts.join(" and ")
}

/// The window's row-major pixels `pixels` as at most three rectangles of
/// the image: the rest of the first row, whole rows, the start of the last.
pub fn pixel_rects(window: &Window, pixels: &Range<u32>) -> Vec<PixelRect> {
    let w = window.width().max(1);
    let (x0, y0) = (window.x.start, window.y.start);
    let mut out = Vec::new();
    let mut i = pixels.start;
    while i < pixels.end {
        let (col, row) = (i % w, i / w);
        let rest = pixels.end - i;
        let rect = if col == 0 && rest >= w {
            let rows = rest / w;
            PixelRect {
                x: x0,
                y: y0 + row,
                width: w,
                height: rows,
            }
        } else {
            PixelRect {
                x: x0 + col,
                y: y0 + row,
                width: (w - col).min(rest),
                height: 1,
            }
        };
        i += rect.width * rect.height;
        out.push(rect);
    }
    out
}

/// What the calling thread did, outside the work items.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Reading the scene and its meshes.
    Load,
    /// Building the BVH (on the render's threads).
    Build,
    /// The render's setup before its first pass: the thread pool, the
    /// film's buffers, the header of a part or checkpoint.
    Setup,
    /// One pass: from handing its work items to the threads until the last
    /// one finished (the barrier).
    Pass,
    /// Adding a pass's sums into the film (serial).
    Film,
    /// What runs after each pass: the checkpoint, the progressive image.
    AfterPass,
    /// Writing the image or the part.
    Output,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Load => "load",
            Phase::Build => "BVH build",
            Phase::Setup => "setup",
            Phase::Pass => "pass",
            Phase::Film => "film",
            Phase::AfterPass => "after pass",
            Phase::Output => "output",
        }
    }
}

/// A span of the calling thread: `pass` for the passes and what follows them.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseSpan {
    pub phase: Phase,
    pub pass: Option<usize>,
    pub samples: Option<Range<u32>>,
    pub start_ns: u64,
    pub end_ns: u64,
}

impl PhaseSpan {
    pub fn seconds(&self) -> f64 {
        self.end_ns.saturating_sub(self.start_ns) as f64 * 1e-9
    }
}

#[derive(Debug, Default)]
struct Spans {
    items: Vec<ItemSpan>,
    phases: Vec<PhaseSpan>,
    threads: usize,
    /// The window the items' pixel indices count in.
    window: Option<Window>,
}

/// Where a render's spans are recorded; times are from `epoch`, which the
/// caller sets before the scene is loaded.
#[derive(Debug)]
pub struct Timeline {
    epoch: Instant,
    spans: Mutex<Spans>,
}

impl Timeline {
    pub fn new(epoch: Instant) -> Self {
        Self {
            epoch,
            spans: Mutex::default(),
        }
    }

    /// Nanoseconds from the epoch to `t`.
    pub fn at(&self, t: Instant) -> u64 {
        t.saturating_duration_since(self.epoch).as_nanos() as u64
    }

    /// Nanoseconds from the epoch to now.
    pub fn now(&self) -> u64 {
        self.at(Instant::now())
    }

    /// Record a phase of the calling thread.
    pub fn phase(&self, phase: Phase, start_ns: u64, end_ns: u64) {
        self.phase_of_pass(phase, None, start_ns, end_ns);
    }

    /// Record a phase belonging to pass `pass` (with its samples).
    pub fn phase_of_pass(
        &self,
        phase: Phase,
        pass: Option<(usize, Range<u32>)>,
        start_ns: u64,
        end_ns: u64,
    ) {
        let (pass, samples) = pass.map_or((None, None), |(p, s)| (Some(p), Some(s)));
        self.lock().phases.push(PhaseSpan {
            phase,
            pass,
            samples,
            start_ns,
            end_ns,
        });
    }

    /// The load and the build as the scene compiler timed them: the load
    /// from the epoch, the build right after it.
    pub fn load_and_build(&self, load: Duration, build: Duration) {
        let load_ns = load.as_nanos() as u64;
        self.phase(Phase::Load, 0, load_ns);
        self.phase(Phase::Build, load_ns, load_ns + build.as_nanos() as u64);
    }

    /// Add one render's work items, recorded on `threads` workers, their
    /// pixels counted in `window`.
    pub fn add_items(
        &self,
        window: &Window,
        threads: usize,
        items: impl IntoIterator<Item = ItemSpan>,
    ) {
        let mut spans = self.lock();
        spans.threads = spans.threads.max(threads);
        spans.window = Some(window.clone());
        spans.items.extend(items);
    }

    /// The window the work items' pixels lie in (the whole image if no
    /// render said).
    pub fn window(&self) -> Window {
        let spans = self.lock();
        spans.window.clone().unwrap_or_else(|| {
            let end = spans.items.iter().map(|i| i.pixels.end).max().unwrap_or(0);
            Window::whole(end.max(1), 1)
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Spans> {
        // A panic while holding the lock leaves whole spans behind.
        self.spans.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The work items, sorted by start.
    pub fn items(&self) -> Vec<ItemSpan> {
        let mut items = self.lock().items.clone();
        items.sort_by_key(|i| (i.start_ns, i.thread));
        items
    }

    /// The calling thread's spans, sorted by start.
    pub fn phases(&self) -> Vec<PhaseSpan> {
        let mut phases = self.lock().phases.clone();
        phases.sort_by_key(|p| p.start_ns);
        phases
    }

    /// Worker threads the render ran on.
    pub fn threads(&self) -> usize {
        self.lock().threads
    }

    /// The trace in Chrome's trace event format: track 0 is the calling
    /// thread (load, build, passes, output), tracks 1.. the workers (a span
    /// per work item), and a counter of rays per second.
    pub fn to_chrome_json(&self, process_name: &str) -> String {
        let items = self.items();
        let phases = self.phases();
        let threads = self.threads();
        let window = self.window();
        let mut events: Vec<String> = Vec::with_capacity(items.len() + phases.len() + 64);
        let name = serde_json::to_string(process_name).expect("a string serialises");
        // Every event carries the same six fields, so that a reader may
        // rely on them; metadata and counters have ts and dur 0 where the
        // format gives them no meaning.
        events.push(format!(
            r#"{{"name":"process_name","ph":"M","ts":0,"dur":0,"pid":1,"tid":0,"args":{{"name":{name}}}}}"#
        ));
        for tid in 0..=threads {
            let label = match tid {
                0 => "main".to_string(),
                t => format!("worker {t}"),
            };
            events.push(format!(
                r#"{{"name":"thread_name","ph":"M","ts":0,"dur":0,"pid":1,"tid":{tid},"args":{{"name":"{label}"}}}}"#
            ));
            events.push(format!(
                r#"{{"name":"thread_sort_index","ph":"M","ts":0,"dur":0,"pid":1,"tid":{tid},"args":{{"sort_index":{tid}}}}}"#
            ));
        }
        let us = |ns: u64| ns as f64 * 1e-3;
        for p in &phases {
            let mut args = String::new();
            let mut label = p.phase.name().to_string();
            if let Some(pass) = p.pass {
                let _ = write!(label, " {}", pass + 1);
                let _ = write!(args, r#""pass":{}"#, pass + 1);
            }
            if let Some(s) = &p.samples {
                let _ = write!(args, r#","samples":"{}..{}""#, s.start, s.end);
            }
            events.push(format!(
                r#"{{"name":"{label}","cat":"phase","ph":"X","ts":{:.3},"dur":{:.3},"pid":1,"tid":0,"args":{{{args}}}}}"#,
                us(p.start_ns),
                us(p.end_ns.saturating_sub(p.start_ns)),
            ));
        }
        for i in &items {
            events.push(format!(
                r#"{{"name":"work item","cat":"work","ph":"X","ts":{:.3},"dur":{:.3},"pid":1,"tid":{},"args":{{"pass":{},"pixels":"{}","samples":"{}..{}","rays":{}}}}}"#,
                us(i.start_ns),
                us(i.end_ns.saturating_sub(i.start_ns)),
                i.thread + 1,
                i.pass + 1,
                rects_text(&i.rects(&window)),
                i.samples.start,
                i.samples.end,
                i.rays
            ));
        }
        for (t, rate) in ray_rate(&items, 200) {
            events.push(format!(
                r#"{{"name":"rays per second","ph":"C","ts":{:.3},"dur":0,"pid":1,"tid":0,"args":{{"Mrays/s":{:.4}}}}}"#,
                us(t),
                rate * 1e-6
            ));
        }
        let mut out = String::from("{\"displayTimeUnit\":\"ms\",\"traceEvents\":[\n");
        out += &events.join(",\n");
        out += "\n]}\n";
        out
    }

    /// What a person reads at a glance (`None` before any work item).
    pub fn summary(&self) -> Option<TimelineSummary> {
        let items = self.items();
        let phases = self.phases();
        let threads = self.threads();
        if items.is_empty() {
            return None;
        }
        let sum = |phase: Phase| seconds_in(&phases, phase);
        let render_s = sum(Phase::Pass);
        let mut per_thread: Vec<ThreadTime> = (0..threads)
            .map(|t| ThreadTime {
                thread: t + 1,
                items: 0,
                rays: 0,
                busy_s: 0.0,
                idle_s: 0.0,
            })
            .collect();
        for i in &items {
            let t = &mut per_thread[i.thread];
            t.items += 1;
            t.rays += i.rays;
            t.busy_s += i.seconds();
        }
        for t in &mut per_thread {
            t.idle_s = (render_s - t.busy_s).max(0.0);
        }
        let longest = items
            .iter()
            .max_by(|a, b| a.seconds().total_cmp(&b.seconds()))
            .expect("items is not empty");
        let mean = items.iter().map(ItemSpan::seconds).sum::<f64>() / items.len() as f64;
        let start = phases.iter().map(|p| p.start_ns).min().unwrap_or(0);
        let end = phases
            .iter()
            .map(|p| p.end_ns)
            .chain(items.iter().map(|i| i.end_ns))
            .max()
            .unwrap_or(0);
        let wall_s = end.saturating_sub(start) as f64 * 1e-9;
        let share = |phase: Phase| PhaseShare {
            phase,
            seconds: sum(phase),
            share: sum(phase) / wall_s.max(1e-12),
        };
        let phases = [
            Phase::Load,
            Phase::Build,
            Phase::Setup,
            Phase::Pass,
            Phase::Film,
            Phase::AfterPass,
            Phase::Output,
        ]
        .into_iter()
        .filter(|&p| phases.iter().any(|s| s.phase == p))
        .map(share)
        .collect();
        Some(TimelineSummary {
            wall_s,
            threads: per_thread,
            items: items.len(),
            mean_item_s: mean,
            longest_item_s: longest.seconds(),
            longest_item: LongestItem {
                pass: longest.pass + 1,
                pixels: longest.rects(&self.window()),
                thread: longest.thread + 1,
            },
            phases,
        })
    }
}

/// The seconds `phases` spent in `phase`, all its spans together.
pub fn seconds_in(phases: &[PhaseSpan], phase: Phase) -> f64 {
    phases
        .iter()
        .filter(|p| p.phase == phase)
        .map(PhaseSpan::seconds)
        .sum()
}

/// Rays per second over `buckets` equal stretches of the render: each work
/// item's rays spread evenly over its span.
fn ray_rate(items: &[ItemSpan], buckets: usize) -> Vec<(u64, f64)> {
    let (Some(start), Some(end)) = (
        items.iter().map(|i| i.start_ns).min(),
        items.iter().map(|i| i.end_ns).max(),
    ) else {
        return Vec::new();
    };
    let width = (end.saturating_sub(start)).div_ceil(buckets as u64).max(1);
    let mut rays = vec![0.0f64; buckets];
    for i in items {
        let len = i.end_ns.saturating_sub(i.start_ns).max(1) as f64;
        let first = ((i.start_ns - start) / width) as usize;
        let last = (((i.end_ns - start) / width) as usize).min(buckets - 1);
        for (b, r) in rays.iter_mut().enumerate().take(last + 1).skip(first) {
            let lo = (start + b as u64 * width).max(i.start_ns);
            let hi = (start + (b as u64 + 1) * width).min(i.end_ns.max(i.start_ns + 1));
            *r += i.rays as f64 * hi.saturating_sub(lo) as f64 / len;
        }
    }
    rays.iter()
        .enumerate()
        .map(|(b, r)| (start + b as u64 * width, r / (width as f64 * 1e-9)))
        .collect()
}

/// One worker's share of the render.
#[derive(Debug, Clone, Serialize)]
pub struct ThreadTime {
    /// The worker's track in the trace (1, 2, …).
    pub thread: usize,
    pub items: usize,
    pub rays: u64,
    /// Time in work items.
    pub busy_s: f64,
    /// Time in passes outside work items: waiting at the barrier, stealing.
    pub idle_s: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct LongestItem {
    pub pass: usize,
    /// Its pixels as rectangles of the image (x, y, width, height): one,
    /// or more where the item wraps past the window's edge.
    pub pixels: Vec<PixelRect>,
    pub thread: usize,
}

#[derive(Debug, Clone, Serialize)]
pub struct PhaseShare {
    pub phase: Phase,
    pub seconds: f64,
    /// Of the wall time from the first span to the last.
    pub share: f64,
}

/// The timeline at a glance, printed by `strata scaling` and `strata
/// render --timeline`, written into the statistics JSON.
#[derive(Debug, Clone, Serialize)]
pub struct TimelineSummary {
    pub wall_s: f64,
    pub threads: Vec<ThreadTime>,
    pub items: usize,
    pub mean_item_s: f64,
    pub longest_item_s: f64,
    pub longest_item: LongestItem,
    pub phases: Vec<PhaseShare>,
}

impl TimelineSummary {
    /// A few lines for a terminal.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let phases: Vec<String> = self
            .phases
            .iter()
            .map(|p| {
                format!(
                    "{} {:.3} s ({:.1}%)",
                    p.phase.name(),
                    p.seconds,
                    100.0 * p.share
                )
            })
            .collect();
        let _ = writeln!(s, "  wall {:.3} s: {}", self.wall_s, phases.join(", "));
        for t in &self.threads {
            let total = (t.busy_s + t.idle_s).max(1e-12);
            let _ = writeln!(
                s,
                "  worker {:>2}: busy {:.3} s ({:.1}%), idle {:.3} s, {} work items, {:.2} M rays",
                t.thread,
                t.busy_s,
                100.0 * t.busy_s / total,
                t.idle_s,
                t.items,
                t.rays as f64 * 1e-6
            );
        }
        let l = &self.longest_item;
        let _ = writeln!(
            s,
            "  {} work items: mean {:.3} ms, longest {:.3} ms ({:.1}x the mean: pass {}, pixels {}, worker {})",
            self.items,
            self.mean_item_s * 1e3,
            self.longest_item_s * 1e3,
            self.longest_item_s / self.mean_item_s.max(1e-12),
            l.pass,
            rects_text(&l.pixels),
            l.thread
        );
        s
    }
}

/// Each worker's own list of work items while a render runs (no lock is
/// ever contended: a worker pushes to its own list only).
#[derive(Debug)]
pub struct ItemLists(Vec<Mutex<Vec<ItemSpan>>>);

impl ItemLists {
    pub fn new(threads: usize) -> Self {
        Self((0..threads).map(|_| Mutex::default()).collect())
    }

    pub fn push(&self, item: ItemSpan) {
        let list = &self.0[item.thread.min(self.0.len() - 1)];
        list.lock().unwrap_or_else(|e| e.into_inner()).push(item);
    }

    pub fn into_items(self) -> impl Iterator<Item = ItemSpan> {
        self.0
            .into_iter()
            .flat_map(|m| m.into_inner().unwrap_or_else(|e| e.into_inner()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(thread: usize, start_ns: u64, end_ns: u64, rays: u64) -> ItemSpan {
        ItemSpan {
            thread,
            pass: 0,
            pixels: 0..64,
            samples: 0..4,
            start_ns,
            end_ns,
            rays,
        }
    }

    #[test]
    fn the_ray_rate_integrates_to_the_rays() {
        let items = [item(0, 0, 1000, 500), item(1, 200, 2999, 700)];
        let rate = ray_rate(&items, 7);
        let width = (rate[1].0 - rate[0].0) as f64 * 1e-9;
        let total: f64 = rate.iter().map(|(_, r)| r * width).sum();
        assert!((total - 1200.0).abs() < 1e-6, "{total}");
    }

    #[test]
    fn the_summary_counts_busy_and_idle_time() {
        let t = Timeline::new(Instant::now());
        t.phase(Phase::Load, 0, 1_000);
        t.phase_of_pass(Phase::Pass, Some((0, 0..4)), 1_000, 11_000);
        t.add_items(
            &Window::whole(64, 1),
            2,
            [item(0, 1_000, 11_000, 10), item(1, 1_000, 3_000, 5)],
        );
        let s = t.summary().unwrap();
        assert_eq!(s.items, 2);
        assert!((s.threads[0].busy_s - 1e-5).abs() < 1e-12);
        assert!((s.threads[1].idle_s - 8e-6).abs() < 1e-12);
        assert!((s.longest_item_s - 1e-5).abs() < 1e-12);
        assert!((s.wall_s - 1.1e-5).abs() < 1e-12);
        let json: serde_json::Value = serde_json::from_str(&t.to_chrome_json("x\"y")).unwrap();
        assert!(json["traceEvents"].as_array().unwrap().len() > 3);
        assert!(s.text().contains("worker  2"));
    }

    /// Issue 62: a work item is named by where its pixels are, not by
    /// their flat indices: a rectangle of a row, or a row's end and the
    /// next one's start where it wraps, in the image's coordinates.
    #[test]
    fn work_items_are_named_by_their_pixel_rectangles() {
        let rect = |x, y, width, height| PixelRect {
            x,
            y,
            width,
            height,
        };
        let whole = Window::whole(100, 50);
        assert_eq!(pixel_rects(&whole, &(0..64)), [rect(0, 0, 64, 1)]);
        assert_eq!(
            pixel_rects(&whole, &(64..128)),
            [rect(64, 0, 36, 1), rect(0, 1, 28, 1)]
        );
        // A window narrower than an item: whole rows between the ends.
        let crop = Window {
            x: 10..30,
            y: 5..25,
            image_width: 100,
        };
        let rects = pixel_rects(&crop, &(15..79));
        assert_eq!(
            rects,
            [rect(25, 5, 5, 1), rect(10, 6, 20, 2), rect(10, 8, 19, 1)]
        );
        let count: u32 = rects.iter().map(|r| r.width * r.height).sum();
        assert_eq!(count, 64);
        assert_eq!(
            rects_text(&rects[..2]),
            "5x1 at (25, 5) and 20x2 at (10, 6)"
        );
        // The trace and the summary say the same.
        let t = Timeline::new(Instant::now());
        t.phase_of_pass(Phase::Pass, Some((0, 0..4)), 0, 20_000);
        let mut long = item(0, 0, 20_000, 1);
        long.pixels = 64..128;
        t.add_items(&whole, 1, [long]);
        let trace: serde_json::Value = serde_json::from_str(&t.to_chrome_json("x")).unwrap();
        let events = trace["traceEvents"].as_array().unwrap();
        let work = events.iter().find(|e| e["name"] == "work item").unwrap();
        assert_eq!(work["args"]["pixels"], "36x1 at (64, 0) and 28x1 at (0, 1)");
        let summary = t.summary().unwrap();
        assert_eq!(
            summary.longest_item.pixels,
            [rect(64, 0, 36, 1), rect(0, 1, 28, 1)]
        );
        assert!(
            summary
                .text()
                .contains("pixels 36x1 at (64, 0) and 28x1 at (0, 1), worker 1"),
            "{}",
            summary.text()
        );
    }
}
