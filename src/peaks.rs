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
//! linearised about θ = 0, has closed-form arcs that start and end at θ = 0:
//! - on a gravity-only side (outward; inward too in two-sided rocking), with
//!   T = t_k − t_{k−1} and t_m the mid-time:
//!   L θ = ±A (1 − cosh(p (t − t_m)) / cosh(p T/2)),  A = L tan α_e;
//! - on the inward side of one-sided rocking, where the transverse walls add a
//!   spring κ θ, with λ = κ − p², ω = √λ and centre C = A p²/λ:
//!   L θ = C (1 − cos(ω (t − t_m)) / cos(ω T/2)); cosh where gravity outweighs the
//!   spring (λ < 0), a parabola at λ = 0 ([`spring_arc`] is smooth across 0);
//! - the release arc, the only large one in one-sided tests, with its own A₀ and
//!   p₀ (absorbing the large-angle nonlinearity) and release time t_r:
//!   L θ = A₀ (1 − cosh(p₀ (t − t_r)) / cosh(p₀ (t_0 − t_r))), held before t_r.
//!
//! The whole record from just before the release to the last impact used is fitted
//! at once by Levenberg–Marquardt ([`crate::fit`]): every impact time t_k, the
//! release, A, A₀, p₀ (p of the small arcs is tied to p₀: short arcs only see the
//! product A p²), λ and the sensor zero are free. Each arc is pinned to the zero at
//! both of its impacts, so the impact times, the zero and the gravity term are all
//! determined by the kinks of the record, and the estimator does not trust the
//! nominal geometry (a 3–5 % error in α or p² would cost 0.5–1.9 pp, SPEC). v_k is
//! the slope of the arc before impact k exactly at t_k: one-sided by construction,
//! no impact bias. The speed after the impact (the next arc's slope) is reported too.
//!
//! Before the fit: isolated spikes are replaced, the line through the final rest is
//! subtracted (the sensor's zero and a linear drift), the readings are turned into
//! L θ with θ = asin(x/L) (the sensor reads L sin θ: 0.1 mm on a 150 mm release), and
//! the impacts are located roughly by zero crossings with hysteresis.
//!
//! Assumptions: free vibration (no base motion), the release from rest on the
//! outward side, a sensor drift that is linear over the record, white noise, a
//! linear inward restraint in one-sided rocking (soft or stiff). Measured error
//! on the fixture campaigns (`tests/truth.rs`, README): at most 0.46 pp one-sided
//! and 0.03 pp two-sided; 0.18 pp on tests decimated to 100 Hz, with spikes, a clock
//! offset or extra drift; 0.34 pp on solver-made logs with a soft (κ = p²/2) or a
//! stiff (κ = 15 p²) inward restraint at 100, 200 and 1000 Hz.
//!
//! No crate does this: it is a domain-specific piecewise model fit; the
//! Levenberg–Marquardt loop is [`crate::fit`], the linear algebra nalgebra's.

use crate::ingest::Rocking;
use crate::signal::savgol::SavGol;
use crate::signal::{median, noise_sigma};

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
            Method::Segments => "impact-resolved piecewise fit of the small-angle free-rocking solution (Eq. 1), evaluated at each impact".into(),
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

/// Side of the wall a segment lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Outward,
    Inward,
}

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
    detrend_by_final_rest(t, &mut x);
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
            })
        }
        Method::Segments => {
            let fit = SegmentFit::run(t, &x, rest, sigma, departure, &crossings, phys, opts.n_peaks)?;
            fit.fill_velocity(t, &mut velocity);
            let impacts = fit.impacts();
            let peaks = impacts
                .iter()
                .take(opts.n_peaks)
                .map(|i| Peak {
                    time_s: i.time_s,
                    velocity_mm_s: i.v_before_mm_s,
                })
                .collect();
            Ok(Analysis {
                release_time_s: fit.release_time(),
                peaks,
                impacts,
                velocity_mm_s: velocity,
                displacement_mm: x,
                fit_curve: fit.curve(),
                noise_mm: sigma,
                spikes_removed: spikes,
                p_fit: Some(fit.p()),
                lambda_fit: fit.lambda(),
                rms_mm: Some(fit.rms),
            })
        }
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

