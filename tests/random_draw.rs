//! Issue #9: random resolvable tests from the seeded generator (`rocklab::synth`),
//! reduced with the default estimator and scored against their truth. The test
//! looks for failures: any test more than 5 pp off with status ok fails it, and
//! the success rate (status ok and every table value within 1 pp) is asserted.
//!
//! `cargo test` runs a small draw; the full draw of the issue (500 rigid tests,
//! 200 compliant) is `cargo test --release --test random_draw -- --ignored --nocapture`.

use rayon::prelude::*;
use rocklab::synth::{draw, score, Family, Scored};

fn run(family: Family, seeds: std::ops::Range<u64>) -> Vec<Scored> {
    seeds.into_par_iter().map(|s| score(&draw(s, family))).collect()
}

/// Print the failures and the summary; return (success rate, silent failures).
fn summarise(name: &str, scored: &[Scored]) -> (f64, usize) {
    let mut ok = 0;
    let mut silent = 0;
    let mut worst_ok: f64 = 0.0;
    let mut flagged = 0;
    for s in scored {
        let good = s.status == "ok";
        match &s.worst_pp {
            Ok(w) if good && *w <= 1.0 => ok += 1,
            Ok(w) => {
                if good && *w > 5.0 {
                    silent += 1;
                }
                if !good {
                    flagged += 1;
                }
                println!(
                    "{name} seed {:4}: {:7.2} pp  [{}]  fs {} Hz, kappa/p2 {:.2}, theta0/alpha {:.2}, sigma {:.3} mm, spikes {}",
                    s.seed,
                    w,
                    s.status,
                    s.spec.fs_hz,
                    s.spec.kappa / s.spec.p2(),
                    s.spec.theta0 / s.spec.alpha(),
                    s.spec.sigma_mm,
                    s.spec.spikes
                );
            }
            Err(e) => {
                flagged += 1;
                println!("{name} seed {:4}: error {e}", s.seed);
            }
        }
        if good {
            if let Ok(w) = s.worst_pp {
                worst_ok = worst_ok.max(w);
            }
        }
    }
    let mut errs: Vec<f64> = scored.iter().filter_map(|s| s.worst_pp.as_ref().ok().copied()).collect();
    errs.sort_by(f64::total_cmp);
    let med = errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN);
    let rate = ok as f64 / scored.len() as f64;
    println!(
        "{name}: {} tests, {:.1} % ok and within 1 pp, {flagged} flagged (suspect/error), {silent} silently > 5 pp, median worst error {med:.3} pp, worst with status ok {worst_ok:.2} pp",
        scored.len(),
        100.0 * rate
    );
    (rate, silent)
}

/// 40 rigid draws in the default test run (seeds 0–39: every one within 1 pp
/// with status ok when this was written; one miss is allowed).
#[test]
fn random_rigid_tests_small_draw() {
    let scored = run(Family::Rigid, 0..40);
    let (rate, silent) = summarise("rigid", &scored);
    assert_eq!(silent, 0, "a test more than 5 pp off was reported ok");
    assert!(rate >= 0.975, "success rate {rate}");
}

/// The five tests of the full draw that were missed before the large-angle
/// correction of the gravity arcs and the rejection of spikes next to impacts
/// (two 0.7 α releases whose large arcs the small-angle model could not follow,
/// so that contact phases absorbed the misfit; three 100 Hz logs with a spike
/// beside an impact): each is now ok and within 1 pp.
#[test]
fn tests_once_missed_are_reduced() {
    use rocklab::synth::{generate, spec_for_seed};
    for seed in [1137003411, 1185003555, 1229003687, 1231003695, 1379004137] {
        let s = score(&generate(&spec_for_seed(seed, Family::Rigid)));
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        assert!(s.status == "ok" && w <= 1.0, "seed {seed}: {w} pp, {}", s.status);
    }
}

/// 12 compliant draws: none silently wrong (the full draw gives the rate).
#[test]
fn random_compliant_tests_small_draw() {
    let scored = run(Family::Compliant, 0..12);
    let (_, silent) = summarise("compliant", &scored);
    assert_eq!(silent, 0, "a test more than 5 pp off was reported ok");
}

/// The draw: 500 resolvable tests of the idealised model. Measured
/// 100 % ok and within 1 pp (worst 0.86 pp), no test more than 5 pp off with
/// status ok. The bound is the 99.5 %.
#[test]
#[ignore = "the full draw of issue #9: run in release (see the module docs)"]
fn random_rigid_tests_full_draw() {
    let scored = run(Family::Rigid, 1000..1500);
    let (rate, silent) = summarise("rigid", &scored);
    assert_eq!(silent, 0);
    assert!(rate >= 0.995, "success rate {rate}");
}

/// 200 tests with finite-duration lossy contacts (the compliant generator): none
/// more than 5 pp off with status ok. The success rate (60 % when this was
/// written) is printed, not asserted: this family is where the estimator's
/// contact model is still weak (README).
#[test]
#[ignore = "the full compliant draw: run in release (see the module docs)"]
fn random_compliant_tests_full_draw() {
    let scored = run(Family::Compliant, 1000..1200);
    let (rate, silent) = summarise("compliant", &scored);
    assert_eq!(silent, 0);
    assert!(rate >= 0.55, "success rate {rate}");
}
