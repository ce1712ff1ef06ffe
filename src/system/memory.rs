//! Resident memory of this process (Linux `/proc/self/status`; `None`
//! elsewhere): the whole run's peak, and the peak of each loading phase.

use std::sync::atomic::{AtomicU64, Ordering};

/// The highest `VmHWM` seen before [`PeakMeter`] last reset it, so that
/// [`peak_rss_bytes`] stays the whole process's peak.
static PEAK_BEFORE_RESET: AtomicU64 = AtomicU64::new(0);

/// Peak resident set size of this process (Linux `VmHWM`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let hwm = status_kb("VmHWM:")?;
    Some(hwm.max(PEAK_BEFORE_RESET.load(Ordering::Relaxed)))
}

/// A `/proc/self/status` field in bytes (`VmHWM:`, `VmRSS:`).
fn status_kb(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Set `VmHWM` back to the current RSS (Linux ≥ 4.0: write 5 to
/// `/proc/self/clear_refs`); false where that is not possible.
fn reset_peak() -> bool {
    if let Some(hwm) = status_kb("VmHWM:") {
        PEAK_BEFORE_RESET.fetch_max(hwm, Ordering::Relaxed);
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
        let reset = reset_peak();
        Self {
            base: status_kb("VmRSS:"),
            reset,
            hwm_at_phase_start: status_kb("VmHWM:").unwrap_or(u64::MAX),
        }
    }

    /// Peak RSS of the phase so far, above the level at `start`.
    pub fn phase_peak(&self) -> Option<u64> {
        let base = self.base?;
        let hwm = status_kb("VmHWM:")?;
        (self.reset || hwm > self.hwm_at_phase_start).then(|| hwm.saturating_sub(base))
    }

    /// End a phase: its peak, and a fresh peak for the next one (same base).
    pub fn next_phase(&mut self) -> Option<u64> {
        let peak = self.phase_peak();
        self.reset = reset_peak();
        self.hwm_at_phase_start = status_kb("VmHWM:").unwrap_or(u64::MAX);
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
