//! The statistics of a render: what `strata render --stats` writes as
//! JSON, and the summary line it prints.

use super::film::BadSample;
use super::timeline::TimelineSummary;
use super::{RenderOptions, RenderOutcome};
use crate::accel::BuildQuality;
use crate::scene::{LoadTimings, Scene};
use crate::shade::{PacketMode, RayCounts};
use crate::system::memory::peak_rss_bytes;
use crate::system::steps::Steps;
use serde::Serialize;
use std::path::Path;

#[derive(Debug, Clone, Serialize)]
pub struct PhaseTimes {
    pub load_s: f64,
    pub bvh_build_s: f64,
    pub render_s: f64,
    /// The load's steps, seconds each: a model file's `read` and `frame`,
    /// then `compile`.
    pub load_steps: Steps,
    /// The build's steps: the primitive `boxes`, the tree's (`bounds`,
    /// `clusters` or `morton`, `ploc`, `reinsertion`, `collapse`) and the
    /// `leaves` (the triangles written in leaf order).
    pub build_steps: Steps,
}

#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub samples_rendered: [u32; 2],
    /// Valid samples per pixel, on average over the image: below the
    /// samples rendered where a noise target stopped pixels early.
    pub mean_spp: f64,
    /// The noise target (`--noise`), if any.
    pub noise: Option<f32>,
    /// The time budget in seconds (`--time`), if any: `spp` is then its
    /// ceiling, and `samples_rendered` what the budget reached.
    pub time_budget_s: Option<f64>,
    pub sampler: String,
    pub seed: u32,
    pub threads: usize,
    pub schedule: String,
    pub slice: String,
    /// `--crop`: the window rendered, as [x0, y0, x1, y1] (half-open).
    pub crop: Option<[u32; 4]>,
    /// `--packets`: auto, on or off (the image does not depend on it).
    pub packets: PacketMode,
    /// The instruction set rays were walked in (`STRATA_SIMD`): avx2
    /// (sse2 in a portable build) or avx512.
    pub kernel: &'static str,
    pub rays: RayCounts,
    pub rays_total: u64,
    pub mrays_per_s: f64,
    pub time: PhaseTimes,
    /// Triangles stored: the scene's own and each instanced mesh's once.
    pub triangles: usize,
    /// Placements of instanced meshes, and the triangles they place
    /// (each instance's mesh counted again).
    pub instances: usize,
    pub instanced_triangles: u64,
    pub analytic_shapes: usize,
    pub planes: usize,
    /// The BVH build preset used (`--bvh-quality`, with `auto` resolved).
    pub bvh_quality: BuildQuality,
    /// Why that preset: `as asked`, or what `auto` weighed (the rays
    /// and primitives, each estimate; [`crate::accel::choice`]).
    pub bvh_why: String,
    pub bvh_nodes: usize,
    pub bvh_bytes: usize,
    /// Whether traversal prefetched (`accel::prefetch`: on for trees of
    /// 8 MiB and more of nodes and leaf blocks; the image does not depend on it).
    pub bvh_prefetch: bool,
    pub peak_rss_bytes: Option<u64>,
    pub memory: BuildMemory,
    pub invalid_samples: u64,
    pub first_invalid_sample: Option<BadSample>,
    pub clamped_samples: u64,
    /// The run at a glance: each thread's busy and idle time, the longest
    /// work item against the mean, each phase's share of the wall time.
    pub timeline: Option<TimelineSummary>,
}

/// Fewest triangles for which the summary gives memory per triangle: below
/// it, fixed costs dominate and the figure says nothing about meshes.
pub const PER_TRIANGLE_MIN: usize = 1000;

/// Memory of loading and building, as `strata render --stats` reports it.
#[derive(Debug, Clone, Serialize)]
pub struct BuildMemory {
    /// Bytes per triangle of the structures traversal reads
    /// ([`crate::geometry::Geometry::accel_bytes`]).
    pub final_bytes_per_triangle: Option<f64>,
    /// Bytes per instance: its record and its share of the scene's tree
    /// ([`crate::geometry::Geometry::instance_bytes`]).
    pub final_bytes_per_instance: Option<f64>,
    /// Peak resident memory above the level before loading, while loading
    /// the meshes and while building the BVH (None where Linux's
    /// `/proc/self/clear_refs` cannot reset the peak and it did not rise).
    pub load_peak_bytes: Option<u64>,
    pub build_peak_bytes: Option<u64>,
    /// The larger of the two, per triangle.
    pub peak_bytes_per_triangle: Option<f64>,
    /// Whether the process put its large allocations on huge pages
    /// (`STRATA_HUGE_PAGES`, [`crate::accel::allocator`]): the same image
    /// either way, but a different time and peak.
    pub huge_pages: bool,
}

