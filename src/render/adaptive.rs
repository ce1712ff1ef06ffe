//! Adaptive sampling to a noise target (`--noise`, `[render] noise`).
//!
//! A pixel stops taking samples once it has taken σ/E² of them, σ the
//! estimated standard deviation of its samples' displayed luminance and E
//! the target; `spp` is the ceiling. Decisions are made at pass
//! boundaries, from the film alone: a pixel's record (its sums, its sum
//! of squared luminance and its count) says whether it goes on. A stopped
//! pixel's record no longer changes, so the decision is the same at every
//! later boundary, and a render resumed from a checkpoint (which holds the
//! film) decides as the uninterrupted one did. The image is therefore the
//! same for any thread count, checkpoint and resume.
//!
//! **The estimate.** With n samples of luminance Yᵢ, mean Ȳ and sample
//! variance s² = (ΣYᵢ² − nȲ²)/(n − 1), the standard error of the mean is
//! s/√n. A pixel's error is that standard error over the square root of
//! its samples' standard deviation, both as displayed (times k =
//! 2^exposure): s·k/√n ÷ √(s·k) = √(s·k/n), at most E once n ≥ s·k/E².
//!
//! **Why samples in proportion to s.** For a given number of samples, the
//! image's mean squared error, the mean over pixels of s²/n, is least
//! when each pixel's n is proportional to its s (Neyman 1934's optimal
//! allocation of a stratified survey; a Lagrange multiplier gives it in a
//! line), and then it is E² times the mean of s·k: the image's RMSE is
//! about E·√mean(s·k). A pixel whose samples agree (s = 0) is done; a
//! dark pixel, whose deviation is small, is done soon. Stopping at a
//! relative error (s/√n ÷ Ȳ) gives n ∝ s²/Ȳ², and the standard error over
//! √Ȳ (Dammertz et al. 2010, Cycles' measure) n ∝ s²/Ȳ: both spend most
//! where the deviation is large beside the mean (the dark side of a
//! penumbra: with a share p of a light's rays unblocked, n ∝ 1 − p under
//! √Ȳ, against Neyman's √(p(1 − p))), past where those samples lower the
//! image's error most. Measured on the dragon under an area light at
//! equal RMSE, the relative measure took 0.8 of the uniform samples,
//! over √Ȳ 0.3, this one about 0.2 (docs/converge.md). s/√n is the error
//! of n independent samples; a pixel's samples are part of one stratified
//! set, whose error is smaller where the integrand is smooth, so the
//! estimate errs on the side of more samples there (the factor is
//! measured in tests/suite/adaptive.rs).
//!
//! **Neighbours.** A pixel whose first samples all agree (eight shadow
//! rays that all missed the light's edge) estimates a deviation of 0
//! though its own is not; alone it would stop, and such pixels set a floor
//! under the image's error. So a pixel keeps sampling while any pixel of
//! its 3 × 3 neighbourhood does (Cycles dilates its active pixels the same
//! way): noise is rarely a single pixel wide. The decision still reads the
//! film alone, so threads, checkpoints and resumes do not change it; a
//! crop is rendered with a margin of one pixel per decision
//! ([`crop_margin`]: how far a neighbour's influence can travel), so it
//! still equals the same window of the whole render.
//!
//! **The passes** are the decision points: the first after
//! [`FIRST_DECISION`] samples, the next at 8, then each ×1.5 or ×4/3 of
//! the one before (4, 8, 12, 16, 24, 32, 48, …) up to `spp`, whatever
//! `--passes` says, so that a checkpoint taken at any of them resumes on
//! the same plan.
//!
//! **What a stopped pixel used:** under the Sobol sampler (the default
//! with a noise target), a prefix of one sequence that is stratified at
//! every power of two (`sampling::sobol`). Under the multi-jittered
//! sampler each pass's samples are a stratified set of their own
//! (`schedule::SampleSet::of`): sets of 4, 4, 4, 4, 8, 8, 16, 16, …
//! samples, each scrambled apart from the
//! others, so a pixel stopped after any pass has used whole sets, never
//! part of one, and a pixel that reaches the ceiling has used those sets,
//! not the one set of spp a render without a noise target uses. (A time
//! budget, `--time`, renders the same passes.)
//!
//! The approach is Dammertz, Hanika, Keller and Lensch 2010, "A
//! Hierarchical Automatic Stopping Condition for Monte Carlo Global
//! Illumination" (per-pixel error from the samples so far, judged at
//! pass ends), with Neyman's allocation for the measure and a
//! neighbourhood of 3 × 3 pixels in place of their hierarchy of blocks.

