//! The restitution law fitted by replay (issue 20): each test replayed with the
//! rocking solver under the law r(a) = r∞ − c g(a), g(a) = 1/√(a (2 − a))
//! ([`crate::restitution_law`], one law per side; e = min(1, r(side, a) e_H) at
//! each impact with a the apex |θ|/α of the half-cycle it ends: paper Eq. 1 with
//! the impact rule of Eqs. 2 and 5 read at the amplitude, [`crate::solver::impact`]),
//! over a window long enough to span amplitude, and fitted to the measured
//! displacement by Levenberg–Marquardt ([`crate::fit`]).
//!
//! # The window
//! From just before the release through every half-cycle that stands clear of the
//! noise: the rest-line crossings of the displacement (hysteresis 3 σ) while the
//! half-cycle that a crossing ends is at least [`MIN_APEX_SIGMA`] σ tall, at most
//! [`MAX_LAW_IMPACTS`]; the window ends half a half-cycle after the last such
//! crossing. The constant-pair calibration ([`crate::calibrate`]) replays only the
//! first six impacts, whose amplitudes span too little to tell r∞ from c.
//!
//! # The fit, per test
//! 1. The constant pair by replay over the long window (unknowns e_in, e_out, or
//!    one e two-sided, and the nuisance of [`crate::calibrate`]: release offset,
//!    zero offset, p² factor, one-sided the inward spring), started from the
//!    short window's fit.
//! 2. The law by replay over the same window: (r∞, c) per side (one pair,
//!    two-sided) and the nuisance, started from 1 with c = 0.
//!
//! Unweighted least squares on the displacement (mm); the parameters' covariance
//! s² (JᵀJ)⁻¹ ([`crate::fit`]) treats the residuals as independent, which model
//! misfit makes them not: the u are lower bounds.
//!
//! # Whether the replay separates r∞ from c
//! A side keeps the law where the fitted speed loss is positive and stands clear
//! of zero: c / u(c) ≥ [`Z_SEPARATE`] (two-sided p = 0.01). Otherwise the replay
//! cannot separate them over the window's amplitudes (or finds no speed loss), and
//! the side is the constant by replay, with the reason. The same test is made on
//! the campaign: the mean of the tests' (r∞, c) (unweighted, as the constant
//! calibration's means; covariance the tests' sample covariance / n, or the one
//! test's own), against the mean of the tests' constants by replay.
//!
//! The replay fits every side with the free-arc shape g(a) = 1/√(a (2 − a))
//! ([`Shape::Free`]), one-sided outward included: the push shape 1/a
//! ([`crate::restitution_law`]) is the law from the readings' alone.
//!
//! No crate replays rocking: the solver is ours ([`crate::solver`]); the fit is
//! the calibration's own Levenberg–Marquardt.

use std::sync::Arc;

use crate::calibrate::{nuisance_of, replay_with, steps_nuisance, window_to, CampaignInput, Geometry, Nuisance, TestFit, TestWindow};
use crate::fit::{least_squares, FitResult, FitStop};
use crate::reduction::Reduced;
use crate::restitution_law::{speed_shape, LawForm, LawParameters, PushSpeed, RestitutionLaw, Shape, SideLaw, AMPLITUDE_FLOOR};
use crate::solver::impact::ImpactLaw;

/// How the calibration fits the restitution law (issue 20; `law_by_replay` in
/// summary.json, the details in `law_replay`).
pub const LAW_BY_REPLAY: &str = "fitted by replay: each included test replayed with the solver under r(a) = r_inf - c g(a) per side over every half-cycle above 20 noise sigma (law_replay; a side whose speed loss the replay cannot separate from r_inf keeps its constant by replay over the same window, with the reason)";

/// [`crate::calibrate::calibrate`], then the restitution law by replay over its
/// included tests.
pub fn calibrate_with_law(c: &CampaignInput, n_impacts: usize) -> (crate::calibrate::Calibration, LawReplay) {
    let cal = crate::calibrate::calibrate(c, n_impacts);
    let law = fit_law_by_replay(c, &cal.tests, &cal.included, cal.e_housner);
    (cal, law)
}

