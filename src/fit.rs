//! A small Levenberg–Marquardt for nonlinear least squares with a forward-
//! difference Jacobian: the problem (a residual function) is separate from the
//! solver, and a fit ends with a stated reason. Used by the calibration, where each
//! residual evaluation is a run of the rocking solver (so derivatives are only
//! available numerically).

use nalgebra::{DMatrix, DVector};

/// Why a fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStop {
    /// Relative decrease of the cost below 1e-12, a step below 1e-10 relative, or
    /// no further decrease after a last step that gained less than 1e-8.
    Converged,
    MaxIterations,
    /// No step of any damping decreased the cost.
    Stalled,
}

/// Why there is no fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FitError {
    /// The residual function is undefined at the starting point (a replay outside
    /// the model's domain).
    #[error("the residuals are undefined at the starting point")]
    UndefinedStart,
    /// Fewer residuals than parameters: the data cannot determine them.
    #[error("{residuals} residuals for {parameters} parameters: expected at least as many residuals")]
    Underdetermined { residuals: usize, parameters: usize },
}

/// Result of a fit.
#[derive(Debug, Clone)]
pub struct FitResult {
    pub q: Vec<f64>,
    pub cost: f64,
    pub residuals: Vec<f64>,
    pub iterations: usize,
    pub stop: FitStop,
    /// Covariance of q: s² (JᵀJ)⁻¹ with s² = cost / (n − p); the pseudo-inverse
    /// when JᵀJ is singular (a parameter the data do not see gets no variance
    /// instead of poisoning the others with NaN); None if even that fails.
    pub covariance: Option<DMatrix<f64>>,
}

/// Residuals of a parameter vector, None where they are undefined.
pub type Residuals<'a> = dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync + 'a;

/// As [`least_squares`], None instead of the reason (for callers that only need to
/// know whether there is a fit, e.g. the estimator's arc fits).
pub fn levenberg_marquardt(q0: &[f64], steps: &[f64], max_iter: usize, residuals: &Residuals) -> Option<FitResult> {
    least_squares(q0, steps, max_iter, residuals).ok()
}

/// Forward-difference Jacobian of the residuals `r` at `q` (columns in parallel);
/// a backward difference where the forward point is undefined, zeros where both are.
fn jacobian(residuals: &Residuals, steps: &[f64], q: &[f64], r: &[f64]) -> DMatrix<f64> {
    use rayon::prelude::*;
    let (n, np) = (r.len(), q.len());
    let cols: Vec<Vec<f64>> = (0..np)
        .into_par_iter()
        .map(|j| {
            let mut qj = q.to_vec();
            qj[j] += steps[j];
            match residuals(&qj) {
                Some(rp) => rp.iter().zip(r).map(|(a, b)| (a - b) / steps[j]).collect(),
                None => {
                    qj[j] -= 2.0 * steps[j];
                    residuals(&qj).map_or(vec![0.0; n], |rm| r.iter().zip(&rm).map(|(a, b)| (a - b) / steps[j]).collect())
                }
            }
        })
        .collect();
    DMatrix::from_fn(n, np, |i, j| cols[j][i])
}

/// The point of a fit: parameters, residuals, cost, damping.
struct Point {
    q: Vec<f64>,
    r: Vec<f64>,
    cost: f64,
    mu: f64,
}

/// What one Levenberg–Marquardt iteration did.
enum Iteration {
    /// A step decreased the cost by the relative amount `rel`; `small` when the
    /// step was below 1e-10 relative.
    Accepted { rel: f64, small: bool },
    /// No damping (16 tries, ×10 each) decreased the cost.
    NoDecrease,
}

/// One iteration: solve (JᵀJ + μ diag JᵀJ) δ = Jᵀr with μ raised until the cost
/// decreases; then μ is lowered.
fn iterate(p: &mut Point, jac: &DMatrix<f64>, residuals: &Residuals) -> Iteration {
    let np = p.q.len();
    let rv = DVector::from_column_slice(&p.r);
    let jtj = jac.tr_mul(jac);
    let jtr = jac.tr_mul(&rv);
    for _ in 0..16 {
        let mut a = jtj.clone();
        for j in 0..np {
            a[(j, j)] += p.mu * jtj[(j, j)].max(1e-300);
        }
        let Some(step) = a.cholesky().map(|c| c.solve(&jtr)) else {
            p.mu *= 10.0;
            continue;
        };
        let trial: Vec<f64> = p.q.iter().zip(step.iter()).map(|(a, b)| a - b).collect();
        if let Some(rt) = residuals(&trial) {
            let ct: f64 = rt.iter().map(|v| v * v).sum();
            if ct < p.cost {
                let rel = (p.cost - ct) / p.cost.max(1e-300);
                let small = step.iter().zip(&p.q).all(|(s, v)| s.abs() <= 1e-10 * v.abs().max(1e-6));
                p.q = trial;
                p.r = rt;
                p.cost = ct;
                p.mu = (p.mu / 3.0).max(1e-15);
                return Iteration::Accepted { rel, small };
            }
        }
        p.mu *= 10.0;
    }
    Iteration::NoDecrease
}

