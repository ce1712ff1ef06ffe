//! Running a query: its rays (or points) in chunks, each on rayon with the
//! GIL released, and Ctrl-C checked between chunks; and the arrays read
//! on the same threads ([`gather`]).

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use strata::math::Ray;

use crate::convert::RaySource;

/// Items between two checks for Ctrl-C: a few milliseconds of work on
/// one core, so an interrupt lands at once and the checks cost nothing.
pub const CHUNK: usize = 65_536;
/// Items a thread takes at a time: as `strata trace` does, many
/// interleaved walks' worth (and a stream's span), few enough that
/// threads balance.
pub const TASK: usize = 256;
/// More threads than any machine has cores: a typo, not a request (the
/// command line's limit too).
const MAX_THREADS: i64 = strata::system::budget::MAX_THREADS as i64;
/// Pools of a given size kept for the next query that asks for as many
/// threads: the most recently used few, so that a loop over thread
/// counts does not keep every pool it made (and its threads) alive.
const POOLS_KEPT: usize = 4;

/// A query's `threads`: how many threads it may use, or `None` for rayon's
/// global pool (one thread per core). Each step of the query runs on no
/// more threads than it has tasks ([`Threads::run`]): ten rays with
/// `threads=1024` run on the calling thread, as with `threads=1`, and
/// start no thread.
#[derive(Clone, Copy)]
pub struct Threads(Option<usize>);

/// Where one step of a query runs.
enum Plan {
    /// On the calling thread alone: one task, or `threads=1`.
    Here,
    /// On rayon's global pool.
    Global,
    /// On a pool of this many threads.
    Pool(usize),
}

impl Threads {
    /// The `threads` argument: a whole number from 1 to [`MAX_THREADS`],
    /// or None for every core. Nothing is started here.
    pub fn new(threads: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let what =
            format!("a whole number of threads, from 1 to {MAX_THREADS} (or None for every core)");
        let Some(n) = crate::args::optional(threads, |t| crate::args::whole(t, "threads", &what))?
        else {
            return Ok(Self(None));
        };
        if !(1..=MAX_THREADS).contains(&n) {
            return Err(PyValueError::new_err(format!(
                "threads must be {what}; got {n}"
            )));
        }
        Ok(Self(Some(n as usize)))
    }

    /// The thread count asked for (`0`: every core), as `RenderOptions`
    /// takes it.
    pub fn count(&self) -> usize {
        self.0.unwrap_or(0)
    }

    fn plan(&self, tasks: usize) -> Plan {
        let n = self.0.map_or(tasks, |n| n.min(tasks));
        if n <= 1 {
            return Plan::Here;
        }
        match self.0 {
            // As many as the global pool has: that pool, not another.
            Some(_) if n != rayon::current_num_threads() => Plan::Pool(n),
            _ => Plan::Global,
        }
    }

    /// `work` for one step of a query, of `tasks` tasks, on no more threads
    /// than `tasks` and than `threads` allow: on the calling thread alone
    /// where that is one (no pool, no hand-over to another thread), else on
    /// rayon's global pool (`threads=None`, or as many threads as it has)
    /// or on a pool of that many threads (made once and kept, the last
    /// [`POOLS_KEPT`] sizes used). `work` gets the fewest items its
    /// parallel iterators may cut off as one piece (`with_min_len`): 1, or
    /// `usize::MAX` on the calling thread, so that they never split and
    /// never hand a piece to rayon's global pool. Answers do not depend on
    /// where the tasks ran.
    pub fn run<T: Send>(&self, tasks: usize, work: impl FnOnce(usize) -> T + Send) -> PyResult<T> {
        Ok(match self.plan(tasks) {
            Plan::Here => work(usize::MAX),
            Plan::Global => work(1),
            Plan::Pool(n) => pool(n)?.install(|| work(1)),
        })
    }