/// Half-cycles less tall than this many σ of the noise end the window.
pub const MIN_APEX_SIGMA: f64 = 20.0;
/// The most impacts a law window holds.
pub const MAX_LAW_IMPACTS: usize = 24;
/// c / u(c) at or above which the replay separates the speed loss from r∞.
pub const Z_SEPARATE: f64 = 2.576;
/// The u of the change of r across a window's amplitudes, u(c) (g(a_min) −
/// g(a_max)), above which a speed loss not told from zero is called "not
/// separated" rather than "none found".
pub const MAX_TREND_U: f64 = 0.02;
/// Iterations of each Levenberg–Marquardt fit.
const MAX_ITER: usize = 60;

/// One half-cycle of a test: the crossing that ends it (s) and its apex |x| (mm).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HalfCycle {
    pub crossing_s: f64,
    pub apex_mm: f64,
}

/// The rest-line crossings of `x` (zero at rest) after `release_s`, with the apex
/// of each half-cycle they end, while that apex is at least `tall` (hysteresis
/// `h`: a crossing counts once x is beyond −h on the other side), at most `max`.
pub fn half_cycles(t: &[f64], x: &[f64], release_s: f64, h: f64, tall: f64, max: usize) -> Vec<HalfCycle> {
    let i0 = t.partition_point(|&v| v < release_s);
    let mut out = Vec::new();
    let Some(&x0) = x.get(i0) else { return out };
    let mut s = if x0 >= 0.0 { 1.0 } else { -1.0 };
    let (mut apex, mut last) = (0.0f64, i0);
    for i in i0..x.len().min(t.len()) {
        let v = s * x[i];
        if v > 0.0 {
            apex = apex.max(v);
            last = i;
        } else if v < -h {
            if apex < tall || last + 1 >= x.len() {
                break;
            }
            let (xa, xb) = (x[last], x[last + 1]);
            let f = if xa != xb { xa / (xa - xb) } else { 0.5 };
            out.push(HalfCycle {
                crossing_s: t[last] + f * (t[last + 1] - t[last]),
                apex_mm: apex,
            });
            if out.len() >= max {
                break;
            }
            s = -s;
            apex = -v;
            last = i;
        }
    }
    out
}

/// The law window of a reduced test and its half-cycles (module docs), None with
/// fewer than three crossings.
pub fn law_window(id: &str, r: &Reduced, lever_mm: f64) -> Option<(TestWindow, Vec<HalfCycle>)> {
    let a = &r.analysis;
    let sigma = a.noise_mm.max(1e-6);
    let hc = half_cycles(
        &r.log.time_s,
        &a.displacement_mm,
        a.release_time_s,
        3.0 * sigma,
        MIN_APEX_SIGMA * sigma,
        MAX_LAW_IMPACTS,
    );
    if hc.len() < 3 {
        return None;
    }
    let n = hc.len();
    let gap = hc[n - 1].crossing_s - hc[n - 2].crossing_s;
    Some((window_to(id, r, lever_mm, hc[n - 1].crossing_s + 0.5 * gap), hc))
}

/// The parameters of a law replay: (r∞, c) once (two-sided) or per side, then
/// each test's nuisance ([`Nuisance`]).
#[derive(Debug, Clone, Copy)]
struct LawPacking {
    shared: bool,
    n_nuisance: usize,
}

impl LawPacking {
    fn n_law(&self) -> usize {
        if self.shared {
            2
        } else {
            4
        }
    }
    /// (r∞, c) inward and outward.
    fn sides(&self, q: &[f64]) -> ([f64; 2], [f64; 2]) {
        let i = [q[0], q[1]];
        (i, if self.shared { i } else { [q[2], q[3]] })
    }
    fn nuisance<'a>(&self, q: &'a [f64]) -> Nuisance<'a> {
        Nuisance(&q[self.n_law()..self.n_law() + self.n_nuisance])
    }
    /// The law of q, None outside 0 < r∞ e_H < 1.5, |c| < 1.
    fn law(&self, q: &[f64], e_h: f64) -> Option<RestitutionLaw> {
        let (i, o) = self.sides(q);
        let ok = |s: [f64; 2]| s[0] > 0.0 && s[0] * e_h < crate::calibrate::E_DOMAIN && s[1].abs() < 1.0;
        if !(ok(i) && ok(o)) {
            return None;
        }
        let side = |s: [f64; 2]| SideLaw {
            r_inf: s[0],
            c: s[1],
            cov: [[0.0; 2]; 2],
            g: Shape::Free,
            energy: None,
        };
        Some(RestitutionLaw {
            form: LawForm::SpeedLoss,
            parameters: LawParameters {
                inward: side(i),
                outward: side(o),
                shared: self.shared,
                amplitude_min: AMPLITUDE_FLOOR,
                amplitude_max: 1.0,
                inward_amplitude_min: None,
                observed: None,
                push_speed: None,
            },
        })
    }
}

