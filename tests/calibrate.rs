//! Issue #4: the calibration recovers constant e_in/e_out from a campaign made with
//! the project's own solver and a realistic sensor (noise 0.02–0.05 mm, 100–1000
//! Hz, drift, quantisation to 0.01 mm). Tolerance 0.01 on each coefficient (the
//! issue's bound); and the fits' 95 % intervals cover the true coefficients
//! (half-widths 0.0002–0.0012 here, errors up to 0.0010), over many seeds at the
//! rate a 95 % interval should.

use std::path::Path;

use rocklab::calibrate::calibrate;
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::reduce_campaign;

mod common;
use common::{synthetic_log, LogSpec};

const E_IN: f64 = 0.55;
const E_OUT: f64 = 0.75;
const KAPPA: f64 = 80.0;

const MANIFEST_HEAD: &str = "[campaign]\nname = \"synthetic\"\nrocking = \"one-sided\"\n[wall]\nheight_m = 2.70\nthickness_m = 0.36\nhinge_height_m = 0.23\n[channels]\ntime = { column = \"time_s\", unit = \"s\" }\ndisplacement = { column = \"disp_mm\", unit = \"mm\", height_m = 2.56 }\n";

/// Whether the interval holds the value.
fn covers(ci: [f64; 2], truth: f64) -> bool {
    ci[0] <= truth && truth <= ci[1]
}

fn log(fs: f64, sigma: f64, drift_mm: f64, x0_mm: f64, seed: u64) -> String {
    synthetic_log(&LogSpec {
        kappa: KAPPA,
        e_in: E_IN,
        e_out: E_OUT,
        fs,
        sigma_mm: sigma,
        drift_mm,
        x0_mm,
        seed,
    })
    .0
}

