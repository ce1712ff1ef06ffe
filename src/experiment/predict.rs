//! Predicting scaling past this machine's cores (`strata scaling
//! --predict`): the work items' costs from one measured run (its
//! [`Timeline`]) replayed on T simulated threads, pass by pass.
//!
//! - **slices** (work stealing): each pass is a list schedule, every idle
//!   thread taking the next work item in order (Graham 1969), which is what
//!   rayon's stealing approximates; the pass ends when the last thread
//!   finishes (the barrier). Its makespan lies between the mean load and
//!   the mean load plus the longest item.
//! - **regions**: one band of `ceil(pixels / T)` pixels per thread, its cost
//!   the measured items' costs spread evenly over their pixels.
//! - **P processes**: each renders slice k/P of every pixel's samples on one
//!   thread (an item's cost spread evenly over its pass's samples), after
//!   loading and building on its own, then writes its part; the merge
//!   reads the P parts one after the other.
//!
//! The serial work the run measured (the setup, each pass's film update,
//! the load, build and output) is kept as it was. What the model leaves
//! out: memory bandwidth and caches shared between cores (a work item costs
//! what it cost in the measured run), turbo clocks that fall as more cores
//! wake, hyperthreads sharing a core, rayon's own stealing costs, and the
//! build's own scaling (it is counted at its measured time). How far off it
//! is where real cores exist is measured in docs/scaling.md.

use crate::render::timeline::{seconds_in, Phase, Timeline};
use crate::render::SliceSpec;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::ops::Range;

/// One pass of the measured run.
#[derive(Debug, Clone, PartialEq)]
pub struct PassCost {
    pub samples: Range<u32>,
    /// Each work item's pixels (window indices) and its seconds, in pixel order.
    pub items: Vec<(Range<u32>, f64)>,
    /// The pass's own time outside its work items when it ran on one
    /// thread: handing the items out and the barrier (0 if measured on
    /// more threads, where it cannot be told from imbalance).
    pub overhead_s: f64,
    /// Serial work after the pass: adding it into the film, the checkpoint.
    pub serial_s: f64,
}

/// The costs of one measured run, as the simulations take them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunCosts {
    pub passes: Vec<PassCost>,
    /// Pixels of the window.
    pub pixels: u32,
    pub load_s: f64,
    pub build_s: f64,
    pub setup_s: f64,
    pub output_s: f64,
}

impl RunCosts {
    /// The costs of the run `timeline` recorded, over a window of `pixels`.
    pub fn from_timeline(timeline: &Timeline, pixels: u32) -> Self {
        let phases = timeline.phases();
        let items = timeline.items();
        let one_thread = timeline.threads() <= 1;
        let sum = |phase: Phase| seconds_in(&phases, phase);
        let mut passes: Vec<PassCost> = phases
            .iter()
            .filter(|p| p.phase == Phase::Pass)
            .map(|p| PassCost {
                samples: p.samples.clone().unwrap_or(0..0),
                items: Vec::new(),
                overhead_s: p.seconds(),
                serial_s: phases
                    .iter()
                    .filter(|q| matches!(q.phase, Phase::Film | Phase::AfterPass))
                    .filter(|q| q.pass == p.pass)
                    .map(|q| q.seconds())
                    .sum(),
            })
            .collect();
        for item in items {
            if let Some(pass) = passes.get_mut(item.pass) {
                pass.items.push((item.pixels.clone(), item.seconds()));
            }
        }
        for pass in &mut passes {
            pass.items.sort_by_key(|(p, _)| p.start);
            let busy: f64 = pass.items.iter().map(|(_, s)| s).sum();
            pass.overhead_s = if one_thread {
                (pass.overhead_s - busy).max(0.0)
            } else {
                0.0
            };
        }
        Self {
            passes,
            pixels,
            load_s: sum(Phase::Load),
            build_s: sum(Phase::Build),
            setup_s: sum(Phase::Setup),
            output_s: sum(Phase::Output),
        }
    }

    /// Samples per pixel the run covered.
    fn sample_range(&self) -> Range<u32> {
        let start = self.passes.iter().map(|p| p.samples.start).min();
        let end = self.passes.iter().map(|p| p.samples.end).max();
        start.unwrap_or(0)..end.unwrap_or(0)
    }

    /// Seconds of every work item together: the 1-thread render's work.
    pub fn work_s(&self) -> f64 {
        self.passes
            .iter()
            .flat_map(|p| &p.items)
            .map(|(_, s)| s)
            .sum()
    }

    /// The serial work of the in-process render (what `strata scaling`
    /// times): each pass's overhead and film update.
    fn pass_serial_s(&self) -> f64 {
        self.passes.iter().map(|p| p.overhead_s + p.serial_s).sum()
    }

