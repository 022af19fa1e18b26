//! Issue #20: every impact's coefficient and the campaign's restitution law against
//! the truth of the engine-made campaigns (`fixtures/campaigns/mujoco-public-*`,
//! truth.json lists e for every impact) and of the idealised demo campaigns.
//!
//! "The impacts the truth lists": those where the engine saw a contact (its
//! `e_engine` is a number ≤ 1; after the motion has died the truth still lists
//! ratios of noise-level peaks, which no tool can call an impact).
//! A truth impact's amplitude is read from the log itself: the largest |x| of the
//! reduction's displacement (zero at the final rest line) between the truth's
//! crossings k − 1 (the release for k = 0) and k, θ = asin(x/L), a = θ/α.

use std::path::Path;

use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::{reduce_campaign, CampaignResult};
use rocklab::wall::Side;
use serde_json::Value;

/// A fixture campaign by name, or a campaign directory by path (one with a '/').
fn campaign_dir(name: &str) -> std::path::PathBuf {
    if name.contains('/') {
        Path::new(name).to_path_buf()
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns").join(name)
    }
}

fn reduce(name: &str) -> (CampaignResult, Value) {
    let dir = campaign_dir(name);
    let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    (reduce_campaign(campaign, PeakOptions::default()), truth)
}

fn truth_test<'a>(truth: &'a Value, id: &str) -> &'a Value {
    truth["tests"].as_array().unwrap().iter().find(|x| x["id"] == id).unwrap()
}

