//! Signal processing of the numeric core: Savitzky–Golay smoothing differentiation
//! and a robust noise level. No I/O here.

pub mod filter;
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

/// Robust standard deviation of white measurement noise from third differences:
/// σ = 1.4826 · MAD(Δ³x) / √20 (Δ³x = x_{i+2} − 3x_{i+1} + 3x_i − x_{i−1} has
/// variance 20σ²). Third differences cancel the motion to O(x⁽³⁾ Δt³), so even a
/// log that rocks for most of its length (two-sided, e ≈ 0.95, or 100 Hz) gives
/// the noise, not the motion (first differences overestimated σ twenty-fold
/// there: issue #9). Impacts and spikes touch a few differences, which the median
/// ignores. Floored at a third of the smallest non-zero step (quantisation).
pub fn noise_sigma(x: &[f64]) -> f64 {
    if x.len() < 4 {
        return 0.0;
    }
    let d2: Vec<f64> = x.windows(4).map(|w| w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]).collect();
    let m = median(&d2);
    let dev: Vec<f64> = d2.iter().map(|v| (v - m).abs()).collect();
    let mad = median(&dev);
    let min_step = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if min_step.is_finite() { min_step / 3.0 } else { 0.0 };
    (1.4826 * mad / 20f64.sqrt()).max(floor)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_of_a_moving_signal_is_the_noise() {
        // A sine (amplitude 500 mm, 0.02 rad per sample) plus uniform noise of σ = 0.05:
        // first differences would see the motion; second differences see σ.
        let mut state = 7u64;
        let x: Vec<f64> = (0..4000)
            .map(|i| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                500.0 * (0.02 * i as f64).sin() + 0.05 * (u - 0.5) * 12f64.sqrt()
            })
            .collect();
        let s = noise_sigma(&x);
        assert!((s - 0.05).abs() < 0.01, "{s}");
    }

    #[test]
    fn median_odd_even() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