impl RenderStats {
    /// The record of one finished render of `scene` (named `scene_name`).
    pub fn new(
        scene_name: &str,
        scene: &Scene,
        timings: &LoadTimings,
        opts: &RenderOptions,
        outcome: &RenderOutcome,
    ) -> Self {
        let s = &scene.settings;
        let g = &scene.geometry;
        // Per triangle only where there are triangles: a figure per triangle
        // of a scene without meshes would be all overhead.
        let unique = g.unique_triangles();
        let per_triangle = |bytes: u64| (unique > 0).then(|| bytes as f64 / unique as f64);
        let instances = g.instances.len();
        let rays_total = outcome.counts.total();
        Self {
            scene: scene_name.to_string(),
            width: s.width,
            height: s.height,
            spp: s.spp,
            samples_rendered: [
                opts.resume_from.unwrap_or(outcome.samples.start),
                outcome.done,
            ],
            mean_spp: outcome.film.mean_samples(),
            noise: s.noise.filter(|_| opts.slice.count == 1),
            time_budget_s: opts.budget,
            sampler: format!("{:?}", s.sampler).to_lowercase(),
            seed: s.seed,
            threads: outcome.threads,
            schedule: format!("{:?}", opts.schedule).to_lowercase(),
            slice: format!("{}/{}", opts.slice.index, opts.slice.count),
            crop: opts
                .window
                .as_ref()
                .map(|w| [w.x.start, w.y.start, w.x.end, w.y.end]),
            packets: opts.packets,
            kernel: crate::accel::Kernel::selected().name(),
            rays: outcome.counts,
            rays_total,
            mrays_per_s: rays_total as f64 / outcome.seconds.max(1e-9) / 1e6,
            time: PhaseTimes {
                load_s: timings.load.as_secs_f64(),
                bvh_build_s: timings.bvh_build.as_secs_f64(),
                render_s: outcome.seconds,
                load_steps: timings.load_steps,
                build_steps: timings.build_steps,
            },
            triangles: unique as usize,
            instances,
            instanced_triangles: g.instanced_triangles(),
            analytic_shapes: g.shapes.len(),
            planes: g.planes.len(),
            bvh_quality: timings.bvh_quality,
            bvh_why: timings.bvh_choice.to_string(),
            bvh_nodes: g.bvh.node_count(),
            bvh_bytes: g.bvh.memory_bytes(),
            bvh_prefetch: g.bvh.prefetch,
            peak_rss_bytes: peak_rss_bytes(),
            memory: BuildMemory {
                final_bytes_per_triangle: per_triangle(
                    (g.accel_bytes() - g.instance_bytes()) as u64,
                ),
                final_bytes_per_instance: (instances > 0)
                    .then(|| g.instance_bytes() as f64 / instances as f64),
                load_peak_bytes: timings.load_peak_bytes,
                build_peak_bytes: timings.build_peak_bytes,
                peak_bytes_per_triangle: timings.peak_bytes().and_then(per_triangle),
                huge_pages: crate::accel::allocator::large_allocations_on_huge_pages(),
            },
            invalid_samples: outcome.film.invalid,
            first_invalid_sample: outcome.film.first_invalid,
            clamped_samples: outcome.film.clamped,
            timeline: None,
        }
    }

    /// Pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("plain numbers and strings serialise")
    }

    /// The one-line summary `strata render` prints, ending `-> output`.
    pub fn summary(&self, output: &Path) -> String {
        let r = &self.rays;
        let peak = self
            .memory
            .load_peak_bytes
            .max(self.memory.build_peak_bytes);
        let peak = match (peak, self.triangles) {
            (Some(b), n) if n >= PER_TRIANGLE_MIN => format!(
                ", peak +{:.0} MB = {:.0} B/triangle",
                b as f64 / 1e6,
                b as f64 / n as f64
            ),
            (Some(b), _) => format!(", peak +{:.0} MB", b as f64 / 1e6),
            (None, _) => String::new(),
        };
        let instanced = match self.instances {
            0 => String::new(),
            n => {
                let t = self.instanced_triangles as f64;
                let placed = match t {
                    t if t >= 1e9 => format!("{:.2} G", t / 1e9),
                    t if t >= 1e6 => format!("{:.2} M", t / 1e6),
                    t => format!("{t}"),
                };
                format!(", {n} instances placing {placed} triangles")
            }
        };
        let [start, end] = self.samples_rendered;
        let mut samples = if end - start == self.spp {
            format!("{} spp", self.spp)
        } else if let (Some(budget), 0) = (self.time_budget_s, start) {
            // The ceiling is the budget's, not a count the user asked for.
            format!("{end} spp in a {budget} s budget")
        } else {
            format!("samples {start}..{end} of {} spp", self.spp)
        };
        if let Some(noise) = self.noise {
            samples = format!(
                "noise {noise}: {:.1} spp on average, {samples}",
                self.mean_spp
            );
        }
        let threads = if self.threads == 1 {
            "thread"
        } else {
            "threads"
        };
        let size = match self.crop {
            Some([x0, y0, x1, y1]) => {
                format!("crop {x0},{y0},{x1},{y1} of {}x{}", self.width, self.height)
            }
            None => format!("{}x{}", self.width, self.height),
        };
        format!(
            "{size} {samples}: {:.2} M rays ({:.2} camera, {:.2} shadow, {:.2} reflection, {:.2} refraction) in {:.2} s = {:.2} Mrays/s on {} {threads} (load {:.2} s, BVH {} {:.2} s, {}{peak}{instanced}) -> {}",
            self.rays_total as f64 / 1e6,
            r.camera as f64 / 1e6,
            r.shadow as f64 / 1e6,
            r.reflection as f64 / 1e6,
            r.refraction as f64 / 1e6,
            self.time.render_s,
            self.mrays_per_s,
            self.threads,
            self.time.load_s,
            self.bvh_quality,
            self.time.bvh_build_s,
            self.bvh_why,
            output.display()
        )
    }
}