/// The modelled readings of a window under the law of q.
fn replay_law(w: &TestWindow, geom: &Geometry, e_h: f64, pack: LawPacking, q: &[f64]) -> Option<Vec<f64>> {
    let law = pack.law(q, e_h)?;
    let impact = ImpactLaw::new(Arc::new(law), e_h);
    replay_with(w, geom, 1.0, 1.0, Some(impact), pack.nuisance(q))
}

/// Measured − modelled.
fn minus(w: &TestWindow, m: Option<Vec<f64>>) -> Option<Vec<f64>> {
    m.map(|m| w.x_mm.iter().zip(&m).map(|(a, b)| a - b).collect())
}

/// One side of a law fit by replay: the parameters, their covariance, and whether
/// the replay separates them (module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SideReplay {
    /// "in", "out", or "both" (two-sided: one law).
    pub side: &'static str,
    pub r_inf: f64,
    pub c: f64,
    pub cov: [[f64; 2]; 2],
    /// Correlation of r∞ and c (None where either has no spread).
    pub correlation: Option<f64>,
    /// c / u(c); None where u(c) is 0 or undefined (the data do not constrain c).
    pub z: Option<f64>,
    /// The constant by replay over the same window (r = e/e_H) and its u.
    pub constant_r: f64,
    pub constant_u: f64,
    /// Whether the law is kept (else the constant, for `reason`).
    pub separated: bool,
    pub reason: Option<String>,
}

/// Why c = `c` ± `u1` (c/u = `z` < [`Z_SEPARATE`]) is not kept: the replay
/// cannot separate r∞ from c, or finds no speed loss (the change of r across the
/// amplitudes is then within [`MAX_TREND_U`]).
fn not_separated(c: f64, u1: f64, z: f64, correlation: Option<f64>, span: (f64, f64)) -> String {
    let trend_u = u1 * (speed_shape(span.0) - speed_shape(span.1));
    if trend_u > MAX_TREND_U {
        format!(
            "the replay cannot separate r_inf from c over a = {:.3}–{:.3}: c = {c:.2e} ± {u1:.2e} (c/u = {z:.2} < {Z_SEPARATE}; correlation of r_inf and c {}; the change of r across these amplitudes is uncertain by ± {trend_u:.3})",
            span.0,
            span.1,
            correlation.map_or("undefined".to_string(), |c| format!("{c:.3}"))
        )
    } else {
        format!(
            "the replay finds no speed loss over a = {:.3}–{:.3}: c = {c:.2e} ± {u1:.2e} (c/u = {z:.2} < {Z_SEPARATE}; the change of r across these amplitudes ± {trend_u:.3})",
            span.0, span.1
        )
    }
}

/// The verdict of one side from its law and its constant (module docs).
fn verdict(side: &'static str, law: [f64; 2], cov: [[f64; 2]; 2], constant: (f64, f64), span: (f64, f64)) -> SideReplay {
    let (u0, u1) = (cov[0][0].max(0.0).sqrt(), cov[1][1].max(0.0).sqrt());
    let correlation = (u0 > 0.0 && u1 > 0.0).then(|| cov[0][1] / (u0 * u1));
    let z = (u1 > 0.0).then(|| law[1] / u1).filter(|z| z.is_finite());
    let reason = match z {
        None => Some("the replay gives c no uncertainty (the data do not constrain it)".to_string()),
        Some(_) if law[1] <= 0.0 => Some(format!(
            "the replay's speed loss is not positive (c = {:.4} ± {:.4}): no loss growing as the amplitude falls",
            law[1], u1
        )),
        Some(z) if z < Z_SEPARATE => Some(not_separated(law[1], u1, z, correlation, span)),
        Some(_) => None,
    };
    SideReplay {
        side,
        r_inf: law[0],
        c: law[1],
        cov,
        correlation,
        z,
        constant_r: constant.0,
        constant_u: constant.1,
        separated: reason.is_none(),
        reason,
    }
}

