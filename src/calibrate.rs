//! Calibration of the coefficients of restitution by replaying each free-vibration
//! test with the rocking solver (paper Eq. 1, free rocking) and fitting the
//! measured displacement by nonlinear least squares (Levenberg–Marquardt, [`fit`]).
//!
//! Per test, the wall above the hinge is a rectangular rocking block (height h −
//! hinge, thickness b: α = atan(b/h'), p² = 3g/(4R)), released from rest at the
//! measured displacement at the release found by `reduce`. Unknowns: e_in and e_out
//! (one e in two-sided rocking) and the nuisance parameters: release-time offset,
//! transducer zero offset, a factor on p² (real walls never match their nominal
//! geometry; SPEC), and in one-sided campaigns the inward spring κ = k/I_0. The
//! modelled reading is z + L sin θ(t). The window runs from just before the release
//! to half-way through the half-cycle after impact N − 1 (N = 6 peaks by default).
//!
//! [`fit`]: crate::fit

use crate::fit::{least_squares, FitError, FitResult, FitStop};
use crate::reduction::Reduced;
use crate::signal::filter::LowPass;
use crate::solver::impact::ImpactLaw;
use crate::solver::{simulate_at, Ground, Restraint, RockingModel, Settings};
use crate::wall::{Rocking, Side, Wall};

/// A reduced test as the calibration takes it (the input edge builds it from a
/// reduced campaign: `rocklab::reduce::CampaignResult::calibration_input`).
#[derive(Debug, Clone, Copy)]
pub struct TestInput<'a> {
    pub id: &'a str,
    pub exclude_from_mean: bool,
    /// Lever arm of the sensor about the hinge, m.
    pub lever_arm_m: f64,
    /// The reduction, or why there is none.
    pub reduced: Result<&'a Reduced, &'a (dyn std::error::Error + Sync)>,
}

/// A reduced campaign as the calibration takes it.
#[derive(Debug, Clone)]
pub struct CampaignInput<'a> {
    pub name: &'a str,
    pub rocking: Rocking,
    pub wall: Wall,
    pub tests: Vec<TestInput<'a>>,
    /// Ω/p of a one-sided campaign's pushes as the reduction measured it (None
    /// two-sided, or with no push read): the law by replay carries it, so that it
    /// can be read by the impact's speed as the law from the readings can.
    pub push_speed: Option<crate::restitution_law::PushSpeed>,
}

/// Why a test has no fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TestFailure {
    /// The reduction failed (its message).
    #[error("not reduced: {0}")]
    NotReduced(String),
    #[error("fewer than {needed} impacts")]
    TooFewImpacts { needed: usize },
    /// No starting point of the κ grid (e at 0.7) gives a replay.
    #[error("the fit failed: no starting point replays the test (the release displacement minus the zero offset is beyond the sensor's lever arm)")]
    NoStart,
    #[error("the fit failed: {0}")]
    Fit(#[from] FitError),
}

impl serde::Serialize for TestFailure {
    /// As its message (summary.json: `"error": "…"`).
    fn serialize<S: serde::Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        ser.collect_str(self)
    }
}

/// The data of one test that the fit uses.
#[derive(Debug, Clone)]
pub struct TestWindow {
    pub id: String,
    pub t: Vec<f64>,
    /// Displacement, mm, outward positive, relative to the final rest line.
    pub x_mm: Vec<f64>,
    pub release_s: f64,
    pub x_release_mm: f64,
    pub lever_mm: f64,
    pub t_end: f64,
    /// The logger's causal low-pass the reduction read this test through
    /// (stated in the manifest or estimated from the log), if any: the replay
    /// is seen through it before it is compared with the samples
    /// ([`through_logger`]).
    pub filter: Option<LowPass>,
}

/// The rocking physics shared by the tests of a campaign.
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    pub alpha: f64,
    pub p2: f64,
    pub one_sided: bool,
}

impl Geometry {
    /// The rocking part above the hinge of a campaign's wall.
    pub fn of(rocking: Rocking, wall: &Wall) -> Geometry {
        let part = wall.rocking_part();
        Geometry {
            alpha: part.slenderness(),
            p2: part.p_squared(),
            one_sided: rocking == Rocking::OneSided,
        }
    }

    /// How many nuisance parameters a test has: [δt, z (mm), ln(p² factor)] and,
    /// one-sided, ln κ.
    fn n_nuisance(&self) -> usize {
        if self.one_sided {
            4
        } else {
            3
        }
    }
}

/// The nuisance parameters of one test, as packed in a parameter vector:
/// [δt (s), z (mm), ln(p² factor), ln κ (one-sided only)].
#[derive(Debug, Clone, Copy)]
pub struct Nuisance<'a>(pub &'a [f64]);

impl Nuisance<'_> {
    /// Offset of the release time, s.
    pub fn release_offset_s(&self) -> f64 {
        self.0[0]
    }
    /// Transducer zero offset z, mm.
    pub fn zero_offset_mm(&self) -> f64 {
        self.0[1]
    }
    /// ln of the factor on p².
    pub fn ln_p2_factor(&self) -> f64 {
        self.0[2]
    }
    /// κ = k/I_0 of the inward spring (s⁻²), one-sided only.
    pub fn kappa(&self) -> Option<f64> {
        self.0.get(3).map(|l| l.exp())
    }
}

