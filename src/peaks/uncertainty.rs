//! Model-form terms of the peaks' covariance, added to the fit's own
//! s²(JᵀJ)⁻¹ (`model::Fitted::peak_covariance`).

use super::{model, Impact};

/// The model-form part of the uncertainty of an instantaneous-impact fit. A
/// contact that lasts less than about a sample cannot be told from an
/// instantaneous impact at this sampling rate, yet the wall is fastest at the
/// onset of contact, which may come a sample or more before the zero (MuJoCo:
/// 2–10 ms). Taking the onset as equally likely anywhere in the last sample
/// interval before the zero, the speed lies between the extrapolated one and
/// |ÿ(t_k)| Δt less (ÿ the free arc's acceleration there): a rectangular
/// distribution of width |ÿ| Δt, standard uncertainty |ÿ| Δt / √12 (GUM 4.3.7),
/// added as an independent variance to each peak. Without it a 200 Hz one-sided
/// MuJoCo test fitted to the noise level claimed ±0.2 mm/s on peaks that were
/// 3–16 mm/s off (issue #9); with it they carry ±2.7 mm/s, which narrows the gap
/// without closing it (its onsets come up to two samples early). At 1 kHz the
/// term is a few tenths of a percent.
pub(super) fn add_unresolved_contact(cov: &mut [Vec<f64>], m: &model::Model, dt: f64) {
    for (k, row) in cov.iter_mut().enumerate() {
        let t = m.onset(k);
        let h = 1e-4 * dt.max(1e-6);
        let acc = (m.arc(k, t).1 - m.arc(k, t - h).1) / h;
        row[k] += (acc * dt).powi(2) / 12.0;
    }
}

/// The model-form part of the uncertainty from the two models of the impacts:
/// with d_k the peak of the model not chosen minus the chosen one, the truth is
/// taken as anywhere between the two (rectangular), so its distance to the
/// chosen end has mean square d_k²/3; the d_k of one test share their cause (the
/// model of the contacts), so the term is added fully correlated, Σ += d dᵀ/3.
/// On the two-sided MuJoCo campaign (contact phases on every test) it brings
/// the largest |error| / u of a table value from 190 to 2.5 (median 23 → 1.9).
pub(super) fn add_model_spread(cov: &mut [Vec<f64>], impacts: &[Impact], alternative: &[f64]) {
    add_correlated(cov, &spread_of(cov.len(), impacts, alternative), 1.0 / 3.0);
}

/// As [`add_model_spread`], but each peak's term on its own, Σ_kk += d_k²/3,
/// no covariance: for a fit whose model is known to miss the log somewhere
/// (a one-sided wall's exits, `peaks::exits_only_misfit`), the position of
/// the truth between the two models is not shared by the peaks. Measured on
/// the one-sided engine campaigns (104 tests, docs/accuracy.md): with the
/// term correlated, 18.5 % of the same-side ratios v_{k+2}/v_k were off by
/// more than 2 of its u, against 6.2 % with it independent; the truth's
/// fraction of the way between the models varies by 0.32 (median standard
/// deviation) from peak to peak of one test.
pub(super) fn add_model_spread_independent(cov: &mut [Vec<f64>], impacts: &[Impact], alternative: &[f64]) {
    let d = spread_of(cov.len(), impacts, alternative);
    for (k, row) in cov.iter_mut().enumerate() {
        row[k] += d[k] * d[k] / 3.0;
    }
}

/// d_k: the peak of the model not chosen minus the chosen one (0 where there is none).
fn spread_of(n: usize, impacts: &[Impact], alternative: &[f64]) -> Vec<f64> {
    (0..n)
        .map(|k| match (impacts.get(k), alternative.get(k)) {
            (Some(i), Some(a)) if a.is_finite() => a - i.v_before_mm_s,
            _ => 0.0,
        })
        .collect()
}

/// The model-form part of the uncertainty from where θ = 0 lies
/// ([`model::Model::peak`]): v_k is the mean of two readings, up to the model's
/// zero and up to the rest line, and the truth is taken as anywhere between
/// them (rectangular, full width |d_k|, `spread[k]` =
/// [`model::Model::peak_spread`]): u² = d_k²/12 (GUM 4.3.7). The d_k of one
/// test share their cause (the fitted zero), so the term is added fully
/// correlated, Σ += d dᵀ/12. Zero without contact phases.
pub(super) fn add_zero_spread(cov: &mut [Vec<f64>], spread: &[f64]) {
    add_correlated(cov, spread, 1.0 / 12.0);
}

/// The part of the uncertainty from a direction of the fit's parameters that
/// the log does not determine but bounds (a contact lag whose end falls
/// between two samples: it may lie anywhere up to the next sample): e_k is
/// the root mean square distance of peak k from its values over that range
/// ([`model::Fitted::admissible_spread`]); one cause, so fully correlated,
/// Σ += e eᵀ.
pub(super) fn add_admissible_range(cov: &mut [Vec<f64>], e: &[f64]) {
    add_correlated(cov, e, 1.0);
}

/// Σ += w d dᵀ: a term whose parts share one cause (fully correlated).
fn add_correlated(cov: &mut [Vec<f64>], d: &[f64], w: f64) {
    for (a, row) in cov.iter_mut().enumerate() {
        for (b, c) in row.iter_mut().enumerate() {
            *c += w * d[a] * d[b];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peaks::Side;

    /// The uncorrelated model-form term has the correlated one's variances and
    /// no covariances: a same-side ratio's u then no longer cancels.
    #[test]
    fn the_independent_model_spread_keeps_the_variances_and_drops_the_covariances() {
        let impacts: Vec<Impact> = [-600.0, 400.0, -350.0]
            .iter()
            .enumerate()
            .map(|(k, &v)| Impact {
                k,
                time_s: k as f64,
                entering: if k % 2 == 0 { Side::Inward } else { Side::Outward },
                v_before_mm_s: v,
                v_after_mm_s: None,
            })
            .collect();
        let alt = [-620.0, 390.0, -380.0];
        let (mut a, mut b) = (vec![vec![0.0; 3]; 3], vec![vec![0.0; 3]; 3]);
        add_model_spread(&mut a, &impacts, &alt);
        add_model_spread_independent(&mut b, &impacts, &alt);
        for k in 0..3 {
            assert!((a[k][k] - b[k][k]).abs() < 1e-9);
            for j in (0..3).filter(|&j| j != k) {
                assert!(a[k][j] != 0.0 && b[k][j] == 0.0);
            }
        }
        assert!((a[2][2] - 30.0f64.powi(2) / 3.0).abs() < 1e-9);
    }
}
