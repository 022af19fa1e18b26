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

use crate::fit::{levenberg_marquardt, FitResult, FitStop};
use crate::ingest::{Campaign, Rocking};
use crate::reduce::{CampaignResult, Reduced};
use crate::solver::{simulate_at, Ground, Restraint, RockingModel, Settings};
use crate::wall::{p_squared_rectangular, slenderness};

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
}

/// The rocking physics shared by the tests of a campaign.
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    pub alpha: f64,
    pub p2: f64,
    pub one_sided: bool,
}

impl Geometry {
    pub fn of(c: &Campaign) -> Geometry {
        let h = c.height_m - c.hinge_height_m;
        Geometry {
            alpha: slenderness(c.thickness_m, h),
            p2: p_squared_rectangular(h, c.thickness_m),
            one_sided: c.rocking == Rocking::OneSided,
        }
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
    let t_end = last + 0.5 * gap;
    let t0 = a.release_time_s - 0.1;
    let t = &r.log.time_s;
    let i0 = t.partition_point(|&v| v < t0);
    let i1 = t.partition_point(|&v| v <= t_end);
    let j = t.partition_point(|&v| v < a.release_time_s).min(t.len() - 1);
    let x_rel = crate::signal::median(&a.displacement_mm[j.saturating_sub(5)..=j]);
    Some(TestWindow {
        id: id.to_string(),
        t: t[i0..i1].to_vec(),
        x_mm: a.displacement_mm[i0..i1].to_vec(),
        release_s: a.release_time_s,
        x_release_mm: x_rel,
        lever_mm,
        t_end,
    })
}

/// Per-test nuisance parameters: [δt, z (mm), ln(p² factor), ln κ (one-sided)].
fn n_nuisance(g: &Geometry) -> usize {
    if g.one_sided {
        4
    } else {
        3
    }
}

/// Modelled readings of one test for coefficients (e_in, e_out) and nuisance q.
pub fn replay(w: &TestWindow, g: &Geometry, e_in: f64, e_out: f64, q: &[f64]) -> Option<Vec<f64>> {
    if !(e_in > 0.0 && e_in < 1.5 && e_out > 0.0 && e_out < 1.5) {
        return None;
    }
    let (dt, z, lnf) = (q[0], q[1], q[2]);
    let kappa = if g.one_sided { q[3].exp() } else { 0.0 };
    let s = (w.x_release_mm - z) / w.lever_mm;
    if s.is_nan() || s.abs() >= 1.0 {
        return None;
    }
    let theta0 = s.asin();
    let model = RockingModel {
        alpha: g.alpha,
        p2: g.p2 * lnf.exp(),
        i0: 1.0,
        restraint: if g.one_sided {
            Restraint::Rotational { k_nm_per_rad: kappa }
        } else {
            Restraint::None
        },
        ties: Vec::new(),
        e_in,
        e_out,
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
    let (_, th) = simulate_at(&model, &ground, w.release_s + dt, Some([theta0, 0.0]), &settings, &w.t);
    Some(th.iter().map(|t| z + w.lever_mm * t.sin()).collect())
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

fn start_nuisance(g: &Geometry) -> Vec<f64> {
    let mut q = vec![0.0, 0.0, 0.0];
    if g.one_sided {
        q.push((12.0 * g.p2).ln());
    }
    q
}

fn steps_nuisance(g: &Geometry) -> Vec<f64> {
    let mut s = vec![1e-6, 1e-5, 1e-7];
    if g.one_sided {
        s.push(1e-6);
    }
    s
}

/// Fit one test: parameters [e_in, e_out | e, nuisance…].
pub fn fit_test(w: &TestWindow, g: &Geometry, two_sided_single_e: bool) -> Option<TestFit> {
    let ne = if two_sided_single_e { 1 } else { 2 };
    let split = |q: &[f64]| -> (f64, f64) {
        if ne == 1 {
            (q[0], q[0])
        } else {
            (q[0], q[1])
        }
    };
    let resid = |q: &[f64]| -> Option<Vec<f64>> {
        let (ei, eo) = split(q);
        let m = replay(w, g, ei, eo, &q[ne..])?;
        Some(w.x_mm.iter().zip(&m).map(|(a, b)| a - b).collect())
    };
    // Start from a sensible κ (one-sided): a small grid on the spring, e at 0.7.
    let mut best: Option<(Vec<f64>, f64)> = None;
    let kappas: Vec<f64> = if g.one_sided {
        [3.0, 6.0, 12.0, 24.0, 48.0].iter().map(|k| k * g.p2).collect()
    } else {
        vec![0.0]
    };
    for k in kappas {
        let mut q0 = vec![0.7; ne];
        let mut nu = start_nuisance(g);
        if g.one_sided {
            nu[3] = k.ln();
        }
        q0.extend(nu);
        if let Some(r) = resid(&q0) {
            let c: f64 = r.iter().map(|v| v * v).sum();
            if best.as_ref().is_none_or(|b| c < b.1) {
                best = Some((q0, c));
            }
        }
    }
    let (q0, _) = best?;
    let mut steps = vec![1e-7; ne];
    steps.extend(steps_nuisance(g));
    let res: FitResult = levenberg_marquardt(&q0, &steps, 80, &resid)?;
    Some(summarise(w, g, &res, ne))
}

fn summarise(w: &TestWindow, g: &Geometry, res: &FitResult, ne: usize) -> TestFit {
    let (ei, eo) = if ne == 1 { (res.q[0], res.q[0]) } else { (res.q[0], res.q[1]) };
    let se = |i: usize| res.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)].max(0.0).sqrt());
    let (se_in, se_out) = if ne == 1 { (se(0), se(0)) } else { (se(0), se(1)) };
    let nu = &res.q[ne..];
    let n = w.x_mm.len();
    let rms = (res.cost / n as f64).sqrt();
    let range = w.x_mm.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v)) - w.x_mm.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    let replay_mm = replay(w, g, ei, eo, nu).unwrap_or_default();
    TestFit {
        id: w.id.clone(),
        e_in: ei,
        e_out: eo,
        se_e_in: se_in,
        se_e_out: se_out,
        ci95_e_in: [ei - 1.96 * se_in, ei + 1.96 * se_in],
        ci95_e_out: [eo - 1.96 * se_out, eo + 1.96 * se_out],
        release_offset_s: nu[0],
        zero_offset_mm: nu[1],
        p2_factor: nu[2].exp(),
        kappa_per_s2: g.one_sided.then(|| nu[3].exp()),
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
                crate::peaks::Side::Inward => inward.push(e),
                crate::peaks::Side::Outward => outward.push(e),
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

pub fn fit_joint(ws: &[TestWindow], g: &Geometry, starts: &[TestFit], single_e: bool) -> Option<JointFit> {
    let ne = if single_e { 1 } else { 2 };
    let nn = n_nuisance(g);
    let mut q0 = if single_e {
        vec![starts.iter().map(|s| s.e_in).sum::<f64>() / starts.len() as f64]
    } else {
        vec![
            starts.iter().map(|s| s.e_in).sum::<f64>() / starts.len() as f64,
            starts.iter().map(|s| s.e_out).sum::<f64>() / starts.len() as f64,
        ]
    };
    let mut steps = vec![1e-7; ne];
    for s in starts {
        q0.extend([s.release_offset_s, s.zero_offset_mm, s.p2_factor.ln()]);
        if g.one_sided {
            q0.push(s.kappa_per_s2.unwrap_or(12.0 * g.p2).ln());
        }
        steps.extend(steps_nuisance(g));
    }
    let resid = |q: &[f64]| -> Option<Vec<f64>> {
        let (ei, eo) = if single_e { (q[0], q[0]) } else { (q[0], q[1]) };
        let mut all = Vec::new();
        for (k, w) in ws.iter().enumerate() {
            let nu = &q[ne + k * nn..ne + (k + 1) * nn];
            let m = replay(w, g, ei, eo, nu)?;
            all.extend(w.x_mm.iter().zip(&m).map(|(a, b)| a - b));
        }
        Some(all)
    };
    let res = levenberg_marquardt(&q0, &steps, 40, &resid)?;
    let se = |i: usize| res.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)].max(0.0).sqrt());
    let n: usize = ws.iter().map(|w| w.t.len()).sum();
    let (ei, eo, si, so) = if single_e {
        (res.q[0], res.q[0], se(0), se(0))
    } else {
        (res.q[0], res.q[1], se(0), se(1))
    };
    Some(JointFit {
        e_in: ei,
        e_out: eo,
        se_e_in: si,
        se_e_out: so,
        rms_mm: (res.cost / n as f64).sqrt(),
        iterations: res.iterations,
        stop: res.stop,
        tests: ws.iter().map(|w| w.id.clone()).collect(),
    })
}