    /// `work` with rayon's parallel iterators on at most `threads`
    /// threads and at most one per core (a render's loading and tree
    /// building, whose tasks are not counted here): rayon's global pool for
    /// `threads=None`.
    pub fn install<T: Send>(&self, work: impl FnOnce() -> T + Send) -> PyResult<T> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        match self.0.map(|n| n.min(cores)) {
            None => Ok(work()),
            Some(n) if n == rayon::current_num_threads() => Ok(work()),
            Some(n) => Ok(pool(n)?.install(work)),
        }
    }
}

/// The pool of `n` threads: made, or one kept from an earlier query.
fn pool(n: usize) -> PyResult<Arc<rayon::ThreadPool>> {
    static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    let pool = match pools.iter().position(|(size, _)| *size == n) {
        Some(i) => pools.remove(i).1,
        None => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("strata_rt-{i}"))
                .build()
                .map_err(|e| {
                    PyValueError::new_err(format!("threads: cannot start {n} threads: {e}"))
                })?;
            Arc::new(pool)
        }
    };
    // Most recently used first; the least recently used pool dropped
    // (its threads end once no query still holds it).
    pools.insert(0, (n, pool.clone()));
    pools.truncate(POOLS_KEPT);
    Ok(pool)
}

/// `out[i] = answer of items[i]`: `answer` fills a task's answers from its
/// items, on every thread of `threads`, with the GIL released, a chunk at a
/// time; between chunks, a pending Ctrl-C raises `KeyboardInterrupt`.
pub fn each<I: Sync, R: Send>(
    py: Python<'_>,
    threads: &Threads,
    items: &[I],
    out: &mut [R],
    answer: impl Fn(&[I], &mut [R]) + Sync,
) -> PyResult<()> {
    debug_assert_eq!(items.len(), out.len());
    for (items, out) in items.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
        answer_chunk(py, threads, items, out, &answer)?;
    }
    Ok(())
}

/// One chunk of [`each`] or [`each_ray`]: `answer` over its tasks on
/// `threads` with the GIL released, then a pending Ctrl-C raised.
fn answer_chunk<I: Sync, R: Send>(
    py: Python<'_>,
    threads: &Threads,
    items: &[I],
    out: &mut [R],
    answer: &(impl Fn(&[I], &mut [R]) + Sync),
) -> PyResult<()> {
    py.detach(|| {
        threads.run(items.len().div_ceil(TASK), |min_len| {
            items
                .par_chunks(TASK)
                .zip(out.par_chunks_mut(TASK))
                .with_min_len(min_len)
                .for_each(|(items, out)| answer(items, out))
        })
    })?;
    py.check_signals()
}

/// [`each`] of a query's rays, read a chunk at a time (with the GIL
/// held) into one buffer that the chunk's tasks then walk
/// ([`RaySource`]).
pub fn each_ray<R: Send>(
    py: Python<'_>,
    threads: &Threads,
    rays: &RaySource<'_>,
    out: &mut [R],
    answer: impl Fn(&[Ray], &mut [R]) + Sync,
) -> PyResult<()> {
    debug_assert_eq!(rays.len(), out.len());
    let mut buffer = Vec::with_capacity(rays.len().min(CHUNK));
    for (k, out) in out.chunks_mut(CHUNK).enumerate() {
        let start = k * CHUNK;
        rays.read(start..start + out.len(), threads, &mut buffer)?;
        answer_chunk(py, threads, &buffer, out, &answer)?;
    }
    Ok(())
}

