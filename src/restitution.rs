//! Coefficients of restitution from the velocity peaks (paper Eqs. 3–6, SPEC table).
//!
//! v_0, v_1, … are the velocity peaks after release, alternating in sign, v_0 the
//! first (inward) one; v_{k+1}/v_k is the coefficient of the impact after peak k.

/// The quantities of one test (first six peaks).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Coefficients {
    /// Eq. 3: mean of |v_{k+1}/v_k|, k = 0..4.
    pub e: f64,
    /// Eq. 4, e⁺: mean of √(v_3/v_1), √(v_5/v_3).
    pub e_plus: f64,
    /// Eq. 4, e⁻: mean of √(v_2/v_0), √(v_4/v_2).
    pub e_minus: f64,
    /// Eqs. 5–6: e / e_H, e⁺ / e_H, e⁻ / e_H.
    pub r: f64,
    pub r_plus: f64,
    pub r_minus: f64,
    /// Table 3: |v_1/v_0| / e_H.
    pub r1: f64,
    /// Table 3: √(v_3/v_1) / e_H.
    pub r1_plus: f64,
    /// Table 3: √(v_2/v_0) / e_H.
    pub r1_minus: f64,
    /// Table 2 "r (2 impacts)": mean of |v_1/v_0|, |v_2/v_1|, divided by e_H.
    pub r2: f64,
}

/// Local ratio of Eq. 3: |v_{k+1}/v_k| for k = 0..n−2.
pub fn local_ratios(v: &[f64]) -> Vec<f64> {
    v.windows(2).map(|w| (w[1] / w[0]).abs()).collect()
}