/// The campaign's calibration.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Calibration {
    pub campaign: String,
    pub rocking: String,
    pub e_housner: f64,
    /// Means over the included tests (the values written as the calibration).
    pub e_in: f64,
    pub e_out: f64,
    pub r_in: f64,
    pub r_out: f64,
    pub joint: Option<JointFit>,
    pub tests: Vec<TestFit>,
    /// Per-impact coefficients from the data, per test: (id, inward, outward).
    pub per_impact: Vec<(String, Vec<f64>, Vec<f64>)>,
    pub included: Vec<String>,
    pub failed: Vec<(String, String)>,
}

/// (id, excluded from the mean, window and fit or why not, per-impact coefficients)
type TestOutcome = (String, bool, Result<(TestWindow, TestFit), String>, Option<(Vec<f64>, Vec<f64>)>);

/// Calibrate a reduced campaign (tests in parallel).
pub fn calibrate(res: &CampaignResult, n_impacts: usize) -> Calibration {
    use rayon::prelude::*;
    let c = &res.campaign;
    let g = Geometry::of(c);
    let single_e = c.rocking == Rocking::TwoSided;
    let outcomes: Vec<TestOutcome> = res
        .tests
        .par_iter()
        .map(|t| {
            let id = t.spec.id.clone();
            let r = match &t.result {
                Ok(r) => r,
                Err(e) => return (id, t.spec.exclude_from_mean, Err(format!("not reduced: {e}")), None),
            };
            let pi = per_impact(r, n_impacts);
            let out = window(&id, r, t.spec.lever_arm_m * 1e3, n_impacts)
                .ok_or_else(|| format!("fewer than {n_impacts} impacts"))
                .and_then(|w| fit_test(&w, &g, single_e).map(|f| (w, f)).ok_or_else(|| "the fit failed".to_string()));
            (id, t.spec.exclude_from_mean, out, Some(pi))
        })
        .collect();
    let mut tests = Vec::new();
    let mut windows = Vec::new();
    let mut included = Vec::new();
    let mut failed = Vec::new();
    let mut per = Vec::new();
    let mut inc_fits = Vec::new();
    for (id, excl, out, pi) in outcomes {
        if let Some((a, b)) = pi {
            per.push((id.clone(), a, b));
        }
        match out {
            Ok((w, f)) => {
                if !excl {
                    included.push(id.clone());
                    windows.push(w);
                    inc_fits.push(f.clone());
                }
                tests.push(f);
            }
            Err(e) => failed.push((id, e)),
        }
    }
    let mean = |f: fn(&TestFit) -> f64| inc_fits.iter().map(f).sum::<f64>() / inc_fits.len().max(1) as f64;
    let (e_in, e_out) = (mean(|t| t.e_in), mean(|t| t.e_out));
    let joint = (!windows.is_empty()).then(|| fit_joint(&windows, &g, &inc_fits, single_e)).flatten();
    Calibration {
        campaign: c.name.clone(),
        rocking: c.rocking.as_str().into(),
        e_housner: c.e_housner,
        e_in,
        e_out,
        r_in: e_in / c.e_housner,
        r_out: e_out / c.e_housner,
        joint,
        tests,
        per_impact: per,
        included,
        failed,
    }
}

