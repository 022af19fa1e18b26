//! Savitzky–Golay smoothing differentiation (Savitzky & Golay 1964): a polynomial of
//! order n fitted by least squares to each window of 2m+1 samples, differentiated at
//! the window's centre (at the edges, at the sample's own place in the first or last
//! window). Coefficients come from the pseudo-inverse of the window's Vandermonde
//! matrix (nalgebra), so any window and order work.
//!
//! This is the classic estimator, kept as an option (`--method savgol`). A symmetric
//! window straddling an impact averages the speed before and after the velocity jump
//! and clips the peak: on one-sided logs it lands several percentage points low. The
//! default estimator is in [`crate::peaks`].

use nalgebra::DMatrix;

/// Validated Savitzky–Golay settings.
/// A window or an order that no Savitzky–Golay filter has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SavGolError {
    #[error("Savitzky–Golay window {window}: expected an odd number from 3 to 1001")]
    Window { window: usize },
    #[error("Savitzky–Golay order {order}: expected an order below the window ({window}) and at most 10")]
    Order { order: usize, window: usize },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SavGol {
    half_window: usize,
    order: usize,
}

impl SavGol {
    /// `window` odd, 3 ≤ window ≤ 1001, `order` < `window` and ≤ 10 (issue 22:
    /// bounds under which the Vandermonde matrix stays finite and well scaled).
    pub fn new(window: usize, order: usize) -> Result<SavGol, SavGolError> {
        if !(3..=1001).contains(&window) || window.is_multiple_of(2) {
            return Err(SavGolError::Window { window });
        }
        if order >= window || order > 10 {
            return Err(SavGolError::Order { order, window });
        }
        Ok(SavGol {
            half_window: window / 2,
            order,
        })
    }

    pub fn window(&self) -> usize {
        2 * self.half_window + 1
    }

    pub fn order(&self) -> usize {
        self.order
    }

    /// Row of the pseudo-inverse giving the first derivative at offset `at` (in
    /// samples, relative to the window's centre) of the polynomial fitted to a
    /// window of unit spacing.
    fn derivative_weights(&self, at: f64) -> Vec<f64> {
        let m = self.half_window as i64;
        let w = self.window();
        let a = DMatrix::from_fn(w, self.order + 1, |i, j| ((i as i64 - m) as f64).powi(j as i32));
        let pinv = a.clone().pseudo_inverse(1e-12).expect("Vandermonde pseudo-inverse");
        // d/dx Σ c_j x^j at x = at  →  Σ j c_j at^{j-1}
        (0..w)
            .map(|col| (1..=self.order).map(|j| j as f64 * at.powi(j as i32 - 1) * pinv[(j, col)]).sum())
            .collect()
    }

    /// First derivative of `x` sampled every `dt` (uniform sampling assumed; the
    /// caller checks it). Output has the length of the input.
    pub fn derivative(&self, x: &[f64], dt: f64) -> Vec<f64> {
        let n = x.len();
        let w = self.window();
        let m = self.half_window;
        if n < w {
            return vec![f64::NAN; n];
        }
        let centre = self.derivative_weights(0.0);
        let mut out = vec![0.0; n];
        for i in m..n - m {
            let s: f64 = centre.iter().zip(&x[i - m..i + m + 1]).map(|(c, v)| c * v).sum();
            out[i] = s / dt;
        }
        for i in 0..m {
            let head = self.derivative_weights(i as f64 - m as f64);
            out[i] = head.iter().zip(&x[..w]).map(|(c, v)| c * v).sum::<f64>() / dt;
            let tail = self.derivative_weights(m as f64 - i as f64);
            let j = n - 1 - i;
            out[j] = tail.iter().zip(&x[n - w..]).map(|(c, v)| c * v).sum::<f64>() / dt;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_on_polynomials_of_its_order() {
        // A cubic is reproduced exactly by an order-3 filter, edges included.
        let dt = 0.01;
        let x: Vec<f64> = (0..50)
            .map(|i| {
                let t = i as f64 * dt;
                1.0 + 2.0 * t - 3.0 * t * t + 0.5 * t.powi(3)
            })
            .collect();
        let d = SavGol::new(9, 3).unwrap().derivative(&x, dt);
        for (i, v) in d.iter().enumerate() {
            let t = i as f64 * dt;
            let exact = 2.0 - 6.0 * t + 1.5 * t * t;
            assert!((v - exact).abs() < 1e-9, "i {i}: {v} vs {exact}");
        }
    }

    #[test]
    fn rejects_bad_settings() {
        assert!(SavGol::new(4, 2).is_err());
        assert!(SavGol::new(5, 5).is_err());
    }
}
