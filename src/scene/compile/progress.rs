//! What a load is doing, for a progress display on another thread, and
//! whether it measures its memory.

use std::sync::atomic::{AtomicU64, AtomicU8, Ordering::Relaxed};

/// What a load is doing, set by the compiler as it goes and read by a
/// progress display on another thread (relaxed atomics: a display needs
/// no order); and whether anything will show its memory figures.
#[derive(Debug, Default)]
pub struct LoadProgress {
    /// 0: loading, 1: building, 2: done.
    phase: AtomicU8,
    triangles: AtomicU64,
    /// Nothing shows the load's memory peaks: it does not measure them
    /// (`LoadTimings`' peaks are None).
    unmetered: bool,
}

/// A phase of a load.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadPhase {
    /// Reading the scene and its mesh files.
    Loading,
    /// Building the BVH over this many triangles.
    Building {
        triangles: u64,
    },
    Done,
}

impl LoadProgress {
    /// The progress of a load whose memory peaks nothing will show
    /// (`strata render -q` without `--stats`): it skips the meters, whose
    /// reads of `/proc/self/status` cost a small scene's render about
    /// 0.3 ms (docs/performance.md).
    pub fn unmetered() -> Self {
        Self {
            unmetered: true,
            ..Self::default()
        }
    }

    /// Whether the load measures its memory peaks.
    pub(super) fn metered(&self) -> bool {
        !self.unmetered
    }

    pub fn phase(&self) -> LoadPhase {
        match self.phase.load(Relaxed) {
            0 => LoadPhase::Loading,
            1 => LoadPhase::Building {
                triangles: self.triangles.load(Relaxed),
            },
            _ => LoadPhase::Done,
        }
    }

    /// The load is over (done or failed).
    pub fn finish(&self) {
        self.phase.store(2, Relaxed);
    }

    pub(super) fn building(&self, triangles: u64) {
        self.triangles.store(triangles, Relaxed);
        self.phase.store(1, Relaxed);
    }
}