/// How a fit packs its parameter vector: the coefficients (e alone when one e
/// holds both ways, else e_in, e_out), then each test's [`Nuisance`].
#[derive(Debug, Clone, Copy)]
struct Packing {
    /// Number of coefficients: 1 or 2.
    n_e: usize,
    /// Nuisance parameters per test.
    n_nuisance: usize,
}

impl Packing {
    fn new(geom: &Geometry, single_e: bool) -> Packing {
        Packing {
            n_e: if single_e { 1 } else { 2 },
            n_nuisance: geom.n_nuisance(),
        }
    }
    /// (e_in, e_out).
    fn coefficients(&self, q: &[f64]) -> (f64, f64) {
        if self.n_e == 1 {
            (q[0], q[0])
        } else {
            (q[0], q[1])
        }
    }
    /// Index in q of e_in and of e_out (the same with one e).
    fn coefficient_indices(&self) -> (usize, usize) {
        (0, self.n_e - 1)
    }
    /// The nuisance of test k.
    fn nuisance<'a>(&self, q: &'a [f64], k: usize) -> Nuisance<'a> {
        let start = self.n_e + k * self.n_nuisance;
        Nuisance(&q[start..start + self.n_nuisance])
    }
}

/// The window of a reduced test holding its first `n_impacts` impacts.
pub fn window(id: &str, r: &Reduced, lever_mm: f64, n_impacts: usize) -> Option<TestWindow> {
    let a = &r.analysis;
    let imp = &a.impacts;
    if imp.len() < n_impacts || n_impacts < 2 {
        return None;
    }
    let last = imp[n_impacts - 1].time_s;
    let gap = last - imp[n_impacts - 2].time_s;
    Some(window_to(id, r, lever_mm, last + 0.5 * gap))
}

/// The window of a reduced test from just before its release to `t_end`.
pub fn window_to(id: &str, r: &Reduced, lever_mm: f64, t_end: f64) -> TestWindow {
    let a = &r.analysis;
    let t0 = a.release_time_s - 0.1;
    let t = &r.log.time_s;
    let i0 = t.partition_point(|&v| v < t0);
    let i1 = t.partition_point(|&v| v <= t_end);
    let j = t.partition_point(|&v| v < a.release_time_s).min(t.len() - 1);
    let x_rel = crate::signal::median(&a.displacement_mm[j.saturating_sub(5)..=j]);
    TestWindow {
        id: id.to_string(),
        t: t[i0..i1].to_vec(),
        x_mm: a.displacement_mm[i0..i1].to_vec(),
        release_s: a.release_time_s,
        x_release_mm: x_rel,
        lever_mm,
        t_end,
        filter: a.response.filter,
    }
}

/// The replay's domain of a coefficient: 0 < e < `E_DOMAIN` (wider than the
/// physical 0–1, so that a fit is not held at 1 and its verdict can see it).
pub const E_DOMAIN: f64 = 1.5;

/// How near the domain's edges (× [`E_DOMAIN`]) a fitted coefficient counts as
/// run to the edge: the least squares stopped against the domain, not at a minimum.
const EDGE: f64 = 1e-3;

/// Why a test's fit is not a measurement of its coefficients, if it is not:
/// a coefficient run to the edge of the replay's domain (0 or [`E_DOMAIN`]), or
/// one above 1 beyond its 95 % interval (an impact that returns more speed than
/// it took: the replay's rigid block does not follow this wall). Such a test is
/// listed but left out of the calibration's means.
pub fn fit_verdict(f: &TestFit) -> Option<String> {
    let shared = f.e_in == f.e_out;
    let sides = [("e_in", f.e_in, f.ci95_e_in), ("e_out", f.e_out, f.ci95_e_out)];
    let why: Vec<String> = sides
        .iter()
        .take(if shared { 1 } else { 2 })
        .filter_map(|&(name, e, ci)| {
            let name = if shared { "e" } else { name };
            if e <= EDGE * E_DOMAIN || e >= (1.0 - EDGE) * E_DOMAIN {
                Some(format!("{name} = {e:.3} is at the edge of the replay's domain (0–{E_DOMAIN})"))
            } else if ci[0] > 1.0 {
                Some(format!(
                    "{name} = {e:.3} (95 % {:.3}–{:.3}) is above 1: an impact cannot return more speed than it took",
                    ci[0], ci[1]
                ))
            } else {
                None
            }
        })
        .collect();
    (!why.is_empty()).then(|| format!("{}: the replay does not follow this wall", why.join("; ")))
}

/// Modelled readings of one test for coefficients (e_in, e_out) and nuisance
/// parameters `nu`; None outside the model's domain (e ∉ (0, 1.5), or a release
/// displacement beyond the lever arm).
pub fn replay(w: &TestWindow, geom: &Geometry, e_in: f64, e_out: f64, nu: Nuisance) -> Option<Vec<f64>> {
    if !(e_in > 0.0 && e_in < E_DOMAIN && e_out > 0.0 && e_out < E_DOMAIN) {
        return None;
    }
    replay_with(w, geom, e_in, e_out, None, nu)
}

