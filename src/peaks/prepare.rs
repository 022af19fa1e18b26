//! Preparation of a log before the fit: isolated spikes replaced, the zero and
//! drift taken from the final rest, the release found.

use crate::signal::median;

/// Replace isolated one-sample spikes. A spike s at sample i adds (s, −2s, s)
/// to the second differences d₂ at i − 1, i, i + 1; an impact's kink gives one
/// large second difference with small neighbours, or two of one sign, so
/// impacts are kept. The arc's own curvature is taken out first: b, the mean
/// of d₂ at i ± 2 (which a spike at i leaves alone), is subtracted from all
/// three, and i must hold the largest of them. Without b, on an arc at 100 Hz
/// (d₂ ≈ 0.2 mm, 15 σ) a 0.9 mm spike's neighbour passed for the spike and was
/// replaced instead of it, and a 0.4 mm spike failed the test (random draw
/// 101144: the fit then missed the log at 4 × the noise). Where d₂ at i ± 2
/// differ by more than a quarter of d₂ at i, the curvature changes there (an
/// impact between them: on a stiff restraint's arcs b then made a kink pass
/// for a spike) and b is 0. The sample is replaced by the value that gives
/// d₂ = b there, (x[i−1] + x[i+1] − b)/2, not by its neighbours' mean, which
/// is off by b/2 on a curved arc. Returns the indices replaced; those beside
/// an impact, where the neighbours may straddle its kink, are left out of the
/// global fit (`peaks::beside_impacts`).
pub(super) fn remove_isolated_spikes(x: &mut [f64], threshold: f64) -> Vec<usize> {
    let n = x.len();
    let mut replaced = Vec::new();
    if n < 7 {
        return replaced;
    }
    for i in 3..n - 3 {
        let d2 = |j: usize, x: &[f64]| x[j - 1] - 2.0 * x[j] + x[j + 1];
        let (before, after, here) = (d2(i - 2, x), d2(i + 2, x), d2(i, x));
        let b = if (before - after).abs() <= here.abs() / 4.0 {
            0.5 * (before + after)
        } else {
            0.0
        };
        let (l, c, r) = (d2(i - 1, x) - b, here - b, d2(i + 1, x) - b);
        let alternates = l * c < 0.0 && r * c < 0.0;
        let shaped = l.abs() > c.abs() / 4.0 && r.abs() > c.abs() / 4.0;
        let centred = c.abs() >= l.abs() && c.abs() >= r.abs();
        if c.abs() > threshold && alternates && shaped && centred {
            x[i] = 0.5 * (x[i - 1] + x[i + 1] - b);
            replaced.push(i);
        }
    }
    replaced
}

/// Subtract the least-squares line through the final rest (the wall at rest after
/// the motion, with the sensor's drift): the samples after the last excursion
/// (three samples in a row) of more than 6 σ from the line through the last 5 %
/// of the record, with the slope shared with the initial hold. A fixed share
/// of the record (the last 15 %, as before issue #9) reaches into the motion when
/// a test rocks for most of its log (two-sided, e ≈ 0.95), and then the zero is
/// off by centimetres.
pub(super) fn detrend_by_final_rest(t: &[f64], x: &mut [f64], sigma: f64) {
    let n = t.len();
    let tail = final_rest_len(n);
    let (m0, s0) = line_fit(&t[n - tail..], &x[n - tail..]);
    let t_ref = t[n - tail];
    // The last excursion: three samples in a row beyond 6 σ (a spike the cleaner
    // left is one sample and does not cut the rest short).
    let off = |i: usize| (x[i] - m0 - s0 * (t[i] - t_ref)).abs() > 6.0 * sigma;
    let start = (2..n)
        .rev()
        .find(|&i| off(i) && off(i - 1) && off(i - 2))
        .map_or(0, |i| i + 1)
        .min(n - tail);
    // The hold before the release lies on the same drift line (another level):
    // fitting both with one slope pins the drift even when the rest is short.
    let hold = hold_samples(x, sigma);
    let slope = common_slope(&[(&t[..hold], &x[..hold]), (&t[start..], &x[start..])]);
    let k = (n - start) as f64;
    let m = t[start..]
        .iter()
        .zip(&x[start..])
        .map(|(ti, xi)| xi - slope * (ti - t[start]))
        .sum::<f64>()
        / k;
    let t0 = t[start];
    for (ti, xi) in t.iter().zip(x.iter_mut()) {
        *xi -= m + slope * (ti - t0);
    }
}

