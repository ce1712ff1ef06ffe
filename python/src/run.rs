//! Running a query: its rays (or points) in chunks, each on rayon with the
//! GIL released, and Ctrl-C checked between chunks.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use std::collections::BTreeMap;
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

/// Where a query runs: rayon's global pool (one thread per core), or a
/// pool of a given size, built once per size and kept.
#[derive(Clone)]
pub struct Threads(Option<Arc<rayon::ThreadPool>>);

impl Threads {
    /// The pool for the `threads` argument (`None`: every core).
    pub fn new(threads: Option<i64>) -> PyResult<Self> {
        let Some(n) = threads else {
            return Ok(Self(None));
        };
        if !(1..=MAX_THREADS).contains(&n) {
            return Err(PyValueError::new_err(format!(
                "threads must be an int from 1 to {MAX_THREADS}, or None for every core; got {n}"
            )));
        }
        static POOLS: Mutex<BTreeMap<usize, Arc<rayon::ThreadPool>>> = Mutex::new(BTreeMap::new());
        let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
        let n = n as usize;
        if let Some(pool) = pools.get(&n) {
            return Ok(Self(Some(pool.clone())));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .thread_name(|i| format!("strata_rt-{i}"))
            .build()
            .map_err(|e| {
                PyValueError::new_err(format!("threads: cannot start {n} threads: {e}"))
            })?;
        let pool = Arc::new(pool);
        pools.insert(n, pool.clone());
        Ok(Self(Some(pool)))
    }

    /// The thread count this runs on (`0`: rayon's global pool).
    pub fn count(&self) -> usize {
        self.0.as_ref().map_or(0, |p| p.current_num_threads())
    }

    /// `work` on this pool.
    pub fn install<T: Send>(&self, work: impl FnOnce() -> T + Send) -> T {
        match &self.0 {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }
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
        threads.install(|| {
            items
                .par_chunks(TASK)
                .zip(out.par_chunks_mut(TASK))
                .for_each(|(items, out)| answer(items, out))
        })
    });
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

/// The answers of a query with any number of answers per ray, in ray
/// order: `answer` appends a task's answers to its vector and returns how
/// many each ray had. Rays, threads, GIL and Ctrl-C as for [`each_ray`].
pub fn flat<R: Send>(
    py: Python<'_>,
    threads: &Threads,
    rays: &RaySource<'_>,
    answer: impl Fn(&[Ray], &mut Vec<R>, &mut Vec<u32>) + Sync,
) -> PyResult<(Vec<u32>, Vec<R>)> {
    let mut counts = Vec::with_capacity(rays.len());
    let mut answers = Vec::new();
    let mut items = Vec::with_capacity(rays.len().min(CHUNK));
    for start in (0..rays.len()).step_by(CHUNK) {
        rays.read(start..(start + CHUNK).min(rays.len()), threads, &mut items)?;
        let parts: Vec<(Vec<u32>, Vec<R>)> = py.detach(|| {
            threads.install(|| {
                items
                    .par_chunks(TASK)
                    .map(|items| {
                        let mut found = Vec::new();
                        let mut counts = Vec::with_capacity(items.len());
                        answer(items, &mut found, &mut counts);
                        (counts, found)
                    })
                    .collect()
            })
        });
        for (c, a) in parts {
            counts.extend(c);
            answers.extend(a);
        }
        py.check_signals()?;
    }
    Ok((counts, answers))
}
