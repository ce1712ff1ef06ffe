//! Piecewise-constant distributions on [0,1) and [0,1)², sampled by
//! inverting their cumulative distribution: the 2D one is a marginal
//! distribution over rows and one conditional distribution per row
//! (Pharr, Jakob and Humphreys, "Physically Based Rendering", 3rd ed.,
//! §13.6.7 and §14.2.4; Mitsuba's lat-long `envmap` does the same with
//! bilinear pieces). An environment map's luminance, times sin θ for the
//! lat-long mapping, is the one user: its bright texels are chosen in
//! proportion to what they contribute.
//!
//! Flat arrays: each row's cumulative sums are one slice of one `Vec`.
//! The sums are built in f64, so a map of millions of texels loses no
//! dim texel to rounding, and stored in f32.

use glam::Vec2;

/// The largest f32 below 1: samples stay in [0,1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A piecewise-constant 2D distribution over `width` × `height` cells of
/// [0,1)², cell (x, y) with density proportional to `func[y·width + x]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution2D {
    width: usize,
    height: usize,
    /// The cell values, row-major (all ones where the given ones were all 0).
    func: Vec<f32>,
    /// Per row, the `width + 1` normalised cumulative sums 0 … 1.
    conditional_cdf: Vec<f32>,
    /// The `height + 1` normalised cumulative sums of the rows' totals.
    marginal_cdf: Vec<f32>,
    /// Each row's mean value (its integral over [0,1)).
    row_integral: Vec<f32>,
    /// The mean of all cells: the integral of `func` over [0,1)².
    integral: f32,
}

/// `cdf[i] ≤ u < cdf[i + 1]` for the largest such `i` over a
/// non-decreasing `cdf` starting at 0 (a run of equal sums, a cell of
/// value 0, is never chosen).
fn find_interval(cdf: &[f32], u: f32) -> usize {
    // partition_point: the first index whose sum exceeds u; the cell before it.
    let n = cdf.len() - 1;
    cdf.partition_point(|&c| c <= u).clamp(1, n) - 1
}

/// Normalised cumulative sums of `values` into `cdf` (`values.len() + 1`
/// entries); returns the mean of `values`. All zeros count as all ones.
fn cumulate(values: &[f32], cdf: &mut [f32]) -> f64 {
    let total: f64 = values.iter().map(|&v| v as f64).sum();
    let n = values.len();
    let mut sum = 0.0f64;
    cdf[0] = 0.0;
    for (i, &v) in values.iter().enumerate() {
        sum += if total > 0.0 { v as f64 } else { 1.0 };
        let whole = if total > 0.0 { total } else { n as f64 };
        cdf[i + 1] = (sum / whole) as f32;
    }
    cdf[n] = 1.0;
    total / n as f64
}

