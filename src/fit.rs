//! A small Levenberg–Marquardt for nonlinear least squares with a forward-
//! difference Jacobian: the problem (a residual function) is separate from the
//! solver, and a fit ends with a stated reason. Used by the calibration, where each
//! residual evaluation is a run of the rocking solver (so derivatives are only
//! available numerically).

use nalgebra::{DMatrix, DVector};

/// Golden-section search for the minimum of `f` on [a, b], down to a bracket
/// narrower than `tol`; returns the better of the bracket's two inner points
/// (ties to the upper one). Used where a 1-D cost is unimodal on a bracket
/// found by a grid (the free arcs' centre, `peaks::late::centre_of`) or a
/// bounded interval (a logger's cut-off, `peaks::acquisition`).
pub fn golden_section(mut a: f64, mut b: f64, tol: f64, f: &mut impl FnMut(f64) -> f64) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let mut fc = f(c);
    let mut fd = f(d);
    while b - a > tol {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    if fc < fd {
        c
    } else {
        d
    }
}

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
    /// Covariance of q: s² (JᵀJ)⁻¹ with s² = cost / (n − p). Where JᵀJ is
    /// singular or too ill-conditioned for its inverse to keep any digits
    /// ([`covariance`]), the pseudo-inverse on the directions the residuals
    /// determine: the [`FitResult::undetermined`] ones get no variance, and a
    /// caller whose results depend on them must not trust it. None if even
    /// the pseudo-inverse fails.
    pub covariance: Option<DMatrix<f64>>,
    /// Directions in q (each scaled so that its largest component is one
    /// finite-difference step of that parameter) along which the residuals do
    /// not change: the data do not determine them, and the covariance says
    /// nothing about them. Empty where JᵀJ is well conditioned.
    pub undetermined: Vec<DVector<f64>>,
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
    let (covariance, undetermined) = covariance(jac.tr_mul(&jac), steps);
    Ok(FitResult {
        q: p.q,
        cost: p.cost,
        residuals: p.r,
        iterations,
        stop,
        covariance: covariance.map(|m| m * (p.cost / dof)),
        undetermined,
    })
}

/// Iterations of the SVD behind a pseudo-inverse before it gives up: a
/// well-posed n × n problem (n ≤ 10 here) converges in a few n iterations.
pub const SVD_MAX_ITERATIONS: usize = 1000;

/// A parameter is not seen by the residuals when one finite-difference step of
/// it moves them by less than 10⁻⁸ of what a step of the most visible
/// parameter does (squared: 10⁻¹⁶): rounding, not dependence. (A contact
/// phase that falls between two samples at every impact of its direction:
/// its length moves no residual at all; issue U, 10⁻²⁵ there, against 10⁻⁹
/// for the least visible parameter that the data do determine.)
const UNSEEN: f64 = 1e-16;

/// Condition number beyond which (JᵀJ)⁻¹ is not trusted: its inverse then
/// keeps fewer than 4 of the 16 significant digits of a double. Measured on
/// the matrix scaled to unit diagonal, so that the parameters' units (s, mm,
/// s⁻², logarithms) do not count as ill-conditioning.
const MAX_CONDITION: f64 = 1e12;