/// The answers of a query with any number of answers per ray: `answer`
/// appends a task's rays' answers to its part. One part per task, in ray
/// order, left as the tasks made them: a caller copies them into its
/// arrays on every thread ([`cut`]), not one part after another on the
/// calling thread. Rays, threads, GIL and Ctrl-C as for [`each_ray`].
pub fn flat<P: Default + Send>(
    py: Python<'_>,
    threads: &Threads,
    rays: &RaySource<'_>,
    answer: impl Fn(&[Ray], &mut P) + Sync,
) -> PyResult<Vec<P>> {
    let mut parts = Vec::with_capacity(rays.len().div_ceil(TASK));
    let mut items = Vec::with_capacity(rays.len().min(CHUNK));
    for start in (0..rays.len()).step_by(CHUNK) {
        rays.read(start..(start + CHUNK).min(rays.len()), threads, &mut items)?;
        let chunk: Vec<P> = py.detach(|| {
            threads.run(items.len().div_ceil(TASK), |min_len| {
                items
                    .par_chunks(TASK)
                    .with_min_len(min_len)
                    .map(|items| {
                        let mut part = P::default();
                        answer(items, &mut part);
                        part
                    })
                    .collect()
            })
        })?;
        parts.extend(chunk);
        py.check_signals()?;
    }
    Ok(parts)
}

/// `column` cut into consecutive pieces of `lengths` (which sum to at most
/// its length), one per part of a [`flat`] query, so that each part's
/// task fills its own.
pub fn cut<T>(mut column: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    lengths
        .map(|n| {
            let (piece, rest) = std::mem::take(&mut column).split_at_mut(n);
            column = rest;
            piece
        })
        .collect()
}

/// How many tasks reading `n` rows makes: rows of [`TASK`] at a time, as
/// many as one chunk of a query has at most (a whole array of points is
/// read at once), so that reading starts no more threads than the query's
/// steps do.
fn read_tasks(n: usize) -> usize {
    n.min(CHUNK).div_ceil(TASK)
}

/// `out` = `make(i)` for `i` in `range` (its old items dropped, its
/// memory kept), on `threads`, and the first `i` whose answer came back
/// marked bad.
///
/// Each task writes its run of [`TASK`] items in place, in a loop of its
/// own into which `make` is inlined: collected item by item through
/// rayon's `map`, `make` stayed a call whose answer went back through
/// memory (narrow stores read again as one wide load, which waited on
/// them), 12 ns a ray, most of what reading the rays cost (docs/python.md,
/// "Reading the rays and writing the answers"). `out` is grown to the
/// range's length with `fill` on `threads` where it is shorter (a chunk's
/// vector kept from the last chunk is only cut), and every item is then
/// written once.
pub fn gather_into<T: Copy + Send + Sync>(
    threads: &Threads,
    range: std::ops::Range<usize>,
    out: &mut Vec<T>,
    fill: T,
    make: impl Fn(usize) -> (T, bool) + Sync,
) -> PyResult<Option<usize>> {
    let first_bad = AtomicUsize::new(usize::MAX);
    let (start, len) = (range.start, range.len());
    let grow = len.saturating_sub(out.len());
    out.truncate(len);
    threads.run(read_tasks(len), |min_len| {
        out.par_extend(rayon::iter::repeat_n(fill, grow).with_min_len(min_len.max(TASK)));
        out.par_chunks_mut(TASK)
            .enumerate()
            .with_min_len(min_len)
            .for_each(|(c, items)| {
                let first = start + c * TASK;
                for (k, item) in items.iter_mut().enumerate() {
                    let (value, bad) = make(first + k);
                    *item = value;
                    if bad {
                        first_bad.fetch_min(first + k, Ordering::Relaxed);
                    }
                }
            })
    })?;
    let bad = first_bad.into_inner();
    Ok((bad != usize::MAX).then_some(bad))
}

/// `make(i)` for `i` in `0..n`, on `threads`, and the first `i` whose
/// answer came back marked bad (`fill`: any value of `T`, which every
/// item overwrites).
pub fn gather<T: Copy + Send + Sync>(
    threads: &Threads,
    n: usize,
    fill: T,
    make: impl Fn(usize) -> (T, bool) + Sync,
) -> PyResult<(Vec<T>, Option<usize>)> {
    let mut out = Vec::with_capacity(n);
    let bad = gather_into(threads, 0..n, &mut out, fill, make)?;
    Ok((out, bad))
}
