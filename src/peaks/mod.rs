//! Release, impacts and velocity peaks of a free-rocking log.
//!
//! # Why not a smoothing derivative
//! Each velocity peak of free rocking sits at an impact, where the velocity jumps
//! (θ' ← e θ'). A symmetric smoothing window averages the speed before and after
//! the jump and clips the peak; late one-sided half-cycles are only 6–10 samples
//! long at 200 Hz, so any window wide enough to beat the noise straddles an impact.
//! On the one-sided fixture campaign a Savitzky–Golay derivative with peak picking
//! lands 4–12 percentage points below the truth (SPEC, last section).
//!
//! # The estimator (default, `Method::Segments`)
//! Between impacts the wall rocks freely, and paper Eq. 1 (no ground motion),
//! linearised about θ = 0, has closed-form arcs that start and end at θ = 0
//! ([`model`]):
//! - on a gravity-only side (outward; inward too in two-sided rocking), with
//!   T the arc's length and t_m its mid-time:
//!   L θ = ±A (1 − cosh(p (t − t_m)) / cosh(p T/2)),  A = L tan α_e;
//! - on the inward side of one-sided rocking, the arc of a spring–dashpot
//!   restraint between its zeros, y'' = A p² − λ y − 2γ y' with y = L θ and
//!   λ = κ − p² ([`model::damped_arc`]: cos for a stiff restraint, cosh where
//!   gravity outweighs it; γ > 0 when the transverse walls absorb energy, so the
//!   wall leaves the half-cycle slower than it entered it);
//! - the release arc, the only large one in one-sided tests, with its own A₀ and
//!   p₀ (absorbing the large-angle nonlinearity) and release time t_r:
//!   L θ = A₀ (1 − cosh(p₀ (t − t_r)) / cosh(p₀ (t_0 − t_r))), held before t_r.
//!
//! The whole record from just before the release to the last impact used is fitted
//! at once by Levenberg–Marquardt ([`crate::fit`], `segments.rs`): every impact time
//! t_k, the release, A, A₀, p₀ (p of the small arcs is tied to p₀: short arcs only
//! see the product A p²), λ, γ and the sensor zero are free, from several starts.
//! Each arc is pinned to the zero at both of its impacts, so the impact times, the
//! zero and the gravity term are all determined by the kinks of the record, and the
//! estimator does not trust the nominal geometry (a 3–5 % error in α or p² would
//! cost 0.5–1.9 pp, SPEC). Where the samples around the impacts show that the
//! contacts take time, a model with contact phases (the free arc ends a few ms
//! before θ = 0) replaces it if the data ask for it. v_k is the extreme of the
//! model's velocity in half-cycle k: with instantaneous impacts, the slope of the
//! arc before impact k exactly at t_k (no smoothing bias).
//!
//! Before the fit: isolated spikes are replaced, the line through the final rest
//! (its slope shared with the initial hold) is subtracted (the sensor's zero and a
//! linear drift), the readings are turned into L θ with θ = asin(x/L) (the sensor
//! reads L sin θ: 0.1 mm on a 150 mm release), and the impacts are located roughly
//! by zero crossings with hysteresis. After it: the plausibility checks of
//! [`checks`] (a test that trips one is [`Quality::Suspect`]) and the covariance
//! of the peaks.
//!
//! Assumptions: free vibration (no base motion), the release from rest on the
//! outward side, a sensor drift that is linear over the record, white noise, a
//! linear (possibly lossy) inward restraint in one-sided rocking. Measured error
//! (`tests/truth.rs`, README): at most 0.44 pp on the one-sided fixture campaign
//! and 0.03 pp two-sided; 1.0 pp on the two-sided MuJoCo campaign (compliant
//! contacts) and 1.16 pp on the one-sided one; 99.0 % of 500 random idealised
//! tests within 1 pp and none more than 5 pp off with status ok
//! (`tests/random_draw.rs`).
//!
//! No crate does this: it is a domain-specific piecewise model fit; the
//! Levenberg–Marquardt loop is [`crate::fit`], the linear algebra nalgebra's.

pub mod checks;
pub mod model;
mod segments;

use crate::signal::savgol::SavGol;
use crate::signal::{median, noise_sigma};
use crate::wall::Rocking;
use segments::{FitInput, SegmentFit};