/// As [`replay`] with a restitution law applied at every impact instead of
/// (e_in, e_out) where `law` is given (the solver's [`ImpactLaw`]: e = min(1,
/// r(side, a) e_H) with a the apex of the half-cycle that ends).
pub fn replay_with(w: &TestWindow, geom: &Geometry, e_in: f64, e_out: f64, law: Option<ImpactLaw>, nu: Nuisance) -> Option<Vec<f64>> {
    let z = nu.zero_offset_mm();
    let s = (w.x_release_mm - z) / w.lever_mm;
    if s.is_nan() || s.abs() >= 1.0 {
        return None;
    }
    let theta0 = s.asin();
    let model = RockingModel {
        alpha: geom.alpha,
        p2: geom.p2 * nu.ln_p2_factor().exp(),
        i0: 1.0,
        restraint: match nu.kappa() {
            Some(kappa) if geom.one_sided => Restraint::Rotational { k_nm_per_rad: kappa },
            _ => Restraint::None,
        },
        ties: Vec::new(),
        e_in,
        e_out,
        law,
        overturn_limit: std::f64::consts::FRAC_PI_2,
        linearized: false,
    };
    let ground = Ground {
        t0: 0.0,
        dt: 1.0,
        acc: vec![0.0, 0.0],
    };
    let mut settings = Settings::new(w.t_end).with_tolerances(1e-10, 1e-13).without_history();
    settings.max_step = 0.05;
    settings.rest_speed = 1e-9;
    settings.max_steps = replay_step_budget(w.t.len());
    let t_release = w.release_s + nu.release_offset_s();
    let reading = |th: Vec<f64>| -> Vec<f64> { th.iter().map(|t| z + w.lever_mm * t.sin()).collect() };
    match w.filter {
        None => {
            let (_, th) = simulate_at(&model, &ground, t_release, Some([theta0, 0.0]), &settings, &w.t).ok()?;
            Some(reading(th))
        }
        Some(filter) => {
            let (nodes, first) = fine_grid(&w.t, t_release);
            let (_, th) = simulate_at(&model, &ground, t_release, Some([theta0, 0.0]), &settings, &nodes).ok()?;
            Some(through_logger(&filter, &nodes, &reading(th), w.t.len(), first))
        }
    }
}

/// Steps of the fine grid per sample interval in a replay seen through a
/// logger's filter. The reading is taken as linear between nodes: the input's
/// error is at most h²|ẍ|/8 on the arcs and a triangle of area Δv h²/8 at an
/// impact's kink (Δv the speed jump). With h = Δt/16 at 100 Hz, Δv = 1000 mm/s
/// and a Bessel low-pass at 10 Hz (impulse response ≤ 30 s⁻¹) that is at most
/// 0.0015 mm at the output: a twentieth of a 0.03 mm sensor's noise.
const FINE_STEPS: usize = 16;

/// The nodes of a replay seen through a filter: the release, then every sample
/// interval from it on cut into [`FINE_STEPS`]; with the index of the first
/// sample after the release (sample i ≥ first is node (i − first + 1) ×
/// [`FINE_STEPS`]).
fn fine_grid(t: &[f64], t_release: f64) -> (Vec<f64>, usize) {
    let first = t.partition_point(|&v| v <= t_release);
    let mut nodes = Vec::with_capacity((t.len() - first) * FINE_STEPS + 1);
    nodes.push(t_release);
    let mut prev = t_release;
    for &ti in &t[first..] {
        let h = (ti - prev) / FINE_STEPS as f64;
        nodes.extend((1..FINE_STEPS).map(|j| prev + j as f64 * h));
        nodes.push(ti);
        prev = ti;
    }
    (nodes, first)
}

/// The replay's reading seen through the logger's causal low-pass (the model
/// the reducer fits, `peaks::acquisition`): the filter holds the release
/// reading x₀ in steady state until the release, then is driven exactly
/// ([`crate::signal::filter::Modal::advance`]) by the reading taken as linear
/// between the fine nodes. Samples before the release read x₀.
fn through_logger(filter: &LowPass, nodes: &[f64], x: &[f64], samples: usize, first: usize) -> Vec<f64> {
    let modal = filter.modal();
    let mut state = modal.steady_state(x[0]);
    let mut out = vec![x[0]; first];
    out.reserve(samples - first);
    let mut steps = modal.step_coefficients(1.0);
    let mut h_steps = f64::NAN;
    for j in 1..nodes.len() {
        let h = nodes[j] - nodes[j - 1];
        if (h - h_steps).abs() > 1e-9 * h || h_steps.is_nan() {
            steps = modal.step_coefficients(h);
            h_steps = h;
        }
        if h > 0.0 {
            modal.advance(&mut state, &steps, [x[j - 1], (x[j] - x[j - 1]) / h, 0.0, 0.0]);
        }
        if j % FINE_STEPS == 0 {
            out.push(modal.output(&state));
        }
    }
    out
}

/// Integration steps a replay of `samples` log samples may take before it is
/// given up (the replay then fails, and a fit that needs it says so).
/// Measured on the shipped campaigns (demos and MuJoCo, ~14,000 replays):
/// at most 4.6 steps per sample and 1,121 steps per replay. A fit that drives
/// the wall's frequency parameter p² to 10¹⁶ (a mutated log whose time column
/// was scaled by 10⁻³) took 2.1 million steps and 39,000 impacts per replay,
/// and calibrate ran for hours; 50 per sample + 10,000 leaves a margin of ten
/// over the worst measured and bounds such a fit to seconds.
pub fn replay_step_budget(samples: usize) -> usize {
    50 * samples + 10_000
}