/// The law by replay of one test.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TestLawReplay {
    pub id: String,
    /// Impacts in the window and the amplitudes a = |θ|/α of the half-cycles they end.
    pub impacts: usize,
    pub amplitude_min: f64,
    pub amplitude_max: f64,
    pub t_end_s: f64,
    /// RMS residual (mm) of the constant pair and of the law over the window.
    pub constant_rms_mm: f64,
    pub law_rms_mm: f64,
    pub iterations: usize,
    pub stop: FitStop,
    /// One entry two-sided ("both"), else "in" and "out".
    pub sides: Vec<SideReplay>,
}

/// The 2×2 covariance of parameters (i, i + 1).
fn block(res: &FitResult, i: usize) -> [[f64; 2]; 2] {
    res.covariance
        .as_ref()
        .map_or([[f64::NAN; 2]; 2], |c| [[c[(i, i)], c[(i, i + 1)]], [c[(i + 1, i)], c[(i + 1, i + 1)]]])
}

/// The constant pair by replay over a window, started from `start` (the short
/// window's fit): (e_in, e_out, their u, RMS mm, nuisance).
fn constant_over(w: &TestWindow, geom: &Geometry, start: &TestFit, shared: bool) -> Option<([f64; 4], f64, Vec<f64>)> {
    let n_e = if shared { 1 } else { 2 };
    let mut q0 = if shared { vec![start.e_in] } else { vec![start.e_in, start.e_out] };
    q0.extend(nuisance_of(start, geom));
    let mut steps = vec![1e-7; n_e];
    steps.extend(steps_nuisance(geom));
    let resid = |q: &[f64]| {
        let (ei, eo) = if shared { (q[0], q[0]) } else { (q[0], q[1]) };
        minus(w, crate::calibrate::replay(w, geom, ei, eo, Nuisance(&q[n_e..])))
    };
    let res = least_squares(&q0, &steps, MAX_ITER, &resid).ok()?;
    let se = |i: usize| res.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)].max(0.0).sqrt());
    let (ei, eo) = if shared { (res.q[0], res.q[0]) } else { (res.q[0], res.q[1]) };
    let rms = (res.cost / w.x_mm.len() as f64).sqrt();
    Some(([ei, eo, se(0), se(n_e - 1)], rms, res.q[n_e..].to_vec()))
}

/// The law by replay of one test whose constant fit over its first impacts is
/// `start`; None where a replay fails.
pub fn fit_test_law(w: &TestWindow, hc: &[HalfCycle], geom: &Geometry, e_h: f64, start: &TestFit) -> Option<TestLawReplay> {
    let shared = !geom.one_sided;
    let (cst, cst_rms, nu) = constant_over(w, geom, start, shared)?;
    let pack = LawPacking {
        shared,
        n_nuisance: nu.len(),
    };
    let mut q0 = if shared {
        vec![cst[0] / e_h, 0.0]
    } else {
        vec![cst[0] / e_h, 0.0, cst[1] / e_h, 0.0]
    };
    q0.extend(&nu);
    let mut steps = vec![1e-7; pack.n_law()];
    steps.extend(steps_nuisance(geom));
    let resid = |q: &[f64]| minus(w, replay_law(w, geom, e_h, pack, q));
    let res = least_squares(&q0, &steps, MAX_ITER, &resid).ok()?;
    let amps: Vec<f64> = hc.iter().map(|h| (h.apex_mm / w.lever_mm).clamp(0.0, 1.0).asin() / geom.alpha).collect();
    let span = (
        amps.iter().copied().fold(f64::INFINITY, f64::min),
        amps.iter().copied().fold(0.0, f64::max),
    );
    let (li, lo) = pack.sides(&res.q);
    let sides = if shared {
        vec![verdict("both", li, block(&res, 0), (cst[0] / e_h, cst[2] / e_h), span)]
    } else {
        vec![
            verdict("in", li, block(&res, 0), (cst[0] / e_h, cst[2] / e_h), span),
            verdict("out", lo, block(&res, 2), (cst[1] / e_h, cst[3] / e_h), span),
        ]
    };
    Some(TestLawReplay {
        id: w.id.clone(),
        impacts: hc.len(),
        amplitude_min: span.0,
        amplitude_max: span.1,
        t_end_s: w.t_end,
        constant_rms_mm: cst_rms,
        law_rms_mm: (res.cost / w.x_mm.len() as f64).sqrt(),
        iterations: res.iterations,
        stop: res.stop,
        sides,
    })
}