/// Sample `u` ∈ [0,1) within cell `i` of `cdf`: the point in [0,1) and
/// the cell.
fn invert(cdf: &[f32], u: f32) -> (f32, usize) {
    let i = find_interval(cdf, u);
    let width = cdf[i + 1] - cdf[i];
    let du = if width > 0.0 {
        ((u - cdf[i]) / width).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let n = (cdf.len() - 1) as f32;
    (((i as f32 + du) / n).min(ONE_MINUS_EPSILON), i)
}

impl Distribution2D {
    /// The distribution of `func` (row-major, `width` × `height`, every
    /// value finite and ≥ 0). All zeros give the uniform distribution.
    /// Panics if the sizes disagree or one is 0 (a caller's mistake, not
    /// input: the map reader checks its sizes).
    pub fn new(func: &[f32], width: usize, height: usize) -> Self {
        assert!(width > 0 && height > 0 && func.len() == width * height);
        let all_zero = func.iter().all(|&v| !(v > 0.0));
        let func: Vec<f32> = if all_zero {
            vec![1.0; func.len()]
        } else {
            func.iter().map(|&v| v.max(0.0)).collect()
        };
        let mut conditional_cdf = vec![0.0; height * (width + 1)];
        let mut row_integral = Vec::with_capacity(height);
        for (row, cdf) in func
            .chunks_exact(width)
            .zip(conditional_cdf.chunks_exact_mut(width + 1))
        {
            row_integral.push(cumulate(row, cdf) as f32);
        }
        let mut marginal_cdf = vec![0.0; height + 1];
        let integral = cumulate(&row_integral, &mut marginal_cdf) as f32;
        Self {
            width,
            height,
            func,
            conditional_cdf,
            marginal_cdf,
            row_integral,
            integral,
        }
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// A point of [0,1)² drawn from the distribution with `u` uniform in
    /// [0,1)², and its density: the row by `u.y` (marginal), then the
    /// column within it by `u.x` (conditional). Monotonic in each
    /// coordinate, so stratified `u` give stratified points.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (y, row) = invert(&self.marginal_cdf, u.y);
        let cdf = &self.conditional_cdf[row * (self.width + 1)..(row + 1) * (self.width + 1)];
        let (x, column) = invert(cdf, u.x);
        let pdf = self.func[row * self.width + column] / self.integral;
        (Vec2::new(x, y), pdf)
    }

    /// The density at point `p` of [0,1)² (coordinates outside are clamped
    /// to the edge cells).
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        let column = ((p.x * self.width as f32) as usize).min(self.width - 1);
        let row = ((p.y * self.height as f32) as usize).min(self.height - 1);
        self.func[row * self.width + column] / self.integral
    }

    /// The density of row `row` alone (the marginal), for tests.
    pub fn row_pdf(&self, row: usize) -> f32 {
        self.row_integral[row] / self.integral
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::{seeded, Draw};

    /// A small function with zeros, a bright cell and a zero row.
    fn lumpy() -> (Vec<f32>, usize, usize) {
        let (w, h) = (7, 5);
        let mut f: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32 * 0.1).collect();
        f[3 * w + 2] = 40.0;
        for x in 0..w {
            f[w + x] = 0.0;
        }
        (f, w, h)
    }

    #[test]
    fn the_pdf_integrates_to_one_and_is_proportional_to_the_function() {
        let (f, w, h) = lumpy();
        let d = Distribution2D::new(&f, w, h);
        let mut integral = 0.0f64;
        let mean = f.iter().sum::<f32>() / f.len() as f32;
        for y in 0..h {
            for x in 0..w {
                let p = d.pdf(Vec2::new(
                    (x as f32 + 0.5) / w as f32,
                    (y as f32 + 0.5) / h as f32,
                ));
                integral += p as f64 / (w * h) as f64;
                assert!((p - f[y * w + x] / mean).abs() < 1e-5, "cell {x},{y}");
            }
        }
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        let rows: f32 = (0..h).map(|y| d.row_pdf(y)).sum::<f32>() / h as f32;
        assert!((rows - 1.0).abs() < 1e-6);
    }

    /// A histogram of many samples matches the pdf cell by cell (within
    /// five standard deviations of a binomial count), no sample lands in a
    /// cell of value 0, each sample's own pdf is the pdf at its point, and
    /// sampling inverts the CDF: monotonic in each coordinate.
    #[test]
    fn samples_follow_the_pdf_and_invert_the_cdf() {
        let (f, w, h) = lumpy();
        let d = Distribution2D::new(&f, w, h);
        let n = 200_000;
        let mut counts = vec![0u32; w * h];
        let mut rng = seeded(3);
        for _ in 0..n {
            let u = Vec2::new(rng.unit(), rng.unit());
            let (p, pdf) = d.sample(u);
            assert!(
                (0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y),
                "{p}"
            );
            assert_eq!(pdf, d.pdf(p), "the sample's pdf is the pdf at its point");
            let cell = (p.y * h as f32) as usize * w + (p.x * w as f32) as usize;
            counts[cell] += 1;
        }
        for (cell, &c) in counts.iter().enumerate() {
            let prob = f[cell] as f64 / f.iter().map(|&v| v as f64).sum::<f64>();
            let expected = prob * n as f64;
            let sd = (n as f64 * prob * (1.0 - prob)).sqrt();
            if f[cell] == 0.0 {
                assert_eq!(c, 0, "a sample in cell {cell} of value 0");
            } else {
                assert!(
                    (c as f64 - expected).abs() < 5.0 * sd + 1.0,
                    "cell {cell}: {c} samples, expected {expected:.0} ± {sd:.0}"
                );
            }
        }
        // Inverse CDF: larger u give larger points, along each axis.
        let mut last = Vec2::splat(-1.0);
        for i in 0..1000 {
            let u = (i as f32 + 0.5) / 1000.0;
            let p = d.sample(Vec2::new(0.3, u)).0;
            assert!(p.y >= last.y, "marginal not monotonic at {u}");
            last.y = p.y;
            let q = d.sample(Vec2::new(u, 0.7)).0;
            assert!(q.x >= last.x, "conditional not monotonic at {u}");
            last.x = q.x;
        }
        // The CDF's ends map to the domain's ends.
        assert_eq!(d.sample(Vec2::ZERO).0.y, 0.0);
        assert!(d.sample(Vec2::splat(ONE_MINUS_EPSILON)).0.y > 0.79);
    }

    #[test]
    fn all_zeros_give_the_uniform_distribution() {
        let d = Distribution2D::new(&[0.0; 6], 3, 2);
        let (p, pdf) = d.sample(Vec2::new(0.5, 0.25));
        assert_eq!(pdf, 1.0);
        assert!((p - Vec2::new(0.5, 0.25)).length() < 1e-6, "{p}");
    }
}