use super::film::{fixed_to_f64, Film, FIXED_SCALE, LUMINANCE};
use crate::scene::settings::RenderSettings;
use rayon::prelude::*;
use std::ops::Range;

/// Samples every pixel takes before the first decision: a power of two
/// of the Sobol sequence (stratified) and a variance of 3 degrees of
/// freedom; the neighbourhood guards what so few samples miss. Most of an
/// image's pixels need no more (the dragon under an area light: 80% of
/// them at E = 0.2), and those pixels' first samples are most of a coarse
/// target's time. After 8 in place of 4, that scene's targets 0.3 and 0.2
/// took 1.2 to 1.3 times the time to the same RMSE (0.14 and 0.1 about
/// the same); after 16, 1.1 to 1.5 times the samples of after 8; after 2,
/// more time than after 4 (docs/converge.md).
pub const FIRST_DECISION: u32 = crate::scene::settings::NOISE_FIRST_DECISION;

/// The share of Ȳ² that the f32 rounding of each sample's Y² can leave
/// as variance where samples agree (`standard_error`): a relative
/// deviation below 0.1% counts as none.
pub const ROUNDING: f64 = 1e-6;

/// The noise target of a render: the error `error` (module docs), judged
/// on luminance times `scale` (2^exposure).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseTarget {
    pub error: f32,
    pub scale: f32,
}

impl NoiseTarget {
    /// The noise target of a render's settings (`--noise`, judged at
    /// `--exposure`), if it has one.
    pub fn of(settings: &RenderSettings) -> Option<Self> {
        settings.noise.map(|error| Self {
            error,
            scale: settings.exposure.exp2(),
        })
    }
}

/// The sample counts at which pixels are judged, for a ceiling of `spp`:
/// 4, 8, 12, 16, 24, 32, … (powers of two and 1.5 times them from 8 on),
/// then `spp`. From 4 straight to 8: a decision at 6 cost the dragon's
/// coarse targets a fifth more time for a pass of two samples.
pub fn decision_points(spp: u32) -> Vec<u32> {
    let mut points = Vec::new();
    let mut p = FIRST_DECISION;
    while p < spp {
        points.push(p);
        // 4 → 8, then 8 → 12 → 16 → 24 → 32: alternately ×1.5 and ×4/3.
        p = if p < 8 {
            2 * p
        } else if p.is_power_of_two() {
            p + p / 2
        } else {
            p / 3 * 4
        };
    }
    points.push(spp);
    points
}

/// The passes of a `--noise` render from sample `start` (0, or a decision
/// point a checkpoint ended at) to `spp`: one per decision point.
pub fn passes(start: u32, spp: u32) -> Vec<Range<u32>> {
    let mut out = Vec::new();
    let mut lo = start;
    for p in decision_points(spp) {
        if p > lo {
            out.push(lo..p);
            lo = p;
        }
    }
    out
}

/// Pixel `index`'s count n and its fixed-point sums of luminance,
/// F·ΣY (from the channel sums), and of squared luminance, F·ΣY², in f64;
/// `None` with fewer than two valid samples or no squares kept.
fn luminance_sums(film: &Film, index: usize) -> Option<(f64, f64, f64)> {
    let n = film.counts[index];
    if n < 2 || film.squares.is_empty() {
        return None;
    }
    let s = &film.sums[index];
    let w = LUMINANCE;
    let sum = w[0] * fixed_to_f64(s[0]) + w[1] * fixed_to_f64(s[1]) + w[2] * fixed_to_f64(s[2]);
    Some((n as f64, sum, fixed_to_f64(film.square(index))))
}

/// Pixel `index`'s mean luminance Ȳ and the estimated standard error of
/// that mean, s/√n (module docs); `None` with fewer than two valid
/// samples or no squares kept.
pub fn standard_error(film: &Film, index: usize) -> Option<(f64, f64)> {
    let (n, sum, squares) = luminance_sums(film, index)?;
    // The squares were rounded from f32 (Y and Y² each to a few units of
    // 2⁻²⁴), so samples that agree leave up to about 7·10⁻⁷ Ȳ² of
    // variance: [`ROUNDING`] Ȳ² is taken off, or the square root in the
    // error would show a bright pixel's rounding as noise (3·10⁻⁴ Ȳ of
    // deviation at Ȳ = 40 is an error of 0.04 at 8 samples).
    let mean = sum / (FIXED_SCALE * n);
    let mean_square = squares / (FIXED_SCALE * n);
    let spread = mean_square - mean * mean * (1.0 + ROUNDING);
    let variance = (spread * n / (n - 1.0)).max(0.0);
    Some((mean, (variance / n).sqrt()))
}