/// How far the final rest may spread about its mean (RMS) before the log is
/// said not to end at rest: [`STILL_NOISE`] × σ and [`STILL_SHARE`] of the
/// release's displacement (both: a noisy rest or a small late wobble passes).
const STILL_NOISE: f64 = 20.0;
const STILL_SHARE: f64 = 0.02;

/// The samples the final rest is first read from: the last 5 % of a log of
/// `n` (at least 5, at most all).
fn final_rest_len(n: usize) -> usize {
    (n * 5 / 100).max(5).min(n)
}

/// The level of the initial hold: the median of the first samples (25, or a
/// tenth of a short log, at least 5).
pub(super) fn hold_level(x: &[f64]) -> f64 {
    median(&x[..(x.len() / 10).clamp(5, 25).min(x.len())])
}

/// A log that ends while the wall still rocks: the RMS spread of its last 5 %
/// (the samples [`detrend_by_final_rest`] starts from) about their mean above
/// both [`STILL_NOISE`] σ and [`STILL_SHARE`] of the release's displacement
/// (the initial hold less that mean). About the mean, not a line: a line
/// through half a cycle takes up most of it, while a drift moves the last 5 %
/// of a log by a few hundredths of a millimetre. [`detrend_by_final_rest`] takes
/// the zero of θ from those samples; through a rocking tail its zero is off by
/// centimetres, and the crossings that follow from it are not the wall's (a
/// 200 Hz penalty-engine log that ended at ±20 mm of rocking after 12 peaks was
/// refused as "too few peaks: only 1 reliable half-cycle"). None where the log
/// ends at rest. Said only where the log then has too few crossings: a
/// smaller offset of the zero the global fit corrects (its rest level is a
/// parameter; a log of the same campaign whose last 0.5 s spread 2.26 mm,
/// 2 % of its release, had every value within 0.29 pp), so such a log is
/// analysed as before.
pub(super) fn still_moving_at_the_end(t: &[f64], x: &[f64], sigma: f64) -> Option<super::PeakError> {
    let n = t.len();
    let tail = final_rest_len(n);
    let (tt, xt) = (&t[n - tail..], &x[n - tail..]);
    let level = xt.iter().sum::<f64>() / tail as f64;
    let spread = (xt.iter().map(|xi| (xi - level).powi(2)).sum::<f64>() / tail as f64).sqrt();
    let share = spread / (hold_level(x) - level).abs().max(f64::MIN_POSITIVE);
    (spread > STILL_NOISE * sigma && share > STILL_SHARE).then(|| super::PeakError::NoFinalRest {
        tail_s: tt[tail - 1] - tt[0],
        spread_mm: spread,
        noise_mm: sigma,
        share,
    })
}

/// The samples of the initial hold: from the start while the reading stays within
/// 6 σ of the median of the first five (at least 5; the wall is held still).
pub(super) fn hold_samples(x: &[f64], sigma: f64) -> usize {
    let n0 = x.len().min(5);
    let level = median(&x[..n0]);
    x.iter().position(|v| (v - level).abs() > 6.0 * sigma).unwrap_or(x.len()).max(n0)
}

