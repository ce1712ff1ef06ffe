//! Multiple importance sampling (Veach and Guibas 1995, "Optimally
//! Combining Sampling Techniques for Monte Carlo Rendering"): the weight of
//! one strategy's sample against another's.

/// The power heuristic (β = 2): the weight of a sample drawn with density
/// `a` against another strategy's density `b` for the same direction.
/// Computed as ratios, so that large densities do not overflow when
/// squared; 0 where `a` is 0 (or NaN).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if !(a > 0.0) {
        0.0
    } else if a >= b {
        let r = b / a;
        1.0 / (1.0 + r * r)
    } else {
        let r = a / b;
        r * r / (1.0 + r * r)
    }
}

#[cfg(test)]
mod tests {
    use super::power_heuristic;

    #[test]
    fn the_power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 1.0), (2.0, 0.5), (1e30, 3.0), (0.0, 4.0), (5.0, 0.0)] {
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-6, "{a} {b}: {sum}");
        }
        assert_eq!(power_heuristic(2.0, 1.0), 0.8);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }
}
