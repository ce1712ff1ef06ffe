//! Which build a tree gets: the preset asked for, or under `auto` the one
//! that fits the work, chosen before the build from the settings alone.
//!
//! For a render, `auto` estimates the rays it will trace (pixels × samples
//! × rays a sample, [`crate::scene::RenderSettings::first_hit_rays`]) and
//! picks the preset whose build time plus trace time is least:
//!
//! ```text
//! cost(q) = BUILD_NS[q] · prims + TRACE_NS(prims) · TRACE_FACTOR[q] · rays
//! ```
//!
//! a linear model of each preset's build (nanoseconds a primitive) and of
//! a ray's walk through its tree (the medium tree's cost a ray, which
//! grows with the log of the primitive count, times the preset's factor).
//! Its constants were measured on the dragon and its subdivisions
//! (docs/performance.md, "The build that fits the render", with the model
//! checked against measurement). Both terms are on the same two threads;
//! the choice takes no thread count and no slice, so every slice and
//! every thread count of one render builds the same tree.
//!
//! The same estimate says which pages the tree goes on ([`Pages`]): huge
//! pages save a share of the trace ([`PAGE_GAIN`]) and cost their first
//! writes ([`PAGE_NS`] a primitive), so a render takes them where
//!
//! ```text
//! PAGE_GAIN · TRACE_NS(prims) · rays > PAGE_NS · prims
//! ```
//!
//! about ten rays a primitive; ray files and Python queries, whose count
//! the build does not know, take them as Embree does. Pages change no
//! answer, only time.

use super::build::BuildQuality;
use super::simd::pages::Pages;

/// The presets `auto` chooses among, in order of effort.
const PRESETS: [BuildQuality; 5] = [
    BuildQuality::Preview,
    BuildQuality::Fastest,
    BuildQuality::Fast,
    BuildQuality::Medium,
    BuildQuality::High,
];

/// Build time a primitive, in nanoseconds, of each preset of [`PRESETS`]
/// (two threads, AMD EPYC; docs/performance.md: the dragon and its two
/// subdivisions, 0.9 to 14 million triangles, for `fastest` and `high`;
/// the others from their build time over the fastest preset's,
/// alternating on the quiet machine: `preview` 0.64 on the dragon, 0.59
/// on its 13.9-million-triangle subdivision; `fast` and `medium` over
/// clusters 1.13 and 1.38, "The full-quality build from clusters").
const BUILD_NS: [f64; 5] = [120.0, 195.0, 220.0, 270.0, 1280.0];

/// Trace time a ray relative to the medium tree's, of each preset of
/// [`PRESETS`]: one plus 0.6 times the tree's SAH cost over the medium
/// tree's, less one, on the dragon (20.9, 19.0, 18.3, 18.1, 17.3); 0.6 is
/// the share of a render's time that moves with the tree
/// (docs/performance.md).
const TRACE_FACTOR: [f64; 5] = [1.094, 1.031, 1.007, 1.0, 0.974];

/// Where the medium preset is in [`PRESETS`]: the estimate shows its
/// time beside the chosen one's.
const MEDIUM: usize = 3;
const _: () = assert!(matches!(PRESETS[MEDIUM], BuildQuality::Medium));

/// The medium tree's trace time a ray of a render, in nanoseconds, over
/// `prims` primitives: 62 ns on the dragon (871,414 triangles), 7.25 ns
/// more for each doubling (the walk a level deeper, the tree further out
/// of the caches), fitted to the dragon and its subdivisions; never
/// under 10 ns.
fn trace_ns(prims: usize) -> f64 {
    let doublings = (prims.max(2) as f64 / 871_414.0).log2();
    (62.0 + 7.25 * doublings).max(10.0)
}

/// Nanoseconds a primitive that putting a tree on huge pages costs at
/// worst: the dragon subdivided twice (13.9 million triangles) built 0.54 s
/// slower on two threads with its nodes and leaf blocks on them, on a VM
/// whose host takes back freed memory, so that each fresh huge page is
/// filled by the host too (docs/performance.md, "Huge pages for the
/// tree"); where pages are reused the same writes are faster than on
/// small pages.
const PAGE_NS: f64 = 38.0;

/// The share of a render's trace time that huge pages save on a tree
/// larger than the TLB reaches: `scenes/large/dragon-rect.toml`, 16 spp,
/// one thread, 0.460 s against 0.439 s. The lone walk gains 8 to 19%
/// (`tools/bench_lone_walk.sh`, three runs); a render less, its streams
/// already overlapping some of the misses.
const PAGE_GAIN: f64 = 0.05;

