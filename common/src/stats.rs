//! Descriptive statistics for Monte Carlo outputs: mean, standard deviation, percentiles,
//! histograms. All functions are deterministic (fixed summation order) so the same inputs give
//! bit-identical outputs whatever the thread count that produced them.

/// Arithmetic mean; `None` for an empty slice.
pub fn mean(x: &[f64]) -> Option<f64> {
    if x.is_empty() {
        None
    } else {
        Some(x.iter().sum::<f64>() / x.len() as f64)
    }
}

/// Sample standard deviation (denominator `n - 1`, as in GUM Supplement 1 summaries);
/// `None` for fewer than two values.
pub fn std_dev(x: &[f64]) -> Option<f64> {
    if x.len() < 2 {
        return None;
    }
    let m = mean(x)?;
    let ss: f64 = x.iter().map(|v| (v - m) * (v - m)).sum();
    Some((ss / (x.len() - 1) as f64).sqrt())
}

/// Percentile `p` (0..=100) of `sorted` (ascending) with linear interpolation between closest
/// ranks, the same rule as numpy's default (`method="linear"`). `None` for an empty slice.
pub fn percentile_sorted(sorted: &[f64], p: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let p = p.clamp(0.0, 100.0);
    let pos = p / 100.0 * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let frac = pos - lo as f64;
    Some(sorted[lo] + (sorted[hi] - sorted[lo]) * frac)
}

/// The median of `x` (a sorted copy; the mean of the two middle values of an even count);
/// `None` for an empty slice.
pub fn median(x: &[f64]) -> Option<f64> {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    percentile_sorted(&s, 50.0)
}

/// Histogram of `x` over `bins` equal bins spanning `[lo, hi]`, normalised as a probability
/// density (area 1 over the values inside the range). Returns the bin centres and densities.
pub fn density_histogram(x: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<(f64, f64)> {
    if bins == 0 || hi <= lo || !lo.is_finite() || !hi.is_finite() {
        return Vec::new();
    }
    let w = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    let mut inside = 0usize;
    for &v in x {
        if v >= lo && v <= hi {
            let i = (((v - lo) / w) as usize).min(bins - 1);
            counts[i] += 1;
            inside += 1;
        }
    }
    counts
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let d = if inside == 0 {
                0.0
            } else {
                c as f64 / (inside as f64 * w)
            };
            (lo + (i as f64 + 0.5) * w, d)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_std_match_closed_form() {
        let x = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert_eq!(mean(&x), Some(5.0));
        // population variance 4, sample variance 32/7
        assert!((std_dev(&x).unwrap() - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(std_dev(&[1.0]), None);
        assert_eq!(mean(&[]), None);
    }

    #[test]
    fn percentiles_follow_numpy_linear_rule() {
        // numpy.percentile([1, 2, 3, 4], [5, 50, 95]) = [1.15, 2.5, 3.85]
        let s = [1.0, 2.0, 3.0, 4.0];
        assert!((percentile_sorted(&s, 5.0).unwrap() - 1.15).abs() < 1e-12);
        assert!((percentile_sorted(&s, 50.0).unwrap() - 2.5).abs() < 1e-12);
        assert!((percentile_sorted(&s, 95.0).unwrap() - 3.85).abs() < 1e-12);
        assert_eq!(percentile_sorted(&[], 50.0), None);
    }

    #[test]
    fn histogram_integrates_to_one() {
        let x: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.618).fract()).collect();
        let h = density_histogram(&x, 0.0, 1.0, 20);
        let area: f64 = h.iter().map(|(_, d)| d * 0.05).sum();
        assert!((area - 1.0).abs() < 1e-12);
        assert!(density_histogram(&x, 1.0, 0.0, 20).is_empty());
    }
}