/// The estimated error of pixel `index` of `film`, as the module docs
/// define it (the standard error over the square root of the samples'
/// standard deviation, √(s/n)), with luminance scaled by `scale`; infinite
/// with fewer than two valid samples or no squares kept.
pub fn pixel_error(film: &Film, index: usize, scale: f32) -> f64 {
    let Some((_, error)) = standard_error(film, index) else {
        return f64::INFINITY;
    };
    // s/√n · k over √(s·k), with s = error·√n: √(error · k / √n).
    let n = film.counts[index] as f64;
    (error * scale as f64 / n.sqrt()).sqrt()
}

/// Whether pixel `index` of `film` has met `target` on its own samples:
/// [`pixel_error`] ≤ E, tested without a division or a root, as every
/// decision reads every pixel that took samples (through `pixel_error`
/// it took 35 ns a pixel, 2.7 ms of a coarse target's 105 on the dragon).
///
/// With the fixed-point sums S = F·ΣY and Q = F·ΣY² of n samples, the
/// variance is s² = (F·n·Q − S²·(1 + [`ROUNDING`])) / (F²·n·(n − 1)), and
/// √(s·k/n) ≤ E is s² ≤ E⁴·n²/k², so: (F·n·Q − S²·(1 + ROUNDING))·k² ≤
/// E⁴·F²·n³·(n − 1), a negative left side being no variance.
pub fn converged(film: &Film, index: usize, target: NoiseTarget) -> bool {
    let Some((n, sum, squares)) = luminance_sums(film, index) else {
        return false;
    };
    let k = target.scale as f64;
    let e2 = target.error as f64 * target.error as f64;
    let spread = FIXED_SCALE * n * squares - sum * sum * (1.0 + ROUNDING);
    spread * k * k <= e2 * e2 * FIXED_SCALE * FIXED_SCALE * n * n * n * (n - 1.0)
}

/// Which pixels take the next pass's samples, kept from one decision to
/// the next: a pixel's own verdict is worked out again only when it took
/// samples in the pass before, as no other pixel's record has changed.
/// The same answer as deciding afresh (a new `Decisions`) at every
/// decision, without reading every pixel's record at every pass (a sixth
/// of a short render's time on the dragon under an area light, where most
/// pixels stop at the first decision).
#[derive(Debug, Default)]
pub struct Decisions {
    /// Each pixel has met the target on its own samples.
    met: Vec<bool>,
    /// Each pixel takes the next pass's samples: `met`, negated and
    /// dilated.
    active: Vec<bool>,
    /// The dilation's first step, along rows.
    along: Vec<bool>,
}

impl Decisions {
    /// Decides from `film`, whose records changed only where
    /// [`Decisions::active`] said at the decision before (every record
    /// is read at the first).
    pub fn update(&mut self, film: &Film, target: NoiseTarget) {
        // In blocks on the current thread pool (a render calls this inside
        // its own): the first decision reads every pixel, 1.8 ms of the
        // dragon's coarsest noise render on one thread.
        const BLOCK: usize = 1 << 12;
        let n = film.pixel_count();
        if self.met.len() != n || self.active.len() != n {
            self.met = vec![false; n];
            self.active = vec![true; n];
        }
        self.met
            .par_chunks_mut(BLOCK)
            .zip(self.active.par_chunks(BLOCK))
            .enumerate()
            .for_each(|(b, (met, active))| {
                for (k, (met, &active)) in met.iter_mut().zip(active).enumerate() {
                    if active {
                        *met = converged(film, b * BLOCK + k, target);
                    }
                }
            });
        self.active.clear();
        self.active.extend(self.met.iter().map(|m| !m));
        dilate(&mut self.active, film.width as usize, &mut self.along);
    }

    /// Whether each pixel takes the next pass's samples (empty before
    /// the first decision).
    pub fn active(&self) -> &[bool] {
        &self.active
    }
}

/// Marks every pixel whose 3 × 3 neighbourhood (inside the image) holds
/// a marked pixel, in rows of `width`: along rows into `along` (kept to
/// be reused), then along columns.
fn dilate(marked: &mut [bool], width: usize, along: &mut Vec<bool>) {
    if width == 0 {
        return;
    }
    along.clear();
    for row in marked.chunks(width) {
        along.extend(
            (0..row.len())
                .map(|x| row[x] || (x > 0 && row[x - 1]) || row.get(x + 1) == Some(&true)),
        );
    }
    // Whole rows: an image's pixels.
    debug_assert_eq!(marked.len() % width, 0);
    let at = |r: usize| along.get(r * width..(r + 1) * width);
    for (y, row) in marked.chunks_mut(width).enumerate() {
        let here = &along[y * width..(y + 1) * width];
        let (above, below) = (y.checked_sub(1).and_then(at), at(y + 1));
        for (x, m) in row.iter_mut().enumerate() {
            *m = here[x] || above.is_some_and(|a| a[x]) || below.is_some_and(|b| b[x]);
        }
    }
}

