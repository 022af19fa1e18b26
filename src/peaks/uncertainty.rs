//! Model-form terms of the peaks' covariance, added to the fit's own
//! s²(JᵀJ)⁻¹ (`model::Fitted::peak_covariance`).

use super::{model, Impact, Onset};

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
///
/// A fit with contact phases is the same model at an impact whose lead (the
/// contact's onset before the zero) has collapsed to nothing
/// ([`COLLAPSED_LEAD`]): the fit found no onset there, and the peak is the
/// free arc's speed at the zero, as without contact phases. Its derivative
/// with respect to the lead's logarithm then vanishes, s²(JᵀJ)⁻¹ gives it
/// nothing, and the peak carried ± 0.03–0.06 % (twenty-eighth session: the
/// penalty engine's one-sided seed 7, E1_155_1, 100 Hz, fitted with contact
/// phases by the campaign rule, whose free-arc ends were read +1.5, +2.3 and
/// +3.5 % of the truth, onsets 3–5 ms before the zero; r⁻ +0.44 ± 0.01 pp).
/// Such an impact takes this term too; one whose lead the fit determined
/// does not.
///
/// Where other tests of the campaign show contact phases that this log does
/// not resolve ([`Onset::ContactsElsewhere`], `ingest::reduce`), the onset
/// lies before the zero, and the reading, the rectangle's upper end, is off
/// by a mean square of (|ÿ| Δt)²/3 (twenty-ninth session: the penalty
/// engine's one-sided seed 11, free-arc ends +0.9 to +3.1 % at ± 0.4–1.2 %,
/// 72 % of the ok peaks within 2 u; with it 100 %). A single test keeps /12:
/// an idealised log's impact is exactly at the zero, and wider terms cost
/// a public campaign a test (daq-public-bessel-1's T1_1, r₁⁺ read to ± 5.0 pp)
/// and let a 100 Hz exit that gains speed pass its check.
pub(super) fn add_unresolved_contact(cov: &mut [Vec<f64>], m: &model::Model, dt: f64, onset: Onset) {
    let var = unresolved_contact_variances(m, dt, cov.len(), onset);
    for (k, row) in cov.iter_mut().enumerate() {
        row[k] += var[k];
    }
}

/// The variance that [`add_unresolved_contact`] adds to each of the first `n`
/// peaks: (|ÿ| Δt)²/12 without contact phases or where the lead collapsed
/// ((|ÿ| Δt)²/3 where the campaign shows contacts elsewhere, [`Onset`]), 0
/// elsewhere.
pub(super) fn unresolved_contact_variances(m: &model::Model, dt: f64, n: usize, onset: Onset) -> Vec<f64> {
    let mean_square = match onset {
        Onset::WithinSample => 1.0 / 12.0,
        Onset::ContactsElsewhere => 1.0 / 3.0,
    };
    let leads = m.contact_windows();
    (0..n)
        .map(|k| {
            if leads
                .as_ref()
                .is_some_and(|w| w.get(k).is_none_or(|&(lead, _)| lead >= COLLAPSED_LEAD * dt))
            {
                return 0.0;
            }
            let t = m.onset(k);
            let h = 1e-4 * dt.max(1e-6);
            let acc = (m.arc(k, t).1 - m.arc(k, t - h).1) / h;
            (acc * dt).powi(2) * mean_square
        })
        .collect()
}

/// A contact lead (s) below this fraction of the sample interval has collapsed:
/// the fit's lower bound on the lead's logarithm is far below any sample
/// interval (6.5·10⁻²⁹ s on the case of [`add_unresolved_contact`]), while a
/// lead the log determines is a good fraction of one.
const COLLAPSED_LEAD: f64 = 1e-3;

/// The model-form part of the uncertainty from the two models of the impacts:
/// with d_k the peak of the model not chosen minus the chosen one, the truth is
/// taken as anywhere between the two (rectangular), so its distance to the
/// chosen end has mean square d_k²/3; the d_k of one test share their cause (the
/// model of the contacts), so the term is added fully correlated, Σ += d dᵀ/3.
/// On the two-sided MuJoCo campaign (contact phases on every test) it brings
/// the largest |error| / u of a table value from 190 to 2.5 (median 23 → 1.9).
/// The two models of the contacts now use [`add_model_spread_partly`]
/// (measured); this fully shared form stays for the rivals of an estimated
/// filter, where nothing was measured.
pub(super) fn add_model_spread(cov: &mut [Vec<f64>], impacts: &[Impact], alternative: &[f64]) {
    add_correlated(cov, &spread_of(cov.len(), impacts, alternative), 1.0 / 3.0);
}

/// A rival model's reading as one standard uncertainty of every peak, fully
/// correlated: Σ += d dᵀ, d_k the rival's peak minus the chosen one. For a
/// rival the log cannot rule out and the truth was found at or beyond
/// (`acquisition::WIDE_ROUNDING`: 1.0–1.5 d from the chosen reading), where
/// the rectangle between the two ([`add_model_spread`], d dᵀ/3) understated
/// the error.
pub(super) fn add_model_alternative(cov: &mut [Vec<f64>], impacts: &[Impact], alternative: &[f64]) {
    add_correlated(cov, &spread_of(cov.len(), impacts, alternative), 1.0);
}