/// √(v_{k+2}/v_k): the same-sign ratio of Eq. 4 (the ratio of two peaks of the same
/// sign is positive; its absolute value is taken so that noise cannot flip it).
pub fn same_sign_ratio(v: &[f64], k: usize) -> f64 {
    (v[k + 2] / v[k]).abs().sqrt()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// All quantities from the first six peaks; `None` with fewer than six.
pub fn coefficients(v: &[f64], e_h: f64) -> Option<Coefficients> {
    if v.len() < 6 {
        return None;
    }
    let local = local_ratios(&v[..6]);
    let e = mean(&local);
    let e_minus = 0.5 * (same_sign_ratio(v, 0) + same_sign_ratio(v, 2));
    let e_plus = 0.5 * (same_sign_ratio(v, 1) + same_sign_ratio(v, 3));
    Some(Coefficients {
        e,
        e_plus,
        e_minus,
        r: e / e_h,
        r_plus: e_plus / e_h,
        r_minus: e_minus / e_h,
        r1: local[0] / e_h,
        r1_plus: same_sign_ratio(v, 1) / e_h,
        r1_minus: same_sign_ratio(v, 0) / e_h,
        r2: 0.5 * (local[0] + local[1]) / e_h,
    })
}

impl Coefficients {
    /// The ten quantities in a fixed order (e, e⁺, e⁻, r, r⁺, r⁻, r₁, r₁⁺, r₁⁻, r₂).
    pub fn to_array(&self) -> [f64; 10] {
        [
            self.e,
            self.e_plus,
            self.e_minus,
            self.r,
            self.r_plus,
            self.r_minus,
            self.r1,
            self.r1_plus,
            self.r1_minus,
            self.r2,
        ]
    }
    fn from_array(a: [f64; 10]) -> Coefficients {
        Coefficients {
            e: a[0],
            e_plus: a[1],
            e_minus: a[2],
            r: a[3],
            r_plus: a[4],
            r_minus: a[5],
            r1: a[6],
            r1_plus: a[7],
            r1_minus: a[8],
            r2: a[9],
        }
    }
}

/// The largest standard uncertainty a ratio of the tables (r, r⁺, r⁻, r₁, r₁⁺,
/// r₁⁻, r₂) may have for the test's values to be vouched for: 0.05 (5 pp). A ratio
/// read to ± 5 pp has a 95 % interval 20 pp wide, wider than the differences the
/// paper's tables are read for (r⁺ against r⁻, one wall against another: 2–10 pp),
/// and five times the accuracy the estimator is held to (1 pp). Every ok value of
/// the shipped campaigns has u ≤ 0.031; a one-sided wall logged at 100 Hz, whose
/// short inward excursions span a few samples, read r₁ as 0.76 ± 0.64 with status
/// ok before this limit (docs/accuracy.md).
pub const RATIO_U_MAX: f64 = 0.05;

/// The ratios whose standard uncertainty exceeds [`RATIO_U_MAX`] (or is not a
/// number), as (symbol, u), largest u first.
pub fn unresolved_ratios(u: &Coefficients) -> Vec<(&'static str, f64)> {
    const SYMBOLS: [&str; 7] = ["r", "r⁺", "r⁻", "r₁", "r₁⁺", "r₁⁻", "r₂"];
    let a = u.to_array();
    let mut out: Vec<(&'static str, f64)> = SYMBOLS
        .iter()
        .zip(&a[3..])
        .filter(|(_, u)| u.is_nan() || **u > RATIO_U_MAX)
        .map(|(s, u)| (*s, *u))
        .collect();
    out.sort_by(|x, y| y.1.total_cmp(&x.1));
    out
}

/// Whether `reason` is one [`unresolved_reason`] gave (ratios read too loosely).
pub fn is_unresolved_reason(reason: &str) -> bool {
    reason.starts_with(UNRESOLVED_OPENING)
}

/// How [`unresolved_reason`]'s reason begins.
const UNRESOLVED_OPENING: &str = "the log does not resolve ";

/// Why a test's values cannot be vouched for when some ratio exceeds
/// [`RATIO_U_MAX`]: the ratios and their u, and the first six peaks read to more
/// than ± 2 [`RATIO_U_MAX`] (relative, from the diagonal of their covariance).
pub fn unresolved_reason(u: &Coefficients, v: &[f64], cov: &[Vec<f64>]) -> Option<String> {
    let bad = unresolved_ratios(u);
    if bad.is_empty() {
        return None;
    }
    let pp = |u: f64| {
        if u.is_finite() {
            format!("{} pp", percent(u, 1))
        } else {
            "no finite u".into()
        }
    };
    let values: Vec<String> = bad.iter().map(|(s, u)| format!("{s} ± {}", pp(*u))).collect();
    let peaks: Vec<String> = v
        .iter()
        .zip(cov)
        .enumerate()
        .take(6)
        .filter_map(|(k, (v, row))| {
            let rel = row.get(k).map(|c| c.max(0.0).sqrt() / v.abs())?;
            (rel.is_nan() || rel > 2.0 * RATIO_U_MAX).then(|| format!("peak {k} ± {} %", percent(rel, 0)))
        })
        .collect();
    let why = if peaks.is_empty() {
        String::new()
    } else {
        format!(" ({}: the log has too few samples or too much noise around them)", peaks.join(", "))
    };
    Some(format!(
        "{UNRESOLVED_OPENING}{}: a ratio read to more than ± {:.0} pp cannot be vouched for{why}",
        values.join(", "),
        100.0 * RATIO_U_MAX
    ))
}

/// A fraction as a percentage with `decimals`, or "more than 100" beyond 1: there
/// the figure says only that the log does not determine it ("r₁ ± 330032.2 pp"
/// read as a fault of the tool).
fn percent(x: f64, decimals: usize) -> String {
    if x > 1.0 {
        "more than 100".into()
    } else {
        format!("{:.*}", decimals, 100.0 * x)
    }
}

/// Standard uncertainty of every quantity, propagated to first order from the
/// covariance Σ_v of the first six peaks: u_q² = ∇q Σ_v ∇qᵀ, with ∇q by central
/// differences (step 10⁻⁶ |v_k|). The peaks of one fit are correlated (they share
/// the impact times), so the full covariance is used, not the diagonal.
pub fn uncertainties(v: &[f64], cov: &[Vec<f64>], e_h: f64) -> Option<Coefficients> {
    if v.len() < 6 || cov.len() < 6 {
        return None;
    }
    let mut grad = [[0.0; 6]; 10];
    for k in 0..6 {
        let h = 1e-6 * v[k].abs().max(1e-9);
        let mut up = v[..6].to_vec();
        let mut dn = v[..6].to_vec();
        up[k] += h;
        dn[k] -= h;
        let (a, b) = (coefficients(&up, e_h)?.to_array(), coefficients(&dn, e_h)?.to_array());
        for q in 0..10 {
            grad[q][k] = (a[q] - b[q]) / (2.0 * h);
        }
    }
    let mut out = [0.0; 10];
    for q in 0..10 {
        let mut s = 0.0;
        for i in 0..6 {
            for j in 0..6 {
                s += grad[q][i] * cov[i][j] * grad[q][j];
            }
        }
        out[q] = s.max(0.0).sqrt();
    }
    out.iter().all(|u| u.is_finite()).then(|| Coefficients::from_array(out))
}

#[cfg(test)]
mod tests {

    /// The ratios above the limit, largest first; a u that is not a number is
    /// never read as resolved; e, e⁺, e⁻ are not ratios of the tables' limit.
    #[test]
    fn unresolved_ratios_are_named_largest_first() {
        // e, e⁺, e⁻ at 0.5, the ratios at or below 0.05.
        let u = Coefficients::from_array([0.5, 0.5, 0.5, 0.01, 0.02, 0.03, 0.04, 0.05, 0.01, 0.01]);
        assert!(unresolved_ratios(&u).is_empty(), "{:?}", unresolved_ratios(&u));
        let mut a = u.to_array();
        (a[4], a[6], a[9]) = (0.06, 0.64, f64::NAN);
        let names: Vec<&str> = unresolved_ratios(&Coefficients::from_array(a)).iter().map(|x| x.0).collect();
        assert_eq!(names, ["r₂", "r₁", "r⁺"]);
        let v = [-500.0, 400.0, -320.0, 260.0, -200.0, 160.0];
        let cov: Vec<Vec<f64>> = (0..6).map(|k| (0..6).map(|j| if j == k { 1.0 } else { 0.0 }).collect()).collect();
        assert_eq!(unresolved_reason(&u, &v, &cov), None);
        let why = unresolved_reason(&Coefficients::from_array(a), &v, &cov).unwrap();
        assert!(
            why.starts_with("the log does not resolve r₂ ± no finite u, r₁ ± 64.0 pp, r⁺ ± 6.0 pp"),
            "{why}"
        );
        assert!(!why.contains("peak"), "no peak is read loosely here: {why}");
        // A u of thousands of pp, and a peak read to ± 500 %: not determined, said so.
        a[6] = 33.0;
        let mut loose = cov.clone();
        loose[1][1] = 2000.0f64.powi(2);
        let why = unresolved_reason(&Coefficients::from_array(a), &v, &loose).unwrap();
        assert!(why.contains("r₁ ± more than 100 pp"), "{why}");
        assert!(why.contains("peak 1 ± more than 100 %"), "{why}");
        assert!(!why.contains("3300") && !why.contains("500 %"), "{why}");
        assert!(is_unresolved_reason(&why));
        assert!(!is_unresolved_reason("the fit misses the log: the residuals spread 0.1 mm"));
    }

    use super::*;

    /// r₁ = |v_1/v_0| / e_H with independent peaks: u(r₁)/r₁ = √((u0/v0)² + (u1/v1)²).
    #[test]
    fn uncertainty_of_r1_by_hand() {
        let v = [-100.0, 50.0, -40.0, 30.0, -20.0, 12.0];
        let u = [1.0, 0.5, 0.4, 0.3, 0.2, 0.1];
        let cov: Vec<Vec<f64>> = (0..6).map(|i| (0..6).map(|j| if i == j { u[i] * u[i] } else { 0.0 }).collect()).collect();
        let c = coefficients(&v, 0.9).unwrap();
        let uc = uncertainties(&v, &cov, 0.9).unwrap();
        let want = c.r1 * ((0.01f64).powi(2) + (0.01f64).powi(2)).sqrt();
        assert!((uc.r1 - want).abs() < 1e-6 * want, "{} {want}", uc.r1);
        // Fully correlated relative errors (a common scale) cancel in every ratio.
        let cov: Vec<Vec<f64>> = (0..6).map(|i| (0..6).map(|j| 0.01 * v[i] * 0.01 * v[j]).collect()).collect();
        let uc = uncertainties(&v, &cov, 0.9).unwrap();
        assert!(uc.to_array().iter().all(|u| *u < 1e-6), "{uc:?}");
    }

    #[test]
    fn hand_computed_sequence() {
        // v = -100, 50, -40, 30, -20, 12 ; e_H = 0.9
        let v = [-100.0, 50.0, -40.0, 30.0, -20.0, 12.0];
        let c = coefficients(&v, 0.9).unwrap();
        let e = (0.5 + 0.8 + 0.75 + 2.0 / 3.0 + 0.6) / 5.0;
        assert!((c.e - e).abs() < 1e-12);
        let em = (0.4f64.sqrt() + 0.5f64.sqrt()) / 2.0;
        let ep = (0.6f64.sqrt() + 0.4f64.sqrt()) / 2.0;
        assert!((c.e_minus - em).abs() < 1e-12);
        assert!((c.e_plus - ep).abs() < 1e-12);
        assert!((c.r - e / 0.9).abs() < 1e-12);
        assert!((c.r_plus - ep / 0.9).abs() < 1e-12);
        assert!((c.r_minus - em / 0.9).abs() < 1e-12);
        assert!((c.r1 - 0.5 / 0.9).abs() < 1e-12);
        assert!((c.r1_plus - 0.6f64.sqrt() / 0.9).abs() < 1e-12);
        assert!((c.r1_minus - 0.4f64.sqrt() / 0.9).abs() < 1e-12);
        assert!((c.r2 - 0.65 / 0.9).abs() < 1e-12);
    }

    #[test]
    fn geometric_sequence_gives_its_ratio_everywhere() {
        let v: Vec<f64> = (0..6).map(|k| 500.0 * (-0.8f64).powi(k)).collect();
        let c = coefficients(&v, 1.0).unwrap();
        for q in [c.e, c.e_plus, c.e_minus, c.r1, c.r1_plus, c.r1_minus, c.r2] {
            assert!((q - 0.8).abs() < 1e-12, "{q}");
        }
    }

    #[test]
    fn fewer_than_six_peaks_is_none() {
        assert!(coefficients(&[1.0, -1.0, 1.0, -1.0, 1.0], 1.0).is_none());
    }
}
