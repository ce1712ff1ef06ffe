//! The statistics JSON of a render.

use crate::shade::integrator::RayCounts;
use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
pub struct PhaseTimes {
    pub load_s: f64,
    pub bvh_build_s: f64,
    pub render_s: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub samples_rendered: [u32; 2],
    pub sampler: String,
    pub seed: u32,
    pub threads: usize,
    pub schedule: String,
    pub slice: String,
    /// `--packets`: auto, on or off (the image does not depend on it).
    pub packets: crate::shade::integrator::PacketMode,
    pub rays: RayCounts,
    pub rays_total: u64,
    pub mrays_per_s: f64,
    pub time: PhaseTimes,
    pub triangles: usize,
    pub analytic_shapes: usize,
    pub planes: usize,
    pub bvh_nodes: usize,
    pub bvh_bytes: usize,
    pub peak_rss_bytes: Option<u64>,
    pub invalid_samples: u64,
    pub first_invalid_sample: Option<crate::render::film::BadSample>,
    pub clamped_samples: u64,
}

/// Peak resident set size of this process (Linux `VmHWM`), if known.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
