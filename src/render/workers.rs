//! The threads a render runs on: the pool it is called on when that pool
//! has the threads asked for, else a pool of its own.
//!
//! Starting a pool costs a render of a small scene more than its load:
//! threads to create, then to wake, each the first time it is handed
//! work. `strata render` runs the whole command on one pool, and the
//! Python package's `render` without `threads` on rayon's global pool,
//! so the render gets threads that are already running. The image does
//! not depend on which threads render it.

use crate::system::cputime::thread_cpu_ns;

/// Whether `threads` (0: one per core) asks for the pool the caller is
/// in: 0, or that pool's size where the caller is one of its workers.
/// What `strata render` decides by (`on_threads` in the CLI): a command
/// given `--threads N` runs on a pool of its own, and never starts
/// rayon's global pool (one idle thread a core beside it, `--threads 1`
/// on a 16-core machine started 16) nor asks the cores (a tenth of a
/// millisecond of cgroup files).
pub fn is_current_pool(threads: usize) -> bool {
    threads == 0
        || (rayon::current_thread_index().is_some() && threads == rayon::current_num_threads())
}

/// Whether a caller outside every pool asks, with `threads`, for rayon's
/// global pool: what a render's workers add to [`is_current_pool`], so
/// that the Python package's `render(threads=N)` with N the global pool's
/// size reuses its running threads. Asking the global pool its size
/// starts it, so the size is asked only where rayon's rule for it
/// ([`global_pool_size`]) says it may match; the answer still decides.
fn is_global_pool(threads: usize) -> bool {
    rayon::current_thread_index().is_none()
        && threads == global_pool_size()
        && threads == rayon::current_num_threads()
}

/// The size rayon gives its global pool, worked out without starting it:
/// `RAYON_NUM_THREADS` where it is a positive number, else one thread a
/// logical core (rayon-core's documented default).
fn global_pool_size() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|n| n.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// `work` on a worker of the pool the caller is in (rayon's global pool
/// outside any), in place where the caller is one. On a worker, not
/// beside the pool: each parallel step started from a thread outside it
/// waits for a worker to wake and take it, which made a one-sphere
/// scene's tree take 0.3 to 0.6 ms beside the global pool's two threads
/// against 0.1 to 0.2 ms in a pool (docs/performance.md).
pub fn on_current_pool<T: Send>(work: impl FnOnce() -> T + Send) -> T {
    rayon::scope(|_| work())
}

/// Where a render's parallel work runs.
pub(super) enum Workers {
    /// The pool the caller runs on, or rayon's global pool outside any.
    Current,
    /// A pool of the size asked for, started for this render.
    Own(rayon::ThreadPool),
}

impl Workers {
    /// Workers for `threads` threads (0: as many as the current pool has,
    /// one per core outside any pool), and their count.
    pub(super) fn for_threads(threads: usize) -> (Self, usize) {
        if is_current_pool(threads) || is_global_pool(threads) {
            return (Self::Current, rayon::current_num_threads());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        (Self::Own(pool), threads)
    }

    /// `work` run where its parallel iterators use these workers. A pass
    /// on the current pool runs in place, not on a worker ([`on_current_pool`]):
    /// called from the Python thread, handing each pass to a worker made
    /// `render(spp=1)` of cornell-planes slower (6.1 to 7.9 ms against 5.6
    /// to 6.8, three alternating rounds of 40 calls), and handing over the
    /// load alone changed nothing measurable.
    pub(super) fn install<T: Send>(&self, work: impl FnOnce() -> T + Send) -> T {
        match self {
            Self::Current => work(),
            Self::Own(pool) => pool.install(work),
        }
    }

    /// The calling thread's index among the workers, if it is one.
    pub(super) fn caller(&self) -> Option<usize> {
        match self {
            Self::Current => rayon::current_thread_index(),
            Self::Own(_) => None,
        }
    }

    /// Each worker's CPU time so far, in nanoseconds (one broadcast);
    /// `None` where threads' CPU time cannot be read.
    pub(super) fn cpu_ns(&self) -> Option<Vec<u64>> {
        let read = |_: rayon::BroadcastContext<'_>| thread_cpu_ns();
        match self {
            Self::Current => rayon::broadcast(read),
            Self::Own(pool) => pool.broadcast(read),
        }
        .into_iter()
        .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A render asked for the current pool's size, or for no size, runs on
    /// that pool; asked for another size, on a pool of that size.
    #[test]
    fn workers_reuse_the_pool_they_are_called_on_when_it_fits() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        pool.install(|| {
            for asked in [0, 3] {
                let (workers, n) = Workers::for_threads(asked);
                assert!(matches!(workers, Workers::Current), "{asked}");
                assert_eq!(n, 3);
                assert_eq!(workers.install(rayon::current_num_threads), 3);
            }
            let (workers, n) = Workers::for_threads(2);
            assert!(matches!(workers, Workers::Own(_)));
            assert_eq!(n, 2);
            assert_eq!(workers.install(rayon::current_num_threads), 2);
            if let Some(times) = workers.cpu_ns() {
                assert_eq!(times.len(), 2, "one reading a worker");
            }
            // On a worker already: in place.
            let here = rayon::current_thread_index();
            assert_eq!(on_current_pool(rayon::current_thread_index), here);
        });
    }

    /// Work for the current pool from a thread outside every pool (the
    /// test's own) runs on one of the global pool's workers.
    #[test]
    fn work_from_outside_a_pool_runs_on_a_worker() {
        assert_eq!(rayon::current_thread_index(), None);
        assert!(is_current_pool(0));
        // The size worked out without starting the pool is rayon's own.
        let global = rayon::current_num_threads();
        assert_eq!(global_pool_size(), global);
        // Outside every pool a size is the global pool's for a render's
        // workers, never for a command.
        assert!(is_global_pool(global) && !is_current_pool(global));
        assert!(!is_global_pool(global + 1));
        let (workers, n) = Workers::for_threads(global);
        assert!(matches!(workers, Workers::Current) && n == global);
        assert!(on_current_pool(rayon::current_thread_index).is_some());
    }
}