/// What the estimator knows about the wall.
#[derive(Debug, Clone, Copy)]
pub struct Physics {
    pub rocking: Rocking,
    /// Sensor lever arm about the hinge, mm.
    pub lever_arm_mm: f64,
    /// Starting value of the rocking frequency parameter p (rad/s) from the geometry.
    pub p_guess: f64,
}

/// How the velocity peaks are estimated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Impact-resolved piecewise fit of the free-rocking solution (default).
    Segments,
    /// Classic: Savitzky–Golay derivative, then the extreme of each half-cycle.
    SavGol(SavGol),
}

impl Method {
    pub fn describe(&self) -> String {
        match self {
            Method::Segments => "global fit of the small-angle free-rocking solution (Eq. 1; lossy inward arcs, contact phases where the log shows them), each peak the extreme of the fitted velocity in its half-cycle, with plausibility checks".into(),
            Method::SavGol(s) => format!("Savitzky–Golay derivative (window {}, order {}) and peak picking", s.window(), s.order()),
        }
    }
}

/// Settings of the peak analysis.
#[derive(Debug, Clone, Copy)]
pub struct PeakOptions {
    /// Number of velocity peaks wanted (the tables need 6).
    pub n_peaks: usize,
    pub method: Method,
}

impl Default for PeakOptions {
    fn default() -> Self {
        PeakOptions {
            n_peaks: 6,
            method: Method::Segments,
        }
    }
}

/// Why a log could not be analysed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PeakError {
    #[error("only {0} samples: expected a log of at least 20")]
    TooShort(usize),
    #[error("no release found: the displacement stays within {amplitude_mm:.3} mm of its final rest level (noise {noise_mm:.3} mm)")]
    NoRelease { amplitude_mm: f64, noise_mm: f64 },
    #[error(
        "the log starts {0:.2} mm on the inward side of its final rest level: expected a release from an outward displacement (check outward_sign)"
    )]
    InwardStart(f64),
    #[error("too few peaks (n = {found} < {needed}): the rocking after release shows only {found} reliable half-cycles above the noise")]
    TooFewPeaks { found: usize, needed: usize },
    #[error("the fit of the free-rocking segments failed: {0}")]
    Fit(String),
}

/// Side of the wall a segment lies on (the one `Side` of the crate).
pub use crate::wall::Side;

/// One impact: the crossing of θ = 0 and the speeds on either side of it.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Impact {
    pub k: usize,
    pub time_s: f64,
    /// Side entered by the impact (impact 0 enters the inward side).
    pub entering: Side,
    /// Sensor velocity just before the impact, mm/s, outward positive (= v_k).
    pub v_before_mm_s: f64,
    /// Sensor velocity just after, mm/s (None where the next segment was not fitted).
    pub v_after_mm_s: Option<f64>,
}

/// A velocity peak v_k of the SPEC.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Peak {
    pub time_s: f64,
    pub velocity_mm_s: f64,
    /// Standard uncertainty of `velocity_mm_s` (mm/s), from the fit's covariance
    /// (default estimator only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity_u_mm_s: Option<f64>,
}

/// The analysis of one log.
#[derive(Debug, Clone)]
pub struct Analysis {
    pub release_time_s: f64,
    pub peaks: Vec<Peak>,
    pub impacts: Vec<Impact>,
    /// Displacement at every sample, mm, relative to the final rest line (drift
    /// removed, isolated spikes replaced).
    pub displacement_mm: Vec<f64>,
    /// Velocity at every sample, mm/s: the fitted segments where they apply, a
    /// Savitzky–Golay derivative elsewhere (for plots).
    pub velocity_mm_s: Vec<f64>,
    /// Fitted displacement on a fine grid over the fitted window: (t, x mm, v mm/s).
    pub fit_curve: Vec<(f64, f64, f64)>,
    pub noise_mm: f64,
    pub spikes_removed: usize,
    /// Fitted effective rate p_e (rad/s) and inward λ (s⁻², one-sided), segments only.
    pub p_fit: Option<f64>,
    pub lambda_fit: Option<f64>,
    /// RMS residual of the segment fit, mm.
    pub rms_mm: Option<f64>,
    /// Whether the estimator can vouch for the peaks (the plausibility checks).
    pub quality: Quality,
    /// Covariance of the peak speeds (mm²/s²), default estimator only.
    pub peak_covariance: Option<Vec<Vec<f64>>>,
    /// Whether the fit chose finite-duration contacts (see [`model`]).
    pub contact_phases: bool,
    /// Fitted decay rate γ of the inward arcs (s⁻¹, one-sided).
    pub gamma_fit: Option<f64>,
    /// The second estimate of each peak: a local fit of the end of its arc
    /// (velocity, standard uncertainty), where the arc has enough samples.
    pub local_peaks: Vec<Option<(f64, f64)>>,
}