/// The fit of one test.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TestFit {
    pub id: String,
    pub e_in: f64,
    pub e_out: f64,
    pub se_e_in: f64,
    pub se_e_out: f64,
    /// 95 % intervals (±1.96 standard errors).
    pub ci95_e_in: [f64; 2],
    pub ci95_e_out: [f64; 2],
    pub release_offset_s: f64,
    pub zero_offset_mm: f64,
    pub p2_factor: f64,
    pub kappa_per_s2: Option<f64>,
    pub rms_mm: f64,
    /// RMS residual over the range of the measured window.
    pub nrmse: f64,
    pub iterations: usize,
    pub stop: FitStop,
    pub samples: usize,
    #[serde(skip)]
    pub replay_mm: Vec<f64>,
}

/// Starting nuisance: no offsets, p² as nominal, κ as given (one-sided).
fn start_nuisance(geom: &Geometry, kappa: f64) -> Vec<f64> {
    let mut q = vec![0.0, 0.0, 0.0];
    if geom.one_sided {
        q.push(kappa.ln());
    }
    q
}

/// The nuisance of a fitted test, packed as [`Nuisance`] reads it (the start
/// of a longer or joint fit).
pub(crate) fn nuisance_of(f: &TestFit, geom: &Geometry) -> Vec<f64> {
    let mut q = vec![f.release_offset_s, f.zero_offset_mm, f.p2_factor.ln()];
    if geom.one_sided {
        q.push(f.kappa_per_s2.unwrap_or(12.0 * geom.p2).ln());
    }
    q
}

/// Finite-difference steps of the nuisance parameters.
pub(crate) fn steps_nuisance(geom: &Geometry) -> Vec<f64> {
    let mut s = vec![1e-6, 1e-5, 1e-7];
    if geom.one_sided {
        s.push(1e-6);
    }
    s
}

/// Residuals (measured − modelled) of the tests `ws` for a packed parameter vector.
fn residuals(ws: &[&TestWindow], geom: &Geometry, pack: Packing, q: &[f64]) -> Option<Vec<f64>> {
    let (ei, eo) = pack.coefficients(q);
    let mut all = Vec::with_capacity(ws.iter().map(|w| w.x_mm.len()).sum());
    for (k, w) in ws.iter().enumerate() {
        let m = replay(w, geom, ei, eo, pack.nuisance(q, k))?;
        all.extend(w.x_mm.iter().zip(&m).map(|(a, b)| a - b));
    }
    Some(all)
}

/// Fit one test: parameters [e_in, e_out | e, nuisance…].
pub fn fit_test(w: &TestWindow, geom: &Geometry, two_sided_single_e: bool) -> Result<TestFit, TestFailure> {
    let pack = Packing::new(geom, two_sided_single_e);
    let resid = |q: &[f64]| residuals(&[w], geom, pack, q);
    // Start from a sensible κ (one-sided): a small grid on the spring, e at 0.7.
    let mut best: Option<(Vec<f64>, f64)> = None;
    let kappas: Vec<f64> = if geom.one_sided {
        [3.0, 6.0, 12.0, 24.0, 48.0].iter().map(|k| k * geom.p2).collect()
    } else {
        vec![0.0]
    };
    for k in kappas {
        let mut q0 = vec![0.7; pack.n_e];
        q0.extend(start_nuisance(geom, k));
        if let Some(r) = resid(&q0) {
            let c: f64 = r.iter().map(|v| v * v).sum();
            if best.as_ref().is_none_or(|b| c < b.1) {
                best = Some((q0, c));
            }
        }
    }
    let (q0, _) = best.ok_or(TestFailure::NoStart)?;
    let mut steps = vec![1e-7; pack.n_e];
    steps.extend(steps_nuisance(geom));
    let res: FitResult = least_squares(&q0, &steps, 80, &resid)?;
    Ok(summarise(w, geom, &res, pack))
}

/// Standard error of parameter i (NaN without a covariance).
fn standard_error(res: &FitResult, i: usize) -> f64 {
    res.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)].max(0.0).sqrt())
}

fn summarise(w: &TestWindow, geom: &Geometry, res: &FitResult, pack: Packing) -> TestFit {
    let (ei, eo) = pack.coefficients(&res.q);
    let (i_in, i_out) = pack.coefficient_indices();
    let (se_in, se_out) = (standard_error(res, i_in), standard_error(res, i_out));
    let nu = pack.nuisance(&res.q, 0);
    let n = w.x_mm.len();
    let rms = (res.cost / n as f64).sqrt();
    let range = w.x_mm.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v)) - w.x_mm.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    let replay_mm = replay(w, geom, ei, eo, nu).unwrap_or_default();
    TestFit {
        id: w.id.clone(),
        e_in: ei,
        e_out: eo,
        se_e_in: se_in,
        se_e_out: se_out,
        ci95_e_in: [ei - 1.96 * se_in, ei + 1.96 * se_in],
        ci95_e_out: [eo - 1.96 * se_out, eo + 1.96 * se_out],
        release_offset_s: nu.release_offset_s(),
        zero_offset_mm: nu.zero_offset_mm(),
        p2_factor: nu.ln_p2_factor().exp(),
        kappa_per_s2: nu.kappa().filter(|_| geom.one_sided),
        rms_mm: rms,
        nrmse: rms / range.max(1e-12),
        iterations: res.iterations,
        stop: res.stop,
        samples: n,
        replay_mm,
    }
}

