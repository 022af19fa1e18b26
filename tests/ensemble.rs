//! Issue 10: the façade ensembles against known answers. Small ensembles (the
//! suite runs in debug builds on 2 cores); the statistics are in the unit tests of
//! `stats`, `ensemble` and `fragility`.

use std::path::Path;

use rayon::prelude::*;
use rocklab::ensemble::{draw, name_key, summarise, CoefficientDist, Dist, Nominal, Outcome, SampleKey, Uncertainty};
use rocklab::facade::{run_ensembles, Study};
use rocklab::solver::{simulate, Ground, Restraint, RockingModel, Settings, Stop};
use rocklab::stats::{wilson, Z95};
use rocklab::study::{run_with, RunSpec};
use rocklab::G;

fn fixture_study() -> Study {
    Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/study.toml")).unwrap()
}

/// (a) A rectangular pulse of duration t_d whose amplitude is drawn around
/// Housner's closed-form threshold a/(g α) = 1/(1 − e^(−p t_d)) (linearised
/// equation, exact; Housner 1963): P(overturn) equals the fraction of draws above
/// the threshold, draw by draw outside a ±0.5 % band (the sampled pulse's ramp
/// shifts the threshold by ~2.5e-4 relative, the solver's own test holds 0.2 %),
/// and the exact probability of the drawing distribution lies in the ensemble's
/// 95 % Wilson interval.
#[test]
fn rectangular_pulse_probability_matches_the_draws_above_housner_threshold() {
    let (alpha, p2, td): (f64, f64, f64) = (0.2, 4.0, 0.3);
    let crit = 1.0 / (1.0 - (-(p2.sqrt()) * td).exp());
    let model = RockingModel {
        alpha,
        p2,
        i0: 1.0,
        restraint: Restraint::None,
        ties: Vec::new(),
        e_in: 0.9,
        e_out: 0.9,
        law: None,
        overturn_limit: alpha,
        linearized: true,
    };
    // The amplitude factor m ~ U[0.92, 1.12]: P(m > 1) = 0.12/0.20 = 0.6 exactly.
    let unc = Uncertainty {
        magnification: Some(Dist::Uniform { lo: 0.92, hi: 1.12 }),
        ..Default::default()
    };
    let nominal = Nominal {
        magnification: 1.0,
        r_m: 1.0,
        alpha,
        i0: 1.0,
        spring_bed: None,
    };
    let set = CoefficientDist::Single(Dist::Fixed { value: 0.9 });
    let n = 120;
    let runs: Vec<(f64, Outcome)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let key = SampleKey {
                seed: 11,
                record: name_key("pulse"),
                row: 1,
                scale: 0,
                sample: i,
            };
            let x = draw(&key, &unc, &nominal, "e", &set, Some(1.0));
            let steps = 2000;
            let a = x.magnification * crit * G * alpha;
            let mut acc = vec![a; steps + 1];
            acc.extend(std::iter::repeat_n(0.0, 10));
            let g = Ground {
                t0: 0.0,
                dt: td / steps as f64,
                acc,
            };
            let sim = simulate(&model, &g, 0.0, None, &Settings::new(td + 8.0).without_history()).unwrap();
            let ov = matches!(sim.stop, Stop::Overturned { .. });
            (
                x.magnification,
                Outcome {
                    overturned: ov,
                    overturn_time_s: None,
                    max_theta_over_alpha: sim.max_theta / alpha,
                },
            )
        })
        .collect();
    for (m, o) in &runs {
        if (m - 1.0).abs() > 0.005 {
            assert_eq!(o.overturned, *m > 1.0, "amplitude {m} × threshold");
        }
    }
    let above = runs.iter().filter(|(m, _)| *m > 1.0).count();
    let stats = summarise(&runs.iter().map(|r| r.1).collect::<Vec<_>>());
    assert_eq!(stats.overturned, above, "P(overturn) is the fraction of draws above the threshold");
    let (lo, hi) = wilson(stats.overturned, n as usize, Z95);
    assert_eq!(stats.p_overturn_ci95, [lo, hi]);
    assert!(lo <= 0.6 && 0.6 <= hi, "exact P = 0.6 outside [{lo}, {hi}]");
}

