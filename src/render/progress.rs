//! What a render reports as it goes, to whoever started it: an
//! [`Observer`] of its passes and work items. The render draws nothing and
//! prints nothing; the front end passes in what does (the CLI's progress
//! bar, Python's check for Ctrl-C), as pbrt-v4's and Mitsuba 3's render
//! loops take a progress reporter their caller made.
//!
//! Every method has a do-nothing default, so `()` observes nothing, and
//! [`each_pass`] turns a closure into an observer of pass ends (for
//! checkpoints); a pair observes with both of its halves.

use super::film::Film;
use std::ops::{ControlFlow, Range};

/// One pass of a render, as it starts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pass {
    /// Which pass (0-based) of `count`.
    pub index: usize,
    pub count: usize,
    /// The sample indices of every pixel this pass renders.
    pub samples: Range<u32>,
    /// Samples per pixel of the whole render (of which `samples` is a part).
    pub spp: u32,
}

/// Where a render stands when a pass ends.
#[derive(Debug, Clone, PartialEq)]
pub struct PassDone {
    pub pass: Pass,
    /// Rays traced since the first pass started, and the seconds since then.
    pub rays: u64,
    pub seconds: f64,
}

/// What a render tells its front end. `render` calls `started`, then for
/// each pass `pass_started`, `item_done` once per work item (on the worker
/// thread that rendered it) and `pass_done`, and last `finished`.
pub trait Observer: Sync {
    /// Before the first pass: the work items of all passes together.
    fn started(&mut self, _work_items: u64) {}
    fn pass_started(&mut self, _pass: &Pass) {}
    /// A work item ended. Called from the render's threads as they go, so
    /// it is kept to an atomic add or less.
    fn item_done(&self) {}
    /// A pass ended: `film` holds every sample below `done.pass.samples.end`.
    /// `Break` ends the render here, with the film as it is.
    fn pass_done(&mut self, _film: &Film, _done: &PassDone) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// After the last pass (or the one that ended the render).
    fn finished(&mut self) {}
}

/// Observes nothing.
impl Observer for () {}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn started(&mut self, work_items: u64) {
        (**self).started(work_items)
    }
    fn pass_started(&mut self, pass: &Pass) {
        (**self).pass_started(pass)
    }
    #[inline]
    fn item_done(&self) {
        (**self).item_done()
    }
    fn pass_done(&mut self, film: &Film, done: &PassDone) -> ControlFlow<()> {
        (**self).pass_done(film, done)
    }
    fn finished(&mut self) {
        (**self).finished()
    }
}

/// Both observe, the first first; the render ends after a pass if either
/// asks it to.
impl<A: Observer, B: Observer> Observer for (A, B) {
    fn started(&mut self, work_items: u64) {
        self.0.started(work_items);
        self.1.started(work_items);
    }
    fn pass_started(&mut self, pass: &Pass) {
        self.0.pass_started(pass);
        self.1.pass_started(pass);
    }
    #[inline]
    fn item_done(&self) {
        self.0.item_done();
        self.1.item_done();
    }
    fn pass_done(&mut self, film: &Film, done: &PassDone) -> ControlFlow<()> {
        let a = self.0.pass_done(film, done);
        let b = self.1.pass_done(film, done);
        if a.is_break() || b.is_break() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
    fn finished(&mut self) {
        self.0.finished();
        self.1.finished();
    }
}

/// The observer that calls `f(film, end)` at each pass's end, where the
/// film holds every sample below `end`: for checkpoints and progressive
/// images.
pub fn each_pass<F: FnMut(&Film, u32) + Sync>(f: F) -> EachPass<F> {
    EachPass(f)
}

/// See [`each_pass`].
pub struct EachPass<F>(F);

impl<F: FnMut(&Film, u32) + Sync> Observer for EachPass<F> {
    fn pass_done(&mut self, film: &Film, done: &PassDone) -> ControlFlow<()> {
        (self.0)(film, done.pass.samples.end);
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Counts what it is told, and stops after `stop_after` passes.
    #[derive(Default)]
    struct Count {
        items: AtomicU64,
        passes: Vec<Range<u32>>,
        stop_after: Option<usize>,
    }

    impl Observer for Count {
        fn item_done(&self) {
            self.items.fetch_add(1, Ordering::Relaxed);
        }
        fn pass_done(&mut self, _: &Film, done: &PassDone) -> ControlFlow<()> {
            self.passes.push(done.pass.samples.clone());
            match self.stop_after {
                Some(n) if self.passes.len() >= n => ControlFlow::Break(()),
                _ => ControlFlow::Continue(()),
            }
        }
    }

    fn done(samples: Range<u32>) -> PassDone {
        PassDone {
            pass: Pass {
                index: 0,
                count: 1,
                samples,
                spp: 8,
            },
            rays: 0,
            seconds: 0.0,
        }
    }

    #[test]
    fn a_pair_tells_both_and_stops_if_either_asks() {
        let film = Film::new(1, 1);
        let mut pair = (
            Count::default(),
            Count {
                stop_after: Some(2),
                ..Count::default()
            },
        );
        pair.item_done();
        assert!(pair.pass_done(&film, &done(0..4)).is_continue());
        assert!(pair.pass_done(&film, &done(4..8)).is_break());
        for half in [&pair.0, &pair.1] {
            assert_eq!(half.items.load(Ordering::Relaxed), 1);
            assert_eq!(half.passes, vec![0..4, 4..8]);
        }
    }

    /// One pass's end told to `observer`, as `render` tells it.
    fn end_pass(mut observer: impl Observer, end: u32) -> ControlFlow<()> {
        observer.pass_done(&Film::new(1, 1), &done(0..end))
    }

    #[test]
    fn each_pass_is_told_where_the_film_ends() {
        let mut ends = Vec::new();
        {
            // Lent, as the CLI lends its observers, then given.
            let mut observer = each_pass(|_: &Film, end| ends.push(end));
            assert!(end_pass(&mut observer, 5).is_continue());
            assert!(end_pass(observer, 9).is_continue());
        }
        assert_eq!(ends, vec![5, 9]);
    }
}
