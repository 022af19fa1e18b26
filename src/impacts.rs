//! Every impact a log resolves, with its coefficient (SPEC, "Per-impact coefficients
//! and the restitution law"): impact k ends half-cycle k, between velocity peaks k
//! and k + 1, and
//!
//!   e_k = |v_{k+1} / v_k|   (the local ratio of paper Eq. 3),   r_k = e_k / e_H (Eq. 5),
//!
//! with its amplitude a_k = |θ|/α at the apex of half-cycle k (θ = asin(x/L) from the
//! sensor reading x at lever arm L), the side it enters (impact 0 enters the inward
//! side) and the standard uncertainties by first-order propagation of the peaks'
//! covariance Σ_v: with J the Jacobian of (r_0, r_1, …) in (v_0, v_1, …), which has
//! ∂r_k/∂v_k = −r_k/v_k and ∂r_k/∂v_{k+1} = r_k/v_{k+1},
//!
//!   Σ_r = J Σ_v Jᵀ,
//!
//! so that two ratios sharing a peak (r_k and r_{k+1} share v_{k+1}) carry their
//! (negative) correlation, and the fully correlated model-form terms of the peaks
//! ([`crate::peaks`]) carry theirs. The law's fit ([`crate::law_fit`]) uses Σ_r.

use crate::peaks::{Analysis, Impact};
use crate::wall::Side;

/// One impact's coefficient (`tests[].impacts[]` in summary.json).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ImpactCoefficient {
    pub k: usize,
    /// The side the wall enters: "in" or "out".
    #[serde(serialize_with = "side_in_out")]
    pub side: Side,
    /// |θ|/α at the apex of the half-cycle the impact ends.
    pub amplitude_over_alpha: f64,
    /// |v_k| and |v_{k+1}|, mm/s at the sensor.
    pub speed_before_mm_s: f64,
    pub speed_after_mm_s: f64,
    pub e: f64,
    /// None where the peaks carry no covariance (the Savitzky–Golay estimator).
    pub e_u: Option<f64>,
    pub r: f64,
    pub r_u: Option<f64>,
}

fn side_in_out<S: serde::Serializer>(side: &Side, ser: S) -> Result<S::Ok, S::Error> {
    ser.serialize_str(side_label(*side))
}

/// "in" or "out", as SPEC writes the side of an impact.
pub fn side_label(side: Side) -> &'static str {
    match side {
        Side::Inward => "in",
        Side::Outward => "out",
    }
}

/// The impacts of one test and the covariance of their r (None without the peaks'
/// covariance).
#[derive(Debug, Clone, Default)]
pub struct ImpactTable {
    pub impacts: Vec<ImpactCoefficient>,
    pub r_cov: Option<Vec<Vec<f64>>>,
    /// The analysis' impacts (time, side entered, signed speeds) these come from: one
    /// more than `impacts` (the last impact's speed after is not a fitted peak).
    pub raw: Vec<Impact>,
}

/// What the amplitude needs besides the analysis: the log's time axis, the sensor's
/// lever arm (mm) and α.
#[derive(Debug, Clone, Copy)]
pub struct Geometry<'a> {
    pub time_s: &'a [f64],
    pub lever_arm_mm: f64,
    pub alpha_rad: f64,
}

/// Every impact between the analysis' peaks (n peaks give n − 1 impacts).
pub fn impact_table(a: &Analysis, geo: &Geometry, e_h: f64) -> ImpactTable {
    let v: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let n = v.len().saturating_sub(1);
    let r_cov = a
        .peak_covariance
        .as_ref()
        .filter(|c| c.len() >= v.len())
        .map(|c| ratio_covariance(&v, c, e_h));
    let impacts = (0..n)
        .map(|k| {
            let e = (v[k + 1] / v[k]).abs();
            let r_u = r_cov.as_ref().map(|c| c[k][k].max(0.0).sqrt());
            ImpactCoefficient {
                k,
                side: a
                    .impacts
                    .get(k)
                    .map_or(if k % 2 == 0 { Side::Inward } else { Side::Outward }, |i| i.entering),
                amplitude_over_alpha: apex(a, geo, k) / geo.alpha_rad,
                speed_before_mm_s: v[k].abs(),
                speed_after_mm_s: v[k + 1].abs(),
                e,
                e_u: r_u.map(|u| u * e_h),
                r: e / e_h,
                r_u,
            }
        })
        .collect();
    ImpactTable {
        impacts,
        r_cov,
        raw: a.impacts.iter().take(v.len()).copied().collect(),
    }
}

