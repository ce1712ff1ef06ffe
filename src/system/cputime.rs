//! CPU time of threads and child processes, for `strata scaling` on shared
//! machines (Linux `/proc`; `None` elsewhere).

/// Nanoseconds the calling thread has run on a CPU: the first field of
/// Linux's `/proc/thread-self/schedstat`. `None` where that file does not
/// exist (other systems, or kernels without scheduler statistics).
pub fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// CPU time of a render: what it would take with a core per thread, apart
/// from what else the machine runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CpuTimes {
    /// All threads together.
    pub total: f64,
    /// The critical path: for each pass, the busiest worker's CPU time (a
    /// pass ends when its slowest thread does), plus the calling thread's
    /// serial work between passes. With a core per thread, the wall time.
    pub critical_path: f64,
}

/// Accumulates [`CpuTimes`] from per-thread CPU clocks read at pass
/// boundaries: `start` before the first pass, `pass` after each, `finish`
/// at the end. Each reading is one rayon broadcast (microseconds).
pub struct CpuMeter {
    workers: Option<Vec<u64>>,
    /// The calling thread's CPU time where its own work, not yet counted
    /// among the workers', began.
    caller: Option<u64>,
    /// Which of the workers the calling thread is, if it is one of them
    /// (a render on the pool it was called from).
    caller_worker: Option<usize>,
    total: f64,
    critical: f64,
}

impl CpuMeter {
    /// From `workers`, each worker thread's [`thread_cpu_ns`] (one
    /// broadcast to the render's workers); `caller_worker`: the calling
    /// thread's index among them, if it is one, so that its time is not
    /// counted twice.
    pub fn start(workers: Option<Vec<u64>>, caller_worker: Option<usize>) -> Self {
        Self {
            workers,
            caller: thread_cpu_ns(),
            caller_worker,
            total: 0.0,
            critical: 0.0,
        }
    }

    /// Close a pass: add its busiest worker's time.
    pub fn pass(&mut self, now: Option<Vec<u64>>) {
        if let (Some(before), Some(after)) = (&self.workers, &now) {
            let deltas = before
                .iter()
                .zip(after)
                .map(|(a, b)| b.saturating_sub(*a) as f64 * 1e-9);
            let (sum, max) = deltas.fold((0.0, 0.0f64), |(s, m), d| (s + d, m.max(d)));
            self.total += sum;
            self.critical += max;
        }
        // A caller that is a worker has had its time so far counted with
        // theirs.
        if let (Some(k), Some(now)) = (self.caller_worker, &now) {
            self.caller = now.get(k).copied().or(self.caller);
        }
        self.workers = now;
    }

    pub fn finish(self) -> Option<CpuTimes> {
        self.workers.as_ref()?;
        let serial = thread_cpu_ns()?.saturating_sub(self.caller?) as f64 * 1e-9;
        Some(CpuTimes {
            total: self.total + serial,
            critical_path: self.critical + serial,
        })
    }
}

/// Clock ticks per second of `/proc/*/stat` times: Linux fixes USER_HZ at
/// 100 for user space, whatever the kernel's internal tick rate.
const USER_HZ: f64 = 100.0;

/// CPU seconds (user + system) of this process's children that have been
/// waited for: `cutime` + `cstime` of `/proc/self/stat`, in 10 ms ticks.
pub fn waited_children_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name, field 2, is in parentheses and may hold spaces.
    let rest = &text[text.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3 (state); cutime and cstime are fields 16 and 17.
    let cutime: u64 = fields.get(13)?.parse().ok()?;
    let cstime: u64 = fields.get(14)?.parse().ok()?;
    Some((cutime + cstime) as f64 / USER_HZ)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work_where_available() {
        let Some(before) = thread_cpu_ns() else {
            return;
        };
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = std::hint::black_box(x.wrapping_mul(31).wrapping_add(i));
        }
        let after = thread_cpu_ns().unwrap();
        assert!(after > before, "{x}");
    }

    #[test]
    fn waited_children_cpu_is_readable_where_proc_exists() {
        if std::path::Path::new("/proc/self/stat").exists() {
            let t = waited_children_cpu_seconds().expect("parse /proc/self/stat");
            assert!(t >= 0.0);
        }
    }
}