/// What the plausibility checks say of an analysis: `Ok`, or `Suspect` with the
/// reasons in words. A suspect test's numbers are reported but left out of the
/// campaign means (SPEC: `"status": "suspect"`).
#[derive(Debug, Clone, PartialEq)]
pub enum Quality {
    Ok,
    Suspect(Vec<String>),
}

impl Quality {
    pub fn is_ok(&self) -> bool {
        matches!(self, Quality::Ok)
    }
    /// "ok", or "suspect: reason; reason".
    pub fn describe(&self) -> String {
        match self {
            Quality::Ok => "ok".into(),
            Quality::Suspect(r) => format!("suspect: {}", r.join("; ")),
        }
    }
}

/// Analyse one log: `t` in s (strictly increasing), `x` in mm outward positive.
pub fn analyse(t: &[f64], x: &[f64], phys: &Physics, opts: &PeakOptions) -> Result<Analysis, PeakError> {
    let n = t.len();
    if n < 20 {
        return Err(PeakError::TooShort(n));
    }
    let sigma = noise_sigma(x).max(1e-9);
    let mut x = x.to_vec();
    let spikes = remove_isolated_spikes(&mut x, 8.0 * sigma);
    let dt = median(&t.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>());

    // The sensor's zero drifts: the line through the final rest (the last 15 % of
    // the record) is the zero of θ at every time. Subtracting it makes the rest
    // level 0 and removes a linear drift.
    detrend_by_final_rest(t, &mut x, sigma);
    let rest = 0.0;
    // The log starts with the wall held at its imposed displacement: its first
    // samples (25, or a tenth of a short log) give the hold level.
    let n_hold = (n / 10).clamp(5, 25);
    let hold = median(&x[..n_hold]);
    let amplitude = hold - rest;
    if amplitude.abs() < 20.0 * sigma {
        return Err(PeakError::NoRelease {
            amplitude_mm: amplitude.abs(),
            noise_mm: sigma,
        });
    }
    if amplitude < 0.0 {
        return Err(PeakError::InwardStart(-amplitude));
    }
    let departure = find_departure(&x, hold, (6.0 * sigma).max(0.01 * amplitude)).ok_or(PeakError::NoRelease {
        amplitude_mm: amplitude,
        noise_mm: sigma,
    })?;
    let crossings = find_crossings(t, &x, rest, sigma, departure, opts.n_peaks + 1);
    if crossings.len() < opts.n_peaks {
        return Err(PeakError::TooFewPeaks {
            found: crossings.len(),
            needed: opts.n_peaks,
        });
    }
    let sg = SavGol::new(7, 2).expect("valid");
    let mut velocity = sg.derivative(&x, dt);
    match opts.method {
        Method::SavGol(filter) => {
            let v = filter.derivative(&x, dt);
            let (peaks, impacts) = pick_peaks(t, &v, &crossings, departure, filter.window() / 2, opts.n_peaks);
            let release = t[departure.saturating_sub(1)];
            Ok(Analysis {
                release_time_s: release,
                peaks,
                impacts,
                velocity_mm_s: v,
                displacement_mm: x,
                fit_curve: Vec::new(),
                noise_mm: sigma,
                spikes_removed: spikes,
                p_fit: None,
                lambda_fit: None,
                rms_mm: None,
                quality: Quality::Ok,
                peak_covariance: None,
                contact_phases: false,
                gamma_fit: None,
                local_peaks: Vec::new(),
            })
        }
        Method::Segments => {
            let fit = SegmentFit::run(&FitInput {
                t,
                x: &x,
                rest,
                sigma,
                departure,
                crossings: &crossings,
                phys,
                n_peaks: opts.n_peaks,
            })?;
            fit.fill_velocity(t, &mut velocity);
            let impacts = fit.impacts();
            let cov = fit.fitted.peak_covariance(opts.n_peaks).map(|mut c| {
                if !fit.contacts {
                    add_unresolved_contact(&mut c, fit.model(), dt);
                }
                c
            });
            let peaks: Vec<Peak> = impacts
                .iter()
                .take(opts.n_peaks)
                .enumerate()
                .map(|(k, i)| Peak {
                    time_s: i.time_s,
                    velocity_mm_s: i.v_before_mm_s,
                    velocity_u_mm_s: cov.as_ref().map(|c| c[k][k].max(0.0).sqrt()),
                })
                .collect();
            let local = local_peaks(&fit, opts.n_peaks, sigma);
            let quality = plausibility(&fit, &peaks, &local, dt, sigma);
            Ok(Analysis {
                release_time_s: fit.model().release_time(),
                peaks,
                impacts,
                velocity_mm_s: velocity,
                displacement_mm: x,
                fit_curve: fit.curve(),
                noise_mm: sigma,
                spikes_removed: spikes,
                p_fit: Some(fit.model().p()),
                lambda_fit: fit.model().lambda(),
                rms_mm: Some(fit.rms),
                quality,
                peak_covariance: cov,
                contact_phases: fit.contacts,
                gamma_fit: fit.model().gamma(),
                local_peaks: local,
            })
        }
    }
}

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
fn add_unresolved_contact(cov: &mut [Vec<f64>], m: &model::Model, dt: f64) {
    for (k, row) in cov.iter_mut().enumerate() {
        let t = m.onset(k);
        let h = 1e-4 * dt.max(1e-6);
        let acc = (m.arc(k, t).1 - m.arc(k, t - h).1) / h;
        row[k] += (acc * dt).powi(2) / 12.0;
    }
}