/// Least-squares slope shared by several segments, each with its own level.
pub(super) fn common_slope(parts: &[(&[f64], &[f64])]) -> f64 {
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (t, x) in parts {
        if t.len() < 2 {
            continue;
        }
        let k = t.len() as f64;
        let tm = t.iter().sum::<f64>() / k;
        let xm = x.iter().sum::<f64>() / k;
        sxx += t.iter().map(|v| (v - tm).powi(2)).sum::<f64>();
        sxy += t.iter().zip(x.iter()).map(|(a, b)| (a - tm) * (b - xm)).sum::<f64>();
    }
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

/// Least-squares line through (t, x): its value at t[0] and its slope.
pub(super) fn line_fit(t: &[f64], x: &[f64]) -> (f64, f64) {
    let k = t.len() as f64;
    let tm = t.iter().sum::<f64>() / k;
    let xm = x.iter().sum::<f64>() / k;
    let sxx: f64 = t.iter().map(|v| (v - tm).powi(2)).sum();
    let sxy: f64 = t.iter().zip(x).map(|(a, b)| (a - tm) * (b - xm)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (xm + slope * (t[0] - tm), slope)
}

/// First sample of three in a row that lie more than `threshold` below the hold.
pub(super) fn find_departure(x: &[f64], hold: f64, threshold: f64) -> Option<usize> {
    (0..x.len().saturating_sub(3)).find(|&i| (0..3).all(|j| hold - x[i + j] > threshold))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isolated_spikes_replaced_impact_kinks_kept() {
        // |t − 10|: a kink (an impact-like velocity jump) at 10, spikes at 4 and 15.
        let mut x: Vec<f64> = (0..20).map(|i| (i as f64 - 10.0).abs()).collect();
        x[4] += 50.0;
        x[15] -= 30.0;
        assert_eq!(remove_isolated_spikes(&mut x, 3.0).len(), 2);
        assert_eq!(x[4], 6.0);
        assert_eq!(x[15], 5.0);
        assert_eq!(x[10], 0.0, "the kink is left alone");
    }

    /// Spikes on a curved arc (random draw 101144, 100 Hz, σ 0.013 mm, the
    /// logged samples): the spike of −0.91 mm at 4.92 s is replaced, not its
    /// neighbour at 4.91 s, and the +0.40 mm spike at 5.34 s is found.
    #[test]
    fn spikes_on_a_curved_arc_are_found() {
        let apex = [-28.95, -30.37, -31.61, -32.65, -34.48, -34.24, -34.72, -35.07, -35.23, -35.16];
        let mut x = apex.to_vec();
        assert_eq!(remove_isolated_spikes(&mut x, 12.0 * 0.0133).len(), 1);
        assert_eq!(x[3], apex[3], "the neighbour is left alone");
        // The arc's value there (the fit's, in the logged frame): −33.565.
        assert!((x[4] - (-33.5275)).abs() < 1e-9, "{}", x[4]);
        let fall = [21.31, 21.59, 21.72, 21.61, 21.38, 21.35, 20.30, 19.48, 18.44, 17.25];
        let mut x = fall.to_vec();
        assert_eq!(remove_isolated_spikes(&mut x, 12.0 * 0.0133).len(), 1);
        // The fit's value there, in the logged frame: 20.95.
        assert!((x[5] - 20.93).abs() < 0.02, "{x:?}");
    }

    /// An impact into a stiff restraint (random draw 1215, 100 Hz, σ 0.08 mm,
    /// κ 13 p², impact 0 at 1.3407 s): the curvature jumps at the kink, and the
    /// kink is no spike.
    #[test]
    fn a_kink_into_a_stiff_restraint_is_kept() {
        let kink = [23.19, 17.73, 12.14, 6.42, 0.26, -4.35, -9.12, -13.05, -16.95, -20.17];
        let mut x = kink.to_vec();
        assert_eq!(remove_isolated_spikes(&mut x, 12.0 * 0.0796).len(), 0);
        assert_eq!(x, kink);
    }

    /// A log held at 150 mm for 1 s, then a decaying 1 Hz oscillation, 200 Hz,
    /// ending after `end_s` with a drift of 0.5 mm over the log and a
    /// deterministic ± `noise` mm sawtooth for the noise.
    fn held_then_rocking(end_s: f64, decay_s: f64, noise: f64) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..(end_s * 200.0) as usize).map(|i| i as f64 / 200.0).collect();
        let x = t
            .iter()
            .enumerate()
            .map(|(i, &ti)| {
                let motion = if ti < 1.0 {
                    150.0
                } else {
                    150.0 * (-(ti - 1.0) / decay_s).exp() * (std::f64::consts::TAU * (ti - 1.0)).cos()
                };
                motion + 0.5 * ti / end_s + noise * ((i % 7) as f64 / 3.0 - 1.0)
            })
            .collect();
        (t, x)
    }

    /// Rocking at ± 20 mm when the log ends (13 % of the release): said so.
    /// At rest (a decay time of 1 s: below 10⁻¹³ mm when the log ends)
    /// and with a late wobble of 1 % of the release (1.5 mm), not.
    #[test]
    fn a_log_that_ends_while_the_wall_rocks_is_said_to() {
        let decay = 10.0 / (150.0f64 / 20.0).ln();
        let (t, x) = held_then_rocking(11.0, decay, 0.03);
        match still_moving_at_the_end(&t, &x, 0.03) {
            Some(crate::peaks::PeakError::NoFinalRest { spread_mm, share, .. }) => {
                assert!(spread_mm > 5.0 && share > 0.05, "{spread_mm} mm, {share}");
            }
            other => panic!("{other:?}"),
        }
        let (t, x) = held_then_rocking(40.0, 1.0, 0.03);
        assert_eq!(still_moving_at_the_end(&t, &x, 0.03), None);
        let decay = 10.0 / 100f64.ln();
        let (t, x) = held_then_rocking(11.0, decay, 0.03);
        assert_eq!(still_moving_at_the_end(&t, &x, 0.03), None, "a wobble of 1 % passes");
    }
}