/// (d) Same seed, same numbers, on one thread or two; another seed, other numbers.
#[test]
fn identical_seeds_give_identical_outputs_on_any_thread_count() {
    let mut study = fixture_study();
    study.records.truncate(1);
    let n = 3;
    let on = |threads: usize, study: &Study| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run_ensembles(study, n, &|| {})).unwrap()
    };
    let (rows1, s1) = on(1, &study);
    let (rows2, s2) = on(2, &study);
    assert_eq!(rows1.len(), 2 * 2);
    assert_eq!(serde_json::to_string(&rows1).unwrap(), serde_json::to_string(&rows2).unwrap());
    assert_eq!(serde_json::to_string(&s1).unwrap(), serde_json::to_string(&s2).unwrap());
    study.seed += 1;
    let (_, s3) = on(2, &study);
    assert_ne!(
        s1.iter().map(|s| s.inputs.magnification).collect::<Vec<_>>(),
        s3.iter().map(|s| s.inputs.magnification).collect::<Vec<_>>()
    );
}

/// The early stop at rest changes no result: every run of the fixture study
/// (nominal inputs, both polarities, both sets, two scales) gives the same
/// summary and the same events with and without it; some of them do come to rest
/// after the last sample that could uplift the wall, so the stop is exercised.
#[test]
fn early_stop_at_rest_changes_no_result() {
    let study = fixture_study();
    let mut rested = 0;
    for rec in &study.records {
        for set in &study.sets {
            for pol in [1.0, -1.0] {
                for scale in [0.6, 1.27] {
                    let spec = RunSpec {
                        e_in: set.e_in,
                        e_out: set.e_out,
                        law: None,
                        law_reading: Default::default(),
                        scale,
                        polarity: pol,
                        overturn_limit: 0.1,
                        t_extra: 2.0,
                        rtol: 1e-8,
                        atol: 1e-10,
                        keep_history: false,
                    };
                    let (a, sa) = run_with(&study.block, &rec.record, &spec, true).unwrap();
                    let (b, sb) = run_with(&study.block, &rec.record, &spec, false).unwrap();
                    let key = |s: &rocklab::study::RunSummary| {
                        (
                            s.max_theta_over_alpha.to_bits(),
                            s.min_theta_over_alpha.to_bits(),
                            s.overturned,
                            s.overturn_time_s.map(f64::to_bits),
                            s.impacts,
                            s.steps,
                        )
                    };
                    assert_eq!(key(&a), key(&b), "{} {} {pol} ×{scale}", rec.name, set.name);
                    assert_eq!(sa.events, sb.events);
                    rested += sa.events.iter().any(|e| matches!(e, rocklab::solver::Event::Rest { .. })) as usize;
                }
            }
        }
    }
    assert!(rested > 0, "no run came to rest: the early stop was not exercised");
}

/// Issue 20: an illustrative law for the tests (fixtures/facade/law.json, written
/// by hand in the shape the issue describes: inward constant 0.62, outward
/// r = 1.0 − 0.05/√(a(2 − a)), from 0.65 at a = 0.01 to 0.95 at a = 1).
fn fixture_law() -> rocklab::restitution_law::RestitutionLaw {
    rocklab::ingest::law::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/law.json")).unwrap()
}