/// (k, side, true r, amplitude from the log) of every impact the truth lists.
fn truth_impacts(res: &CampaignResult, truth: &Value) -> Vec<(String, usize, Side, f64, f64)> {
    let mut out = Vec::new();
    for t in &res.tests {
        let r = t.result.as_ref().unwrap();
        let tt = truth_test(truth, &t.spec.id);
        let cross: Vec<f64> = tt["sim"]["impacts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i["t_cross"].as_f64().unwrap())
            .collect();
        let release = tt["sim"]["t_release_s"].as_f64().unwrap();
        let lever_mm = t.spec.lever_arm_m * 1e3;
        for e in tt["e_true"].as_array().unwrap() {
            let k = e["k"].as_u64().unwrap() as usize;
            let real = e["e_engine"].as_f64().is_some_and(|x| x <= 1.0);
            if !real || k >= cross.len() {
                continue;
            }
            let t0 = if k == 0 { release } else { cross[k - 1] };
            let x = r
                .log
                .time_s
                .iter()
                .zip(&r.analysis.displacement_mm)
                .filter(|(s, _)| **s >= t0 && **s <= cross[k])
                .map(|(_, x)| x.abs())
                .fold(0.0, f64::max);
            let a = (x / lever_mm).min(1.0).asin() / res.campaign.alpha_rad;
            let side = if e["direction"] == "in" { Side::Inward } else { Side::Outward };
            out.push((t.spec.id.clone(), k, side, e["e_over_eH"].as_f64().unwrap(), a));
        }
    }
    out
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// Per-impact r against the truth: (RMS over the impacts reported, reported / listed).
fn per_impact(res: &CampaignResult, truth: &Value) -> (f64, f64, f64) {
    let listed = truth_impacts(res, truth);
    let mut err = Vec::new();
    let mut z = Vec::new();
    for (id, k, _, r_true, _) in &listed {
        let t = res.tests.iter().find(|t| &t.spec.id == id).unwrap();
        let r = t.result.as_ref().unwrap();
        if !r.analysis.quality.is_ok() {
            continue;
        }
        if let Some(i) = r.impacts.impacts.iter().find(|i| i.k == *k) {
            if std::env::var("READ_DEBUG").is_ok() {
                println!(
                    "read {id} k{k} {:?} a={:.4} r={:.3} true={r_true:.3} err={:+.4} u={:.4}",
                    i.side,
                    i.amplitude_over_alpha,
                    i.r,
                    i.r - r_true,
                    i.r_u.unwrap()
                );
            }
            err.push(i.r - r_true);
            z.push((i.r - r_true).abs() / i.r_u.unwrap());
        }
    }
    z.sort_by(f64::total_cmp);
    let median_z = z.get(z.len() / 2).copied().unwrap_or(f64::NAN);
    (rms(&err), err.len() as f64 / listed.len() as f64, median_z)
}

/// The law read at every listed impact's amplitude against the truth, and the best
/// constant pair (each side's mean true r: the least-squares constant) likewise.
fn law_against_truth(res: &CampaignResult, truth: &Value) -> (f64, f64, f64) {
    law_vs_truth(&res.law.as_ref().unwrap().law, res, truth)
}

/// As [`law_against_truth`] for any law.
fn law_vs_truth(law: &rocklab::restitution_law::RestitutionLaw, res: &CampaignResult, truth: &Value) -> (f64, f64, f64) {
    let listed = truth_impacts(res, truth);
    let err: Vec<f64> = listed.iter().map(|(_, _, side, r, a)| law.r(*side, *a) - r).collect();
    if std::env::var("LAW_DEBUG").is_ok() {
        for (i, e) in listed.iter().zip(&err) {
            println!("{} k{} {:?} a={:.4} r={:.3} err={:+.3}", i.0, i.1, i.2, i.4, i.3, e);
        }
    }
    let two_sided = law.parameters.shared;
    let mean = |s: Side| {
        let v: Vec<f64> = listed.iter().filter(|i| two_sided || i.2 == s).map(|i| i.3).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (ci, co) = (mean(Side::Inward), mean(Side::Outward));
    let cst: Vec<f64> = listed
        .iter()
        .map(|(_, _, side, r, _)| if *side == Side::Inward { ci } else { co } - r)
        .collect();
    let a_min = law.parameters.amplitude_min;
    let inside: Vec<f64> = listed.iter().zip(&err).filter(|(i, _)| i.4 >= a_min).map(|(_, e)| *e).collect();
    (rms(&err), rms(&cst), rms(&inside))
}

/// Two-sided compliant contacts. Asserted: every impact reported within RMS 0.015 of
/// the truth (the bound); the law within RMS 0.02 of the truth over every
/// listed impact (the bound; measured 0.0124 with the contact model's late
/// impacts and the stop where the wall no longer rocks, 0.0149 before them, 0.0235
/// with the bare u before the fit added the form's own misfit τ to every u) and closer than the best
/// constant pair; the data reject the constant. Also printed: the same fit to the
/// truth's own r with the readings' u (what the weighting alone gives):
/// docs/restitution-law.md.
/// Ignored (seconds in a debug build, beside the two reductions): run with
/// `cargo test --test law -- --ignored --nocapture`.
#[test]
#[ignore]
fn mujoco_two_sided_impacts_and_law() {
    let (res, truth) = reduce("mujoco-public-two-sided");
    let (rms_r, coverage, z) = per_impact(&res, &truth);
    let (law_rms, cst_rms, inside) = law_against_truth(&res, &truth);
    println!(
        "two-sided: per-impact RMS {rms_r:.4} over {:.0} % of the listed impacts (median |err|/u {z:.2}); law RMS {law_rms:.4} ({inside:.4} inside the fitted amplitudes), best constant pair {cst_rms:.4}",
        100.0 * coverage
    );
    assert!(rms_r <= 0.015, "per-impact RMS {rms_r:.4}");
    // The law with the readings' weights and covariance fitted to the truth's own r
    // at the same impacts: the weighting's share of the law's misfit.
    let listed = truth_impacts(&res, &truth);
    let tables: Vec<(String, rocklab::impacts::ImpactTable)> = res
        .tests
        .iter()
        .map(|t| {
            let mut table = t.result.as_ref().unwrap().impacts.clone();
            for i in table.impacts.iter_mut() {
                if let Some(l) = listed.iter().find(|l| l.0 == t.spec.id && l.1 == i.k) {
                    i.r = l.3;
                }
            }
            (t.spec.id.clone(), table)
        })
        .collect();
    let inputs: Vec<rocklab::law_fit::TestImpacts> = tables.iter().map(|(id, table)| rocklab::law_fit::TestImpacts { id, table }).collect();
    let on_truth = rocklab::law_fit::fit_law(rocklab::wall::Rocking::TwoSided, &inputs).unwrap();
    let (w_rms, _, _) = law_vs_truth(&on_truth.law, &res, &truth);
    let p = on_truth.law.parameters.inward;
    let q = res.law.as_ref().unwrap().law.parameters.inward;
    println!(
        "two-sided: the law with the readings' weights on the truth's r: r_inf {:.4} c {:.4}, RMS {w_rms:.4} against the truth; on the readings r_inf {:.4} c {:.4}",
        p.r_inf, p.c, q.r_inf, q.c
    );
    assert!(law_rms < cst_rms, "law {law_rms:.4} vs constant {cst_rms:.4}");
    assert!(law_rms <= 0.02, "law RMS {law_rms:.4} against the truth");
    assert!(res.law.as_ref().unwrap().rejects_constant);
}

/// One-sided compliant contacts. The impacts after the table's five are read
/// with the contact model (src/peaks/late.rs, `contact_peaks`). Asserted: at
/// least 80 % of the listed impacts reported (94 % when written: 31 of 33; 88 %, 29 of 33,
/// since the contact readings' model-form term, `impacts::CONTACT_READING_FORM`), the
/// per-impact RMS within the 0.015 (0.0123 when written, 0.0137 and 0.0125 before; the late
/// readings with the contact model, docs/restitution-law.md), and
/// the law from them closer to the truth than the best constant pair (0.0287
/// against 0.0537 when written; the same law fitted to the truth's own r:
/// 0.0287, `law_form_against_the_engine_truth`). Printed, not asserted: the law's RMS against
/// the 0.025 (not met: no law of amplitude alone meets it here, even
/// fitted to the truth). Where a side keeps the constant, the report must say
/// it is not vouched for below the readings. Ignored as the two-sided one.
#[test]
#[ignore]
fn mujoco_one_sided_impacts_and_law() {
    let (res, truth) = reduce("mujoco-public-one-sided");
    let (rms_r, coverage, z) = per_impact(&res, &truth);
    let (law_rms, cst_rms, inside) = law_against_truth(&res, &truth);
    println!(
        "one-sided: per-impact RMS {rms_r:.4} over {:.0} % of the listed impacts (median |err|/u {z:.2}); law RMS {law_rms:.4} ({inside:.4} inside the fitted amplitudes), best constant pair {cst_rms:.4}",
        100.0 * coverage
    );
    assert!(coverage >= 0.8, "coverage {coverage:.2}");
    // The bound (0.0137 over 31 of 33 when written).
    assert!(rms_r <= 0.015, "per-impact RMS {rms_r:.4}");
    assert!(law_rms < cst_rms, "law {law_rms:.4} vs constant {cst_rms:.4}");
    let fit = res.law.as_ref().unwrap();
    for (side, f) in &fit.sides {
        println!("one-sided {side}: {f:?}");
    }
    let listed = truth_impacts(&res, &truth);
    let mut errs = Vec::new();
    for t in &res.tests {
        for i in t.result.as_ref().unwrap().impacts.impacts.iter().filter(|i| i.side == Side::Outward) {
            if let Some(l) = listed.iter().find(|l| l.0 == t.spec.id && l.1 == i.k) {
                errs.push((i.r - l.3, i.r_u.unwrap()));
            }
        }
    }
    let mean = errs.iter().map(|e| e.0).sum::<f64>() / errs.len() as f64;
    println!(
        "one-sided outward readings against the truth: {} impacts, mean error {mean:+.4}, RMS {:.4}, u {:.3}–{:.3}",
        errs.len(),
        rms(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
        errs.iter().map(|e| e.1).fold(1.0, f64::min),
        errs.iter().map(|e| e.1).fold(0.0, f64::max)
    );
    println!("notes: {:?}", fit.notes);
    if fit.law.parameters.outward.c == 0.0 {
        assert!(
            fit.notes.iter().any(|n| n.starts_with("side out") && n.contains("not vouched for")),
            "{:?}",
            fit.notes
        );
    }
}

/// The idealised two-sided demo draws every impact's e independently of its
/// amplitude: the law fitted to it must not reject the constant.
#[test]
fn two_sided_demo_keeps_a_constant() {
    let (res, _) = reduce("two-sided-demo");
    let fit = res.law.as_ref().unwrap();
    println!("two-sided demo: {:?}", fit.sides);
    assert!(!fit.rejects_constant, "{:?}", fit.sides);
    assert_eq!(fit.law.form, rocklab::restitution_law::LawForm::Constant);
}

/// The idealised one-sided demo: its generator gives the first (inward,
/// largest-amplitude) impact of every test e/e_H = 0.32–0.37 and the later ones
/// 0.45–0.95 at random (truth.json, `e_list_input`), the paper's r₁ effect. The
/// inward speed-loss fit has c < 0 (r rising as the amplitude falls, a speed gain),
/// so the law keeps the constant pair, with or without impact 0: Akaike's criterion
/// favours the rise (F = 6.07), but without each test's first impact it does not,
/// and a rise the release's impacts alone carry is no law of amplitude
/// (src/law_fit.rs, "The inward side of a one-sided wall"). Since the fit adds
/// the form's own misfit τ to every impact's u (Paule–Mandel, src/law_fit.rs), the
/// precise first impacts no longer carry the test against the constant alone: it
/// is not rejected (p = 0.033 > 0.005; it was p = 8e-4 with the bare u); without
/// impact 0 it must not be either (the rest carries no trend with amplitude).
#[test]
fn one_sided_demo_keeps_a_constant_law() {
    use rocklab::impacts::ImpactTable;
    use rocklab::law_fit::{fit_law, TestImpacts};
    let (res, _) = reduce("one-sided-demo");
    let fit = res.law.as_ref().unwrap();
    println!("one-sided demo: {:?}", fit.sides);
    assert!(fit.speed_loss.parameters.inward.c < 0.0);
    assert_eq!(fit.law.form, rocklab::restitution_law::LawForm::Constant);
    assert!(fit.notes[0].contains("but not without each test's first impact"), "{:?}", fit.notes);
    let trimmed: Vec<(String, ImpactTable)> = res
        .tests
        .iter()
        .filter(|t| !t.spec.exclude_from_mean)
        .map(|t| (t.spec.id.clone(), t.result.as_ref().unwrap().impacts.after_release()))
        .collect();
    let input: Vec<TestImpacts> = trimmed.iter().map(|(id, table)| TestImpacts { id, table }).collect();
    let without = fit_law(rocklab::wall::Rocking::OneSided, &input).unwrap();
    println!("without impact 0: {:?}", without.sides);
    assert!(!without.rejects_constant, "{:?}", without.sides);
}

// ---------------------------------------------------------------------------------
// The law's form judged on the engine's own per-impact truth (no reduction: cheap).
// ---------------------------------------------------------------------------------

/// One impact the truth lists: (test, k, side, a from the log, true r).
type Listed = (String, usize, Side, f64, f64);

/// (time, displacement) of a campaign CSV (`#` lines, then `time_s,disp_mm`).
fn read_log(path: &Path) -> (Vec<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(path).unwrap();
    let rows = text.lines().filter(|l| !l.starts_with('#')).skip(1);
    rows.map(|l| {
        let mut it = l.split(',').map(|x| x.trim().parse::<f64>().unwrap());
        (it.next().unwrap(), it.next().unwrap())
    })
    .unzip()
}

/// Least-squares line (intercept, slope) through (t, x).
fn line(t: &[f64], x: &[f64]) -> (f64, f64) {
    let n = t.len() as f64;
    let (mt, mx) = (t.iter().sum::<f64>() / n, x.iter().sum::<f64>() / n);
    let sxy: f64 = t.iter().zip(x).map(|(a, b)| (a - mt) * (b - mx)).sum();
    let sxx: f64 = t.iter().map(|a| (a - mt).powi(2)).sum();
    let slope = sxy / sxx;
    (mx - slope * mt, slope)
}

/// Every impact a MuJoCo campaign's truth lists, with its amplitude read from the
/// log: the rest line (the logger's linear drift) is the line through the samples
/// from 0.5 s after the last zero crossing to the end; a = asin(max |x| / L)/α over
/// the half-cycle between the truth's crossings k − 1 (the release) and k.
/// Listed: public campaigns, `e_engine` a number ≤ 1 (the engine saw a contact);
/// hold-out campaigns (made by tools/mujoco_campaign.py, whose truth gives the
/// velocity peaks, not `e_true`), r_k = |v_{k+1}/v_k|/e_H (the public truth's own
/// definition of `e_true`) where the wall rocks through both half-cycles (one edge
/// off the bedding for at least half of each, `lift_fraction_per_half_cycle`).
fn truth_listed(name: &str) -> (rocklab::wall::Rocking, Vec<Listed>) {
    let dir = campaign_dir(name);
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let rocking = if truth["rocking"] == "two-sided" {
        rocklab::wall::Rocking::TwoSided
    } else {
        rocklab::wall::Rocking::OneSided
    };
    let (alpha, e_h) = (truth["alpha_rad"].as_f64().unwrap(), truth["e_H"].as_f64().unwrap());
    let mut out = Vec::new();
    for t in truth["tests"].as_array().unwrap() {
        let sim = &t["sim"];
        let cross: Vec<f64> = match sim["impacts"].as_array() {
            Some(imp) if !imp.is_empty() => imp.iter().map(|i| i["t_cross"].as_f64().unwrap()).collect(),
            _ => sim["zero_crossings_s"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect(),
        };
        let lever_mm = 1e3
            * sim["lever_arm_m"]
                .as_f64()
                .unwrap_or_else(|| truth["wall"]["sensor_height_m"].as_f64().unwrap());
        let (time, x) = read_log(&dir.join(t["file"].as_str().unwrap()));
        let rest: Vec<usize> = (0..time.len()).filter(|&i| time[i] > cross[cross.len() - 1] + 0.5).collect();
        let (x0, slope) = line(
            &rest.iter().map(|&i| time[i]).collect::<Vec<_>>(),
            &rest.iter().map(|&i| x[i]).collect::<Vec<_>>(),
        );
        let release = sim["t_release_s"].as_f64().unwrap();
        let listed: Vec<(usize, f64, bool)> = match t["e_true"].as_array() {
            Some(e) => e
                .iter()
                .map(|e| {
                    let real = e["e_engine"].as_f64().is_some_and(|x| x <= 1.0);
                    (e["k"].as_u64().unwrap() as usize, e["e_over_eH"].as_f64().unwrap(), real)
                })
                .collect(),
            None => {
                let v: Vec<f64> = t["peaks"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| p["velocity_mm_s"].as_f64().unwrap())
                    .collect();
                let lift: Vec<f64> = sim["lift_fraction_per_half_cycle"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                (0..v.len() - 1)
                    .map(|k| (k, (v[k + 1] / v[k]).abs() / e_h, lift[k] >= 0.5 && lift[k + 1] >= 0.5))
                    .collect()
            }
        };
        for (k, r, real) in listed {
            if !real || k >= cross.len() {
                continue;
            }
            let t0 = if k == 0 { release } else { cross[k - 1] };
            let apex = (0..time.len())
                .filter(|&i| time[i] >= t0 && time[i] <= cross[k])
                .map(|i| (x[i] - x0 - slope * time[i]).abs())
                .fold(0.0, f64::max);
            let a = (apex / lever_mm).min(1.0).asin() / alpha;
            // Impact 0 enters the inward side; the sides alternate.
            let side = if k % 2 == 0 { Side::Inward } else { Side::Outward };
            out.push((t["id"].as_str().unwrap().to_string(), k, side, a, r));
        }
    }
    (rocking, out)
}

/// g(a) = 1/√(a(2 − a)).
fn g(a: f64) -> f64 {
    rocklab::restitution_law::speed_shape(a)
}

/// The plausible u of a reading of r at amplitude a: u = 0.002 g(a). The estimator's
/// own u on P2_140_1 (two-sided MuJoCo, 200 Hz) grows from 0.002 at a = 0.36 to 0.009
/// at a = 0.065, about as g (1.3 → 3.9) does: a speed's error is roughly fixed, and
/// the speed at impact is ∝ 1/g.
fn plausible_u(a: f64) -> f64 {
    0.002 * g(a)
}

/// Weighted least squares of r = b0 − b1 h(a) on `pts` (a, r), weights 1/u².
fn wls(pts: &[(f64, f64)], h: &dyn Fn(f64) -> f64) -> (f64, f64) {
    let (mut s, mut sx, mut sxx, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(a, r) in pts {
        let (w, x) = (plausible_u(a).powi(-2), -h(a));
        s += w;
        sx += w * x;
        sxx += w * x * x;
        sy += w * r;
        sxy += w * x * r;
    }
    let b1 = (s * sxy - sx * sy) / (s * sxx - sx * sx);
    ((sy - b1 * sx) / s, b1)
}

/// As [`wls`] with h = g^q, q the weighted-χ² best on a grid 0.5, 0.55, …, 4.
fn wls_free_exponent(pts: &[(f64, f64)]) -> (f64, f64, f64) {
    let chi2 = |q: f64| {
        let (b0, b1) = wls(pts, &|a| g(a).powf(q));
        let c: f64 = pts.iter().map(|&(a, r)| ((b0 - b1 * g(a).powf(q) - r) / plausible_u(a)).powi(2)).sum();
        (c, b0, b1)
    };
    (0..=70)
        .map(|i| 0.5 + 0.05 * i as f64)
        .map(|q| (chi2(q), q))
        .min_by(|x, y| x.0 .0.total_cmp(&y.0 .0))
        .map(|((_, b0, b1), q)| (b0, b1, q))
        .unwrap()
}

/// The truth of one side (or of both, two-sided) as the law fits it: one ImpactTable
/// per test with r = the truth's own, u = [`plausible_u`], uncorrelated.
fn truth_tables(listed: &[Listed]) -> Vec<(String, rocklab::impacts::ImpactTable)> {
    use rocklab::impacts::{ImpactCoefficient, ImpactTable};
    let mut ids: Vec<&String> = listed.iter().map(|l| &l.0).collect();
    ids.dedup();
    ids.iter()
        .map(|id| {
            let impacts: Vec<ImpactCoefficient> = listed
                .iter()
                .filter(|l| &&l.0 == id)
                .map(|l| ImpactCoefficient {
                    k: l.1,
                    side: l.2,
                    amplitude_over_alpha: l.3,
                    speed_before_mm_s: 1.0,
                    speed_after_mm_s: l.4,
                    e: l.4,
                    e_u: Some(plausible_u(l.3)),
                    r: l.4,
                    r_u: Some(plausible_u(l.3)),
                })
                .collect();
            let n = impacts.len();
            let cov = (0..n)
                .map(|i| (0..n).map(|j| if i == j { impacts[i].r_u.unwrap().powi(2) } else { 0.0 }).collect())
                .collect();
            (
                id.to_string(),
                ImpactTable {
                    impacts,
                    r_cov: Some(cov),
                    raw: Vec::new(),
                    end: None,
                },
            )
        })
        .collect()
}

/// RMS against the truth of the law fitted to the truth (rocklab's own fit, with its
/// test against the constant) and of the best constant pair (each side's mean).
fn law_on_truth(rocking: rocklab::wall::Rocking, listed: &[Listed]) -> (rocklab::law_fit::LawFit, f64, f64) {
    use rocklab::law_fit::{fit_law, TestImpacts};
    let tables = truth_tables(listed);
    let input: Vec<TestImpacts> = tables.iter().map(|(id, table)| TestImpacts { id, table }).collect();
    let fit = fit_law(rocking, &input).unwrap();
    let err: Vec<f64> = listed.iter().map(|l| fit.law.r(l.2, l.3) - l.4).collect();
    let two = rocking == rocklab::wall::Rocking::TwoSided;
    let mean = |s: Side| {
        let v: Vec<f64> = listed.iter().filter(|l| two || l.2 == s).map(|l| l.4).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let cst: Vec<f64> = listed.iter().map(|l| mean(l.2) - l.4).collect();
    (fit, rms(&err), rms(&cst))
}

/// The groups a law is fitted on: both sides two-sided, each side one-sided.
fn groups(rocking: rocklab::wall::Rocking, listed: &[Listed]) -> Vec<(&'static str, Vec<(f64, f64)>)> {
    let pick = |s: Option<Side>| listed.iter().filter(|l| s.is_none_or(|s| l.2 == s)).map(|l| (l.3, l.4)).collect();
    match rocking {
        rocklab::wall::Rocking::TwoSided => vec![("both", pick(None))],
        rocklab::wall::Rocking::OneSided => vec![("in", pick(Some(Side::Inward))), ("out", pick(Some(Side::Outward)))],
    }
}

/// Which form follows the engine's per-impact truth, on two walls of each rocking
/// type (public and hold-out campaigns), down to the smallest listed amplitudes
/// (docs/restitution-law.md, "The form"). Printed per campaign and side: the RMS of
/// r = b0 − b1 h(a) for h = g (the speed-loss form), g² (a fixed energy loss), −ln a,
/// and g^q with q free; and each fitted to the upper 60 % of the amplitudes and read
/// below them (extrapolation). Asserted, on the falling groups (two-sided, one-sided
/// outward): the free exponent's worst extrapolation is worse than the speed-loss
/// form's (it runs to its bounds), which is why the law keeps q = 1; rocklab's own
/// law fitted to the truth of the public campaigns is within the bounds and
/// closer than the best constant pair where a law of amplitude alone can be
/// (two-sided: 0.02 over every listed impact; one-sided outward: 0.025). Printed too,
/// two floors of any law of amplitude: the best monotone step function fitted to the
/// truth itself, and a curve learnt from the other tests; asserted, on the two
/// campaigns whose bound the law misses, that the second misses it too.
#[test]
fn law_form_against_the_engine_truth() {
    let mut worst_q1: f64 = 0.0;
    let mut worst_free: f64 = 0.0;
    let mut floors: Vec<Floor> = Vec::new();
    for name in [
        "mujoco-public-two-sided",
        "mujoco-holdout-two-sided",
        "mujoco-public-one-sided",
        "mujoco-holdout-one-sided",
    ] {
        let (rocking, listed) = truth_listed(name);
        for (side, pts) in groups(rocking, &listed) {
            let shapes: [(&str, &dyn Fn(f64) -> f64); 3] = [("g", &g), ("g²", &|a| g(a).powi(2)), ("−ln a", &|a: f64| -a.ln())];
            let mut line = format!(
                "{name} {side}: {} impacts, a = {:.4}–{:.3};",
                pts.len(),
                pts.iter().map(|p| p.0).fold(1.0, f64::min),
                pts.iter().map(|p| p.0).fold(0.0, f64::max)
            );
            let mut sorted: Vec<f64> = pts.iter().map(|p| p.0).collect();
            sorted.sort_by(f64::total_cmp);
            let cut = sorted[(0.4 * sorted.len() as f64) as usize];
            let upper: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.0 >= cut).collect();
            let lower: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.0 < cut).collect();
            for (label, h) in shapes {
                let (b0, b1) = wls(&pts, h);
                let (u0, u1) = wls(&upper, h);
                let fit = rms(&pts.iter().map(|&(a, r)| b0 - b1 * h(a) - r).collect::<Vec<_>>());
                let ex = rms(&lower.iter().map(|&(a, r)| u0 - u1 * h(a) - r).collect::<Vec<_>>());
                line += &format!(" {label}: {fit:.4} (extrapolated {ex:.3});");
                if label == "g" && side != "in" {
                    worst_q1 = worst_q1.max(ex);
                }
            }
            let (b0, b1, q) = wls_free_exponent(&pts);
            let (u0, u1, uq) = wls_free_exponent(&upper);
            let fit = rms(&pts.iter().map(|&(a, r)| b0 - b1 * g(a).powf(q) - r).collect::<Vec<_>>());
            let ex = rms(&lower.iter().map(|&(a, r)| u0 - u1 * g(a).powf(uq) - r).collect::<Vec<_>>());
            line += &format!(" g^q: {fit:.4} at q = {q:.2} (extrapolated {ex:.3} at q = {uq:.2})");
            if side != "in" {
                worst_free = worst_free.max(ex);
            }
            // One law per test (the test's own bedding or transverse walls): what is
            // left is the form's own misfit, the rest of the campaign's is the tests'
            // differences, which no law of amplitude alone can follow.
            let (mut own_g, mut own_q) = (Vec::new(), Vec::new());
            let mut ids: Vec<&String> = listed.iter().map(|l| &l.0).collect();
            ids.dedup();
            for id in ids {
                let mine: Vec<(f64, f64)> = listed
                    .iter()
                    .filter(|l| &l.0 == id && (side == "both" || (side == "in") == (l.2 == Side::Inward)))
                    .map(|l| (l.3, l.4))
                    .collect();
                if mine.len() < 4 {
                    continue;
                }
                let (b0, b1) = wls(&mine, &g);
                own_g.extend(mine.iter().map(|&(a, r)| b0 - b1 * g(a) - r));
                let (b0, b1, q) = wls_free_exponent(&mine);
                own_q.extend(mine.iter().map(|&(a, r)| b0 - b1 * g(a).powf(q) - r));
            }
            if own_g.is_empty() {
                line += "; one law per test: too few impacts per test";
            } else {
                line += &format!("; one law per test: g {:.4}, g^q {:.4}", rms(&own_g), rms(&own_q));
            }
            let tagged: Vec<(&str, f64, f64)> = listed
                .iter()
                .filter(|l| side == "both" || (side == "in") == (l.2 == Side::Inward))
                .map(|l| (l.0.as_str(), l.3, l.4))
                .collect();
            let (iso, loto) = (monotone_floor(&pts), other_tests_floor(&tagged));
            line += &format!("; any monotone r(a), in-sample: {iso:.4}; a curve of a from the other tests: {loto:.4}");
            floors.push((name, pts.len(), iso, loto));
            println!("{line}");
        }
        let (fit, law_rms, cst_rms) = law_on_truth(rocking, &listed);
        let by_side = |s: Side| {
            let e: Vec<f64> = listed.iter().filter(|l| l.2 == s).map(|l| fit.law.r(l.2, l.3) - l.4).collect();
            rms(&e)
        };
        println!(
            "{name}: rocklab's law fitted to the truth ({}, u = 0.002 g(a)): RMS {law_rms:.4} over {} listed impacts (in {:.4}, out {:.4}), best constant pair {cst_rms:.4}; {:?}",
            fit.law.form.as_str(),
            listed.len(),
            by_side(Side::Inward),
            by_side(Side::Outward),
            fit.law.parameters
        );
        if name == "mujoco-public-two-sided" {
            assert!(law_rms <= 0.02 && law_rms < cst_rms, "{law_rms:.4} vs constant {cst_rms:.4}");
        }
        if name == "mujoco-public-one-sided" {
            truth_law_fixture(&fit);
            let out: Vec<&Listed> = listed.iter().filter(|l| l.2 == Side::Outward).collect();
            let mean = out.iter().map(|l| l.4).sum::<f64>() / out.len() as f64;
            let cst_out = rms(&out.iter().map(|l| mean - l.4).collect::<Vec<_>>());
            let law_out = by_side(Side::Outward);
            assert!(law_out <= 0.025 && law_out < cst_out, "outward {law_out:.4} vs constant {cst_out:.4}");
        }
    }
    println!("worst extrapolation on the falling groups: speed-loss {worst_q1:.3}, free exponent {worst_free:.3}");
    assert!(worst_q1 < worst_free, "{worst_q1:.3} vs {worst_free:.3}");
    // The campaigns whose bound the law misses (docs/restitution-law.md, "The form"):
    // over both sides, a curve of amplitude drawn from the other tests of the campaign
    // misses the truth by more than the bound, so the tests' own differences,
    // not the law's form, are what is left.
    let campaign = |name: &str| {
        let mine: Vec<&Floor> = floors.iter().filter(|f| f.0 == name).collect();
        let n: usize = mine.iter().map(|f| f.1).sum();
        let pool = |v: fn(&Floor) -> f64| (mine.iter().map(|f| f.1 as f64 * v(f).powi(2)).sum::<f64>() / n as f64).sqrt();
        (pool(|f| f.2), pool(|f| f.3))
    };
    for (name, bound) in [("mujoco-holdout-two-sided", 0.02), ("mujoco-public-one-sided", 0.025)] {
        let (iso, loto) = campaign(name);
        println!("{name}: any monotone r(a) per side, in-sample {iso:.4}; from the other tests {loto:.4}; bound {bound}");
        assert!(loto > bound, "{name}: {loto:.4}");
    }
}

/// Issue 20's law criterion on campaigns outside the repository (the
/// directories of `FRESH_CAMPAIGNS`, colon-separated): what any law of
/// amplitude alone can reach there, beside the bound. Printed per campaign:
/// rocklab's law fitted to the truth's own r (`law_on_truth`), the best
/// constant pair, and over both sides pooled, any monotone r(a) in-sample and
/// a curve of a drawn from the other tests (`other_tests_floor`). Where the
/// last exceeds the bound, the tests' own differences, not the law's form or
/// the readings, keep the campaign from it.
/// `FRESH_CAMPAIGNS=/a:/b cargo test --release --test law law_floors -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement on campaigns outside the repository, printed (docs/restitution-law.md)"]
fn law_floors_of_engine_campaigns() {
    let Ok(dirs) = std::env::var("FRESH_CAMPAIGNS") else {
        println!("FRESH_CAMPAIGNS is not set: nothing measured");
        return;
    };
    for dir in dirs.split(':').filter(|d| !d.is_empty()) {
        let (rocking, listed) = truth_listed(dir);
        let (mut n, mut iso2, mut loto2) = (0usize, 0.0, 0.0);
        for (side, pts) in groups(rocking, &listed) {
            let tagged: Vec<(&str, f64, f64)> = listed
                .iter()
                .filter(|l| side == "both" || (side == "in") == (l.2 == Side::Inward))
                .map(|l| (l.0.as_str(), l.3, l.4))
                .collect();
            n += pts.len();
            iso2 += pts.len() as f64 * monotone_floor(&pts).powi(2);
            loto2 += pts.len() as f64 * other_tests_floor(&tagged).powi(2);
        }
        let (_, law_rms, cst_rms) = law_on_truth(rocking, &listed);
        let bound = if rocking == rocklab::wall::Rocking::TwoSided { 0.02 } else { 0.025 };
        println!(
            "{dir}: {n} listed impacts; law fitted to the truth {law_rms:.4}, best constant pair {cst_rms:.4}; any monotone r(a) {:.4}, a curve from the other tests {:.4}; bound {bound}",
            (iso2 / n as f64).sqrt(),
            (loto2 / n as f64).sqrt()
        );
    }
}

/// (campaign, impacts, monotone floor, other-tests floor) of one side.
type Floor = (&'static str, usize, f64, f64);

/// RMS of the best monotone function of amplitude (either direction) fitted to the
/// points themselves: pool-adjacent-violators on r sorted by a. A step function with
/// as many steps as the data allow: an in-sample floor that no smooth law reaches.
fn monotone_floor(pts: &[(f64, f64)]) -> f64 {
    let mut sorted = pts.to_vec();
    sorted.sort_by(|x, y| x.0.total_cmp(&y.0));
    let r: Vec<f64> = sorted.iter().map(|p| p.1).collect();
    let rising = pav(&r);
    let falling: Vec<f64> = pav(&r.iter().map(|x| -x).collect::<Vec<_>>()).iter().map(|x| -x).collect();
    let miss = |fit: &[f64]| rms(&fit.iter().zip(&r).map(|(f, r)| f - r).collect::<Vec<_>>());
    miss(&rising).min(miss(&falling))
}

/// Non-decreasing least-squares fit of `y` (pool adjacent violators, equal weights).
fn pav(y: &[f64]) -> Vec<f64> {
    let mut blocks: Vec<(f64, usize)> = Vec::new();
    for &v in y {
        blocks.push((v, 1));
        while blocks.len() > 1 && blocks[blocks.len() - 2].0 > blocks[blocks.len() - 1].0 {
            let (m1, n1) = blocks.pop().unwrap();
            let (m0, n0) = blocks.pop().unwrap();
            blocks.push(((m0 * n0 as f64 + m1 * n1 as f64) / (n0 + n1) as f64, n0 + n1));
        }
    }
    blocks.iter().flat_map(|&(m, n)| std::iter::repeat_n(m, n)).collect()
}

/// RMS of each impact's r against the Gaussian-weighted mean (bandwidth 0.3 in ln a)
/// of the other tests' r at its amplitude: how well a curve of amplitude learnt from
/// the rest of the campaign predicts a test it has not seen.
fn other_tests_floor(pts: &[(&str, f64, f64)]) -> f64 {
    let miss: Vec<f64> = pts
        .iter()
        .filter_map(|&(id, a, r)| {
            let (mut sw, mut swr) = (0.0, 0.0);
            for &(_, b, s) in pts.iter().filter(|p| p.0 != id) {
                let w = (-0.5 * ((a.ln() - b.ln()) / 0.3).powi(2)).exp();
                sw += w;
                swr += w * s;
            }
            (sw > 1e-9).then(|| swr / sw - r)
        })
        .collect();
    rms(&miss)
}

/// `fixtures/laws/mujoco-public-one-sided-truth.json`, the law `rocklab demo` carries
/// into the façade beside the campaign's own (docs/facade.md): rocklab's law fitted to
/// the engine's per-impact truth of mujoco-public-one-sided (what the readings would
/// give if they reached every listed impact), with its constant pair. Checked here
/// against the fit to 1e-9; `ROCKLAB_WRITE_TRUTH_LAW=1` rewrites it.
fn truth_law_fixture(fit: &rocklab::law_fit::LawFit) {
    let c = &fit.constant.parameters;
    let mut law = serde_json::to_value(fit.law).unwrap();
    law["constant"] = serde_json::json!({
        "r_in": c.inward.r_inf, "r_in_u": c.inward.cov[0][0].sqrt(),
        "r_out": c.outward.r_inf, "r_out_u": c.outward.cov[0][0].sqrt(),
    });
    law["notes"] = serde_json::json!(fit.notes);
    let doc = serde_json::json!({
        "source": "rocklab's law (src/law_fit.rs) fitted to the per-impact truth (e_true, every listed impact) of fixtures/campaigns/mujoco-public-one-sided, u = 0.002 g(a); written by tests/law.rs law_form_against_the_engine_truth",
        "restitution_law": law,
    });
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/laws/mujoco-public-one-sided-truth.json");
    if std::env::var("ROCKLAB_WRITE_TRUTH_LAW").is_ok() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap() + "\n").unwrap();
    }
    let stored = rocklab::ingest::law::read(&path).unwrap();
    let (a, b) = (stored.parameters, fit.law.parameters);
    for (x, y) in [(a.inward, b.inward), (a.outward, b.outward)] {
        assert!((x.r_inf - y.r_inf).abs() < 1e-9 && (x.c - y.c).abs() < 1e-9, "{x:?} vs {y:?}");
        assert_eq!(x.g, y.g);
    }
    assert_eq!(stored.form, fit.law.form);
}

/// Issue 20: `calibrate` fits the law by replay as well. On the two MuJoCo
/// campaigns: each test replayed under r(a) = r∞ − c g(a) over every half-cycle
/// above 20 σ; printed per test and for the campaign, against the engine's
/// per-impact truth (RMS over every listed impact) beside the law from the
/// per-impact readings and the best constant pair (docs/calibration.md).
/// Asserted: every included test has a law replay, and where the campaign's law
/// by replay keeps the speed-loss form it is closer to the truth than the best
/// constant pair. Ignored: minutes in a debug build.
#[test]
#[ignore]
fn mujoco_law_by_replay() {
    for name in ["mujoco-public-two-sided", "mujoco-public-one-sided"] {
        let (res, truth) = reduce(name);
        let t0 = std::time::Instant::now();
        let (cal, law_replay) = rocklab::law_replay::calibrate_with_law(&res.calibration_input(), 6);
        let wall = t0.elapsed().as_secs_f64();
        let lr = &law_replay;
        for t in &lr.tests {
            println!(
                "{name} {}: {} impacts, a = {:.4}–{:.3}, RMS {:.3} mm (constant {:.3} mm), {} it {:?}",
                t.id, t.impacts, t.amplitude_min, t.amplitude_max, t.law_rms_mm, t.constant_rms_mm, t.iterations, t.stop
            );
            for s in &t.sides {
                println!(
                    "    {}: r_inf {:.4} ± {:.4}, c {:.4} ± {:.4} (rho {:?}, z {:.1}); constant {:.4}; {}",
                    s.side,
                    s.r_inf,
                    s.cov[0][0].sqrt(),
                    s.c,
                    s.cov[1][1].sqrt(),
                    s.correlation,
                    s.z.unwrap_or(f64::NAN),
                    s.constant_r,
                    s.reason.as_deref().unwrap_or("law")
                );
            }
        }
        assert!(lr.failed.is_empty(), "{:?}", lr.failed);
        assert_eq!(lr.tests.len(), cal.included.len());
        let law = lr.law.as_ref().unwrap();
        let (rms_replay, cst, inside) = law_vs_truth(law, &res, &truth);
        let (rms_readings, _, _) = law_against_truth(&res, &truth);
        // Each test's own law by replay against that test's listed impacts.
        let listed = truth_impacts(&res, &truth);
        let mut per_test = Vec::new();
        for t in &lr.tests {
            let one = |s: &rocklab::law_replay::SideReplay| (s.r_inf, s.c);
            let (i, o) = (one(&t.sides[0]), one(t.sides.last().unwrap()));
            for l in listed.iter().filter(|l| l.0 == t.id) {
                let (r_inf, c) = if l.2 == Side::Inward { i } else { o };
                per_test.push(r_inf - c * rocklab::restitution_law::speed_shape(l.4) - l.3);
            }
        }
        println!("{name}: notes {:?}", lr.notes);
        println!("{name}: against the readings {:?}", lr.against_readings);
        println!(
            "{name}: law by replay RMS {rms_replay:.4} over all listed impacts ({inside:.4} inside its amplitudes); each test's own law by replay {:.4}; law from the readings {rms_readings:.4}; best constant pair {cst:.4}; calibrate with the law {wall:.1} s",
            rms(&per_test)
        );
        if law.form == rocklab::restitution_law::LawForm::SpeedLoss {
            assert!(rms_replay < cst, "law by replay {rms_replay:.4} vs constant {cst:.4}");
        }
    }
}

/// The law from the readings on the hold-out campaigns (another wall and bedding,
/// made by tools/mujoco_campaign.py; not tuned on), against their truth's r at
/// every listed impact (`truth_listed`: velocity-peak ratios while the wall lifts
/// off), beside the best constant pair of those impacts; likewise the campaign
/// directories in `FRESH_CAMPAIGNS` (colon-separated; `python3
/// tools/mujoco_campaign.py --preset fresh-two-sided --out DIR`). Printed; the
/// hold-outs' laws asserted closer than the constant pair, the two-sided one
/// within 0.05 (docs/restitution-law.md). Ignored: two reductions or more.
#[test]
#[ignore]
fn holdout_law_from_readings() {
    let fresh = std::env::var("FRESH_CAMPAIGNS").unwrap_or_default();
    let names = ["mujoco-holdout-two-sided", "mujoco-holdout-one-sided"]
        .into_iter()
        .chain(fresh.split(':').filter(|s| !s.is_empty()));
    for name in names {
        let (res, _) = reduce(name);
        let (rocking, listed) = truth_listed(name);
        let Ok(fit) = res.law.as_ref() else {
            println!("{name}: no law: {:?}", res.law.as_ref().err());
            continue;
        };
        let law = &fit.law;
        let err: Vec<f64> = listed.iter().map(|l| law.r(l.2, l.3) - l.4).collect();
        let mean = |s: Side| {
            let v: Vec<f64> = listed
                .iter()
                .filter(|l| rocking == rocklab::wall::Rocking::TwoSided || l.2 == s)
                .map(|l| l.4)
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let cst: Vec<f64> = listed.iter().map(|l| mean(l.2) - l.4).collect();
        if rocking == rocklab::wall::Rocking::OneSided {
            for s in [Side::Inward, Side::Outward] {
                let pick = |v: &[f64]| -> Vec<f64> { listed.iter().zip(v).filter(|(l, _)| l.2 == s).map(|(_, e)| *e).collect() };
                println!(
                    "{name}: side {s:?} ({:?}): {} listed impacts, law RMS {:.4}, best constant {:.4}",
                    law.side(s).g,
                    pick(&err).len(),
                    rms(&pick(&err)),
                    rms(&pick(&cst))
                );
            }
        }
        // Where the law misses: inside the amplitudes it was fitted on, and
        // below them (extrapolated).
        let (lo, hi) = (law.parameters.amplitude_min, law.parameters.amplitude_max);
        for (label, keep) in [("inside", true), ("outside", false)] {
            let part: Vec<f64> = listed
                .iter()
                .zip(&err)
                .filter(|(l, _)| (l.3 >= lo && l.3 <= hi) == keep)
                .map(|(_, e)| *e)
                .collect();
            let mean_err = part.iter().sum::<f64>() / part.len().max(1) as f64;
            println!(
                "{name}: {label} a = {lo:.4}–{hi:.4}: {} listed impacts, law RMS {:.4}, mean error {mean_err:+.4}",
                part.len(),
                rms(&part)
            );
        }
        // The "closer than the best constant pair" on the MuJoCo
        // hold-outs (0.0440 against 0.1256 two-sided, 0.0385 against 0.0446
        // one-sided when written), and the two-sided law within 0.05 (0.0440
        // when written, 0.0600 before the R3 session; the speed-loss form fitted
        // to the truth's own r reaches 0.0414 there).
        if name.starts_with("mujoco-holdout") {
            assert!(rms(&err) < rms(&cst), "{name}: law {:.4} vs constant {:.4}", rms(&err), rms(&cst));
        }
        if name == "mujoco-holdout-two-sided" {
            assert!(rms(&err) <= 0.05, "{name}: law {:.4}", rms(&err));
        }
        // One-sided: the impacts the log keeps out of the law (a half-cycle
        // around them lifts off for less than half of it, `impacts::law_end`)
        // against the truth's lift fractions, and the 0.025 on the
        // hold-out (0.0225 when written: the inward r rising as the amplitude
        // falls, c < 0, and the low-lift impacts out of the fit; 0.0376 before).
        if rocking == rocklab::wall::Rocking::OneSided {
            let (agree, total) = lift_proxy_against_truth(name, &res);
            println!("{name}: impacts in the law where the truth has the wall lift off for half of both half-cycles around them: {agree} of {total}");
            if name == "mujoco-holdout-one-sided" {
                assert_eq!(agree, total, "{name}: the log's lift-off test against the truth");
                assert!(rms(&err) <= 0.025, "{name}: law {:.4}", rms(&err));
                assert!(law.parameters.inward.c < 0.0, "{:?}", law.parameters.inward);
            }
        }
        println!(
            "{name}: law from the readings ({:?}, {:?}) RMS {:.4} over {} listed impacts; best constant pair {:.4}; sides {:?}",
            law.form,
            law.parameters.inward,
            rms(&err),
            listed.len(),
            rms(&cst),
            fit.sides
                .iter()
                .map(|s| (s.0.clone(), s.1.impacts, s.1.p_value, s.1.form_u))
                .collect::<Vec<_>>()
        );
    }
}

/// Every reported impact of the ok tests: (those the law takes exactly where the
/// truth has an edge off the bedding for at least half of both half-cycles
/// around them, all), from `truth.json`'s `lift_fraction_per_half_cycle`.
fn lift_proxy_against_truth(name: &str, res: &CampaignResult) -> (usize, usize) {
    let dir = campaign_dir(name);
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let (mut agree, mut total) = (0, 0);
    for t in &res.tests {
        let Ok(r) = &t.result else { continue };
        if !r.analysis.quality.is_ok() {
            continue;
        }
        let lift: Vec<f64> = truth_test(&truth, &t.spec.id)["sim"]["lift_fraction_per_half_cycle"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for i in &r.impacts.impacts {
            let lifts = i.k + 1 < lift.len() && lift[i.k] >= 0.5 && lift[i.k + 1] >= 0.5;
            let in_law = r.law_end.as_ref().is_none_or(|(from, _)| i.k < *from);
            total += 1;
            agree += usize::from(lifts == in_law);
        }
    }
    (agree, total)
}

/// A one-sided wall's impacts around a half-cycle in which it barely lifts
/// off stay in the table but out of the law (`impacts::law_end`). P1_150_2
/// of the public campaign: half-cycle 9 lasts 1.10 × the rigid free arc of its
/// amplitude, and the truth has the wall off the bedding for 0.31 of it (0.73
/// and 0.69 of half-cycles 7 and 8): impact 8 and on are kept out; the law's
/// fit, reduced with the test alone, uses impacts 0–7 only.
#[test]
fn a_half_cycle_that_barely_lifts_off_keeps_its_impacts_out_of_the_law() {
    let dir = campaign_dir("mujoco-public-one-sided");
    let path = dir.join("campaign.toml");
    let mut c = Campaign::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    c.tests.retain(|t| t.id == "P1_150_2");
    let res = reduce_campaign(c, PeakOptions::default());
    let r = res.tests[0].result.as_ref().unwrap();
    let (from, why) = r.law_end.clone().expect("impacts kept out of the law");
    assert_eq!(from, 8, "{why}");
    assert!(why.contains("half-cycle 9"), "{why}");
    assert!(r.impacts.impacts.iter().any(|i| i.k == 8), "the table keeps impact 8");
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let lift = &truth_test(&truth, "P1_150_2")["sim"]["lift_fraction_per_half_cycle"];
    assert!(lift[9].as_f64().unwrap() < 0.5 && lift[8].as_f64().unwrap() >= 0.5 && lift[7].as_f64().unwrap() >= 0.5);
    let fit = res.law.as_ref().unwrap();
    let used: usize = fit.sides.iter().map(|s| s.1.impacts).sum();
    assert_eq!(used, 8, "{:?}", fit.sides);
}

/// A real wall never matches its manifest's nominal geometry (SPEC): the late
/// one-sided readings take the free arc's rate and centre from the log's own fit
/// (`Analysis::small_arc`), not from the manifest. The same logs with the wall
/// declared 10 % thicker (α, p and e_H all change) give the same impacts and the
/// same e at each, within 10⁻³ (measured: 2·10⁻⁵ on every test of the public and
/// hold-out one-sided campaigns, for thickness and height ×0.9 and ×1.1; with
/// the manifest's geometry fixed in the reading, a 10 % change cost a third of
/// the public campaign's late readings). One test, to keep the debug run short.
#[test]
fn one_sided_readings_do_not_lean_on_the_nominal_geometry() {
    let dir = campaign_dir("mujoco-public-one-sided");
    let path = dir.join("campaign.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let reduced = |text: &str| {
        let mut c = Campaign::parse(text, &path).unwrap();
        c.tests.retain(|t| t.id == "P1_150_2");
        let res = reduce_campaign(c, PeakOptions::default());
        let r = res.tests[0].result.as_ref().unwrap().clone();
        // Where the list ends is said, naming the first impact not reported.
        let end = r.impacts.end.clone().expect("why the impacts end");
        assert!(end.starts_with(&format!("impact {}:", r.impacts.impacts.len())), "{end}");
        (res.campaign.alpha_rad, r.impacts.impacts.iter().map(|i| (i.k, i.e)).collect::<Vec<_>>())
    };
    let (alpha, nominal) = reduced(&text);
    let thicker = text.replacen("thickness_m = 0.40", "thickness_m = 0.44", 1);
    assert_ne!(thicker, text, "the fixture's thickness line changed: update the test");
    let (alpha_thick, other) = reduced(&thicker);
    assert!(alpha_thick > alpha * 1.05, "α {alpha} → {alpha_thick}");
    assert!(nominal.len() >= 7, "{nominal:?}");
    assert_eq!(
        nominal.iter().map(|i| i.0).collect::<Vec<_>>(),
        other.iter().map(|i| i.0).collect::<Vec<_>>()
    );
    for ((k, a), (_, b)) in nominal.iter().zip(&other) {
        assert!(
            (a - b).abs() <= 1e-3,
            "impact {k}: e {a:.5} with the manifest's geometry, {b:.5} with a 10 % thicker wall"
        );
    }
}

/// The campaign's Ω/p of its pushes (`parameters.push_speed`, read by a façade
/// study that reads the law by speed) against the engine's own speeds: each
/// outward impact the law is fitted on, ŵ/a with ŵ = |v_k|/(L p α), v_k the
/// truth's peak speed of the sensor before impact k (what the reducer reads; the
/// engine's `omega_before` is taken at first touch, up to 25 ms before the
/// crossing on the late pushes, and is up to 17 % slower), L the lever arm, a the
/// impact's reported amplitude, p and α the manifest's wall. The readings'
/// speeds are within 2 % of the truth's here (measured: 0.1–1.7 %), so the
/// median and the range agree to 2 %. One test, to keep the debug run short.
#[test]
fn push_speed_against_the_engine_speeds() {
    let dir = campaign_dir("mujoco-public-one-sided");
    let path = dir.join("campaign.toml");
    let mut c = Campaign::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    c.tests.retain(|t| t.id == "P1_150_2");
    let part = c.wall().rocking_part();
    let scale = c.tests[0].lever_arm_m * 1e3 * part.p_squared().sqrt() * part.slenderness();
    let res = reduce_campaign(c, PeakOptions::default());
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let peaks = &truth_test(&truth, "P1_150_2")["peaks"];
    let r = res.tests[0].result.as_ref().unwrap();
    let end = r.law_end.as_ref().map_or(usize::MAX, |e| e.0);
    let pushes: Vec<_> = r.impacts.impacts.iter().filter(|i| i.side == Side::Outward && i.k < end).collect();
    for i in &pushes {
        let v = peaks[i.k]["velocity_mm_s"].as_f64().unwrap().abs();
        println!(
            "k{} a {:.4}: {:.2} mm/s read, {v:.2} mm/s true",
            i.k, i.amplitude_over_alpha, i.speed_before_mm_s
        );
    }
    let ratios = pushes
        .iter()
        .map(|i| (i.amplitude_over_alpha, peaks[i.k]["velocity_mm_s"].as_f64().unwrap().abs() / scale));
    let want = rocklab::restitution_law::PushSpeed::of(ratios).unwrap();
    let got = res.law.as_ref().unwrap().law.parameters.push_speed.expect("a one-sided law carries Ω/p");
    println!("push_speed {got:?} against the truth's {want:?}");
    assert_eq!(got.impacts, want.impacts);
    assert!(got.impacts >= 3, "{got:?}");
    assert!((got.median / want.median - 1.0).abs() < 0.02, "{got:?} vs {want:?}");
    for i in 0..2 {
        assert!((got.range[i] / want.range[i] - 1.0).abs() < 0.02, "{got:?} vs {want:?}");
    }
}