/// The second estimate of each peak: the end of free arc k re-fitted from its own
/// samples (the later half of the arc, at least 4 samples) by [`checks::local_slope`].
fn local_peaks(fit: &SegmentFit, n: usize, sigma: f64) -> Vec<Option<(f64, f64)>> {
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
            let (slope, u) = checks::local_slope(&fit.tw[i0..i1], &fit.yw[i0..i1], end, lambda, sigma)?;
            Some((slope, u))
        })
        .collect()
}

/// Run every check of [`checks`] on a fit.
fn plausibility(fit: &SegmentFit, peaks: &[Peak], local: &[Option<(f64, f64)>], dt: f64, sigma: f64) -> Quality {
    let v: Vec<f64> = peaks.iter().map(|p| p.velocity_mm_s).collect();
    let u: Vec<f64> = peaks.iter().map(|p| p.velocity_u_mm_s.unwrap_or(0.0)).collect();
    let m = fit.model();
    // Half-cycle s is an inward arc against the transverse walls (one-sided, s odd).
    let spring: Vec<bool> = (0..m.m()).map(|s| m.one_sided && s % 2 == 1).collect();
    // The local re-fit estimates the free arc's slope at the onset of contact.
    let v_onset: Vec<f64> = (0..v.len()).map(|k| m.speeds(k).0).collect();
    let zeros: Vec<f64> = (0..m.m()).map(|k| m.impact(k)).collect();
    let onsets: Vec<f64> = (0..m.m()).map(|k| m.onset(k)).collect();
    let resid = fit.residuals();
    // Impacts 0..n−2: the ones between the peaks the tables use.
    let after: Vec<Option<f64>> = (0..v.len().saturating_sub(1)).map(|k| m.speeds(k).1).collect();
    let reasons: Vec<String> = [
        checks::merged_impacts(&zeros, dt),
        checks::alternation(&v),
        checks::energy_gain(&v, &u),
        checks::impact_gains_speed(&v, &after, &u),
        checks::misfit(&resid, sigma),
        checks::structured_near_impacts(&fit.tw, &resid, &onsets, dt, sigma),
        checks::disagreement(&v_onset, &u, local),
        m.contact_windows().and_then(|w| {
            let arcs: Vec<f64> = (0..m.m()).map(|s| m.arc_length(s)).collect();
            let windows = if m.layout.by_direction { &w[..] } else { &w[..1] };
            checks::contact_too_long(windows, &arcs, &spring)
        }),
        if fit.contacts {
            checks::contact_overshoot(&v, &v_onset, &u, &spring)
        } else {
            None
        },
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

/// Replace isolated one-sample spikes. A spike leaves the second difference with the
/// pattern (+s, −2s, +s); an impact's kink gives one large second difference with
/// small neighbours, so impacts are kept. Returns the number replaced.
fn remove_isolated_spikes(x: &mut [f64], threshold: f64) -> usize {
    let n = x.len();
    let mut count = 0;
    if n < 5 {
        return 0;
    }
    for i in 2..n - 2 {
        let d2 = |j: usize, x: &[f64]| x[j - 1] - 2.0 * x[j] + x[j + 1];
        let c = d2(i, x);
        let l = d2(i - 1, x);
        let r = d2(i + 1, x);
        if c.abs() > threshold && l * c < 0.0 && r * c < 0.0 && l.abs() > c.abs() / 4.0 && r.abs() > c.abs() / 4.0 {
            x[i] = 0.5 * (x[i - 1] + x[i + 1]);
            count += 1;
        }
    }
    count
}

/// Subtract the least-squares line through the final rest (the wall at rest after
/// the motion, with the sensor's drift): the samples after the last excursion
/// (three samples in a row) of more than 6 σ from the line through the last 5 %
/// of the record, with the slope shared with the initial hold. A fixed share
/// of the record (the last 15 %, as before issue #9) reaches into the motion when
/// a test rocks for most of its log (two-sided, e ≈ 0.95), and then the zero is
/// off by centimetres.
fn detrend_by_final_rest(t: &[f64], x: &mut [f64], sigma: f64) {
    let n = t.len();
    let tail = (n * 5 / 100).max(5).min(n);
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

/// The samples of the initial hold: from the start while the reading stays within
/// 6 σ of the median of the first five (at least 5; the wall is held still).
fn hold_samples(x: &[f64], sigma: f64) -> usize {
    let n0 = x.len().min(5);
    let level = median(&x[..n0]);
    x.iter().position(|v| (v - level).abs() > 6.0 * sigma).unwrap_or(x.len()).max(n0)
}

/// Least-squares slope shared by several segments, each with its own level.
fn common_slope(parts: &[(&[f64], &[f64])]) -> f64 {
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
fn line_fit(t: &[f64], x: &[f64]) -> (f64, f64) {
    let k = t.len() as f64;
    let tm = t.iter().sum::<f64>() / k;
    let xm = x.iter().sum::<f64>() / k;
    let sxx: f64 = t.iter().map(|v| (v - tm).powi(2)).sum();
    let sxy: f64 = t.iter().zip(x).map(|(a, b)| (a - tm) * (b - xm)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (xm + slope * (t[0] - tm), slope)
}

/// First sample of three in a row that lie more than `threshold` below the hold.
fn find_departure(x: &[f64], hold: f64, threshold: f64) -> Option<usize> {
    (0..x.len().saturating_sub(3)).find(|&i| (0..3).all(|j| hold - x[i + j] > threshold))
}

/// Zero crossings of x − rest after `start`, with hysteresis: a new side counts
/// once two consecutive samples lie beyond 2.5 σ on it, or one beyond 5 σ. The
/// crossing time is the linear interpolation of the last sign change before the
/// confirmation. A last side that never confirms its end gets the first sign change
/// after its extreme (the late half-cycles of one-sided rocking are tiny).
fn find_crossings(t: &[f64], x: &[f64], rest: f64, sigma: f64, start: usize, max: usize) -> Vec<f64> {
    let y = |i: usize| x[i] - rest;
    let n = x.len();
    let mut out: Vec<f64> = Vec::new();
    let mut side = 1.0; // outward at release
    let mut last_confirm = start;
    let mut i = start;
    while i + 1 < n && out.len() < max {
        let a = -side * y(i);
        let b = -side * y(i + 1);
        if (a > 2.5 * sigma && b > 2.5 * sigma) || a > 5.0 * sigma {
            // Last sign change in [last_confirm, i].
            let mut j = i;
            while j > last_confirm && side * y(j - 1) <= 0.0 {
                j -= 1;
            }
            let j0 = j.saturating_sub(1).max(last_confirm);
            let (ya, yb) = (y(j0), y(j));
            let tc = if j0 < j && ya != yb {
                t[j0] + (t[j] - t[j0]) * ya / (ya - yb)
            } else {
                t[j]
            };
            // Free rocking only slows down: a half-cycle never lasts more than
            // three times the longer of the previous one and the previous one on
            // the same side (the release arc counted from the departure). A later
            // "crossing" is noise at rest (two samples beyond 2.5 σ happen in long
            // records): the motion ended unconfirmed, and the fallback below finds
            // its last crossing.
            if !out.is_empty() && tc - out[out.len() - 1] > 3.0 * longest_recent(t[start], &out) {
                break;
            }
            out.push(tc);
            side = -side;
            last_confirm = i;
        }
        i += 1;
    }
    if out.len() < max && !out.is_empty() {
        // We are on side `side`, confirmed at `last_confirm`. Its end is the first
        // sign change after its extreme, looked for within 1.5 × the previous
        // half-cycle (a later one would be noise at rest, not rocking).
        let prev = if out.len() >= 2 {
            out[out.len() - 1] - out[out.len() - 2]
        } else {
            // The release arc is about half a half-cycle, hence the factor 2 after it.
            2.0 * (out[0] - t[start])
        };
        let t_last = out[out.len() - 1];
        let stop = t.partition_point(|&v| v < t_last + 1.5 * prev).min(n);
        let begin = t.partition_point(|&v| v <= t_last).min(n.saturating_sub(1));
        let mut ext = begin;
        for k in begin..stop {
            if side * y(k) > side * y(ext) {
                ext = k;
            }
        }
        if side * y(ext) > 2.0 * sigma {
            if let Some(j) = (ext..stop.saturating_sub(1)).find(|&k| side * y(k) > 0.0 && side * y(k + 1) <= 0.0) {
                let (ya, yb) = (y(j), y(j + 1));
                out.push(t[j] + (t[j + 1] - t[j]) * ya / (ya - yb));
            }
        }
    }
    out
}

/// The longer of the last two half-cycles before the one ending now (the release
/// arc runs from the departure `t0` to the first crossing).
fn longest_recent(t0: f64, out: &[f64]) -> f64 {
    let mut b = vec![t0];
    b.extend_from_slice(out);
    let n = b.len();
    let last = b[n - 1] - b[n - 2];
    if n >= 3 {
        last.max(b[n - 2] - b[n - 3])
    } else {
        last
    }
}

/// Peak picking on a smoothed derivative: v_k is the extreme of the half-cycle that
/// ends at crossing k (searched up to `half` samples past the crossing, since the
/// smoothed peak is displaced by the window).
fn pick_peaks(t: &[f64], v: &[f64], crossings: &[f64], start: usize, half: usize, n_peaks: usize) -> (Vec<Peak>, Vec<Impact>) {
    let idx = |tc: f64| t.partition_point(|&s| s < tc);
    let mut peaks = Vec::new();
    let mut impacts = Vec::new();
    let mut from = start;
    for (k, &tc) in crossings.iter().enumerate().take(n_peaks) {
        let end = (idx(tc) + half).min(v.len() - 1);
        let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
        let mut best = from;
        for i in from..=end {
            if sign * v[i] > sign * v[best] {
                best = i;
            }
        }
        peaks.push(Peak {
            time_s: t[best],
            velocity_mm_s: v[best],
            velocity_u_mm_s: None,
        });
        impacts.push(Impact {
            k,
            time_s: tc,
            entering: if k % 2 == 0 { Side::Inward } else { Side::Outward },
            v_before_mm_s: v[best],
            v_after_mm_s: None,
        });
        from = idx(tc).min(v.len() - 1);
    }
    (peaks, impacts)
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
        assert_eq!(remove_isolated_spikes(&mut x, 3.0), 2);
        assert_eq!(x[4], 6.0);
        assert_eq!(x[15], 5.0);
        assert_eq!(x[10], 0.0, "the kink is left alone");
    }

    #[test]
    fn crossings_with_hysteresis_ignore_noise_at_rest() {
        // 10 cos(π t) from the release at t = 0 to t = 1.5 (crossings at 0.5 and 1.5),
        // then rest with ±1.5 σ noise (σ = 0.01): the noise never counts as a crossing,
        // and the last, unconfirmed half-cycle still gets its end.
        let t: Vec<f64> = (0..400).map(|i| i as f64 * 0.01).collect();
        let x: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                if s < 1.495 {
                    10.0 * (std::f64::consts::PI * s).cos()
                } else {
                    0.015 * ((i % 3) as f64 - 1.0)
                }
            })
            .collect();
        let c = find_crossings(&t, &x, 0.0, 0.01, 0, 10);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!((c[0] - 0.5).abs() < 1e-3, "{c:?}");
        assert!((c[1] - 1.5).abs() < 0.02, "{c:?}");
    }
}