/// How far the truth's place between the two models of the contacts (the
/// fraction f_k of the way from the chosen peak to the other, d_k) varies
/// from peak to peak of one test: its standard deviation s, measured on the
/// engine campaigns, MuJoCo's and the penalty engine's (docs/accuracy.md, "The
/// model-form term, partly shared"): median 0.32 over 104 one-sided tests with
/// contact phases, 0.14 over 58 two-sided ones.
pub(super) const PEAK_TO_PEAK_ONE_SIDED: f64 = 0.32;
/// See [`PEAK_TO_PEAK_ONE_SIDED`].
pub(super) const PEAK_TO_PEAK_TWO_SIDED: f64 = 0.14;

/// As [`add_model_spread`], but only partly shared by the peaks: with the
/// truth's fraction f_k of the way between the models varying from peak to
/// peak by s about a shared value, Σ += (1/3 − s²) d dᵀ + s² diag(d_k²). Each
/// peak's variance stays d_k²/3; a ratio keeps the part that is not shared.
/// s = 0 is [`add_model_spread`]; s² = 1/3 makes every peak's term its own
/// (`peaks::exits_only_misfit`: a model known to miss the log). Fully shared,
/// the term cancelled in the ratios more than the errors did: on the engine
/// campaigns, with that term alone, 18.5 % (one-sided) and 18.1 % (two-sided)
/// of the same-side ratios v_{k+2}/v_k were more than 2 of its u off, and
/// among the ok tests' table values one-sided H1_140_1 (seed 34) r⁻ was 2.45 u
/// off and the penalty engine's E2_70_1 r⁺ 7.0 u; partly shared, every ok
/// value of the 32 engine campaigns is within 2 u (docs/accuracy.md).
pub(super) fn add_model_spread_partly(cov: &mut [Vec<f64>], impacts: &[Impact], alternative: &[f64], s: f64) {
    let s2 = (s * s).min(1.0 / 3.0);
    let d = spread_of(cov.len(), impacts, alternative);
    add_correlated(cov, &d, 1.0 / 3.0 - s2);
    for (k, row) in cov.iter_mut().enumerate() {
        row[k] += s2 * d[k] * d[k];
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

/// Σ += d dᵀ over the peaks both have: `d` one standard uncertainty of every
/// peak from one cause, fully correlated (a rival reading's difference,
/// `peaks::contacts_for_a_wide_rounding`).
pub(super) fn add_outer(cov: &mut [Vec<f64>], d: &[f64]) {
    add_correlated(cov, d, 1.0);
}

/// Σ += w d dᵀ: a term whose parts share one cause (fully correlated), over
/// the peaks `d` has.
fn add_correlated(cov: &mut [Vec<f64>], d: &[f64], w: f64) {
    for (row, da) in cov.iter_mut().zip(d) {
        for (c, db) in row.iter_mut().zip(d) {
            *c += w * da * db;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peaks::Side;

    /// d dᵀ is added over the peaks `d` has; the other rows and columns are
    /// left as they were.
    #[test]
    fn an_outer_term_is_added_over_the_peaks_both_have() {
        let mut cov = vec![vec![1.0, 0.0, 0.0], vec![0.0, 4.0, 0.0], vec![0.0, 0.0, 9.0]];
        add_outer(&mut cov, &[2.0, -1.0]);
        assert_eq!(cov, vec![vec![5.0, -2.0, 0.0], vec![-2.0, 5.0, 0.0], vec![0.0, 0.0, 9.0]]);
    }

    /// The partly shared model-form term has the shared one's variances and
    /// smaller covariances (none where s² = 1/3): a same-side ratio's u then
    /// no longer cancels.
    #[test]
    fn the_partly_shared_model_spread_keeps_the_variances_and_shrinks_the_covariances() {
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
        let zero = || vec![vec![0.0; 3]; 3];
        let (mut a, mut b, mut c, mut none) = (zero(), zero(), zero(), zero());
        add_model_spread(&mut a, &impacts, &alt);
        add_model_spread_partly(&mut b, &impacts, &alt, 1.0 / 3f64.sqrt());
        add_model_spread_partly(&mut c, &impacts, &alt, PEAK_TO_PEAK_TWO_SIDED);
        add_model_spread_partly(&mut none, &impacts, &alt, 0.0);
        for k in 0..3 {
            assert!((a[k][k] - b[k][k]).abs() < 1e-9 && (a[k][k] - c[k][k]).abs() < 1e-9);
            for j in (0..3).filter(|&j| j != k) {
                assert!(b[k][j].abs() < 1e-9);
                let shared = 1.0 - 3.0 * PEAK_TO_PEAK_TWO_SIDED.powi(2);
                assert!((c[k][j] - shared * a[k][j]).abs() < 1e-9 && a[k][j] != 0.0);
                assert!((none[k][j] - a[k][j]).abs() < 1e-9);
            }
        }
        assert!((a[2][2] - 30.0f64.powi(2) / 3.0).abs() < 1e-9);
    }
}
