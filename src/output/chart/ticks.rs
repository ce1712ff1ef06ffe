//! Axis ranges, tick values and tick labels.

/// An axis' tick values, their labels, and unlabelled grid lines.
#[derive(Debug, Clone, PartialEq)]
pub struct Ticks {
    pub values: Vec<f64>,
    pub labels: Vec<String>,
    pub light: Vec<f64>,
}

impl Ticks {
    /// The label of a tick value (plotters hands the values back).
    pub fn label(&self, v: f64) -> String {
        self.values
            .iter()
            .zip(&self.labels)
            .min_by(|a, b| (a.0 - v).abs().total_cmp(&(b.0 - v).abs()))
            .map_or_else(|| format_number(v, false), |(_, l)| l.clone())
    }
}

/// `m`·10^`e`, correctly rounded (dividing for negative exponents keeps
/// 0.3 from becoming 0.30000000000000004).
fn scaled(m: f64, e: i32) -> f64 {
    if e >= 0 {
        m * 10f64.powi(e)
    } else {
        m / 10f64.powi(-e)
    }
}

/// A number rounded to six significant digits, in plain decimals ("0.002",
/// "100") or in exponent notation ("2e-5"), either way without a trailing
/// ".0".
fn format_number(v: f64, exponent: bool) -> String {
    let r: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    match (r == 0.0, exponent) {
        (true, _) => "0".into(),
        (false, true) => format!("{r:e}"),
        (false, false) => format!("{r}"),
    }
}

/// Labels for tick values, all in one notation: exponents only when some
/// magnitude is very small or very large.
pub fn number_labels(values: &[f64]) -> Vec<String> {
    let exponent = values
        .iter()
        .any(|v| *v != 0.0 && (v.abs() < 1e-4 || v.abs() >= 1e6));
    values.iter().map(|&v| format_number(v, exponent)).collect()
}

/// Evenly spaced ticks of step 1, 2 or 5 times a power of ten, about
/// `target` of them; at least 1 apart on an integer axis. All labels have
/// the step's decimals ("0.5, 1.0, 1.5"; "0, 20, 40").
fn linear_ticks(lo: f64, hi: f64, target: usize, integer: bool) -> Ticks {
    let raw = ((hi - lo) / target as f64).max(f64::MIN_POSITIVE);
    let mut e = raw.log10().floor() as i32;
    let f = raw / scaled(1.0, e);
    // The nearest of 1, 2, 5 and 10 (between them at 1.5, 3 and 7).
    let mut m = [(1.5, 1.0), (3.0, 2.0), (7.0, 5.0)]
        .into_iter()
        .find(|&(below, _)| f < below)
        .map_or(10.0, |(_, m)| m);
    if m == 10.0 {
        (m, e) = (1.0, e + 1);
    }
    if integer && e < 0 {
        (m, e) = (1.0, 0);
    }
    let step = scaled(m, e);
    let (k0, k1) = ((lo / step).ceil() as i64, (hi / step).floor() as i64);
    let decimals = (-e).max(0) as usize;
    let values: Vec<f64> = (k0..=k1).map(|k| scaled(k as f64 * m, e)).collect();
    // Formatting "-0.0" would be a minus sign on zero.
    let labels = values
        .iter()
        .map(|v| format!("{:.decimals$}", if *v == 0.0 { 0.0 } else { *v }))
        .collect();
    Ticks {
        values,
        labels,
        light: Vec::new(),
    }
}

/// Powers of `base` in [lo, hi] from exponent `min_exp`, every k-th
/// (exponents that are multiples of k, so 1 stays when it is in range) so
/// that there are at most `max`.
fn powers(lo: f64, hi: f64, base: f64, min_exp: i32, max: usize) -> Vec<f64> {
    let e0 = ((lo.ln() / base.ln()) - 1e-9).ceil() as i32;
    let e1 = ((hi.ln() / base.ln()) + 1e-9).floor() as i32;
    let e0 = e0.max(min_exp);
    if e1 < e0 {
        return Vec::new();
    }
    let stride = ((e1 - e0 + 1) as usize).div_ceil(max).max(1) as i32;
    let power = |e: i32| {
        if base == 10.0 {
            scaled(1.0, e)
        } else {
            base.powi(e)
        }
    };
    (e0..=e1)
        .filter(|e| e.rem_euclid(stride) == 0)
        .map(power)
        .collect()
}