#[test]
fn recovers_constant_coefficients_from_synthetic_campaign() {
    let dir = tempfile::tempdir().unwrap();
    let tests = [
        ("a", 100.0, 0.05, 0.08, 150.0),
        ("b", 200.0, 0.02, -0.1, 120.0),
        ("c", 1000.0, 0.03, 0.05, 100.0),
    ];
    let mut manifest = String::from(MANIFEST_HEAD);
    for (i, (id, fs, sigma, drift, x0)) in tests.iter().enumerate() {
        std::fs::write(dir.path().join(format!("{id}.csv")), log(*fs, *sigma, *drift, *x0, 17 + i as u64)).unwrap();
        manifest.push_str(&format!("[[test]]\nid = \"{id}\"\nfile = \"{id}.csv\"\n"));
    }
    let path = dir.path().join("campaign.toml");
    std::fs::write(&path, manifest).unwrap();
    let res = reduce_campaign(Campaign::load(&path).unwrap(), PeakOptions::default());
    for t in &res.tests {
        assert!(t.result.is_ok(), "{}: {:?}", t.spec.id, t.result.as_ref().err());
    }
    let cal = calibrate(&res.calibration_input(), 6);
    assert!(cal.failed.is_empty(), "{:?}", cal.failed);
    for f in &cal.tests {
        println!(
            "{}: e_in {:.4} ± {:.4}, e_out {:.4} ± {:.4}, rms {:.4} mm, {:?}",
            f.id,
            f.e_in,
            1.96 * f.se_e_in,
            f.e_out,
            1.96 * f.se_e_out,
            f.rms_mm,
            f.stop
        );
        assert!((f.e_in - E_IN).abs() < 0.01, "{}: e_in {}", f.id, f.e_in);
        assert!((f.e_out - E_OUT).abs() < 0.01, "{}: e_out {}", f.id, f.e_out);
        // The 95 % intervals cover the coefficients the logs were made with (not
        // merely the estimate: that was always true). Drift is not in the model,
        // so this can fail; the coverage rate without drift is measured below.
        assert!(covers(f.ci95_e_in, E_IN), "{}: e_in interval {:?} misses {E_IN}", f.id, f.ci95_e_in);
        assert!(covers(f.ci95_e_out, E_OUT), "{}: e_out interval {:?} misses {E_OUT}", f.id, f.ci95_e_out);
    }
    assert!((cal.e_in - E_IN).abs() < 0.01 && (cal.e_out - E_OUT).abs() < 0.01);
    let j = cal.joint.clone().expect("joint fit");
    assert!(
        (j.e_in - E_IN).abs() < 0.01 && (j.e_out - E_OUT).abs() < 0.01,
        "joint {} {}",
        j.e_in,
        j.e_out
    );
    // calibration.toml round-trips into the readers of simulate and the façade study.
    let toml_path = Path::new(dir.path()).join("calibration.toml");
    std::fs::write(&toml_path, rocklab::calibrate::to_toml(&cal).unwrap()).unwrap();
    let (ei, eo) = rocklab::ingest::calibration::read_coefficients(&toml_path).unwrap();
    assert_eq!((ei, eo), (cal.e_in, cal.e_out));
    // Issue 10: it carries what a façade ensemble draws from, and the study's
    // calibration set draws e_in ~ N(mean, √(sd_tests² + se_fit²)).
    let file = rocklab::ingest::calibration::read(&toml_path).unwrap().calibration;
    // The tests were made with one pair: their fits agree on it, and the file says so.
    let agreement = cal.agreement.expect("three tests");
    println!("{}", agreement.describe());
    assert!(agreement.share_one_pair, "{}", agreement.describe());
    assert_eq!(file.joint.as_ref().and_then(|j| j.agreement), Some(agreement));
    let sp = file.spread.clone().expect("[calibration.spread]").spread;
    let inc: Vec<_> = cal.tests.iter().filter(|t| cal.included.contains(&t.id)).collect();
    assert_eq!(sp.n_tests, inc.len());
    let n = inc.len() as f64;
    let mean = inc.iter().map(|t| t.e_in).sum::<f64>() / n;
    let sd = (inc.iter().map(|t| (t.e_in - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!((sp.sd_e_in_tests - sd).abs() < 1e-12, "{} vs {sd}", sp.sd_e_in_tests);
    assert!((sp.se_e_in_mean - sd / n.sqrt()).abs() < 1e-12);
    let set = rocklab::facade::calibration_set("campaign", "calibration.toml", &file, "tests").unwrap();
    match set.dist {
        rocklab::ensemble::CoefficientDist::Pair { e_in, .. } => assert_eq!(
            e_in,
            rocklab::ensemble::Dist::Normal {
                mean: cal.e_in,
                sd: sp.sd_e_in_tests.hypot(sp.se_e_in_fit)
            }
        ),
        other => panic!("one-sided calibration gives a pair, not {other:?}"),
    }
    assert!(rocklab::facade::calibration_set("c", "f", &file, "sideways").is_err());
}

/// The fits' 95 % intervals over 16 seeded noisy tests (100–1000 Hz, σ 0.02–0.05
/// mm, quantised to 0.01 mm, releases from 100–150 mm, no drift: the model is then
/// exact), counted per coefficient: how often they cover the true e_in and e_out.
///
/// Measured: 15 of 16 for e_in and 15 of 16 for e_out (one test, s7, misses both:
/// its two errors are correlated). Bound: at least 13 of 16 each. With honest 95 %
/// intervals the chance of 4 or more misses out of 16 is 0.7 % (binomial), so a
/// failure means the standard errors are too small or the fit biased; the seeds
/// are fixed, so the test is deterministic.
#[test]
fn intervals_cover_the_true_coefficients() {
    let dir = tempfile::tempdir().unwrap();
    let n = 16u64;
    let mut manifest = String::from(MANIFEST_HEAD);
    for seed in 0..n {
        let k = seed as usize;
        let (fs, sigma, x0) = (
            [100.0, 200.0, 500.0, 1000.0][k % 4],
            [0.02, 0.03, 0.05][k % 3],
            100.0 + 10.0 * (k % 6) as f64,
        );
        let id = format!("s{seed}");
        std::fs::write(dir.path().join(format!("{id}.csv")), log(fs, sigma, 0.0, x0, 1000 + seed)).unwrap();
        manifest.push_str(&format!("[[test]]\nid = \"{id}\"\nfile = \"{id}.csv\"\n"));
    }
    let path = dir.path().join("campaign.toml");
    std::fs::write(&path, manifest).unwrap();
    let res = reduce_campaign(Campaign::load(&path).unwrap(), PeakOptions::default());
    let cal = calibrate(&res.calibration_input(), 6);
    assert!(cal.failed.is_empty(), "{:?}", cal.failed);
    assert_eq!(cal.tests.len(), n as usize);
    let (mut covered_in, mut covered_out) = (0, 0);
    for f in &cal.tests {
        let (ci, co) = (covers(f.ci95_e_in, E_IN), covers(f.ci95_e_out, E_OUT));
        let word = |c: bool| if c { "covers" } else { "MISSES" };
        println!(
            "{}: e_in {:.5} ± {:.5} ({}), e_out {:.5} ± {:.5} ({})",
            f.id,
            f.e_in,
            1.96 * f.se_e_in,
            word(ci),
            f.e_out,
            1.96 * f.se_e_out,
            word(co)
        );
        covered_in += ci as usize;
        covered_out += co as usize;
    }
    println!("coverage: e_in {covered_in}/{n}, e_out {covered_out}/{n}");
    assert!(covered_in >= 13, "e_in intervals cover the truth in only {covered_in} of {n} tests");
    assert!(covered_out >= 13, "e_out intervals cover the truth in only {covered_out} of {n} tests");
}

/// A two-sided test made with the project's own solver under a law (or a
/// constant), 200 Hz, noise 0.02 mm: the window of the law replay (every
/// half-cycle above 20 σ) and the constant fit over the first six impacts that
/// starts it.
fn law_test(
    law: Option<(f64, f64)>,
    seed: u64,
) -> (
    rocklab::calibrate::TestWindow,
    Vec<rocklab::law_replay::HalfCycle>,
    rocklab::calibrate::Geometry,
    f64,
) {
    use rocklab::restitution_law::{LawForm, LawParameters, RestitutionLaw, SideLaw};
    use rocklab::solver::{ImpactLaw, Restraint, RockingModel};
    use rocklab::wall::{p_squared_rectangular, slenderness};
    let (h, b, lever, fs, sigma, x0) = (2.47, 0.36, common::LEVER_MM, 200.0, 0.02, 130.0);
    let alpha = slenderness(b, h);
    let e_h = 1.0 - 1.5 * alpha.sin().powi(2);
    let side = |(r_inf, c): (f64, f64)| SideLaw {
        r_inf,
        c,
        cov: [[0.0; 2]; 2],
        g: Default::default(),
        energy: None,
    };
    let model = RockingModel {
        alpha,
        p2: p_squared_rectangular(h, b),
        i0: 1.0,
        restraint: Restraint::None,
        ties: Vec::new(),
        e_in: 0.9,
        e_out: 0.9,
        law: law.map(|l| {
            let law = RestitutionLaw {
                form: LawForm::SpeedLoss,
                parameters: LawParameters {
                    inward: side(l),
                    outward: side(l),
                    shared: true,
                    amplitude_min: 1e-6,
                    amplitude_max: 1.0,
                    inward_amplitude_min: None,
                    observed: None,
                    push_speed: None,
                },
            };
            ImpactLaw::new(std::sync::Arc::new(law), e_h)
        }),
        overturn_limit: 1.0,
        linearized: false,
    };
    let (t_r, dur) = (0.5 + 0.37 / fs, 8.0);
    let t: Vec<f64> = (0..(dur * fs) as usize).map(|i| i as f64 / fs).collect();
    let th0 = (x0 / lever).asin();
    let (_, th) = common::free_rocking(&model, &t, t_r, th0, dur);
    let mut rng = common::Rng(seed);
    let x: Vec<f64> = th.iter().map(|v| lever * v.sin() + sigma * rng.normal()).collect();
    let hc = rocklab::law_replay::half_cycles(&t, &x, t_r, 3.0 * sigma, 20.0 * sigma, 24);
    let n = hc.len();
    let t_end = hc[n - 1].crossing_s + 0.5 * (hc[n - 1].crossing_s - hc[n - 2].crossing_s);
    let i1 = t.partition_point(|&v| v <= t_end);
    let i0 = t.partition_point(|&v| v < t_r - 0.1);
    let w = rocklab::calibrate::TestWindow {
        id: "law".into(),
        t: t[i0..i1].to_vec(),
        x_mm: x[i0..i1].to_vec(),
        release_s: t_r,
        x_release_mm: x0,
        lever_mm: lever,
        t_end,
        filter: None,
    };
    let geom = rocklab::calibrate::Geometry {
        alpha,
        p2: p_squared_rectangular(h, b),
        one_sided: false,
    };
    (w, hc, geom, e_h)
}

/// Issue 20: the law by replay recovers (r∞, c) from a test its own solver made
/// under a law, and finds no speed loss in a test made with a constant.
/// Tolerances: 0.005 on r∞ and c (the fit's own u here is ~1e-4; the start from a
/// six-impact constant fit, the 200 Hz sampling and the 0.02 mm noise are all
/// the error there is), and on the constant test the verdict must be the
/// constant (c/u below 2.576, or c ≤ 0).
#[test]
fn law_by_replay_recovers_its_own_law() {
    for (law, seed) in [(Some((1.0, 0.02)), 5u64), (None, 6)] {
        let (w, hc, geom, e_h) = law_test(law, seed);
        let short = {
            let k = hc[5].crossing_s + 0.5 * (hc[5].crossing_s - hc[4].crossing_s);
            let n = w.t.partition_point(|&v| v <= k);
            rocklab::calibrate::TestWindow {
                t: w.t[..n].to_vec(),
                x_mm: w.x_mm[..n].to_vec(),
                t_end: k,
                ..w.clone()
            }
        };
        let start = rocklab::calibrate::fit_test(&short, &geom, true).unwrap();
        let fit = rocklab::law_replay::fit_test_law(&w, &hc, &geom, e_h, &start).expect("a law replay");
        let s = &fit.sides[0];
        println!(
            "made with {law:?}: {} impacts over a = {:.3}–{:.3}; r_inf {:.4}, c {:.4} ± {:.4} (z {:.1}), constant {:.4}; RMS {:.4} mm (constant {:.4}); {:?}",
            fit.impacts, fit.amplitude_min, fit.amplitude_max, s.r_inf, s.c, s.cov[1][1].sqrt(), s.z.unwrap_or(f64::NAN), s.constant_r, fit.law_rms_mm, fit.constant_rms_mm, s.reason
        );
        assert!(fit.impacts >= 10, "{} impacts", fit.impacts);
        match law {
            Some((r_inf, c)) => {
                assert!(s.separated, "{:?}", s.reason);
                assert!((s.r_inf - r_inf).abs() < 0.005 && (s.c - c).abs() < 0.005, "r_inf {} c {}", s.r_inf, s.c);
                assert!(fit.law_rms_mm < fit.constant_rms_mm);
            }
            None => {
                assert!(!s.separated, "a constant test read as a law: c {} ± {}", s.c, s.cov[1][1].sqrt());
                assert!((s.constant_r * e_h - 0.9).abs() < 0.005, "constant r {}", s.constant_r);
            }
        }
    }
}

/// A fit that drives the wall's frequency parameter p² up by 10¹⁴ (what a
/// mutated log whose time column was scaled by 10⁻³ did: 2.1 million steps and
/// 39,000 impacts per replay, and `calibrate` ran for hours) has its replay
/// given up at `replay_step_budget` steps instead; the same window at the
/// geometry's p² replays as before.
#[test]
fn a_replay_that_runs_away_is_given_up() {
    let (w, _, geom, _) = law_test(None, 6);
    let nominal = [0.0, 0.0, 0.0];
    assert!(rocklab::calibrate::replay(&w, &geom, 0.9, 0.9, rocklab::calibrate::Nuisance(&nominal)).is_some());
    let runaway = [0.0, 0.0, (1e14f64).ln()];
    assert!(rocklab::calibrate::replay(&w, &geom, 0.999, 0.999, rocklab::calibrate::Nuisance(&runaway)).is_none());
    assert!(rocklab::calibrate::replay_step_budget(w.t.len()) < 1_000_000);
}

/// A test the reducer cannot vouch for is fitted and listed but left out of the
/// calibration's means, as `reduce` leaves it out of the campaign means: the
/// reducer's impacts window the replay. The means are then those of the other
/// tests alone.
#[test]
fn a_suspect_test_is_left_out_of_the_means() {
    let dir = tempfile::tempdir().unwrap();
    let mut manifest = String::from(MANIFEST_HEAD);
    for (i, id) in ["a", "b"].iter().enumerate() {
        std::fs::write(dir.path().join(format!("{id}.csv")), log(200.0, 0.02, 0.05, 140.0, 40 + i as u64)).unwrap();
        manifest.push_str(&format!("[[test]]\nid = \"{id}\"\nfile = \"{id}.csv\"\n"));
    }
    let path = dir.path().join("campaign.toml");
    std::fs::write(&path, manifest).unwrap();
    let mut res = reduce_campaign(Campaign::load(&path).unwrap(), PeakOptions::default());
    let b = res.tests.iter_mut().find(|t| t.spec.id == "b").unwrap();
    b.result.as_mut().unwrap().analysis.quality = rocklab::peaks::Quality::Suspect(vec!["planted".into()]);
    let cal = calibrate(&res.calibration_input(), 6);
    assert_eq!(cal.included, vec!["a".to_string()]);
    assert_eq!(cal.left_out, vec![("b".to_string(), "suspect: planted".to_string())]);
    assert_eq!(cal.tests.len(), 2, "the suspect test is still fitted and listed");
    let a = cal.tests.iter().find(|t| t.id == "a").unwrap();
    assert_eq!((cal.e_in, cal.e_out), (a.e_in, a.e_out));
    assert!(rocklab::calibrate::to_toml(&cal).unwrap().contains("left out: b (suspect)"));
}

/// The logger's filter is part of the replay: `fixtures/campaigns/bessel-replay`
/// was made outside rocklab (`tools/filtered_replay_campaign.py`: scipy's rigid
/// block with e = 0.85, seen through scipy's 4th-order Bessel at 0.10 fs, stated
/// in the manifest, noise σ = 0.03 mm). Replayed through the stated filter, every
/// fit's residuals are at the noise (RMS ≤ 1.15 σ; 0.030–0.031 mm measured) and
/// the joint e is within 3 standard errors of 0.85 (0.849993 ± 0.000004 when
/// written). The same logs declared unfiltered (`filter = "none"`: what the
/// replay did before it saw the filter) leave residuals above 3 σ (0.097–0.111
/// mm) and a joint e 0.0004 low, some 40 standard errors: a bias its interval
/// does not hold.
#[test]
fn a_stated_filter_is_replayed() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns/bessel-replay");
    let calibrate_as = |manifest: &Path| {
        let res = reduce_campaign(Campaign::load(manifest).unwrap(), PeakOptions::default());
        calibrate(&res.calibration_input(), 6)
    };
    const SIGMA: f64 = 0.03;
    let stated = calibrate_as(&src.join("campaign.toml"));
    assert_eq!(stated.included.len(), 4, "{:?}", stated.left_out);
    for t in &stated.tests {
        assert!(t.rms_mm <= 1.15 * SIGMA, "{}: RMS {:.4} mm", t.id, t.rms_mm);
    }
    let j = stated.joint.as_ref().expect("a joint fit");
    assert!((j.e_in - 0.85).abs() <= 3.0 * j.se_e_in, "e {:.6} ± {:.6}", j.e_in, j.se_e_in);
    // One e made every test: the fits agree on it (p = 0.23 when written).
    let agreement = stated.agreement.expect("four tests");
    assert!(agreement.share_one_pair, "{}", agreement.describe());

    let dir = tempfile::tempdir().unwrap();
    for f in std::fs::read_dir(&src).unwrap() {
        let p = f.unwrap().path();
        if p.extension().is_some_and(|e| e == "csv") {
            std::fs::copy(&p, dir.path().join(p.file_name().unwrap())).unwrap();
        }
    }
    let text = std::fs::read_to_string(src.join("campaign.toml")).unwrap();
    let none: String = text
        .lines()
        .map(|l| {
            if l.starts_with("acquisition") {
                "acquisition = { filter = \"none\" }"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(dir.path().join("campaign.toml"), none).unwrap();
    let unfiltered = calibrate_as(&dir.path().join("campaign.toml"));
    for t in &unfiltered.tests {
        assert!(t.rms_mm > 3.0 * SIGMA, "{}: RMS {:.4} mm: the filter no longer shows", t.id, t.rms_mm);
    }
    let j = unfiltered.joint.as_ref().expect("a joint fit");
    assert!((j.e_in - 0.85).abs() > 10.0 * j.se_e_in, "e {:.6} ± {:.6}", j.e_in, j.se_e_in);
}