/// Below this many primitives every preset builds in a few milliseconds
/// and `auto` keeps the medium tree whatever the work (the fastest
/// preset's clusters would put up to eight instances or shapes in a leaf).
pub const MODEL_MIN_PRIMS: usize = 100_000;

/// What was built and why.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BuildChoice {
    /// The preset built: never `auto`.
    pub quality: BuildQuality,
    pub reason: Reason,
    /// The pages the tree goes on: huge for a tree of at least
    /// [`MODEL_MIN_PRIMS`] primitives where the rays pay for them.
    pub pages: Pages,
}

/// Why a build has its preset.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Reason {
    /// `--bvh-quality` (or Python's `bvh_quality`) named it.
    #[default]
    Asked,
    /// `auto` under [`MODEL_MIN_PRIMS`] primitives: the medium tree.
    Small { prims: usize },
    /// `auto` for tracing ray files: the medium tree, whatever their count.
    Count { prims: usize },
    /// `auto` for a render: the least estimated build plus trace time.
    Fits(Estimate),
}

/// The model's estimate for the chosen preset, and the work it weighed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub prims: usize,
    pub rays: u64,
    /// Estimated seconds of the chosen preset's build and of the trace.
    pub build_s: f64,
    pub trace_s: f64,
    /// The same sum for the full (medium) build, for comparison.
    pub medium_s: f64,
}

impl BuildQuality {
    /// The preset for a render that traces about `rays` rays over `prims`
    /// primitives (`None`: ray files, the same tree however many rays),
    /// and why. Any preset but `auto` stands.
    pub fn choose(self, prims: usize, rays: Option<u64>) -> BuildChoice {
        let (quality, reason) = match (self, rays) {
            (Self::Auto, _) if prims < MODEL_MIN_PRIMS => (Self::Medium, Reason::Small { prims }),
            (Self::Auto, None) => (Self::Medium, Reason::Count { prims }),
            (Self::Auto, Some(rays)) => {
                let (k, estimate) = fit(prims, rays);
                (PRESETS[k], Reason::Fits(estimate))
            }
            (asked, _) => (asked, Reason::Asked),
        };
        BuildChoice {
            quality,
            reason,
            pages: pages(prims, rays),
        }
    }
}

/// The pages a tree over `prims` primitives goes on when about `rays` rays
/// will walk it (`None`: not known before the build): huge where the
/// rays pay for their first write, or where every large allocation is on
/// them anyway (`accel::allocator`).
fn pages(prims: usize, rays: Option<u64>) -> Pages {
    let pay = |rays: u64| PAGE_GAIN * trace_ns(prims) * rays as f64 > PAGE_NS * prims as f64;
    let everywhere = super::simd::allocator::large_allocations_on_huge_pages();
    if prims >= MODEL_MIN_PRIMS && (everywhere || rays.is_none_or(pay)) {
        Pages::Huge
    } else {
        Pages::Small
    }
}

/// The index into [`PRESETS`] of the least estimated build plus trace
/// time for `rays` rays over `prims` primitives (the less effort on a
/// tie), and its estimate.
fn fit(prims: usize, rays: u64) -> (usize, Estimate) {
    let per_ray = trace_ns(prims) * 1e-9;
    let parts = |k: usize| {
        (
            BUILD_NS[k] * 1e-9 * prims as f64,
            per_ray * TRACE_FACTOR[k] * rays as f64,
        )
    };
    let total = |k: usize| {
        let (b, t) = parts(k);
        b + t
    };
    let best = (0..PRESETS.len()).fold(0, |best, k| if total(k) < total(best) { k } else { best });
    let (build_s, trace_s) = parts(best);
    (
        best,
        Estimate {
            prims,
            rays,
            build_s,
            trace_s,
            medium_s: total(MEDIUM),
        },
    )
}

