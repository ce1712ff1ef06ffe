//! `acos`, `sin` and `cos` of eight `f32x8` lanes at once, for sampling
//! rect lights by solid angle: libm's scalar `acosf`, `sinf` and `cosf`,
//! called once per lane, were the largest scalar cost of light sampling.
//!
//! Each function is one polynomial evaluated with plain IEEE operations (no
//! fused multiply-adds, no table), so a lane's result depends on that lane
//! alone: a single value splatted into a register gets the same bits as it
//! does among seven others, and the scalar and lane light samplers that
//! share these functions stay bit-identical.
//!
//! * `acos` goes through the arcsine, following Cody and Waite 1980
//!   ("Software Manual for the Elementary Functions"): acos(x) =
//!   π/2 − asin(x) for |x| ≤ 1/2, and 2·asin(√((1 − |x|)/2)) beyond
//!   (π minus that for negative x). The half-angle form keeps full relative
//!   accuracy near ±1, where 1 − |x| is exact (Sterbenz).
//! * `sin` and `cos` reduce the argument by the nearest multiple of π/2,
//!   with π/2 split in four parts whose products with the multiple are
//!   exact (Cody and Waite's additive reduction), then evaluate both on
//!   [−π/4, π/4] and pick by quadrant.
//!
//! The coefficients are minimax fits of relative error (Lawson's iteratively
//! reweighted least squares, in f64; `tools/fit_trig.py`), rounded to f32.
//! Measured errors are asserted by the tests below: within 2 units in the
//! last place of the f64 result.

use wide::f32x8;

/// asin(s) = s + s·z·P(z), z = s², on 0 ≤ s ≤ 1/2.
const ASIN: [f32; 5] = [
    0.166_667_52,
    0.074_952_975,
    0.045_470_4,
    0.024_179_379,
    0.042_166_56,
];
/// sin(r) = r + r·z·S(z), z = r², on |r| ≤ π/4.
const SIN: [f32; 3] = [-0.166_666_54, 0.008_332_151, -0.000_195_139_84];
/// cos(r) = 1 − z/2 + z²·C(z), z = r², on |r| ≤ π/4.
const COS: [f32; 3] = [0.041_666_646, -0.001_388_730_4, 2.443_166_7e-5];

/// π/2 = PIO2_1 + PIO2_2 + PIO2_3 + PIO2_4 to about 1e-19; the first three
/// have 12 significant bits, so their products with a multiple below 2^12
/// are exact, and only the last, tiny, product rounds.
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_533_6e-8;
const PIO2_4: f32 = 2.563_344e-12;

/// `c[0] + z·(c[1] + z·(…))`, Horner's rule without fused operations.
#[inline(always)]
fn horner<const N: usize>(z: f32x8, c: &[f32; N]) -> f32x8 {
    let mut p = f32x8::splat(c[N - 1]);
    for &k in c[..N - 1].iter().rev() {
        p = p * z + f32x8::splat(k);
    }
    p
}

/// Arc cosine of each lane, in [0, π]. NaN for NaN or |x| > 1.
#[inline]
pub fn acos8(x: f32x8) -> f32x8 {
    let half = f32x8::splat(0.5);
    let a = x.abs();
    let near_one = a.simd_gt(half);
    // asin(s) of s = |x| (small) or s = √((1 − |x|)/2) (near ±1).
    let z = near_one.select((f32x8::ONE - a) * half, a * a);
    let s = near_one.select(z.sqrt(), a);
    let asin_s = s + s * z * horner(z, &ASIN);
    let twice = asin_s + asin_s;
    let near_one_acos = x
        .simd_lt(f32x8::ZERO)
        .select(f32x8::splat(std::f32::consts::PI) - twice, twice);
    // asin(x) carries x's sign.
    let signed = asin_s | (x & f32x8::splat(-0.0));
    let small_acos = f32x8::splat(std::f32::consts::FRAC_PI_2) - signed;
    near_one.select(near_one_acos, small_acos)
}

/// Sine and cosine of each lane; NaN for NaN or infinity. The tests cover
/// [−4π, 4π] (light sampling asks for [0, 2π]); the reduction stays exact
/// while the multiple of π/2 is below 2^12, for |x| up to about 6400.
#[inline]
pub fn sin_cos8(x: f32x8) -> (f32x8, f32x8) {
    // The nearest multiple n of π/2 (a tie either way is as good).
    let n = (x * f32x8::splat(std::f32::consts::FRAC_2_PI) + f32x8::splat(0.5)).floor();
    let r = [PIO2_1, PIO2_2, PIO2_3, PIO2_4]
        .into_iter()
        .fold(x, |r, part| r - n * f32x8::splat(part));
    let z = r * r;
    let sin_r = r + r * z * horner(z, &SIN);
    let cos_r = (f32x8::ONE - z * f32x8::splat(0.5)) + z * z * horner(z, &COS);
    // Quadrant n mod 4: sin x = sin r, cos r, −sin r, −cos r; cos x = cos r,
    // −sin r, −cos r, sin r.
    let quadrant = n - (n * f32x8::splat(0.25)).floor() * f32x8::splat(4.0);
    let is = |q: f32| quadrant.simd_eq(f32x8::splat(q));
    let swap = is(1.0) | is(3.0);
    let (sin, cos) = (swap.select(cos_r, sin_r), swap.select(sin_r, cos_r));
    let sin_negative = is(2.0) | is(3.0);
    let cos_negative = is(1.0) | is(2.0);
    (
        sin_negative.select(-sin, sin),
        cos_negative.select(-cos, cos),
    )
}