/// (JᵀJ)⁻¹ and the directions the data do not determine (none when it is well
/// conditioned, [`FitResult::undetermined`]).
///
/// The inverse is checked before it is used: an LU inverse of a matrix that
/// is singular to working precision "succeeds" with garbage (issue U: a
/// diagonal of −10³³, not symmetric, that `max(0).sqrt()` then turned into a
/// stated u = 0). Parameters no residual sees ([`UNSEEN`]) are set aside;
/// the rest, scaled to unit diagonal, must have a condition number below
/// [`MAX_CONDITION`]. Otherwise the covariance is the pseudo-inverse on the
/// determined directions (singular values of the scaled matrix below
/// 1/[`MAX_CONDITION`] of the largest dropped), zero on the unseen
/// parameters, and every dropped direction is returned. None (and no
/// directions) when JᵀJ is not finite or its SVD does not converge.
fn covariance(jtj: DMatrix<f64>, steps: &[f64]) -> (Option<DMatrix<f64>>, Vec<DVector<f64>>) {
    let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    let np = jtj.nrows();
    if !finite(&jtj) || np == 0 {
        return (None, Vec::new());
    }
    // Squared change of the residuals for one step of each parameter.
    let moved: Vec<f64> = (0..np).map(|j| jtj[(j, j)] * steps[j] * steps[j]).collect();
    let most = moved.iter().fold(0.0f64, |a, &b| a.max(b));
    let seen: Vec<usize> = (0..np).filter(|&j| moved[j] > UNSEEN * most).collect();
    let unit = |j: usize| {
        let mut e = DVector::zeros(np);
        e[j] = steps[j];
        e
    };
    let mut undetermined: Vec<DVector<f64>> = (0..np).filter(|j| !seen.contains(j)).map(unit).collect();
    if seen.is_empty() {
        return (Some(DMatrix::zeros(np, np)), undetermined);
    }
    let d: Vec<f64> = seen.iter().map(|&j| jtj[(j, j)].sqrt()).collect();
    let scaled = DMatrix::from_fn(seen.len(), seen.len(), |a, b| jtj[(seen[a], seen[b])] / (d[a] * d[b]));
    // nalgebra's `pseudo_inverse` runs an SVD without an iteration limit (issue 22:
    // a log whose time was scaled by 10⁻⁶ hung in it); `try_svd` stops after
    // SVD_MAX_ITERATIONS and the covariance is then unknown (None).
    let Some(svd) = scaled.try_svd(true, true, f64::EPSILON, SVD_MAX_ITERATIONS) else {
        return (None, Vec::new());
    };
    let largest = svd.singular_values.max();
    let floor = largest / MAX_CONDITION;
    if undetermined.is_empty() && svd.singular_values.min() > floor {
        // Well conditioned: the plain inverse, as before the check.
        if let Some(inv) = jtj.clone().try_inverse().filter(finite) {
            return (Some(inv), Vec::new());
        }
    }
    let (Some(u), Some(v_t)) = (&svd.u, &svd.v_t) else {
        return (None, Vec::new());
    };
    let mut cov = DMatrix::zeros(np, np);
    for (i, &sv) in svd.singular_values.iter().enumerate() {
        if sv > floor && sv > 0.0 {
            for a in 0..seen.len() {
                for b in 0..seen.len() {
                    cov[(seen[a], seen[b])] += u[(a, i)] * v_t[(i, b)] / (sv * d[a] * d[b]);
                }
            }
        } else {
            // The direction in q: back from the unit-diagonal scaling, then
            // its largest component one step of that parameter.
            let mut n = DVector::zeros(np);
            for (a, &j) in seen.iter().enumerate() {
                n[j] = v_t[(i, a)] / d[a];
            }
            let big = (0..np).map(|j| n[j].abs() / steps[j]).fold(0.0f64, f64::max);
            if big > 0.0 && big.is_finite() {
                undetermined.push(n / big);
            }
        }
    }
    // Symmetric by construction up to rounding; make it exactly so.
    let cov = (&cov + cov.transpose()) * 0.5;
    (finite(&cov).then_some(cov), undetermined)
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

    /// A line y = a + b t sampled at 200 Hz, and a "contact" of lead e^{q₂}
    /// and lag e^{q₃} around t = 0.5025 s, between two samples: no residual
    /// sees its length beyond rounding (a 10⁻¹² mm trace of it, as in issue
    /// U's fit, whose JᵀJ had 10⁻²⁰ on those diagonals against 10⁸).
    fn line_with_unseen_contact(q: &[f64], t: &[f64], y: &[f64]) -> Vec<f64> {
        let (u, w) = (q[2].exp(), q[3].exp());
        t.iter()
            .zip(y)
            .map(|(&t, &y)| {
                let inside = t > 0.5025 - u && t < 0.5025 + w;
                let bump = if inside { 1.0 } else { 1e-12 * (u + 2.0 * w) * t };
                y - q[0] - q[1] * t - bump
            })
            .collect()
    }

    /// The covariance of a fit with parameters the data do not determine is a
    /// covariance: finite, symmetric, no negative variance; those parameters
    /// are returned as undetermined, and the determined ones keep the
    /// variance of the fit without them.
    #[test]
    fn undetermined_parameters_are_set_aside() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
        // Deterministic "noise" of ±0.01 mm.
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, t)| 1.0 + 3.0 * t + 0.01 * ((i * 7919 % 13) as f64 / 6.0 - 1.0))
            .collect();
        let steps = [1e-7, 1e-7, 1e-4, 1e-4];
        let f = |q: &[f64]| Some(line_with_unseen_contact(q, &t, &y));
        let res = least_squares(&[0.0, 0.0, (1e-6f64).ln(), (2e-3f64).ln()], &steps, 100, &f).unwrap();
        let cov = res.covariance.as_ref().expect("a covariance");
        for a in 0..4 {
            assert!(cov[(a, a)].is_finite() && cov[(a, a)] >= 0.0, "variance {a}: {}", cov[(a, a)]);
            for b in 0..4 {
                assert!((cov[(a, b)] - cov[(b, a)]).abs() <= 1e-12 * (cov[(a, a)] * cov[(b, b)]).sqrt(), "{cov}");
            }
        }
        // Both contact parameters set aside, each as one step of itself.
        assert_eq!(res.undetermined.len(), 2, "{:?}", res.undetermined);
        for (dir, j) in res.undetermined.iter().zip([2, 3]) {
            assert!(
                (dir[j] - steps[j]).abs() < 1e-15 && (0..4).filter(|&i| i != j).all(|i| dir[i] == 0.0),
                "{dir}"
            );
        }
        // The line's own covariance: s² (XᵀX)⁻¹ of the two-parameter fit.
        let line = |q: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| y - q[0] - q[1] * t).collect::<Vec<f64>>());
        let alone = least_squares(&[0.0, 0.0], &steps[..2], 100, &line).unwrap();
        let c2 = alone.covariance.unwrap();
        let dof = |n: usize| (t.len() - n) as f64;
        for a in 0..2 {
            for b in 0..2 {
                let want = c2[(a, b)] * dof(2) / dof(4);
                assert!(
                    (cov[(a, b)] - want).abs() < 1e-6 * want.abs().max(c2[(a, a)].sqrt() * c2[(b, b)].sqrt() * 1e-3),
                    "({a}, {b}): {} against {want}",
                    cov[(a, b)]
                );
            }
        }
        assert!(alone.undetermined.is_empty());
    }

    /// Exactly collinear parameters (y = a + (b + c) t): the direction b − c
    /// is undetermined, b + c keeps its variance.
    #[test]
    fn collinear_parameters_give_one_undetermined_direction() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().enumerate().map(|(i, t)| 2.0 - t + 0.05 * ((i * 31 % 7) as f64 - 3.0)).collect();
        let f = |q: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| y - q[0] - (q[1] + q[2]) * t).collect());
        let res = least_squares(&[0.0, 0.0, 0.0], &[1e-7; 3], 100, &f).unwrap();
        assert_eq!(res.undetermined.len(), 1, "{:?}", res.undetermined);
        let dir = &res.undetermined[0];
        assert!(
            dir[0].abs() < 1e-12 * dir[1].abs() && (dir[1] + dir[2]).abs() < 1e-6 * dir[1].abs(),
            "{dir}"
        );
        let cov = res.covariance.unwrap();
        // var(b + c) of the pseudo-inverse equals var(slope) of the plain line fit.
        let line = |q: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| y - q[0] - q[1] * t).collect::<Vec<f64>>());
        let c2 = least_squares(&[0.0, 0.0], &[1e-7; 2], 100, &line).unwrap().covariance.unwrap();
        let sum = cov[(1, 1)] + 2.0 * cov[(1, 2)] + cov[(2, 2)];
        let want = c2[(1, 1)] * 48.0 / 47.0;
        assert!((sum / want - 1.0).abs() < 1e-6, "{sum} against {want}");
    }

    /// Issue U's mechanism: JᵀJ of a fit whose parameters are not all
    /// determined is singular, and the rounding of its product makes it
    /// slightly indefinite on the null directions. An LU inverse then
    /// "succeeds" with a negative variance (the defect: stated as u = 0);
    /// the checked covariance sets the null directions aside and stays a
    /// covariance. Parameters: a, b of a line; c, d exactly collinear and
    /// visible (their JᵀJ block 10⁻¹⁴ into the indefinite, the rounding of a
    /// 200-term product: n ε = 4·10⁻¹⁴); e seen by
    /// no residual beyond a 10⁻¹² trace.
    #[test]
    fn an_indefinite_jtj_is_not_inverted() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.005).collect();
        let cols: Vec<Vec<f64>> = vec![
            t.iter().map(|_| 1.0).collect(),
            t.clone(),
            t.iter().map(|t| 1e-3 * (37.0 * t).sin()).collect(),
            t.iter().map(|t| 1e-3 * (37.0 * t).sin()).collect(),
            t.iter().map(|t| 1e-12 * (11.0 * t).cos()).collect(),
        ];
        let jac = DMatrix::from_fn(t.len(), 5, |i, j| cols[j][i]);
        let mut jtj = jac.tr_mul(&jac);
        jtj[(3, 3)] *= 1.0 - 1e-14;
        let steps = [1e-7, 1e-7, 1e-6, 1e-6, 1e-4];
        // What the unchecked inverse made of it.
        let naive = jtj.clone().try_inverse().expect("LU finds no zero pivot");
        assert!((0..5).any(|j| naive[(j, j)] < 0.0), "{naive}");
        let (cov, undetermined) = covariance(jtj.clone(), &steps);
        let cov = cov.expect("a covariance");
        for a in 0..5 {
            assert!(cov[(a, a)].is_finite() && cov[(a, a)] >= 0.0, "{cov}");
            for b in 0..5 {
                assert!(cov[(a, b)] == cov[(b, a)], "{cov}");
            }
        }
        assert_eq!(undetermined.len(), 2, "{undetermined:?}");
        // e on its own (one step), then c − d (one step in its largest part).
        let (e, cd) = (&undetermined[0], &undetermined[1]);
        assert!(e[4] == steps[4] && (0..4).all(|j| e[j] == 0.0), "{e}");
        assert!(
            (cd[2].abs() - steps[2]).abs() < 1e-12 && (cd[2] + cd[3]).abs() < 1e-12 && cd[4] == 0.0,
            "{cd}"
        );
        // The data see c + d only: its variance is that of the fit on (a, b, s),
        // s the one parameter of the sine column, and so are a's and b's.
        let r3 = jtj.view((0, 0), (3, 3)).into_owned().try_inverse().unwrap();
        let sum = cov[(2, 2)] + 2.0 * cov[(2, 3)] + cov[(3, 3)];
        assert!((sum / r3[(2, 2)] - 1.0).abs() < 1e-6, "{sum} against {}", r3[(2, 2)]);
        for a in 0..2 {
            for b in 0..2 {
                assert!(
                    (cov[(a, b)] / r3[(a, b)] - 1.0).abs() < 1e-6,
                    "({a}, {b}): {} against {}",
                    cov[(a, b)],
                    r3[(a, b)]
                );
            }
        }
    }
}