/// Per-impact coefficients straight from the data (speed after ÷ speed before at
/// each impact of the reduce step's impact-resolved estimate), grouped by the side
/// entered: (inward values, outward values).
pub fn per_impact(r: &Reduced, n_impacts: usize) -> (Vec<f64>, Vec<f64>) {
    let mut inward = Vec::new();
    let mut outward = Vec::new();
    for i in r.analysis.impacts.iter().take(n_impacts) {
        if let Some(after) = i.v_after_mm_s {
            let e = (after / i.v_before_mm_s).abs();
            match i.entering {
                Side::Inward => inward.push(e),
                Side::Outward => outward.push(e),
            }
        }
    }
    (inward, outward)
}

/// The joint fit over several tests: shared e_in, e_out; nuisance per test.
#[derive(Debug, Clone, serde::Serialize)]
pub struct JointFit {
    pub e_in: f64,
    pub e_out: f64,
    pub se_e_in: f64,
    pub se_e_out: f64,
    pub rms_mm: f64,
    pub iterations: usize,
    pub stop: FitStop,
    pub tests: Vec<String>,
}

/// The joint fit: shared e (or e_in, e_out) and each test's nuisance, started
/// from the mean of the per-test fits `starts` and their nuisance.
pub fn fit_joint(ws: &[TestWindow], geom: &Geometry, starts: &[TestFit], single_e: bool) -> Result<JointFit, FitError> {
    let pack = Packing::new(geom, single_e);
    let mean = |f: fn(&TestFit) -> f64| starts.iter().map(f).sum::<f64>() / starts.len() as f64;
    let mut q0 = if single_e {
        vec![mean(|s| s.e_in)]
    } else {
        vec![mean(|s| s.e_in), mean(|s| s.e_out)]
    };
    let mut steps = vec![1e-7; pack.n_e];
    for s in starts {
        q0.extend(nuisance_of(s, geom));
        steps.extend(steps_nuisance(geom));
    }
    let refs: Vec<&TestWindow> = ws.iter().collect();
    let res = least_squares(&q0, &steps, 40, &|q: &[f64]| residuals(&refs, geom, pack, q))?;
    let n: usize = ws.iter().map(|w| w.t.len()).sum();
    let (ei, eo) = pack.coefficients(&res.q);
    let (i_in, i_out) = pack.coefficient_indices();
    Ok(JointFit {
        e_in: ei,
        e_out: eo,
        se_e_in: standard_error(&res, i_in),
        se_e_out: standard_error(&res, i_out),
        rms_mm: (res.cost / n as f64).sqrt(),
        iterations: res.iterations,
        stop: res.stop,
        tests: ws.iter().map(|w| w.id.clone()).collect(),
    })
}

/// Whether the included tests' fits agree on one pair (e_in, e_out), which the
/// joint fit assumes: per coefficient, χ² = Σ ((e_i − ē)/se_i)² about the
/// inverse-variance mean ē on n − 1 degrees of freedom, and the smaller of the
/// two p-values. Where the tests differ beyond their fits' standard errors, the
/// joint fit's interval measures none of them: the campaign's coefficient is the
/// mean, with its test-to-test spread ([`Spread`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Agreement {
    pub chi2_e_in: f64,
    pub chi2_e_out: f64,
    pub dof: usize,
    pub p_value: f64,
    /// p ≥ [`AGREEMENT_LEVEL`].
    pub share_one_pair: bool,
}

/// The level below which the tests are taken not to share one pair. Strict
/// (10⁻³, not 0.05) because each fit's standard error comes from residuals that
/// are correlated in time, which makes it small: on a campaign made outside
/// rocklab with one e (`fixtures/campaigns/bessel-replay`) p = 0.23; on every
/// shipped campaign of walls or of per-impact coefficients p < 10⁻¹⁷.
pub const AGREEMENT_LEVEL: f64 = 1e-3;

/// [`Agreement`] of the fits (None with fewer than two).
pub fn agreement(fits: &[TestFit]) -> Option<Agreement> {
    if fits.len() < 2 {
        return None;
    }
    let chi2 = |e: fn(&TestFit) -> f64, se: fn(&TestFit) -> f64| {
        let w: Vec<f64> = fits.iter().map(|f| se(f).powi(-2)).collect();
        let mean = fits.iter().zip(&w).map(|(f, w)| w * e(f)).sum::<f64>() / w.iter().sum::<f64>();
        fits.iter().map(|f| ((e(f) - mean) / se(f)).powi(2)).sum::<f64>()
    };
    let chi2_e_in = chi2(|f| f.e_in, |f| f.se_e_in);
    let chi2_e_out = chi2(|f| f.e_out, |f| f.se_e_out);
    let dof = fits.len() - 1;
    let p_value = crate::stats::chi2_sf(chi2_e_in, dof).min(crate::stats::chi2_sf(chi2_e_out, dof));
    // A fit with a zero standard error makes χ² infinite or NaN: no agreement vouched for.
    let p_value = if p_value.is_nan() { 0.0 } else { p_value };
    Some(Agreement {
        chi2_e_in,
        chi2_e_out,
        dof,
        p_value,
        share_one_pair: p_value >= AGREEMENT_LEVEL,
    })
}