/// Tick values and labels for an axis spanning `lo..hi` (the drawn range).
/// - Linear: steps of 1, 2 or 5 × 10^k; whole steps on an integer axis.
/// - Log, integer: powers of 2 (1, 2, 4, 8 …), thinned to eight at most.
/// - Log: powers of 10, with grid lines at their multiples; over less than
///   three decades, also 2 and 5 times them; within a factor of about
///   two, linear ticks.
pub fn ticks(lo: f64, hi: f64, log: bool, integer: bool) -> Ticks {
    const MAX: usize = 8;
    if !log {
        return linear_ticks(lo, hi, 6, integer);
    }
    let labelled = |values: Vec<f64>, light: Vec<f64>| Ticks {
        labels: number_labels(&values),
        values,
        light,
    };
    if integer {
        let values = powers(lo, hi, 2.0, 0, MAX);
        return if values.len() >= 2 {
            labelled(values, Vec::new())
        } else {
            linear_ticks(lo, hi, 4, true)
        };
    }
    let decades = powers(lo, hi, 10.0, i32::MIN, MAX);
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    if decades.len() >= 3 {
        let mut light = Vec::new();
        for e in first..=last {
            for m in 2..=9 {
                let v = scaled(m as f64, e);
                if v > lo && v < hi {
                    light.push(v);
                }
            }
        }
        return labelled(decades, light);
    }
    let values: Vec<f64> = (first..=last)
        .flat_map(|e| [1.0, 2.0, 5.0].map(|m| scaled(m, e)))
        .filter(|&v| v >= lo && v <= hi)
        .collect();
    if values.len() >= 3 {
        labelled(values, Vec::new())
    } else {
        linear_ticks(lo, hi, 4, false)
    }
}

/// The drawn range of an axis: the data padded by 5% (linear) or a factor
/// 1.5 (log); a single value gets room around it.
pub fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (if log { 0.1 } else { 0.0 }, 1.0);
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let span = hi - lo;
        let pad = if span > 1e-12 * hi.abs().max(lo.abs()) {
            span * 0.05
        } else {
            (lo.abs() * 0.1).max(0.5)
        };
        (lo - pad, hi + pad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_integer_label(l: &str) -> bool {
        !l.is_empty()
            && l.trim_start_matches('-')
                .chars()
                .all(|c| c.is_ascii_digit())
    }

    #[test]
    fn integer_axes_tick_only_at_integers() {
        // The thread axis of a 1- and 2-thread run used to read 1.1 … 1.9.
        assert_eq!(ticks(0.95, 2.05, false, true).labels, ["1", "2"]);
        assert_eq!(ticks(0.5, 1.5, false, true).labels, ["1"]);
        let spans = [
            (0.95, 2.05),
            (0.65, 8.35),
            (0.45, 12.55),
            (0.5, 1.5),
            (-2.2, 66.2),
        ];
        for (lo, hi) in spans {
            let t = ticks(lo, hi, false, true);
            assert!(!t.values.is_empty(), "{lo}..{hi}: no ticks");
            for (v, l) in t.values.iter().zip(&t.labels) {
                assert!(v.fract() == 0.0 && is_integer_label(l), "{lo}..{hi}: {l}");
                assert!(*v >= lo && *v <= hi);
            }
        }
        // The same spans without the integer constraint may subdivide.
        assert!(ticks(0.95, 2.05, false, false)
            .values
            .iter()
            .any(|v| v.fract() != 0.0));
    }

    #[test]
    fn log_axes_label_powers_without_trailing_zeros() {
        // spp 1 … 16 padded by 1.5: powers of two, as integers.
        assert_eq!(
            ticks(1.0 / 1.5, 24.0, true, true).labels,
            ["1", "2", "4", "8", "16"]
        );
        // spp 1 … 4096: thinned to at most eight, still powers of two from 1.
        let t = ticks(1.0 / 1.5, 6144.0, true, true);
        assert!(t.values.len() <= 8 && t.values[0] == 1.0, "{:?}", t.labels);
        assert!(t.values.iter().all(|v| v.log2().fract() == 0.0));
        // Seconds over several decades: powers of ten only.
        let t = ticks(1e-3 / 1.5, 45.0, true, false);
        assert_eq!(t.labels, ["0.001", "0.01", "0.1", "1", "10"]);
        assert!(!t.light.is_empty());
        // RMSE within a decade or two: 1, 2 and 5 times powers of ten.
        let t = ticks(0.0046, 0.14, true, false);
        assert_eq!(t.labels, ["0.005", "0.01", "0.02", "0.05", "0.1"]);
        // Tiny magnitudes switch the whole axis to exponents.
        assert_eq!(ticks(5e-7, 2e-4, true, false).labels[0], "1e-6");
        for (lo, hi, integer) in [(0.67, 24.0, true), (0.5, 2000.0, false), (1e-4, 0.3, false)] {
            for l in ticks(lo, hi, true, integer).labels {
                assert!(!l.ends_with(".0") && !l.contains(".0e"), "{l}");
            }
        }
    }

    #[test]
    fn linear_labels_share_the_step_decimals_and_zero_has_no_sign() {
        let t = ticks(-0.05, 1.05, false, false);
        assert_eq!(t.labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        assert_eq!(
            ticks(-5.0, 105.0, false, false).labels[..3],
            ["0", "20", "40"]
        );
        assert_eq!(ticks(0.89, 1.11, false, false).labels[0], "0.90");
    }

    #[test]
    fn ranges_pad_the_data_and_give_a_single_value_room() {
        assert_eq!(axis_range([1.0, 3.0].into_iter(), false), (0.9, 3.1));
        assert_eq!(axis_range([2.0, 8.0].into_iter(), true), (2.0 / 1.5, 12.0));
        let (lo, hi) = axis_range([1.0, 1.0].into_iter(), false);
        assert!(lo < 1.0 && hi > 1.0 && hi - lo >= 1.0);
        assert_eq!(axis_range([0.0, -1.0].into_iter(), true), (0.1, 1.0));
    }
}