    /// The serial phases around the render: load, build, setup, output.
    pub fn around_s(&self) -> f64 {
        self.load_s + self.build_s + self.setup_s + self.output_s
    }
}

/// The makespan of `costs` list-scheduled in order on `threads` threads:
/// every item goes to the thread that frees up first.
pub fn list_schedule(costs: impl IntoIterator<Item = f64>, threads: usize) -> f64 {
    let threads = threads.max(1);
    // Finish times in integer picoseconds, so the heap orders exactly.
    let mut free: BinaryHeap<Reverse<u64>> = (0..threads).map(|_| Reverse(0)).collect();
    let mut makespan = 0u64;
    for c in costs {
        let Reverse(t) = free.pop().expect("threads > 0");
        let end = t + (c.max(0.0) * 1e12).round() as u64;
        makespan = makespan.max(end);
        free.push(Reverse(end));
    }
    makespan as f64 * 1e-12
}

/// The makespan of one band of `ceil(pixels / threads)` pixels per thread,
/// each item's cost spread evenly over its pixels.
pub fn bands(items: &[(Range<u32>, f64)], pixels: u32, threads: usize) -> f64 {
    let threads = threads.max(1) as u64;
    let band = (pixels as u64).div_ceil(threads).max(1);
    let mut cost = vec![0.0f64; threads as usize];
    for (range, seconds) in items {
        let len = (range.end - range.start).max(1) as f64;
        let (lo, hi) = (range.start as u64, range.end as u64);
        for (b, c) in cost.iter_mut().enumerate() {
            let (b_lo, b_hi) = (b as u64 * band, (b as u64 + 1) * band);
            let overlap = hi.min(b_hi).saturating_sub(lo.max(b_lo));
            *c += seconds * overlap as f64 / len;
        }
    }
    cost.into_iter().fold(0.0, f64::max)
}

/// How the simulated render splits its work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    Slices,
    Regions,
}

/// One simulated configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Predicted {
    /// The in-process render (what `strata scaling` times), or for
    /// processes, from their start to the merged film.
    pub seconds: f64,
    /// Of the threads' time in passes, the part spent idle (waiting at a
    /// barrier for the longest work item, or for the busiest band).
    pub imbalance: f64,
    /// With the load, build, setup and output around it: the whole run.
    pub end_to_end_s: f64,
}

/// The render of `costs` on `threads` threads.
pub fn predict_threads(costs: &RunCosts, split: Split, threads: usize) -> Predicted {
    let mut passes_s = 0.0;
    for p in &costs.passes {
        passes_s += match split {
            Split::Slices => list_schedule(p.items.iter().map(|(_, s)| *s), threads),
            Split::Regions => bands(&p.items, costs.pixels, threads),
        };
    }
    let seconds = passes_s + costs.pass_serial_s();
    let work = costs.work_s();
    Predicted {
        seconds,
        imbalance: (1.0 - work / (threads.max(1) as f64 * passes_s).max(1e-12)).max(0.0),
        end_to_end_s: seconds + costs.around_s(),
    }
}

/// What a child process costs besides its samples, measured apart: its
/// start, its load and build on its one thread, writing its part (the
/// scene fingerprint included), and reading the part back in the merge.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProcessCosts {
    pub start_s: f64,
    pub load_s: f64,
    pub build_s: f64,
    pub write_s: f64,
    pub read_s: f64,
}

