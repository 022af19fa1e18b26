//! The second estimate of each peak and the plausibility checks of one
//! analysis ([`super::checks`]).

use super::late::LatePeak;
use super::segments::SegmentFit;
use super::{checks, vouch, Peak, Quality, ReadingMethod};

/// The second estimate of each peak: the end of free arc k re-fitted from its own
/// samples (the later half of the arc, at least 4 samples) by [`checks::local_slope`].
pub(super) fn local_peaks(fit: &SegmentFit, n: usize, sigma: f64) -> Vec<Option<(f64, f64)>> {
    let m = fit.model();
    (0..n.min(m.m()))
        .map(|k| {
            let start = if k == 0 { m.release_time() } else { m.release_from_contact(k - 1) };
            let end = m.onset(k);
            let from = start + 0.5 * (end - start);
            let i0 = fit.tw.partition_point(|&v| v < from);
            let i1 = fit.tw.partition_point(|&v| v < end);
            let i0 = i0.min(i1.saturating_sub(4)).max(fit.tw.partition_point(|&v| v < start));
            let inward_spring = m.one_sided && k % 2 == 1;
            let lambda = if inward_spring { m.lambda().unwrap_or(0.0) } else { -m.p().powi(2) };
            // Through a causal filter the arc's samples come out late by its
            // group delay (the samples before the kink do not see it yet).
            let late = m.filter.as_ref().map_or(0.0, |f| f.delay());
            let (slope, u) = checks::local_slope(&fit.tw[i0..i1], &fit.yw[i0..i1], end + late, lambda, sigma)?;
            Some((slope, u))
        })
        .collect()
}

/// The two ways the peaks may be vouched for despite residuals that stand out
/// around an impact: the local readings (computed only then) and the
/// caller's leave-out re-fit, given the onsets to leave out.
pub(super) type Vouchers<'a> = (&'a dyn Fn() -> Vec<LatePeak>, &'a dyn Fn(&[f64]) -> bool);

/// Run every check of [`checks`] on a fit (`spread[k]`: the difference between
/// peak k's two readings of where its half-cycle ends,
/// [`super::model::Model::peak_spread`]).
///
/// A peak read locally (`methods[k]`, [`super::local`]) does not depend on the
/// global fit's contact phase at impact k nor on where its zero lies: the checks
/// of that contact (its length, its overshoot, its zero readings, the residuals
/// around it, the re-fit of the arc's end) are not run for it.
///
/// `resid`: the fit's residuals over its window ([`SegmentFit::residuals`]).
///
/// Residuals that stand out around an impact are a reason only where the
/// local readings of the peaks (`late`, computed only then) do not vouch for
/// the global fit's ([`vouch`]); not checked here (`structured_elsewhere`)
/// where they stand out around a one-sided wall's exits only
/// (`super::exits_only_misfit`) or where the caller defers them
/// ([`super::Analysis::deferred_misfit`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn plausibility(
    fit: &SegmentFit,
    resid: &[f64],
    peaks: &[Peak],
    local: &[Option<(f64, f64)>],
    spread: &[f64],
    methods: &[ReadingMethod],
    (dt, sigma): (f64, f64),
    structured_elsewhere: bool,
    (late, left_out): Vouchers,
) -> Quality {
    let is_local = |k: usize| methods.get(k) == Some(&ReadingMethod::LocalExtreme);
    let local: Vec<Option<(f64, f64)>> = local.iter().enumerate().map(|(k, l)| if is_local(k) { None } else { *l }).collect();
    let spread: Vec<f64> = spread.iter().enumerate().map(|(k, &d)| if is_local(k) { 0.0 } else { d }).collect();
    let v: Vec<f64> = peaks.iter().map(|p| p.velocity_mm_s).collect();
    let u: Vec<f64> = peaks.iter().map(|p| p.velocity_u_mm_s.unwrap_or(0.0)).collect();
    let m = fit.model();
    let spring = checks::inward_arcs(m);
    let overshoot_skip: Vec<bool> = (0..m.m()).map(|s| spring[s] || is_local(s)).collect();
    // The local re-fit estimates the free arc's slope at the onset of contact.
    let v_onset: Vec<f64> = (0..v.len()).map(|k| m.speeds(k).0).collect();
    let zeros: Vec<f64> = (0..m.m()).map(|k| m.impact(k)).collect();
    let onsets = checked_onsets(m, methods);
    // Impacts 0..n−1: the ones that end the peaks the tables use, the last
    // one's included (it ends peak n−1: an exit that gains speed there has
    // that peak's time wrong, docs/estimator.md).
    let after: Vec<Option<f64>> = (0..v.len().min(m.m())).map(|k| m.speeds(k).1).collect();
    let reasons: Vec<String> = [
        checks::merged_impacts(&zeros, dt),
        checks::alternation(&v),
        checks::energy_gain(&v, &u),
        checks::impact_gains_speed(&v, &after, &u),
        checks::misfit(resid, sigma),
        if structured_elsewhere {
            None
        } else {
            structured_unvouched(fit, resid, &onsets, peaks, (dt, sigma), (late, left_out))
        },
        checks::disagreement(&v_onset, &u, &local),
        m.contact_windows().and_then(|windows| {
            let windows: Vec<(f64, f64)> = windows
                .iter()
                .enumerate()
                .map(|(k, &w)| if is_local(k) { (0.0, 0.0) } else { w })
                .collect();
            checks::contacts_too_long(m, &windows, v.len())
        }),
        if fit.contacts {
            checks::contact_overshoot(&v, &v_onset, &u, &overshoot_skip)
        } else {
            None
        },
        checks::zero_readings_disagree(&v, &spread),
    ]
    .into_iter()
    .flatten()
    .collect();
    if reasons.is_empty() {
        Quality::Ok
    } else {
        Quality::Suspect(reasons)
    }
}

/// The onset of every impact of `m` whose residuals the checks read: NaN where
/// the peak that ends there is a local extreme's (`methods`), not the global
/// fit's.
pub(super) fn checked_onsets(m: &super::model::Model, methods: &[ReadingMethod]) -> Vec<f64> {
    (0..m.m())
        .map(|k| {
            if methods.get(k) == Some(&ReadingMethod::LocalExtreme) {
                f64::NAN
            } else {
                m.onset(k)
            }
        })
        .collect()
}

/// [`checks::structured_near_impacts`], unless the local readings vouch for the
/// peaks ([`vouch`]) or the peaks do not depend on the samples around the
/// impacts that stand out (`left_out`, given their onsets: the caller's
/// leave-out re-fit, `super::left_out_vouches`).
fn structured_unvouched(
    fit: &SegmentFit,
    resid: &[f64],
    onsets: &[f64],
    peaks: &[Peak],
    (dt, sigma): (f64, f64),
    (late, left_out): Vouchers,
) -> Option<String> {
    let standing = checks::structured_impacts(&fit.tw, resid, onsets, dt, sigma);
    let &(first, spread) = standing.first()?;
    if vouch::vouched(peaks, &late()) {
        return None;
    }
    let at: Vec<f64> = standing.iter().map(|&(k, _)| onsets[k]).collect();
    (!left_out(&at)).then(|| checks::standing_out(first, spread, sigma))
}
