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

fn reduce(name: &str) -> (CampaignResult, Value) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns").join(name);
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
    let law = &res.law.as_ref().unwrap().law;
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
/// the truth (the bound); the law closer to the truth than the best constant
/// pair over every listed impact; the data reject the constant. Measured and
/// printed, not met: RMS 0.02 of the law over the listed impacts. Since the late
/// impacts are read locally (issue E) every listed impact is reported and the law
/// is fitted to all of them: 0.0235 over all 40 (0.032 before, 0.016 inside the
/// amplitudes 0.041–0.36 it was then fitted to; the small impacts fall faster than
/// the form follows): docs/restitution-law.md.
#[test]
fn mujoco_two_sided_impacts_and_law() {
    let (res, truth) = reduce("mujoco-public-two-sided");
    let (rms_r, coverage, z) = per_impact(&res, &truth);
    let (law_rms, cst_rms, inside) = law_against_truth(&res, &truth);
    println!(
        "two-sided: per-impact RMS {rms_r:.4} over {:.0} % of the listed impacts (median |err|/u {z:.2}); law RMS {law_rms:.4} ({inside:.4} inside the fitted amplitudes), best constant pair {cst_rms:.4}",
        100.0 * coverage
    );
    assert!(rms_r <= 0.015, "per-impact RMS {rms_r:.4}");
    assert!(law_rms < cst_rms, "law {law_rms:.4} vs constant {cst_rms:.4}");
    assert!(res.law.as_ref().unwrap().rejects_constant);
}

/// One-sided compliant contacts. Asserted: every impact reported within RMS 0.015
/// of the truth. The first five impacts of each test are all the estimator resolves
/// here (longer fits turn suspect), and over them the data do not reject a constant
/// on either side: the law is then the constant pair, and it is printed against the
/// truth (docs/restitution-law.md).
#[test]
fn mujoco_one_sided_impacts_and_law() {
    let (res, truth) = reduce("mujoco-public-one-sided");
    let (rms_r, coverage, z) = per_impact(&res, &truth);
    let (law_rms, cst_rms, inside) = law_against_truth(&res, &truth);
    println!(
        "one-sided: per-impact RMS {rms_r:.4} over {:.0} % of the listed impacts (median |err|/u {z:.2}); law RMS {law_rms:.4} ({inside:.4} inside the fitted amplitudes), best constant pair {cst_rms:.4}",
        100.0 * coverage
    );
    assert!(rms_r <= 0.015, "per-impact RMS {rms_r:.4}");
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

/// The idealised one-sided demo is not a constant: its generator gives the first
/// (inward, largest-amplitude) impact of every test e/e_H = 0.32–0.37 and the later
/// ones 0.45–0.95 at random (truth.json, `e_list_input`), the paper's r₁ effect. The
/// fit sees that and rejects the constant inward; without impact 0 of each test it
/// must not (the rest carries no trend with amplitude). The inward speed-loss fit has
/// c < 0 (r rising as the amplitude falls, a speed gain), so the law keeps the
/// constant pair.
#[test]
fn one_sided_demo_rejects_only_through_its_first_impact() {
    use rocklab::impacts::ImpactTable;
    use rocklab::law_fit::{fit_law, TestImpacts};
    let (res, _) = reduce("one-sided-demo");
    let fit = res.law.as_ref().unwrap();
    println!("one-sided demo: {:?}", fit.sides);
    assert!(fit.rejects_constant);
    assert!(fit.speed_loss.parameters.inward.c < 0.0);
    assert_eq!(fit.law.form, rocklab::restitution_law::LawForm::Constant);
    let trimmed: Vec<(String, ImpactTable)> = res
        .tests
        .iter()
        .filter(|t| !t.spec.exclude_from_mean)
        .map(|t| {
            let table = &t.result.as_ref().unwrap().impacts;
            let cov = table.r_cov.as_ref().unwrap();
            let keep: Vec<usize> = (1..table.impacts.len()).collect();
            let sub = ImpactTable {
                impacts: keep.iter().map(|&i| table.impacts[i]).collect(),
                r_cov: Some(keep.iter().map(|&i| keep.iter().map(|&j| cov[i][j]).collect()).collect()),
                raw: Vec::new(),
            };
            (t.spec.id.clone(), sub)
        })
        .collect();
    let input: Vec<TestImpacts> = trimmed.iter().map(|(id, table)| TestImpacts { id, table }).collect();
    let without = fit_law(rocklab::wall::Rocking::OneSided, &input).unwrap();
    println!("without impact 0: {:?}", without.sides);
    assert!(!without.rejects_constant, "{:?}", without.sides);
}