/// Σ_r = J Σ_v Jᵀ for r_k = |v_{k+1}/v_k| / e_H (module docs).
pub fn ratio_covariance(v: &[f64], cov_v: &[Vec<f64>], e_h: f64) -> Vec<Vec<f64>> {
    let n = v.len().saturating_sub(1);
    // Row k of J has two entries: at k and k + 1.
    let jac: Vec<[(usize, f64); 2]> = (0..n)
        .map(|k| {
            let r = (v[k + 1] / v[k]).abs() / e_h;
            [(k, -r / v[k]), (k + 1, r / v[k + 1])]
        })
        .collect();
    // |v_{k+1}/v_k| = −v_{k+1}/v_k for alternating signs: the derivative of the
    // absolute ratio is that of r = (v_{k+1}/v_k)·sign, which the two entries give.
    let mut out = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0;
            for &(a, ga) in &jac[i] {
                for &(b, gb) in &jac[j] {
                    s += ga * cov_v[a][b] * gb;
                }
            }
            out[i][j] = s;
        }
    }
    out
}

/// θ at the apex of half-cycle k: the largest |x| of the fitted displacement (or of
/// the log where there is no fit) between the peaks of impacts k − 1 (the release for
/// k = 0) and k, θ = asin(|x|/L).
fn apex(a: &Analysis, geo: &Geometry, k: usize) -> f64 {
    let t0 = if k == 0 {
        a.release_time_s
    } else {
        a.impacts.get(k - 1).map_or(a.release_time_s, |i| i.time_s)
    };
    let t1 = a.impacts.get(k).map_or(f64::INFINITY, |i| i.time_s);
    let inside = |t: f64| t >= t0 && t <= t1;
    let from_fit = a.fit_curve.iter().filter(|p| inside(p.0)).map(|p| p.1.abs()).fold(0.0, f64::max);
    let x = if from_fit > 0.0 {
        from_fit
    } else {
        geo.time_s
            .iter()
            .zip(&a.displacement_mm)
            .filter(|(t, _)| inside(**t))
            .map(|(_, x)| x.abs())
            .fold(0.0, f64::max)
    };
    (x / geo.lever_arm_mm).clamp(0.0, 1.0).asin()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Σ_r by hand for independent peaks: u(r_k)/r_k = √((u_k/v_k)² + (u_{k+1}/v_{k+1})²),
    /// and r_0, r_1 share v_1: cov = (r_0/v_1)(−r_1/v_1) u_1².
    #[test]
    fn ratio_covariance_by_hand() {
        let v = [-100.0, 50.0, -40.0];
        let u = [1.0, 0.5, 0.4];
        let cov: Vec<Vec<f64>> = (0..3).map(|i| (0..3).map(|j| if i == j { u[i] * u[i] } else { 0.0 }).collect()).collect();
        let c = ratio_covariance(&v, &cov, 1.0);
        let (r0, r1) = (0.5, 0.8);
        assert!((c[0][0].sqrt() - r0 * (0.01f64.powi(2) * 2.0).sqrt()).abs() < 1e-12);
        assert!((c[1][1].sqrt() - r1 * (0.01f64.powi(2) * 2.0).sqrt()).abs() < 1e-12);
        let want = (r0 / 50.0) * (-r1 / 50.0) * 0.25;
        assert!((c[0][1] - want).abs() < 1e-15 && c[0][1] < 0.0, "{} {want}", c[0][1]);
        // A common relative scale of all peaks cancels in every ratio.
        let cov: Vec<Vec<f64>> = (0..3).map(|i| (0..3).map(|j| 1e-4 * v[i] * v[j]).collect()).collect();
        let c = ratio_covariance(&v, &cov, 1.0);
        assert!(c.iter().flatten().all(|x| x.abs() < 1e-18), "{c:?}");
    }
}