impl std::fmt::Display for BuildChoice {
    /// Why, in a few words: what `--stats` records and the summary line
    /// shows after the preset.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let pages = match self.pages {
            Pages::Small => "",
            Pages::Huge => "; huge pages",
        };
        match self.reason {
            Reason::Asked => write!(f, "as asked"),
            Reason::Small { prims } => write!(
                f,
                "auto: {prims} primitives, under {MODEL_MIN_PRIMS}"
            ),
            Reason::Count { prims } => write!(f, "auto for ray files: {prims} primitives"),
            Reason::Fits(e) => write!(
                f,
                "auto: {:.2} M rays over {:.2} M primitives, est. build {:.2} s + trace {:.2} s (medium {:.2} s)",
                e.rays as f64 / 1e6,
                e.prims as f64 / 1e6,
                e.build_s,
                e.trace_s,
                e.medium_s
            ),
        }?;
        f.write_str(pages)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Few rays a primitive build the preview tree, many the best, and the
    /// choice moves one way only as the rays grow.
    #[test]
    fn more_rays_never_choose_a_cheaper_build() {
        for prims in [MODEL_MIN_PRIMS, 871_414, 13_942_624] {
            let chosen: Vec<usize> = (0..40).map(|e| fit(prims, 1u64 << e).0).collect();
            assert!(
                chosen.windows(2).all(|w| w[0] <= w[1]),
                "{prims}: {chosen:?}"
            );
            assert_eq!(chosen[0], 0, "{prims}: one ray builds the preview tree");
            assert_eq!(*chosen.last().unwrap(), 4, "{prims}: 2^39 rays build high");
        }
    }

    /// The chosen preset's estimate is never above any other preset's,
    /// by brute force over every preset.
    #[test]
    fn the_choice_is_the_least_estimated_time() {
        for prims in [100_000usize, 1_000_000, 20_000_000] {
            for rays in [1u64, 77_000, 5_000_000, 300_000_000, 1 << 34] {
                let (k, e) = fit(prims, rays);
                let per_ray = trace_ns(prims) * 1e-9;
                for j in 0..PRESETS.len() {
                    let other =
                        BUILD_NS[j] * 1e-9 * prims as f64 + per_ray * TRACE_FACTOR[j] * rays as f64;
                    assert!(
                        e.build_s + e.trace_s <= other,
                        "{prims} {rays}: {k} over {j}"
                    );
                }
            }
        }
    }

    /// A named preset wins over the model; `auto` for a small scene or
    /// for ray files does not weigh rays.
    #[test]
    fn a_named_preset_wins_and_auto_resolves() {
        for q in PRESETS {
            for rays in [None, Some(1), Some(u64::MAX)] {
                let c = q.choose(5_000_000, rays);
                assert_eq!((c.quality, c.reason), (q, Reason::Asked));
            }
        }
        let auto = BuildQuality::Auto;
        assert_eq!(auto.choose(50_000, Some(1)).quality, BuildQuality::Medium);
        assert_eq!(auto.choose(50_000, None).quality, BuildQuality::Medium);
        assert_eq!(auto.choose(30_000_000, None).quality, BuildQuality::Medium);
        assert_eq!(auto.choose(1_000_000, None).quality, BuildQuality::Medium);
        assert_eq!(
            auto.choose(1_000_000, Some(1)).quality,
            BuildQuality::Preview
        );
        assert_eq!(
            auto.choose(1_000_000, Some(1 << 40)).quality,
            BuildQuality::High
        );
        for rays in [None, Some(0), Some(1 << 20), Some(u64::MAX)] {
            assert_ne!(auto.choose(1 << 20, rays).quality, BuildQuality::Auto);
        }
    }

    /// Huge pages for a large tree whose rays pay for them, whatever its
    /// preset, and for one whose rays are not known; never for a small
    /// tree; and once they pay, more rays never take them away.
    #[test]
    fn huge_pages_where_the_rays_pay_for_them() {
        let dragon = 871_414;
        for q in [
            BuildQuality::Auto,
            BuildQuality::Preview,
            BuildQuality::High,
        ] {
            assert_eq!(q.choose(dragon, None).pages, Pages::Huge);
            assert_eq!(q.choose(dragon, Some(1)).pages, Pages::Small);
            assert_eq!(q.choose(dragon, Some(1 << 30)).pages, Pages::Huge);
            for rays in [None, Some(u64::MAX)] {
                assert_eq!(q.choose(MODEL_MIN_PRIMS - 1, rays).pages, Pages::Small);
            }
        }
        for prims in [MODEL_MIN_PRIMS, dragon, 13_942_624] {
            let huge: Vec<bool> = (0..40)
                .map(|e| pages(prims, Some(1 << e)) == Pages::Huge)
                .collect();
            assert!(huge.windows(2).all(|w| w[0] <= w[1]), "{prims}: {huge:?}");
            // The break-even is where the saved trace time equals the cost.
            let even = PAGE_NS / (PAGE_GAIN * trace_ns(prims)) * prims as f64;
            assert_eq!(pages(prims, Some((even * 0.99) as u64)), Pages::Small);
            assert_eq!(pages(prims, Some((even * 1.01) as u64)), Pages::Huge);
        }
        // A huge mesh's first image (320 × 240, 1 spp) stays on small pages.
        assert_eq!(pages(13_942_624, Some(230_000)), Pages::Small);
    }
}