/// Issue 20: a set with a constant law (r_in, r_out) and a given e_H runs exactly as
/// the pair (r_in e_H, r_out e_H): the nominal runs and every sample of the
/// ensembles (common random numbers: the sets differ only in how e is given) have
/// the same outcome and peak, bit for bit.
#[test]
fn a_constant_law_set_runs_as_its_pair() {
    use rocklab::facade::{run_study, CoefficientSet};
    use rocklab::restitution_law::RestitutionLaw;
    let mut study = fixture_study();
    study.records.truncate(1);
    let (r_in, r_out, e_h) = (0.61, 0.7, 0.98);
    let alpha = study.block.block.alpha;
    let law = CoefficientSet::law(
        "law",
        RestitutionLaw::constant(r_in, 0.0, r_out, 0.0),
        Some(e_h),
        alpha,
        true,
        "test".into(),
    );
    let pair = CoefficientSet {
        name: "pair".into(),
        e_in: r_in * e_h,
        e_out: r_out * e_h,
        source: "test".into(),
        dist: CoefficientDist::Pair {
            e_in: Dist::Fixed { value: r_in * e_h },
            e_out: Dist::Fixed { value: r_out * e_h },
        },
    };
    assert_eq!((law.e_in, law.e_out), (pair.e_in, pair.e_out));
    study.sets = vec![pair, law];
    let runs = run_study(&study, 1.0, false, &|| {}).unwrap();
    let key = |r: &rocklab::facade::StudyRun| {
        (
            r.summary.max_theta_over_alpha.to_bits(),
            r.summary.overturned,
            r.summary.impacts,
            r.summary.steps,
        )
    };
    // Runs are record-major, then set, then polarity: the pair's two polarities, then the law's.
    assert_eq!(runs.len(), 4);
    for k in 0..2 {
        assert_eq!(key(&runs[k]), key(&runs[k + 2]), "{} {}", runs[k].record, runs[k].polarity);
    }
    let (rows, samples) = run_ensembles(&study, 3, &|| {}).unwrap();
    for p in rows.chunks(2) {
        assert_eq!(p[0].stats, p[1].stats);
    }
    let n_impacts: usize = runs.iter().map(|r| r.summary.impacts).sum();
    assert!(n_impacts > 0, "no impacts: nothing compared");
    for p in samples.chunks(3).collect::<Vec<_>>().chunks(2) {
        for (a, b) in p[0].iter().zip(p[1]) {
            assert_eq!(a.outcome, b.outcome);
            assert_eq!((a.inputs.magnification, a.inputs.alpha), (b.inputs.magnification, b.inputs.alpha));
        }
    }
}

/// Issue 20: a law set's draws are pure functions of the sample's key, differ from
/// sample to sample when the law has a covariance, keep the nominal law when
/// `drawn` is off, and apply e_H by Eq. 2 with the sample's α when none is given.
#[test]
fn law_draws_follow_the_seed_and_the_sample() {
    use rocklab::wall::{housner_e, Side};
    let law = fixture_law();
    let nominal = Nominal {
        magnification: 1.27,
        r_m: 3.84,
        alpha: 0.1,
        i0: 2.6e6,
        spring_bed: None,
    };
    let unc = Uncertainty {
        alpha_rad: Some(Dist::Uniform { lo: 0.1, hi: 0.1044 }),
        ..Default::default()
    };
    let key = |sample: u64| SampleKey {
        seed: 2021,
        record: name_key("r"),
        row: 1,
        scale: 0,
        sample,
    };
    let set = |drawn: bool| CoefficientDist::Law {
        law,
        e_housner: None,
        drawn,
        reading: Default::default(),
    };
    assert!(set(true).is_random() && !set(false).is_random());
    let a = draw(&key(1), &unc, &nominal, "law", &set(true), Some(1.0));
    assert_eq!(a, draw(&key(1), &unc, &nominal, "law", &set(true), Some(1.0)));
    let b = draw(&key(2), &unc, &nominal, "law", &set(true), Some(1.0));
    let (la, eh) = a.law.unwrap();
    assert_eq!(eh, housner_e(a.alpha));
    assert_ne!(la.r(Side::Outward, 0.5), b.law.unwrap().0.r(Side::Outward, 0.5));
    assert_eq!(a.e_out, la.e(Side::Outward, 1.0, eh));
    let c = draw(&key(1), &unc, &nominal, "law", &set(false), Some(1.0));
    assert_eq!(c.law.unwrap().0, law);
}
