//! What a load is doing, for a progress display on another thread.

use std::sync::atomic::{AtomicU64, AtomicU8, Ordering::Relaxed};

/// What a load is doing, set by the compiler as it goes and read by a
/// progress display on another thread (relaxed atomics: a display needs
/// no order).
#[derive(Debug, Default)]
pub struct LoadProgress {
    /// 0: loading, 1: building, 2: done.
    phase: AtomicU8,
    triangles: AtomicU64,
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