/// Subtract the least-squares line through the last 15 % of the samples (the wall
/// at rest after the motion, with the sensor's drift).
fn detrend_by_final_rest(t: &[f64], x: &mut [f64]) {
    let n = t.len();
    let k = (n * 15 / 100).max(5).min(n);
    let (ts, xs) = (&t[n - k..], &x[n - k..]);
    let tm = ts.iter().sum::<f64>() / k as f64;
    let xm = xs.iter().sum::<f64>() / k as f64;
    let sxx: f64 = ts.iter().map(|v| (v - tm).powi(2)).sum();
    let sxy: f64 = ts.iter().zip(xs).map(|(a, b)| (a - tm) * (b - xm)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    for (ti, xi) in t.iter().zip(x.iter_mut()) {
        *xi -= xm + slope * (ti - tm);
    }
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
    let mut out = Vec::new();
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

/// Parameters of the global free-rocking model (see the module docs). Rates and
/// lengths are stored as logarithms so that they stay positive; λ (s⁻²) is signed.
#[derive(Debug, Clone)]
struct Model {
    one_sided: bool,
    t_ref: f64,
    /// [z, d, ln A, ln p, λ, ln A0, ln p0, t_r, t_0, …, t_{m−1}]
    q: Vec<f64>,
}

const IZ: usize = 0;
const ID: usize = 1;
const IA: usize = 2;
const IP: usize = 3;
const IL: usize = 4;
const IA0: usize = 5;
const IP0: usize = 6;
const ITR: usize = 7;
const IT0: usize = 8;

impl Model {
    fn m(&self) -> usize {
        self.q.len() - IT0
    }
    fn impact(&self, k: usize) -> f64 {
        self.q[IT0 + k]
    }
    fn zero_line(&self, t: f64) -> f64 {
        self.q[IZ] + self.q[ID] * (t - self.t_ref)
    }
    fn valid(&self) -> bool {
        let tr = self.q[ITR];
        let mut prev = tr;
        for k in 0..self.m() {
            let t = self.impact(k);
            if t.partial_cmp(&prev) != Some(std::cmp::Ordering::Greater) {
                return false;
            }
            prev = t;
        }
        self.q.iter().all(|v| v.is_finite())
    }

    /// Segment index owning t: 0 for t < t_0 (release arc and hold), k for
    /// t_{k−1} ≤ t < t_k; None past the last impact.
    fn owner(&self, t: f64) -> Option<usize> {
        let k = self.q[IT0..].partition_point(|&b| b <= t);
        (k < self.m()).then_some(k)
    }

    /// L θ of segment s at t and its time derivative (the zero line excluded).
    ///
    /// - release arc (s = 0): L θ = A0 (1 − cosh(p0 (t − t_r)) / cosh(p0 (t_0 − t_r)))
    ///   after the release, constant before it (the wall is held);
    /// - gravity side (outward; inward in two-sided rocking, with −A):
    ///   L θ = ±A (1 − cosh(p (t − t_m)) / cosh(p T/2)), T = t_k − t_{k−1};
    /// - inward side of one-sided rocking, centre C = A p²/λ, ω = √λ:
    ///   L θ = C (1 − cos(ω (t − t_m)) / cos(ω T/2)).
    fn segment(&self, s: usize, t: f64) -> (f64, f64) {
        if s == 0 {
            let (a0, p0, tr, t0) = (self.q[IA0].exp(), self.q[IP0].exp(), self.q[ITR], self.q[IT0]);
            let c = (p0 * (t0 - tr)).cosh();
            let tau = (t - tr).max(0.0);
            return (a0 * (1.0 - (p0 * tau).cosh() / c), -a0 * p0 * (p0 * tau).sinh() / c);
        }
        let (ta, tb) = (self.impact(s - 1), self.impact(s));
        let (tm, half) = (0.5 * (ta + tb), 0.5 * (tb - ta));
        let tau = t - tm;
        let a = self.q[IA].exp();
        // p_e is tied to the release arc's rate: the short arcs after it only see the
        // gravity term A p² (their curvature at θ = 0), so p and A are not
        // separable there.
        let p = self.q[IP0].exp();
        let inward = s % 2 == 1;
        if inward && self.one_sided {
            let (g, dg) = spring_arc(self.q[IL], tau, half);
            let ap2 = a * p * p;
            (-ap2 * g, -ap2 * dg)
        } else {
            let sign = if inward { -1.0 } else { 1.0 };
            let den = (p * half).cosh();
            (sign * a * (1.0 - (p * tau).cosh() / den), -sign * a * p * (p * tau).sinh() / den)
        }
    }

    /// Modelled reading at t (L θ space) and its slope.
    fn eval(&self, t: f64) -> Option<(f64, f64)> {
        let s = self.owner(t)?;
        let (f, df) = self.segment(s, t);
        Some((self.zero_line(t) + f, df + self.q[ID]))
    }

    fn residuals(&self, t: &[f64], y: &[f64], out: &mut Vec<f64>) -> bool {
        out.clear();
        if !self.valid() {
            return false;
        }
        if self.one_sided && self.q[IL] > 0.0 {
            // The inward arc must stay below a quarter period (ω T/2 < π/2).
            let w = self.q[IL].sqrt();
            for s in (1..self.m()).step_by(2) {
                if w * 0.5 * (self.impact(s) - self.impact(s - 1)) >= std::f64::consts::FRAC_PI_2 {
                    return false;
                }
            }
        }
        for (ti, yi) in t.iter().zip(y) {
            match self.eval(*ti) {
                Some((m, _)) => out.push(yi - m),
                None => out.push(0.0),
            }
        }
        true
    }

    /// Velocity (mm/s) just before and just after impact k.
    fn speeds(&self, k: usize) -> (f64, Option<f64>) {
        let tk = self.impact(k);
        let before = self.segment(k, tk).1 + self.q[ID];
        let after = (k + 1 < self.m()).then(|| self.segment(k + 1, tk).1 + self.q[ID]);
        (before, after)
    }
}

/// The inward arc of one-sided rocking between two impacts, per unit A p²:
/// g = (cos(√λ τ) − cos(√λ h)) / (λ cos(√λ h)) with h = T/2 (so L θ = −A p² g),
/// and dg/dτ; cosh for λ < 0 (gravity stronger than the spring) and the series
/// (h² − τ²)/2 + λ [(h² − τ²) h²/4 − (h⁴ − τ⁴)/24] near λ = 0, so the arc is smooth
/// in λ across 0.
fn spring_arc(l: f64, tau: f64, h: f64) -> (f64, f64) {
    if (l * h * h).abs() < 1e-4 {
        let (h2, t2) = (h * h, tau * tau);
        let g = 0.5 * (h2 - t2) + l * ((h2 - t2) * h2 / 4.0 - (h2 * h2 - t2 * t2) / 24.0);
        let dg = -tau + l * (-tau * h2 / 2.0 + tau * t2 / 6.0);
        (g, dg)
    } else if l > 0.0 {
        let w = l.sqrt();
        let den = (w * h).cos();
        (((w * tau).cos() - den) / (l * den), -(w * tau).sin() / (w * den))
    } else {
        let v = (-l).sqrt();
        let den = (v * h).cosh();
        (((v * tau).cosh() - den) / (l * den), -(v * tau).sinh() / (v * den))
    }
}

/// Fit a [`Model`] by Levenberg–Marquardt ([`crate::fit`]) over its free
/// parameters (all but p, which is tied to p0, the drift, which is fixed by the
/// final rest line, and λ in two-sided rocking). Returns the fitted model and its
/// residual sum of squares.
fn fit_model(model: Model, t: &[f64], y: &[f64], max_iter: usize) -> Option<(Model, f64)> {
    let free: Vec<usize> = (0..model.q.len())
        .filter(|&j| j != IP && j != ID && (j != IL || model.one_sided))
        .collect();
    let with = |qf: &[f64]| {
        let mut m = model.clone();
        for (k, &j) in free.iter().enumerate() {
            m.q[j] = qf[k];
        }
        m
    };
    let resid = |qf: &[f64]| {
        let mut r = Vec::with_capacity(t.len());
        with(qf).residuals(t, y, &mut r).then_some(r)
    };
    let q0: Vec<f64> = free.iter().map(|&j| model.q[j]).collect();
    let steps: Vec<f64> = free
        .iter()
        .map(|&j| match j {
            _ if j >= ITR => 1e-6,
            IL => 1e-6 * model.q[j].abs().max(1.0),
            _ => 1e-7 * model.q[j].abs().max(1e-3),
        })
        .collect();
    let res = crate::fit::levenberg_marquardt(&q0, &steps, max_iter, &resid)?;
    Some((with(&res.q), res.cost))
}

/// Result of the global fit, in the form the analysis reports.
#[derive(Debug, Clone)]
struct SegmentFit {
    model: Model,
    rms: f64,
    lever_mm: f64,
    rest: f64,
}

impl SegmentFit {
    #[allow(clippy::too_many_arguments)]
    fn run(
        t: &[f64],
        x: &[f64],
        rest: f64,
        _sigma: f64,
        departure: usize,
        crossings: &[f64],
        phys: &Physics,
        n_peaks: usize,
    ) -> Result<SegmentFit, PeakError> {
        let lever = phys.lever_arm_mm;
        let m = crossings.len().min(n_peaks + 1);
        let one_sided = phys.rocking == Rocking::OneSided;
        // Window: from a little before the release to the last impact used.
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        let t_dep = t[departure];
        let t0 = crossings[0];
        let start_t = t_dep - 0.5 * (t0 - t_dep).max(10.0 * dt);
        let end_t = crossings[m - 1] - 0.25 * dt;
        let i0 = t.partition_point(|&v| v < start_t);
        let i1 = t.partition_point(|&v| v <= end_t);
        let tw = &t[i0..i1];
        // L θ from the sensor's L sin θ.
        let yw: Vec<f64> = x[i0..i1]
            .iter()
            .map(|&v| rest + lever * ((v - rest) / lever).clamp(-1.0, 1.0).asin())
            .collect();
        if tw.len() < 3 * m + 8 {
            return Err(PeakError::Fit(format!("only {} samples in the rocking window", tw.len())));
        }
        // Starting values from the geometry and the crossings.
        let hold = median(&yw[..(t.partition_point(|&v| v < t_dep) - i0).max(1)]) - rest;
        let p = phys.p_guess;
        let a = lever * 0.15;
        let h0 = hold.max(1e-3);
        let a0 = a.max(1.5 * h0);
        let tr = t0 - ((a0 / (a0 - h0)).acosh() / p).min(t0 - start_t - dt);
        let mut q = vec![rest, 0.0, a.ln(), p.ln(), 10.0 * p * p, a0.ln(), p.ln(), tr];
        q.extend_from_slice(&crossings[..m]);
        let base = Model { one_sided, t_ref: t0, q };
        let starts: Vec<f64> = if one_sided {
            vec![-0.5, 0.5, 3.0, 8.0, 15.0, 30.0, 60.0]
        } else {
            vec![1.0]
        };
        let mut best: Option<(Model, f64)> = None;
        for s in starts {
            let mut mdl = base.clone();
            mdl.q[IL] = s * p * p;
            // Keep the inward arcs below a quarter period at the start.
            if one_sided && s > 0.0 {
                let w = (s * p * p).sqrt();
                let longest = (1..m).step_by(2).map(|k| crossings[k] - crossings[k - 1]).fold(0.0, f64::max);
                if w * 0.5 * longest >= 1.5 {
                    continue;
                }
            }
            if let Some((fit, cost)) = fit_model(mdl, tw, &yw, 60) {
                if best.as_ref().is_none_or(|b| cost < b.1) {
                    best = Some((fit, cost));
                }
            }
        }
        let (model, cost) = best.ok_or_else(|| PeakError::Fit("no starting point gave a valid model".into()))?;
        Ok(SegmentFit {
            model,
            rms: (cost / tw.len() as f64).sqrt(),
            lever_mm: lever,
            rest,
        })
    }

    fn release_time(&self) -> f64 {
        self.model.q[ITR]
    }

    fn p(&self) -> f64 {
        self.model.q[IP0].exp()
    }

    fn lambda(&self) -> Option<f64> {
        self.model.one_sided.then(|| self.model.q[IL])
    }

    fn impacts(&self) -> Vec<Impact> {
        (0..self.model.m())
            .map(|k| {
                let (before, after) = self.model.speeds(k);
                Impact {
                    k,
                    time_s: self.model.impact(k),
                    entering: if k % 2 == 0 { Side::Inward } else { Side::Outward },
                    v_before_mm_s: before,
                    v_after_mm_s: after,
                }
            })
            .collect()
    }

    /// Replace the velocity inside the fitted window by the fit's derivative.
    fn fill_velocity(&self, t: &[f64], v: &mut [f64]) {
        let tr = self.release_time();
        for (i, &ti) in t.iter().enumerate() {
            if ti >= tr {
                if let Some((_, s)) = self.model.eval(ti) {
                    v[i] = s;
                }
            }
        }
    }

    /// Fitted displacement (back in sensor space, L sin θ) and velocity on a grid of
    /// 200 points per segment.
    fn curve(&self) -> Vec<(f64, f64, f64)> {
        let mut out = Vec::new();
        let mut start = self.release_time();
        for k in 0..self.model.m() {
            let end = self.model.impact(k);
            for q in 0..200 {
                let tq = start + (end - start) * q as f64 / 200.0;
                if let Some((lt, v)) = self.model.eval(tq) {
                    let x = self.rest + self.lever_mm * ((lt - self.rest) / self.lever_mm).sin();
                    out.push((tq, x, v));
                }
            }
            start = end;
        }
        out
    }
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