/// `processes` single-threaded renders of one slice each, each writing its
/// part instead of the run's output, then the merge reading the parts.
pub fn predict_processes(costs: &RunCosts, processes: usize, child: ProcessCosts) -> Predicted {
    let all = costs.sample_range();
    let spp = all.end;
    let n = processes.max(1) as u32;
    let serial_per_pass = costs.pass_serial_s() / costs.passes.len().max(1) as f64;
    let slowest = (0..n)
        .map(|k| {
            let mine = SliceSpec { index: k, count: n }.samples(spp);
            let work: f64 = costs
                .passes
                .iter()
                .map(|p| {
                    let overlap = p
                        .samples
                        .end
                        .min(mine.end)
                        .saturating_sub(p.samples.start.max(mine.start));
                    let per_sample = 1.0 / (p.samples.end - p.samples.start).max(1) as f64;
                    p.items.iter().map(|(_, s)| s).sum::<f64>() * overlap as f64 * per_sample
                })
                .sum();
            let passes = crate::render::schedule::default_passes(mine.end - mine.start);
            work + serial_per_pass * passes as f64
        })
        .fold(0.0, f64::max);
    let serial = child.start_s + child.load_s + child.build_s + costs.setup_s + child.write_s;
    let seconds = serial + slowest + child.read_s * n as f64;
    Predicted {
        seconds,
        imbalance: 0.0,
        end_to_end_s: seconds,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `items` equal work items of one second in one pass over `pixels`.
    fn run(costs: &[f64], around_s: f64) -> RunCosts {
        let items = costs
            .iter()
            .enumerate()
            .map(|(i, &s)| (i as u32 * 64..(i as u32 + 1) * 64, s))
            .collect();
        RunCosts {
            passes: vec![PassCost {
                samples: 0..16,
                items,
                overhead_s: 0.0,
                serial_s: 0.0,
            }],
            pixels: costs.len() as u32 * 64,
            load_s: around_s,
            ..RunCosts::default()
        }
    }

    fn speedup(c: &RunCosts, split: Split, t: usize) -> f64 {
        predict_threads(c, split, 1).seconds / predict_threads(c, split, t).seconds
    }

    #[test]
    fn equal_items_on_t_threads_give_t_times() {
        let c = run(&[0.25; 64 * 3], 0.0);
        for t in [1, 2, 4, 8, 16, 32, 64] {
            for split in [Split::Slices, Split::Regions] {
                let s = speedup(&c, split, t);
                assert!((s - t as f64).abs() < 1e-9, "{split:?} {t}: {s}");
            }
            assert!(predict_threads(&c, Split::Slices, t).imbalance < 1e-9);
        }
    }

    #[test]
    fn one_item_as_long_as_all_others_caps_the_speedup_at_two() {
        let mut costs = vec![0.01; 1000];
        costs.push(10.0);
        costs.rotate_right(1); // the long one first, as a schedule in order meets it
        let c = run(&costs, 0.0);
        let mut last = 0.0;
        for t in [2, 4, 8, 64, 1024] {
            let s = speedup(&c, Split::Slices, t);
            assert!(s <= 2.0 + 1e-9 && s >= last, "{t}: {s}");
            last = s;
        }
        assert!((last - 2.0).abs() < 1e-9, "{last}");
        // The other threads wait for it: at 64 threads most of the time is idle.
        assert!(predict_threads(&c, Split::Slices, 64).imbalance > 0.9);
    }

    #[test]
    fn a_serial_fraction_obeys_amdahl() {
        for f in [0.05, 0.2, 0.5] {
            // 1 s in all: f serial, the rest in 4096 equal items.
            let c = run(&vec![(1.0 - f) / 4096.0; 4096], f);
            for t in [1, 2, 4, 16, 64] {
                let whole = |t| predict_threads(&c, Split::Slices, t).end_to_end_s;
                let s = whole(1) / whole(t);
                let amdahl = 1.0 / (f + (1.0 - f) / t as f64);
                assert!(
                    (s - amdahl).abs() < 1e-6 * amdahl,
                    "f {f}, {t}: {s} vs {amdahl}"
                );
            }
        }
    }

    #[test]
    fn list_scheduling_lies_between_the_mean_and_the_mean_plus_the_longest() {
        use rand::RngExt;
        let mut rng = crate::sampling::stream::seeded(7);
        let costs: Vec<f64> = (0..500).map(|_| rng.random::<f64>().powi(4)).collect();
        let (sum, max) = (
            costs.iter().sum::<f64>(),
            costs.iter().copied().fold(0.0, f64::max),
        );
        for t in [1, 3, 7, 64] {
            let m = list_schedule(costs.iter().copied(), t);
            assert!(m >= (sum / t as f64).max(max) - 1e-9 && m <= sum / t as f64 + max + 1e-9);
        }
    }

    #[test]
    fn bands_take_the_costly_band() {
        // The first quarter of the pixels holds all the work.
        let mut costs = vec![0.0; 16];
        costs[..4].fill(1.0);
        let c = run(&costs, 0.0);
        assert!((speedup(&c, Split::Regions, 2) - 1.0).abs() < 1e-9);
        assert!((speedup(&c, Split::Regions, 4) - 1.0).abs() < 1e-9);
        assert!((speedup(&c, Split::Regions, 8) - 2.0).abs() < 1e-9);
        assert!((speedup(&c, Split::Slices, 4) - 4.0).abs() < 1e-9);
    }

    #[test]
    fn processes_split_the_samples_and_pay_the_serial_phases_each() {
        let c = run(&[0.5; 8], 1.0);
        let child = ProcessCosts {
            start_s: 0.05,
            load_s: 0.5,
            build_s: 0.45,
            write_s: 0.2,
            read_s: 0.1,
        };
        let one = predict_processes(&c, 1, child).seconds;
        assert!((one - 5.3).abs() < 1e-9, "{one}");
        let four = predict_processes(&c, 4, child).seconds;
        assert!((four - (1.2 + 1.0 + 0.4)).abs() < 1e-9, "{four}");
    }
}