/// Minimise the sum of squared `residuals` from `q0` by Levenberg–Marquardt;
/// finite-difference steps: `steps[j]` absolute step of parameter j.
pub fn least_squares(q0: &[f64], steps: &[f64], max_iter: usize, residuals: &Residuals) -> Result<FitResult, FitError> {
    let r = residuals(q0).ok_or(FitError::UndefinedStart)?;
    let (n, np) = (r.len(), q0.len());
    if n < np {
        return Err(FitError::Underdetermined {
            residuals: n,
            parameters: np,
        });
    }
    let cost: f64 = r.iter().map(|v| v * v).sum();
    let mut p = Point {
        q: q0.to_vec(),
        r,
        cost,
        mu: 1e-3,
    };
    let mut stop = FitStop::MaxIterations;
    let mut iterations = 0;
    let mut last_rel = f64::INFINITY;
    for it in 0..max_iter {
        iterations = it + 1;
        let jac = jacobian(residuals, steps, &p.q, &p.r);
        match iterate(&mut p, &jac, residuals) {
            Iteration::Accepted { rel, small } => {
                last_rel = rel;
                if rel < 1e-12 || small {
                    stop = FitStop::Converged;
                    break;
                }
            }
            Iteration::NoDecrease => {
                // Nothing decreases the cost: at a minimum to working precision (the
                // last accepted step gained < 1e-8), or stuck.
                stop = if p.mu > 1e10 || last_rel < 1e-8 {
                    FitStop::Converged
                } else {
                    FitStop::Stalled
                };
                break;
            }
        }
    }
    let jac = jacobian(residuals, steps, &p.q, &p.r);
    let dof = n.saturating_sub(np).max(1) as f64;
    let covariance = covariance(jac.tr_mul(&jac)).map(|m| m * (p.cost / dof));
    Ok(FitResult {
        q: p.q,
        cost: p.cost,
        residuals: p.r,
        iterations,
        stop,
        covariance,
    })
}

/// Iterations of the SVD behind a pseudo-inverse before it gives up: a
/// well-posed n × n problem (n ≤ 10 here) converges in a few n iterations.
pub const SVD_MAX_ITERATIONS: usize = 1000;

/// (JᵀJ)⁻¹, or its pseudo-inverse (singular values below 10⁻¹² of the largest
/// dropped) when the inverse is singular or not finite.
fn covariance(jtj: DMatrix<f64>) -> Option<DMatrix<f64>> {
    let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    if let Some(inv) = jtj.clone().try_inverse().filter(finite) {
        return Some(inv);
    }
    if !finite(&jtj) {
        return None;
    }
    let scale = jtj.diagonal().iter().fold(0.0f64, |a, b| a.max(b.abs()));
    // nalgebra's `pseudo_inverse` runs an SVD without an iteration limit (issue 22:
    // a log whose time was scaled by 10⁻⁶ hung in it); `try_svd` stops after
    // SVD_MAX_ITERATIONS and the covariance is then unknown (None).
    let svd = jtj.try_svd(true, true, f64::EPSILON, SVD_MAX_ITERATIONS)?;
    svd.pseudo_inverse(1e-12 * scale.max(1e-300)).ok().filter(finite)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a e^{b t} with known a, b and no noise: recovered to 1e-8; the
    /// covariance of a noise-free fit is ~0.
    #[test]
    fn exponential_fit() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        let f = |q: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| y - q[0] * (q[1] * t).exp()).collect());
        let res = levenberg_marquardt(&[1.0, -0.1], &[1e-7, 1e-7], 100, &f).unwrap();
        assert!(
            (res.q[0] - 2.0).abs() < 1e-8 && (res.q[1] + 0.7).abs() < 1e-8,
            "{:?} {:?}",
            res.q,
            res.stop
        );
        assert_eq!(res.stop, FitStop::Converged);
    }

    /// A fit that cannot start says why (it used to be a bare None).
    #[test]
    fn a_failed_fit_says_why() {
        let undefined = |_: &[f64]| None;
        assert_eq!(least_squares(&[1.0], &[1e-7], 10, &undefined).unwrap_err(), FitError::UndefinedStart);
        let one = |q: &[f64]| Some(vec![q[0] - 1.0]);
        assert_eq!(
            least_squares(&[0.0, 0.0], &[1e-7, 1e-7], 10, &one).unwrap_err(),
            FitError::Underdetermined { residuals: 1, parameters: 2 }
        );
        assert!(levenberg_marquardt(&[1.0], &[1e-7], 10, &undefined).is_none());
    }
}