/// What an uncertainty ensemble needs from a calibration: the spread of the
/// per-test fits over the included tests and the fits' own standard errors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
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

/// calibration.toml (read by `simulate --calibration` and the façade study):
/// the means, the spread an ensemble draws from (`[calibration.spread]`) and the
/// joint fit.
pub fn to_toml(c: &Calibration) -> String {
    let mut s = format!(
        "# Written by rocklab calibrate. e_in/e_out: means of the per-test fits over the\n# included tests ({}); [calibration.spread]: their test-to-test spread and the\n# fits' standard errors (what a façade ensemble draws from); [calibration.joint]:\n# one fit over all of them.\n[calibration]\ncampaign = {:?}\nrocking = {:?}\ne_in = {}\ne_out = {}\nr_in = {}\nr_out = {}\ne_housner = {}\n",
        c.included.join(", "),
        c.campaign,
        c.rocking,
        c.e_in,
        c.e_out,
        c.r_in,
        c.r_out,
        c.e_housner
    );
    let sp = spread(c);
    s.push_str(&format!(
        "\n[calibration.spread]\n# Each test: unweighted least squares on the displacement (mm) over the window of\n# its first impacts, nuisance parameters free (release time, zero, p² factor{}).\nweighting = \"unweighted least squares on displacement, per test\"\nn_tests = {}\nsd_e_in_tests = {}\nsd_e_out_tests = {}\nse_e_in_mean = {}\nse_e_out_mean = {}\nse_e_in_fit = {}\nse_e_out_fit = {}\n",
        if c.rocking == "one-sided" { ", inward spring" } else { "" },
        sp.n_tests,
        sp.sd_e_in_tests,
        sp.sd_e_out_tests,
        sp.se_e_in_mean,
        sp.se_e_out_mean,
        sp.se_e_in_fit,
        sp.se_e_out_fit
    ));
    if let Some(j) = &c.joint {
        s.push_str(&format!(
            "\n[calibration.joint]\ne_in = {}\ne_out = {}\nse_e_in = {}\nse_e_out = {}\nrms_mm = {}\n",
            j.e_in, j.e_out, j.se_e_in, j.se_e_out, j.rms_mm
        ));
    }
    s
}