impl Agreement {
    /// "The tests do not share one pair (χ² of the per-test values = …, p =
    /// 0.00): …", or that they agree.
    pub fn describe(&self) -> String {
        let chi2 = if self.chi2_e_in == self.chi2_e_out {
            format!("{:.1}", self.chi2_e_in)
        } else {
            format!("{:.1} (e_in) and {:.1} (e_out)", self.chi2_e_in, self.chi2_e_out)
        };
        let p = if self.p_value < AGREEMENT_LEVEL {
            format!("p < {AGREEMENT_LEVEL}")
        } else {
            format!("p = {:.2}", self.p_value)
        };
        let stat = format!("χ² of the per-test values = {chi2} on {} degrees of freedom, {p}", self.dof);
        if self.share_one_pair {
            format!("The tests agree on one pair ({stat})")
        } else {
            format!(
                "The tests do not share one pair ({stat}): the joint fit's interval assumes they do and measures none of them; the calibration is the means, with the test-to-test spread"
            )
        }
    }
}

/// The campaign's calibration.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Calibration {
    pub campaign: String,
    pub rocking: Rocking,
    pub e_housner: f64,
    /// Means over the included tests (the values written as the calibration).
    pub e_in: f64,
    pub e_out: f64,
    pub r_in: f64,
    pub r_out: f64,
    pub joint: Option<JointFit>,
    /// Whether the included tests agree on the one pair the joint fit assumes.
    pub agreement: Option<Agreement>,
    /// Why there is no joint fit, when there are included tests but no joint fit.
    #[serde(skip)]
    pub joint_failure: Option<FitError>,
    pub tests: Vec<TestFit>,
    /// Per-impact coefficients from the data, per test: (id, inward, outward).
    pub per_impact: Vec<(String, Vec<f64>, Vec<f64>)>,
    pub included: Vec<String>,
    /// (id, why) of every test the means leave out: `exclude_from_mean`, suspect
    /// (with the reducer's reason) or not fitted (with the failure).
    pub left_out: Vec<(String, String)>,
    pub failed: Vec<(String, TestFailure)>,
}

impl Calibration {
    /// "50_1 (exclude_from_mean), 150_3 (suspect: …)".
    pub fn left_out_text(&self) -> String {
        crate::campaign_means::left_out_text(&self.left_out)
    }