/// How far, in pixels, the samples of one pixel can change a decision
/// elsewhere in a render of `spp` samples: one step of the neighbourhood
/// a decision, so a crop rendered with this margin around it takes the
/// samples the whole render gives it.
pub fn crop_margin(spp: u32) -> u32 {
    decision_points(spp).len() as u32 - 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::film::PixelSum;
    use glam::Vec3;

    #[test]
    fn decision_points_grow_by_half_and_third_and_end_at_the_ceiling() {
        assert_eq!(
            decision_points(200),
            [4, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 200]
        );
        assert_eq!(decision_points(8), [4, 8]);
        assert_eq!(decision_points(4), [4]);
        assert_eq!(decision_points(3), [3]);
        assert_eq!(decision_points(1024).last(), Some(&1024));
        assert_eq!(
            passes(0, 40),
            [0..4, 4..8, 8..12, 12..16, 16..24, 24..32, 32..40]
        );
        assert_eq!(passes(24, 40), [24..32, 32..40]);
        assert_eq!(passes(40, 40), Vec::<Range<u32>>::new());
    }

    fn film_of(values: &[Vec3]) -> Film {
        let mut p = PixelSum::default();
        for (i, v) in values.iter().enumerate() {
            p.add(*v, i as u32);
        }
        let mut film = Film::new(1, 1);
        film.track_squares();
        film.add_pixel(0, &p);
        film
    }

    /// Samples that agree have no error; two values a and b, half each,
    /// have s = |a − b|/2 · √(n/(n−1)), and an error √(s·k/n).
    #[test]
    fn the_estimate_is_the_root_of_the_deviation_over_the_count() {
        // However bright: f32's rounding of the squares is no deviation.
        for v in [
            Vec3::new(0.3, 0.2, 0.7),
            Vec3::new(40.3, 40.2, 39.7),
            Vec3::splat(1e4),
        ] {
            assert_eq!(pixel_error(&film_of(&[v; 16]), 0, 1.0), 0.0, "{v}");
        }
        let same = film_of(&[Vec3::new(0.3, 0.2, 0.7); 16]);
        let target = NoiseTarget {
            error: 1e-3,
            scale: 1.0,
        };
        assert!(converged(&same, 0, target));
        let values: Vec<Vec3> = (0..16)
            .map(|i| Vec3::splat(if i % 2 == 0 { 1.0 } else { 3.0 }))
            .collect();
        let film = film_of(&values);
        let s = (16.0f64 / 15.0).sqrt();
        let expected = (s / 16.0).sqrt();
        let e = pixel_error(&film, 0, 1.0);
        assert!((e - expected).abs() < 1e-5, "{e} vs {expected}");
        // Four times the exposure shows four times the deviation: twice
        // the error, so four times the samples to the same target.
        assert!((pixel_error(&film, 0, 4.0) - 2.0 * expected).abs() < 1e-5);
    }

    /// The division-free test is the error's test: for pixels of 2 to 600
    /// samples, dark to bright, agreeing to wild, at targets and exposures
    /// on either side of their error, `converged` says what `pixel_error`
    /// ≤ E says, but for errors within a millionth of E.
    #[test]
    fn the_convergence_test_agrees_with_the_error_it_stands_for() {
        let mut state = 0x9e37_79b9_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let (mut met, mut missed) = (0, 0);
        for case in 0..600 {
            let n = 2 + case;
            let (level, spread) = (next() * 50.0, next().powi(4) * 20.0);
            let values: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(1.0, 0.8, 0.6) * (level + spread * next()))
                .collect();
            let film = film_of(&values);
            for scale in [0.25, 1.0, 8.0] {
                let e = pixel_error(&film, 0, scale);
                for factor in [0.5, 0.99, 1.01, 2.0] {
                    let target = NoiseTarget {
                        error: (e * factor) as f32,
                        scale,
                    };
                    let error = target.error as f64;
                    if error > 0.0 && (e - error).abs() <= 1e-6 * error {
                        continue;
                    }
                    let expected = e <= error;
                    assert_eq!(
                        converged(&film, 0, target),
                        expected,
                        "n {n}, e {e}, E {error}"
                    );
                    if expected {
                        met += 1;
                    } else {
                        missed += 1;
                    }
                }
            }
        }
        assert!(met > 1000 && missed > 1000, "{met} met, {missed} missed");
        let one = NoiseTarget {
            error: 1.0,
            scale: 1.0,
        };
        assert!(!converged(&film_of(&[Vec3::ONE]), 0, one));
        assert!(!converged(&Film::new(1, 1), 0, one));
    }

    /// Neyman's allocation: a pixel whose samples deviate a hundredth as
    /// much (however dark or bright it is) meets a target with a
    /// hundredth of the samples, so its error at the same count is a
    /// tenth; with fewer than two samples, or no squares kept, the error
    /// is unknown.
    #[test]
    fn the_samples_a_pixel_needs_are_in_proportion_to_its_deviation() {
        let spread = |low: f32, high: f32| {
            let values: Vec<Vec3> = (0..16)
                .map(|i| Vec3::splat(if i % 2 == 0 { low } else { high }))
                .collect();
            pixel_error(&film_of(&values), 0, 1.0)
        };
        let (wide, narrow) = (spread(0.0, 2.0), spread(0.0, 0.02));
        assert!((narrow / wide - 0.1).abs() < 1e-4, "{narrow} / {wide}");
        // The level does not count, only the spread.
        assert!((spread(5.0, 5.2) / spread(0.0, 0.2) - 1.0).abs() < 1e-2);
        assert_eq!(pixel_error(&film_of(&[Vec3::ONE]), 0, 1.0), f64::INFINITY);
        assert_eq!(pixel_error(&Film::new(1, 1), 0, 1.0), f64::INFINITY);
    }

    /// One marked pixel marks its 3 × 3 neighbourhood and nothing else,
    /// cut off at the image's edges and not wrapped to the next row.
    #[test]
    fn a_pixel_that_samples_on_keeps_its_neighbours_sampling() {
        let (w, h) = (5usize, 4usize);
        for marked in [(0usize, 0usize), (4, 1), (2, 2), (4, 3)] {
            let mut m = vec![false; w * h];
            m[marked.1 * w + marked.0] = true;
            dilate(&mut m, w, &mut Vec::new());
            for y in 0..h {
                for x in 0..w {
                    let near = x.abs_diff(marked.0) <= 1 && y.abs_diff(marked.1) <= 1;
                    assert_eq!(m[y * w + x], near, "{marked:?}: ({x}, {y})");
                }
            }
        }
        let mut none = vec![false; w * h];
        dilate(&mut none, w, &mut Vec::new());
        assert!(none.iter().all(|&m| !m));
    }

    /// Decisions kept between passes equal decisions made afresh, when
    /// only the pixels that took samples change.
    #[test]
    fn kept_decisions_equal_fresh_ones() {
        let (w, h) = (9u32, 7u32);
        let target = NoiseTarget {
            error: 0.05,
            scale: 1.0,
        };
        let mut film = Film::new(w, h);
        film.track_squares();
        let mut kept = Decisions::default();
        // A pixel's samples: noisy near the centre, agreeing elsewhere.
        let sample = |i: usize, k: u32| {
            let (x, y) = ((i as u32 % w) as i32 - 4, (i as u32 / w) as i32 - 3);
            let noisy = x.abs() + y.abs() <= 2;
            Vec3::splat(if noisy && k % 2 == 1 { 2.0 } else { 0.5 })
        };
        let mut counts_seen = std::collections::BTreeSet::new();
        for pass in 0..6u32 {
            let active: Vec<bool> = kept.active().to_vec();
            for i in 0..film.pixel_count() {
                // Every pixel before the first decision.
                if active.get(i).copied().unwrap_or(true) {
                    let mut p = PixelSum::default();
                    for k in 0..8 {
                        p.add(sample(i, pass * 8 + k), k);
                    }
                    film.add_pixel(i, &p);
                }
            }
            kept.update(&film, target);
            // A new one reads every pixel's record.
            let mut fresh = Decisions::default();
            fresh.update(&film, target);
            assert_eq!(kept.active(), fresh.active(), "pass {pass}");
            counts_seen.extend(film.counts.iter().copied());
        }
        // Some pixels stopped at the first decision, some went on.
        assert!(
            counts_seen.contains(&8) && counts_seen.contains(&48),
            "{counts_seen:?}"
        );
    }

    /// One pixel of margin per decision after the first, so a crop's
    /// margin covers every step a neighbour's influence can take.
    #[test]
    fn the_crop_margin_is_the_decisions_after_the_first() {
        assert_eq!(crop_margin(4), 0);
        assert_eq!(crop_margin(8), 1);
        assert_eq!(crop_margin(12), 2);
        assert_eq!(crop_margin(200), decision_points(200).len() as u32 - 1);
    }
}
