//! Signal processing of the numeric core: Savitzky–Golay smoothing differentiation
//! and a robust noise level. No I/O here.

pub mod savgol;

/// Median of a slice (copies; O(n) selection). NaN-free input expected.
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    let m = *m;
    if v.len() % 2 == 1 {
        m
    } else {
        let lower = v[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (m + lower)
    }
}

/// Robust standard deviation of white measurement noise from first differences:
/// σ = 1.4826 · MAD(Δx) / √2. Motion occupies a small part of a free-vibration log
/// (most of it is the static hold and the final rest), so the median ignores it.
/// Floored at a third of the smallest non-zero step (quantisation).
pub fn noise_sigma(x: &[f64]) -> f64 {
    if x.len() < 3 {
        return 0.0;
    }
    let d: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median(&d);
    let dev: Vec<f64> = d.iter().map(|v| (v - m).abs()).collect();
    let mad = median(&dev);
    let min_step = d.iter().map(|v| v.abs()).filter(|v| *v > 0.0).fold(f64::INFINITY, f64::min);
    let floor = if min_step.is_finite() { min_step / 3.0 } else { 0.0 };
    (1.4826 * mad / std::f64::consts::SQRT_2).max(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_odd_even() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