    /// "50_1 (exclude_from_mean), 150_3 (suspect)": the reasons cut at their first colon.
    fn left_out_short(&self) -> String {
        self.left_out
            .iter()
            .map(|(id, why)| format!("{id} ({})", why.split(':').next().unwrap_or(why)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Why a calibration has no calibration.toml.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationFileError {
    /// Every test is left out: no mean to write (a façade study would read it as e).
    #[error("no test of {campaign} can be included in the calibration ({why}): calibration.toml needs at least one")]
    NoIncludedTest { campaign: String, why: String },
    #[error(transparent)]
    Toml(#[from] toml::ser::Error),
}

/// What calibrating one test gave.
struct TestCalibration {
    id: String,
    exclude_from_mean: bool,
    /// Why the reducer cannot vouch for this test, if it cannot.
    suspect: Option<String>,
    fit: Result<(TestWindow, TestFit), TestFailure>,
    /// Per-impact coefficients (inward, outward), when the test was reduced.
    per_impact: Option<(Vec<f64>, Vec<f64>)>,
}

/// Window and fit one reduced test.
fn calibrate_test(t: &TestInput, geom: &Geometry, single_e: bool, n_impacts: usize) -> TestCalibration {
    let suspect = t.reduced.ok().and_then(Reduced::suspect_reason);
    let (fit, per_impact) = match t.reduced {
        Err(e) => (Err(TestFailure::NotReduced(e.to_string())), None),
        Ok(r) => {
            let fit = window(t.id, r, t.lever_arm_m * 1e3, n_impacts)
                .ok_or(TestFailure::TooFewImpacts { needed: n_impacts })
                .and_then(|w| fit_test(&w, geom, single_e).map(|f| (w, f)));
            (fit, Some(per_impact(r, n_impacts)))
        }
    };
    TestCalibration {
        id: t.id.to_string(),
        exclude_from_mean: t.exclude_from_mean,
        suspect,
        fit,
        per_impact,
    }
}

/// Calibrate a reduced campaign (tests in parallel). The means and the joint fit
/// take the tests the campaign means of `reduce` take: not `exclude_from_mean`,
/// and not suspect (the reducer's impacts window the replay; where it cannot place
/// them, the window is not vouched for); and of those, the tests whose fit
/// [`fit_verdict`] vouches for. The others are fitted and listed, with why they
/// are left out.
pub fn calibrate(c: &CampaignInput, n_impacts: usize) -> Calibration {
    use rayon::prelude::*;
    let geom = Geometry::of(c.rocking, &c.wall);
    let single_e = c.rocking == Rocking::TwoSided;
    let outcomes: Vec<TestCalibration> = c.tests.par_iter().map(|t| calibrate_test(t, &geom, single_e, n_impacts)).collect();
    let mut tests = Vec::new();
    let mut windows = Vec::new();
    let mut included = Vec::new();
    let mut left_out = Vec::new();
    let mut failed = Vec::new();
    let mut per = Vec::new();
    let mut inc_fits = Vec::new();
    for o in outcomes {
        if let Some((a, b)) = o.per_impact {
            per.push((o.id.clone(), a, b));
        }
        match o.fit {
            Ok((w, f)) => {
                match (o.exclude_from_mean, &o.suspect, fit_verdict(&f)) {
                    (true, ..) => left_out.push((o.id.clone(), "exclude_from_mean".to_string())),
                    (false, Some(why), _) => left_out.push((o.id.clone(), format!("suspect: {why}"))),
                    (false, None, Some(why)) => left_out.push((o.id.clone(), format!("fit not vouched for: {why}"))),
                    (false, None, None) => {
                        included.push(o.id.clone());
                        windows.push(w);
                        inc_fits.push(f.clone());
                    }
                }
                tests.push(f);
            }
            Err(e) => {
                left_out.push((o.id.clone(), e.to_string()));
                failed.push((o.id, e));
            }
        }
    }
    let mean = |f: fn(&TestFit) -> f64| inc_fits.iter().map(f).sum::<f64>() / inc_fits.len().max(1) as f64;
    let (e_in, e_out) = (mean(|t| t.e_in), mean(|t| t.e_out));
    let joint = (!windows.is_empty()).then(|| fit_joint(&windows, &geom, &inc_fits, single_e));
    let e_housner = c.wall.e_housner;
    Calibration {
        campaign: c.name.to_string(),
        rocking: c.rocking,
        e_housner,
        e_in,
        e_out,
        r_in: e_in / e_housner,
        r_out: e_out / e_housner,
        agreement: agreement(&inc_fits),
        joint_failure: joint.clone().and_then(Result::err),
        joint: joint.and_then(Result::ok),
        tests,
        per_impact: per,
        included,
        left_out,
        failed,
    }
}

/// What an uncertainty ensemble needs from a calibration: the spread of the
/// per-test fits over the included tests and the fits' own standard errors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spread {
    pub n_tests: usize,
    /// Test-to-test sample standard deviation (n − 1) of the per-test e_in, e_out
    /// (0 with one test).
    pub sd_e_in_tests: f64,
    pub sd_e_out_tests: f64,
    /// Standard error of the means: sd / √n.
    pub se_e_in_mean: f64,
    pub se_e_out_mean: f64,
    /// Root mean square of the per-test fits' standard errors.
    pub se_e_in_fit: f64,
    pub se_e_out_fit: f64,
}

/// The spread of the included per-test fits.
pub fn spread(c: &Calibration) -> Spread {
    let inc: Vec<&TestFit> = c.tests.iter().filter(|t| c.included.contains(&t.id)).collect();
    let n = inc.len();
    let sd = |f: fn(&TestFit) -> f64| {
        if n < 2 {
            return 0.0;
        }
        let m = inc.iter().map(|t| f(t)).sum::<f64>() / n as f64;
        (inc.iter().map(|t| (f(t) - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    };
    let rms = |f: fn(&TestFit) -> f64| {
        let v: Vec<f64> = inc.iter().map(|t| f(t)).filter(|x| x.is_finite()).collect();
        (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
    };
    let (si, so) = (sd(|t| t.e_in), sd(|t| t.e_out));
    let root = (n.max(1) as f64).sqrt();
    Spread {
        n_tests: n,
        sd_e_in_tests: si,
        sd_e_out_tests: so,
        se_e_in_mean: si / root,
        se_e_out_mean: so / root,
        se_e_in_fit: rms(|t| t.se_e_in),
        se_e_out_fit: rms(|t| t.se_e_out),
    }
}

/// calibration.toml: written by `rocklab calibrate` ([`to_toml`]), read by
/// `simulate --calibration` and the façade study (`rocklab::ingest::calibration`):
/// one type for the writer and the readers.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationFile {
    pub calibration: CalibrationValues,
}

/// The `[calibration]` table: the means of the per-test fits over the included
/// tests, the spread an ensemble draws from and the joint fit. Only e_in and e_out
/// are required of a file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationValues {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub campaign: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rocking: Option<Rocking>,
    pub e_in: f64,
    pub e_out: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_in: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_out: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e_housner: Option<f64>,
    /// `[calibration.spread]` (absent in files written before it was added).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spread: Option<SpreadTable>,
    /// `[calibration.joint]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointValues>,
}

/// `[calibration.spread]`: how the per-test fits were weighted, and their spread.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpreadTable {
    pub weighting: String,
    #[serde(flatten)]
    pub spread: Spread,
}

/// `[calibration.joint]`: the joint fit's values.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointValues {
    pub e_in: f64,
    pub e_out: f64,
    pub se_e_in: f64,
    pub se_e_out: f64,
    pub rms_mm: f64,
    /// Whether the tests share the one pair this fit assumes (absent in files
    /// written before it was checked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub agreement: Option<Agreement>,
}

impl CalibrationFile {
    /// The file of a calibration.
    pub fn of(c: &Calibration) -> CalibrationFile {
        CalibrationFile {
            calibration: CalibrationValues {
                campaign: Some(c.campaign.clone()),
                rocking: Some(c.rocking),
                e_in: c.e_in,
                e_out: c.e_out,
                r_in: Some(c.r_in),
                r_out: Some(c.r_out),
                e_housner: Some(c.e_housner),
                spread: Some(SpreadTable {
                    weighting: "unweighted least squares on displacement, per test".into(),
                    spread: spread(c),
                }),
                joint: c.joint.as_ref().map(|j| JointValues {
                    e_in: j.e_in,
                    e_out: j.e_out,
                    se_e_in: j.se_e_in,
                    se_e_out: j.se_e_out,
                    rms_mm: j.rms_mm,
                    agreement: c.agreement,
                }),
            },
        }
    }
}

/// calibration.toml of a calibration: a comment saying what the values are, then
/// [`CalibrationFile`].
pub fn to_toml(c: &Calibration) -> Result<String, CalibrationFileError> {
    if c.included.is_empty() {
        return Err(CalibrationFileError::NoIncludedTest {
            campaign: c.campaign.clone(),
            why: if c.left_out.is_empty() {
                "it has no test".to_string()
            } else {
                c.left_out_text()
            },
        });
    }
    let header = format!(
        "# Written by rocklab calibrate. e_in/e_out: means of the per-test fits over the\n# included tests ({}{}); [calibration.spread]: their test-to-test spread and the\n# fits' standard errors (what a façade ensemble draws from). Each test: unweighted\n# least squares on the displacement (mm) over the window of its first impacts,\n# nuisance parameters free (release time, zero, p² factor{}).\n# [calibration.joint]: one fit over all of them{}.\n",
        c.included.join(", "),
        if c.left_out.is_empty() { String::new() } else { format!("; left out: {}", c.left_out_short()) },
        if c.rocking == Rocking::OneSided { ", inward spring" } else { "" },
        match c.agreement {
            Some(a) if !a.share_one_pair => " (the tests do not share one pair: its interval\n# measures none of them; use the means and [calibration.spread])",
            _ => "",
        },
    );
    Ok(header + &toml::to_string(&CalibrationFile::of(c))?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wall::Provenance;

    fn wall() -> Wall {
        Wall {
            height_m: 2.70,
            thickness_m: 0.36,
            hinge_height_m: 0.23,
            alpha_rad: 0.133,
            alpha_source: Provenance::Computed("test".into()),
            e_housner: 0.974,
            e_housner_source: Provenance::Computed("test".into()),
        }
    }

    /// A window whose release lies beyond the lever arm cannot be replayed from
    /// any start: the failure says so (it used to be "the fit failed").
    #[test]
    fn a_window_that_cannot_be_replayed_says_why() {
        let geom = Geometry::of(Rocking::OneSided, &wall());
        let w = TestWindow {
            id: "x".into(),
            t: (0..100).map(|i| 1.0 + i as f64 * 0.01).collect(),
            x_mm: vec![0.0; 100],
            release_s: 1.0,
            x_release_mm: 3000.0,
            lever_mm: 2330.0,
            t_end: 2.0,
            filter: None,
        };
        let e = fit_test(&w, &geom, false).unwrap_err();
        assert_eq!(e, TestFailure::NoStart);
        assert!(e.to_string().starts_with("the fit failed: no starting point"), "{e}");
    }

    /// A test that was not reduced is listed as failed with the reduction's reason.
    #[test]
    fn a_test_not_reduced_is_failed_with_its_reason() {
        let err = std::io::Error::other("x.csv: file not found");
        let input = CampaignInput {
            name: "c",
            rocking: Rocking::TwoSided,
            wall: wall(),
            tests: vec![TestInput {
                id: "a",
                exclude_from_mean: false,
                lever_arm_m: 2.33,
                reduced: Err(&err),
            }],
            push_speed: None,
        };
        let cal = calibrate(&input, 6);
        assert_eq!(
            cal.failed,
            vec![("a".to_string(), TestFailure::NotReduced("x.csv: file not found".into()))]
        );
        assert_eq!(
            serde_json::to_value(&cal.failed[0].1).unwrap(),
            serde_json::json!("not reduced: x.csv: file not found")
        );
        assert!(cal.joint.is_none() && cal.tests.is_empty());
    }

    fn fitted(e_in: f64, se_in: f64, e_out: f64, se_out: f64) -> TestFit {
        TestFit {
            id: "a".into(),
            e_in,
            e_out,
            se_e_in: se_in,
            se_e_out: se_out,
            ci95_e_in: [e_in - 1.96 * se_in, e_in + 1.96 * se_in],
            ci95_e_out: [e_out - 1.96 * se_out, e_out + 1.96 * se_out],
            release_offset_s: 0.0,
            zero_offset_mm: 0.0,
            p2_factor: 1.0,
            kappa_per_s2: None,
            rms_mm: 0.1,
            nrmse: 0.01,
            iterations: 5,
            stop: FitStop::Converged,
            samples: 100,
            replay_mm: Vec::new(),
        }
    }

    /// A fit against the domain's edge, or above 1 beyond its interval, is not a
    /// measurement; above 1 within the interval, or inside 0–1, it is.
    #[test]
    fn fits_at_the_edge_or_above_one_are_not_vouched_for() {
        assert_eq!(fit_verdict(&fitted(0.45, 0.01, 0.85, 0.01)), None);
        assert_eq!(fit_verdict(&fitted(0.45, 0.01, 1.02, 0.02)), None, "1 is inside its interval");
        let edge = fit_verdict(&fitted(0.45, 0.01, 1.4999, 0.3)).unwrap();
        assert!(edge.starts_with("e_out = 1.500 is at the edge of the replay's domain (0–1.5)"), "{edge}");
        let low = fit_verdict(&fitted(1e-4, 0.01, 0.8, 0.01)).unwrap();
        assert!(low.starts_with("e_in = 0.000 is at the edge"), "{low}");
        let above = fit_verdict(&fitted(0.45, 0.01, 1.2, 0.05)).unwrap();
        assert!(above.starts_with("e_out = 1.200 (95 % 1.102–1.298) is above 1"), "{above}");
        let shared = fit_verdict(&fitted(1.2, 0.05, 1.2, 0.05)).unwrap();
        assert!(shared.starts_with("e = 1.200") && !shared.contains("e_out"), "said once: {shared}");
    }
}