/// [`sin_cos8`] of one value: the bits lane 0 gets.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let (s, c) = sin_cos8(f32x8::splat(x));
    (s.to_array()[0], c.to_array()[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`acos8`] of one value: the bits lane 0 gets. (The renderer's scalar
    /// rectangle makes its four arc cosines in one vector call instead.)
    fn acos(x: f32) -> f32 {
        acos8(f32x8::splat(x)).to_array()[0]
    }

    /// Error of `got` in units in the last place of the f64 value `exact`
    /// (the spacing of f32 numbers at its magnitude).
    fn ulps(got: f32, exact: f64) -> f64 {
        let ulp = if exact == 0.0 {
            f32::MIN_POSITIVE as f64
        } else {
            let e = (exact.abs() as f32).to_bits() >> 23;
            let spacing = f32::from_bits(e.max(1) << 23) as f64 * f32::EPSILON as f64;
            spacing.max(f32::from_bits(1) as f64)
        };
        (got as f64 - exact).abs() / ulp
    }

    /// Lanes at a time, so a fault that mixes lanes would show too.
    fn in_lanes(xs: &[f32], mut check: impl FnMut(f32, f32x8, usize)) {
        for chunk in xs.chunks(8) {
            let mut lanes = [0.0; 8];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let v = f32x8::from(lanes);
            for (i, &x) in chunk.iter().enumerate() {
                check(x, v, i);
            }
        }
    }

    /// Every 64th f32 in [0, 1] with both signs, and every f32 within 2^16
    /// steps of ±1/2 and ±1, where the formula switches and where acos
    /// is steepest.
    fn acos_inputs() -> Vec<f32> {
        let mut xs: Vec<f32> = (0..=1.0f32.to_bits())
            .step_by(64)
            .map(f32::from_bits)
            .collect();
        for edge in [0.5f32, 1.0] {
            let b = edge.to_bits();
            xs.extend((b - (1 << 16)..=b).map(f32::from_bits));
            xs.extend((b..b + (1 << 16)).map(f32::from_bits).filter(|x| *x <= 1.0));
        }
        let negative: Vec<f32> = xs.iter().map(|x| -x).collect();
        xs.extend(negative);
        xs
    }

    #[test]
    fn acos_is_within_two_ulps_everywhere_in_its_domain() {
        let xs = acos_inputs();
        let mut worst = 0.0f64;
        in_lanes(&xs, |x, lanes, i| {
            let got = acos8(lanes).to_array()[i];
            let e = ulps(got, (x as f64).acos());
            assert!(e <= 2.0, "acos({x:e}) = {got:e}, {e:.2} ulp off");
            worst = worst.max(e);
        });
        assert!(worst > 0.0, "the sweep measured no error at all");
        println!("acos: worst {worst:.2} ulp over {} inputs", xs.len());
    }

    #[test]
    fn acos_keeps_its_exact_values_and_rejects_what_is_outside() {
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), std::f32::consts::PI);
        assert_eq!(acos(0.0), std::f32::consts::FRAC_PI_2);
        for bad in [f32::NAN, 1.000_001, -1.5, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(acos(bad).is_nan(), "acos({bad})");
        }
    }

    #[test]
    fn sin_and_cos_are_within_two_ulps_over_the_range_light_sampling_uses() {
        // Every 32nd f32 in [-4π, 4π] (light sampling asks for [0, 2π]), and
        // every f32 within 2^12 steps of each multiple of π/2 there, where
        // one of them passes through zero.
        let top = (4.0 * std::f32::consts::PI).to_bits();
        let mut xs: Vec<f32> = (0..=top).step_by(32).map(f32::from_bits).collect();
        for k in 1..=8 {
            let b = (k as f32 * std::f32::consts::FRAC_PI_2).to_bits();
            xs.extend((b - (1 << 12)..b + (1 << 12)).map(f32::from_bits));
        }
        let negative: Vec<f32> = xs.iter().map(|x| -x).collect();
        xs.extend(negative);
        let (mut worst_sin, mut worst_cos) = (0.0f64, 0.0f64);
        in_lanes(&xs, |x, lanes, i| {
            let (s, c) = sin_cos8(lanes);
            let (s, c) = (s.to_array()[i], c.to_array()[i]);
            let (es, ec) = (ulps(s, (x as f64).sin()), ulps(c, (x as f64).cos()));
            assert!(es <= 2.0, "sin({x:e}) = {s:e}, {es:.2} ulp off");
            assert!(ec <= 2.0, "cos({x:e}) = {c:e}, {ec:.2} ulp off");
            worst_sin = worst_sin.max(es);
            worst_cos = worst_cos.max(ec);
        });
        println!("sin: worst {worst_sin:.2} ulp, cos: worst {worst_cos:.2} ulp");
    }

    #[test]
    fn sin_and_cos_keep_zero_and_reject_what_is_not_finite() {
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let (s, c) = sin_cos(bad);
            assert!(s.is_nan() && c.is_nan(), "sin_cos({bad})");
        }
    }

    /// A lane's result does not depend on its neighbours: a value alone
    /// (lane 0 of a splat: `acos`, [`sin_cos`]) gets the bits every lane gets.
    #[test]
    fn a_lane_gives_the_same_bits_as_the_value_alone() {
        let xs: Vec<f32> = (0..4000).map(|i| (i as f32 * 0.7371).sin()).collect();
        in_lanes(&xs, |x, lanes, i| {
            assert_eq!(acos8(lanes).to_array()[i].to_bits(), acos(x).to_bits());
            let angle = x * 9.0;
            let (s, c) = sin_cos8(lanes * f32x8::splat(9.0));
            let (ss, cc) = sin_cos(angle);
            assert_eq!(
                (s.to_array()[i].to_bits(), c.to_array()[i].to_bits()),
                (ss.to_bits(), cc.to_bits())
            );
        });
    }
}
