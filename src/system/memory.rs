//! Resident memory of this process (Linux `/proc/self/status`; `None`
//! elsewhere): the whole run's peak, and the peak of each loading phase.

use std::sync::atomic::{AtomicU64, Ordering};

/// The highest `VmHWM` seen before [`PeakMeter`] last reset it, so that
/// [`peak_rss_bytes`] stays the whole process's peak.
static PEAK_BEFORE_RESET: AtomicU64 = AtomicU64::new(0);

/// Peak resident set size of this process (Linux `VmHWM`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let hwm = Status::read()?.hwm;
    Some(hwm.max(PEAK_BEFORE_RESET.load(Ordering::Relaxed)))
}

/// Resident memory of this process now (Linux `VmRSS`), if known.
pub fn resident_bytes() -> Option<u64> {
    Some(Status::read()?.rss)
}

/// The two `/proc/self/status` fields the meters read, in bytes: one read
/// of the file for both. Each read is the kernel writing the whole file
/// (about 20 µs); a render's load read it eight times, one field each,
/// which took 0.14 ms of a small scene's 0.55 ms load.
#[derive(Debug, Clone, Copy)]
struct Status {
    /// `VmRSS`: resident now.
    rss: u64,
    /// `VmHWM`: the peak of `rss` since the process began or the last
    /// reset.
    hwm: u64,
}

impl Status {
    fn read() -> Option<Self> {
        // One read call: the file is about 1.5 KB; `read_to_string` read
        // it in growing pieces.
        let mut buffer = [0u8; 8192];
        let n = std::io::Read::read(
            &mut std::fs::File::open("/proc/self/status").ok()?,
            &mut buffer,
        )
        .ok()?;
        Self::parse(&String::from_utf8_lossy(&buffer[..n]))
    }

    fn parse(status: &str) -> Option<Self> {
        let field = |name: &str| -> Option<u64> {
            let line = status.lines().find(|l| l.starts_with(name))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024)
        };
        Some(Self {
            rss: field("VmRSS:")?,
            hwm: field("VmHWM:")?,
        })
    }
}

/// Set `VmHWM` back to the current RSS (Linux ≥ 4.0: write 5 to
/// `/proc/self/clear_refs`), keeping the peak it had, `before`, for
/// [`peak_rss_bytes`]; false where that is not possible.
fn reset_peak(before: Option<Status>) -> bool {
    if let Some(s) = before {
        PEAK_BEFORE_RESET.fetch_max(s.hwm, Ordering::Relaxed);
    }
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// How far resident memory rises above its level at [`PeakMeter::start`]
/// during a phase: the kernel's own peak (`VmHWM`), reset at the start of
/// each phase. Process-wide, so threads allocating beside the phase count
/// too. Where the peak cannot be reset, a phase's peak is known only if
/// it exceeds every earlier one; otherwise it is None.
#[derive(Debug)]
pub struct PeakMeter {
    base: Option<u64>,
    reset: bool,
    hwm_at_phase_start: u64,
}

impl PeakMeter {
    pub fn start() -> Self {
        let reset = reset_peak(Status::read());
        let now = Status::read();
        Self {
            base: now.map(|s| s.rss),
            reset,
            hwm_at_phase_start: now.map_or(u64::MAX, |s| s.hwm),
        }
    }

    /// Peak RSS of the phase so far, above the level at `start`.
    pub fn phase_peak(&self) -> Option<u64> {
        self.peak_in(Status::read())
    }

    /// The phase's peak by the reading `now`.
    fn peak_in(&self, now: Option<Status>) -> Option<u64> {
        let base = self.base?;
        let hwm = now?.hwm;
        (self.reset || hwm > self.hwm_at_phase_start).then(|| hwm.saturating_sub(base))
    }

    /// End a phase: its peak, and a fresh peak for the next one (same base).
    pub fn next_phase(&mut self) -> Option<u64> {
        let now = Status::read();
        let peak = self.peak_in(now);
        self.reset = reset_peak(now);
        self.hwm_at_phase_start = Status::read().map_or(u64::MAX, |s| s.hwm);
        peak
    }
}

/// The smallest array [`drop_aside`] frees on a thread of its own: a
/// smaller one takes less time to unmap (tens of microseconds) than a
/// thread to start (about a tenth of a millisecond).
pub const ASIDE_MIN_BYTES: usize = 1 << 20;

/// Frees `value` on a thread of its own, so that the caller goes on at
/// once: glibc hands every block over 32 MB back to the kernel when it is
/// freed, and unmapping a large mesh's arrays took 30 to 45 ms a build on
/// the thread that would go on to the next step (docs/performance.md,
/// "Memory asked for ahead"). An array under [`ASIDE_MIN_BYTES`], a
/// caller in a pool of one thread (a run told to use one core), or one
/// where no thread can be started, frees it here.
pub fn drop_aside<T: Send + 'static>(value: Vec<T>) {
    if value.capacity() * std::mem::size_of::<T>() < ASIDE_MIN_BYTES
        || rayon::current_num_threads() <= 1
    {
        return drop(value);
    }
    let _ = std::thread::Builder::new()
        .name("strata-free".into())
        .spawn(move || drop(value));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_gives_both_fields_in_bytes() {
        let text =
            "Name:\tstrata\nVmPeak:\t  900 kB\nVmHWM:\t   700 kB\nVmRSS:\t   512 kB\nThreads:\t3\n";
        let s = Status::parse(text).unwrap();
        assert_eq!((s.rss, s.hwm), (512 * 1024, 700 * 1024));
        assert!(Status::parse("VmRSS:\t512 kB\n").is_none(), "no VmHWM");
    }

    /// With 64 MB touched and held, one reading has both fields: the
    /// resident size at least that, the peak at least the resident size,
    /// and so the run's peak. (A phase's peak is process-wide, and other
    /// tests reset it and free memory beside this one: not asserted.)
    #[test]
    fn a_reading_holds_what_is_touched() {
        if Status::read().is_none() {
            return;
        }
        let bytes = 64 << 20;
        let touched = vec![1u8; bytes];
        std::hint::black_box(&touched);
        let now = Status::read().unwrap();
        assert!(now.rss >= bytes as u64 * 9 / 10, "{now:?}");
        assert!(now.hwm >= now.rss, "{now:?}");
        assert!(peak_rss_bytes().unwrap() >= bytes as u64 * 9 / 10);
        drop(touched);
    }
}