/// The campaign's law by replay.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LawReplay {
    /// The law the replays support (a side that the replay cannot separate is its
    /// constant by replay); None without a test.
    pub law: Option<RestitutionLaw>,
    /// Per side: the mean of the tests' (r∞, c) and the verdict.
    pub sides: Vec<SideReplay>,
    pub tests: Vec<TestLawReplay>,
    /// Tests with no law replay, and why.
    pub failed: Vec<(String, String)>,
    /// What the law can vouch for, in words.
    pub notes: Vec<String>,
    /// The law by replay read at the amplitude of every impact the reduction
    /// read (included tests): (impacts, RMS of law − reading, mean of it).
    pub against_readings: Option<(usize, f64, f64)>,
    /// Whether that RMS is within [`MAX_READINGS_RMS`].
    pub agrees_with_readings: Option<bool>,
}

/// The RMS difference between the law by replay and the per-impact readings
/// beyond which the replay is reported as not following the wall: the largest u
/// of a reported reading ([`crate::impacts::MAX_LATE_R_U`]); a law farther than
/// that from the readings on average is beyond what any of them could allow.
pub const MAX_READINGS_RMS: f64 = crate::impacts::MAX_LATE_R_U;

/// (n, RMS, mean) of law − r over the per-impact readings of the included tests.
fn against_readings(c: &CampaignInput, included: &[String], law: &RestitutionLaw) -> Option<(usize, f64, f64)> {
    let d: Vec<f64> = c
        .tests
        .iter()
        .filter(|t| included.iter().any(|i| i == t.id))
        .filter_map(|t| t.reduced.ok())
        .flat_map(|r| r.impacts.impacts.iter().map(|i| law.r(i.side, i.amplitude_over_alpha) - i.r))
        .collect();
    if d.is_empty() {
        return None;
    }
    let n = d.len() as f64;
    Some((d.len(), (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt(), d.iter().sum::<f64>() / n))
}

/// Mean and covariance of the mean of 2-vectors (sample covariance / n; with one
/// vector, its own covariance `own`).
fn mean_cov(v: &[[f64; 2]], own: [[f64; 2]; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let n = v.len() as f64;
    let m = [v.iter().map(|x| x[0]).sum::<f64>() / n, v.iter().map(|x| x[1]).sum::<f64>() / n];
    if v.len() < 2 {
        return (m, own);
    }
    let mut c = [[0.0; 2]; 2];
    for x in v {
        for i in 0..2 {
            for j in 0..2 {
                c[i][j] += (x[i] - m[i]) * (x[j] - m[j]) / ((n - 1.0) * n);
            }
        }
    }
    (m, c)
}

/// Mean and standard error of the mean (one value: its own u).
fn mean_se(v: &[(f64, f64)]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().map(|x| x.0).sum::<f64>() / n;
    if v.len() < 2 {
        return (m, v[0].1);
    }
    let var = v.iter().map(|x| (x.0 - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The campaign's verdict on side `k` (index in each test's `sides`).
fn campaign_side(tests: &[TestLawReplay], k: usize, span: (f64, f64)) -> SideReplay {
    let s: Vec<&SideReplay> = tests.iter().map(|t| &t.sides[k]).collect();
    let (m, cov) = mean_cov(&s.iter().map(|x| [x.r_inf, x.c]).collect::<Vec<_>>(), s[0].cov);
    let cst = mean_se(&s.iter().map(|x| (x.constant_r, x.constant_u)).collect::<Vec<_>>());
    verdict(s[0].side, m, cov, cst, span)
}

/// The law the verdicts give; a one-sided law carries the campaign's Ω/p
/// (`push_speed`, [`CampaignInput::push_speed`]): its outward impacts end pushes,
/// and a study that reads it by speed reads them at that Ω/p.
fn law_of(sides: &[SideReplay], span: (f64, f64), push_speed: Option<PushSpeed>) -> RestitutionLaw {
    let side = |s: &SideReplay| {
        if s.separated {
            SideLaw {
                r_inf: s.r_inf,
                c: s.c,
                cov: s.cov,
                g: Shape::Free,
                energy: None,
            }
        } else {
            SideLaw::constant(s.constant_r, s.constant_u)
        }
    };
    let (i, o) = (side(&sides[0]), side(sides.last().unwrap_or(&sides[0])));
    let any = sides.iter().any(|s| s.separated);
    let shared = sides.len() == 1;
    let strip = |l: SideLaw| {
        if any {
            l
        } else {
            SideLaw::constant(l.r_inf, l.cov[0][0].max(0.0).sqrt())
        }
    };
    RestitutionLaw {
        form: if any { LawForm::SpeedLoss } else { LawForm::Constant },
        parameters: LawParameters {
            inward: strip(i),
            outward: strip(o),
            shared,
            amplitude_min: span.0.max(AMPLITUDE_FLOOR),
            amplitude_max: span.1.clamp(span.0.max(AMPLITUDE_FLOOR), 1.0),
            inward_amplitude_min: None,
            observed: None,
            push_speed: push_speed.filter(|_| !shared),
        },
    }
}

/// Notes on what the law by replay vouches for.
fn notes(sides: &[SideReplay], span: (f64, f64)) -> Vec<String> {
    sides
        .iter()
        .map(|s| match &s.reason {
            None => format!(
                "side {}: r(a) = {:.4} − {:.4} g(a) by replay over a = {:.3}–{:.3} ({}); extrapolated outside",
                s.side,
                s.r_inf,
                s.c,
                span.0,
                span.1,
                law_ends(s.r_inf, s.c, span)
            ),
            Some(why) => format!("side {}: constant r = {:.4} ± {:.4} by replay: {why}", s.side, s.constant_r, s.constant_u),
        })
        .collect()
}

/// The law r∞ − c g(a) at both ends of `span`, in words. Where it falls to 0
/// inside the span (the solver then stops the wall: r is clamped at 0), the
/// amplitude at which it does is said instead of a row of zeros:
/// g(a₀) = r∞/c ⇔ a₀ = 1 − √(1 − (c/r∞)²).
fn law_ends(r_inf: f64, c: f64, span: (f64, f64)) -> String {
    let r = |a: f64| r_inf - c * speed_shape(a);
    let top = format!("r = {:.3} at a = {:.3}", r(span.1).max(0.0), span.1);
    if r(span.0) > 0.0 || r_inf <= 0.0 || c <= 0.0 {
        return format!("r = {:.3} at a = {:.3}, {top}", r(span.0).max(0.0), span.0);
    }
    let a0 = Shape::Free.eval_inverse(r_inf / c);
    format!("{top}; it falls to 0 at a = {a0:.4}, inside the span: below that the law stops the wall")
}

/// Fits the law by replay on every included test of a campaign whose constant
/// fits are `fits` (the calibration's, by id).
pub fn fit_law_by_replay(c: &CampaignInput, fits: &[TestFit], included: &[String], e_h: f64) -> LawReplay {
    use rayon::prelude::*;
    let geom = Geometry::of(c.rocking, &c.wall);
    let outcomes: Vec<(String, Result<TestLawReplay, String>)> = c
        .tests
        .par_iter()
        .filter(|t| included.iter().any(|i| i == t.id))
        .map(|t| (t.id.to_string(), test_outcome(t, fits, &geom, e_h)))
        .collect();
    let mut tests = Vec::new();
    let mut failed = Vec::new();
    for (id, o) in outcomes {
        match o {
            Ok(t) => tests.push(t),
            Err(e) => failed.push((id, e)),
        }
    }
    if tests.is_empty() {
        return LawReplay {
            law: None,
            sides: Vec::new(),
            tests,
            failed,
            notes: vec!["no test could be replayed with a law".into()],
            against_readings: None,
            agrees_with_readings: None,
        };
    }
    let span = (
        tests.iter().map(|t| t.amplitude_min).fold(f64::INFINITY, f64::min),
        tests.iter().map(|t| t.amplitude_max).fold(0.0, f64::max),
    );
    let sides: Vec<SideReplay> = (0..tests[0].sides.len()).map(|k| campaign_side(&tests, k, span)).collect();
    let law = law_of(&sides, span, c.push_speed);
    let readings = against_readings(c, included, &law);
    let mut notes = notes(&sides, span);
    if let Some((n, rms, mean)) = readings {
        notes.push(if rms <= MAX_READINGS_RMS {
            format!("the law by replay is within RMS {rms:.3} (mean {mean:+.3}) of the {n} per-impact readings at their amplitudes")
        } else {
            format!("not vouched for: the law by replay is RMS {rms:.3} (mean {mean:+.3}) from the {n} per-impact readings at their amplitudes, beyond {MAX_READINGS_RMS}: the replay's rigid block (with an elastic inward restraint, one-sided) does not follow this wall; use the law from the readings (restitution_law)")
        });
    }
    LawReplay {
        law: Some(law),
        notes,
        sides,
        tests,
        failed,
        against_readings: readings,
        agrees_with_readings: readings.map(|r| r.1 <= MAX_READINGS_RMS),
    }
}

/// The law replay of one included test, or why there is none.
fn test_outcome(t: &crate::calibrate::TestInput, fits: &[TestFit], geom: &Geometry, e_h: f64) -> Result<TestLawReplay, String> {
    let r = t.reduced.map_err(|e| format!("not reduced: {e}"))?;
    let fit = fits.iter().find(|f| f.id == t.id).ok_or("no constant fit to start from")?;
    let (w, hc) = law_window(t.id, r, t.lever_arm_m * 1e3).ok_or("fewer than three half-cycles above the noise")?;
    let law = fit_test_law(&w, &hc, geom, e_h, fit).ok_or_else(|| "the law replay failed (a replay outside the model's domain)".to_string())?;
    let finite = |s: &SideReplay| {
        [s.r_inf, s.c, s.z.unwrap_or(f64::NAN), s.constant_r, s.constant_u]
            .into_iter()
            .chain(s.cov.into_iter().flatten())
            .all(f64::is_finite)
    };
    if !law.sides.iter().all(finite) {
        // A singular information matrix (block() gives NaN) or c without an
        // uncertainty: no number of it can be vouched for, and no output may hold NaN.
        return Err("the law replay does not constrain (r_inf, c): its covariance is singular".into());
    }
    Ok(law)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_law_s_ends_say_where_it_falls_to_zero() {
        let s = super::law_ends(1.0349, 0.0568, (0.001, 0.36));
        assert!(s.contains("falls to 0 at a = 0.0015"), "{s}");
        assert!(!s.contains("r = 0.000"), "{s}");
        let s = super::law_ends(1.0, 0.02, (0.05, 0.36));
        assert!(s.starts_with("r = 0.936 at a = 0.050, r = 0.974 at a = 0.360"), "{s}");
    }

    use super::*;
    use crate::wall::Side;

    /// Crossings with hysteresis, the apex of each half-cycle, and the stop at a
    /// half-cycle below the tall level.
    #[test]
    fn half_cycles_by_hand() {
        let t: Vec<f64> = (0..12).map(|i| i as f64).collect();
        let x = [10.0, 8.0, 2.0, -0.5, 0.4, -6.0, -4.0, 1.0, 5.0, -1.0, -2.0, -2.0];
        let hc = half_cycles(&t, &x, 0.0, 1.0, 3.0, 10);
        // Crossing 0: the chatter at samples 3–4 stays inside h, so the last sample
        // on the first side is 4 (0.4) and the crossing lies between 4 and 5;
        // crossing 1 between 6 and 7 (apex 6); crossing 2 between 8 and 9, counted
        // once x passes −h at sample 10 (apex 5).
        assert_eq!(hc.len(), 3, "{hc:?}");
        assert!((hc[0].crossing_s - (4.0 + 0.4 / 6.4)).abs() < 1e-12);
        assert_eq!(hc[0].apex_mm, 10.0);
        assert!((hc[1].crossing_s - 6.8).abs() < 1e-12);
        assert!((hc[2].crossing_s - (8.0 + 5.0 / 6.0)).abs() < 1e-12);
        assert_eq!(hc[1].apex_mm, 6.0);
        assert_eq!(hc[2].apex_mm, 5.0);
        // A taller level stops before the apex-5 half-cycle.
        assert_eq!(half_cycles(&t, &x, 0.0, 1.0, 5.5, 10).len(), 2);
        assert_eq!(half_cycles(&t, &x, 0.0, 1.0, 3.0, 1).len(), 1);
    }

    /// A one-sided law by replay carries the campaign's Ω/p, so that a study can
    /// read it by speed (its outward impacts end pushes); a two-sided one does
    /// not, and a one-sided law with it passes `readable_by_speed`, where it
    /// would be refused without it once a side changes with the amplitude.
    #[test]
    fn a_one_sided_law_by_replay_carries_the_campaign_push_speed() {
        let q = PushSpeed::of([(0.02, 0.34), (0.03, 0.5)]).unwrap();
        let mut side = super::verdict("in", [0.7, 0.0], [[1e-4, 0.0], [0.0, 1e-8]], (0.7, 0.01), (0.01, 0.3));
        side.separated = false;
        let mut out = side.clone();
        out.side = "out";
        (out.separated, out.r_inf, out.c) = (true, 1.02, 0.004);
        let one = law_of(&[side, out.clone()], (0.01, 0.3), Some(q));
        assert_eq!(one.parameters.push_speed, Some(q));
        assert!(one.ends_a_push(Side::Outward));
        one.readable_by_speed().unwrap();
        let mut bare = one;
        bare.parameters.push_speed = None;
        assert!(bare.readable_by_speed().is_err());
        let two = law_of(&[out], (0.01, 0.3), Some(q));
        assert_eq!(two.parameters.push_speed, None);
        two.readable_by_speed().unwrap();
    }

    /// The campaign mean: sample covariance / n.
    #[test]
    fn mean_and_covariance_of_the_mean() {
        let (m, c) = mean_cov(&[[1.0, 0.0], [3.0, 2.0]], [[9.0; 2]; 2]);
        assert_eq!(m, [2.0, 1.0]);
        assert!((c[0][0] - 1.0).abs() < 1e-15 && (c[0][1] - 1.0).abs() < 1e-15);
        assert_eq!(mean_cov(&[[1.0, 2.0]], [[9.0; 2]; 2]).1, [[9.0; 2]; 2]);
    }

    /// Tests whose c are all the same (the replay left c where it started, as the
    /// outward sides of mujoco-holdout-one-sided did) give the campaign's c no
    /// spread: c/u is undefined, the side keeps its constant with that reason, and
    /// nothing non-finite reaches summary.json (its writer once refused the whole
    /// calibration over `"z": NaN`).
    #[test]
    fn a_side_whose_c_has_no_spread_keeps_its_constant_without_nan() {
        let (m, cov) = super::mean_cov(&[[1.4, 0.0], [1.5, 0.0]], [[0.0; 2]; 2]);
        let s = super::verdict("out", m, cov, (1.45, 0.05), (0.01, 0.03));
        assert_eq!(s.z, None);
        assert!(!s.separated && s.reason.as_deref().unwrap().contains("no uncertainty"), "{:?}", s.reason);
        assert_eq!(serde_json::to_value(&s).unwrap()["z"], serde_json::Value::Null);
    }
}
