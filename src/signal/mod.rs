//! Signal processing of the numeric core: Savitzky–Golay smoothing differentiation,
//! robust noise level, spike removal and the linear least-squares kernel shared by
//! the estimators. No I/O here.

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

/// Replace isolated spikes: a sample that differs from the median of its five
/// neighbours (itself included) by more than `threshold` while that median is
/// consistent with the neighbours. Monotonic stretches (an impact's kink) have a
/// median equal to the sample itself, so impacts are never touched. Returns the
/// indices replaced.
pub fn remove_spikes(x: &mut [f64], threshold: f64) -> Vec<usize> {
    let n = x.len();
    let mut fixed = Vec::new();
    if n < 5 {
        return fixed;
    }
    let orig = x.to_vec();
    for i in 2..n - 2 {
        let mut w = [orig[i - 2], orig[i - 1], orig[i], orig[i + 1], orig[i + 2]];
        w.sort_by(|a, b| a.total_cmp(b));
        let med = w[2];
        if (orig[i] - med).abs() > threshold {
            x[i] = med;
            fixed.push(i);
        }
    }
    fixed
}

/// Solve the linear least-squares problem min ‖A c − y‖ through the normal
/// equations with a Cholesky factorisation (A is column-scaled first; the problems
/// here are small and well scaled). Returns the coefficients and the residual sum
/// of squares, or None when AᵀA is singular.
pub fn least_squares(a: &nalgebra::DMatrix<f64>, y: &nalgebra::DVector<f64>) -> Option<(nalgebra::DVector<f64>, f64)> {
    let ncol = a.ncols();
    let mut scale = nalgebra::DVector::zeros(ncol);
    for j in 0..ncol {
        let s = a.column(j).norm();
        scale[j] = if s > 0.0 { 1.0 / s } else { 0.0 };
    }
    let mut a_s = a.clone();
    for j in 0..ncol {
        let s = scale[j];
        a_s.column_mut(j).scale_mut(s);
    }
    let ata = a_s.tr_mul(&a_s);
    let aty = a_s.tr_mul(y);
    let c = match ata.clone().cholesky() {
        Some(ch) => ch.solve(&aty),
        None => ata.svd(true, true).solve(&aty, 1e-12).ok()?,
    };
    let coef = c.component_mul(&scale);
    let r = a * &coef - y;
    Some((coef, r.norm_squared()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_odd_even() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    #[test]
    fn spikes_removed_kinks_kept() {
        let mut x: Vec<f64> = (0..20).map(|i| (i as f64 - 10.0).abs()).collect();
        x[5] += 50.0;
        let fixed = remove_spikes(&mut x, 3.0);
        assert_eq!(fixed, vec![5]);
        assert_eq!(x[10], 0.0, "the kink at the minimum is left alone");
    }

    #[test]
    fn least_squares_recovers_a_line() {
        let a = nalgebra::DMatrix::from_fn(5, 2, |i, j| if j == 0 { 1.0 } else { i as f64 });
        let y = nalgebra::DVector::from_fn(5, |i, _| 2.0 + 3.0 * i as f64);
        let (c, rss) = least_squares(&a, &y).unwrap();
        assert!((c[0] - 2.0).abs() < 1e-12 && (c[1] - 3.0).abs() < 1e-12 && rss < 1e-20);
    }
}
