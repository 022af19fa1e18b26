//! Issue 10 benchmark: 10,000 façade runs under the shipped real records (the
//! fixture study: 3 records × 2 polarities × 2 coefficient sets × 834 samples =
//! 10,008 runs, every uncertain input drawn), in parallel (rayon, all cores).

use std::path::Path;

use rocklab::facade::{run_ensembles, Study};

fn main() {
    divan::main();
}

#[divan::bench(sample_count = 3)]
fn facade_ensemble_10000_runs(bencher: divan::Bencher) {
    let study = Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/study.toml")).unwrap();
    let rows = study.records.len() * study.rows().len() * study.sets.len();
    let n = 10_000usize.div_ceil(rows);
    bencher.bench(|| {
        let (r, s) = run_ensembles(&study, n, &|| {}).unwrap();
        divan::black_box((r.len(), s.len()))
    });
}

/// Issue 20: 2,400 runs of the fixture study with its calibrated pair, or with the
/// same pair as a constant restitution law whose r carries the pair's spread
/// (r = e/e_H, u = sd/e_H: statistically the same runs), each sample drawing it;
/// "law-by-speed" reads that law at each impact's speed (the same e: what the
/// reading itself costs).
#[divan::bench(args = ["pair", "law", "law-by-speed"], sample_count = 3)]
fn facade_ensemble_2400_runs_pair_or_law(bencher: divan::Bencher, how: &str) {
    use rocklab::facade::CoefficientSet;
    use rocklab::restitution_law::RestitutionLaw;
    let mut study = Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/study.toml")).unwrap();
    let e_h = study.e_housner_eq2;
    study.sets.retain(|s| s.name == "calibrated");
    if how != "pair" {
        let law = RestitutionLaw::constant(0.59 / e_h, 0.017 / e_h, 0.68 / e_h, 0.025 / e_h);
        let set = CoefficientSet::law("law", law, Some(e_h), study.block.block.alpha, true, "bench".into());
        let reading = match how {
            "law-by-speed" => rocklab::restitution_law::LawReading::Speed,
            _ => rocklab::restitution_law::LawReading::Amplitude,
        };
        study.sets = vec![set.read_by(reading)];
    }
    let n = 2400 / (study.records.len() * study.rows().len());
    bencher.bench(|| {
        let (r, s) = run_ensembles(&study, n, &|| {}).unwrap();
        divan::black_box((r.len(), s.len()))
    });
}

/// One run that comes to rest at 21.5 s, long before the record ends (30 Oct 2016
/// NRC ×1.27, polarity −1, e_in 0.59, e_out 0.68), with and without the early stop.
#[divan::bench(args = [true, false])]
fn facade_run_resting_early_stop(bencher: divan::Bencher, stop: bool) {
    use rocklab::study::{run_with, RunSpec};
    let study = Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/study.toml")).unwrap();
    let rec = &study.records[0].record;
    let spec = RunSpec {
        e_in: 0.59,
        e_out: 0.68,
        law: None,
        law_reading: Default::default(),
        scale: 1.27,
        polarity: -1.0,
        overturn_limit: 0.1,
        t_extra: 0.0,
        rtol: 1e-8,
        atol: 1e-10,
        keep_history: false,
    };
    bencher.bench(|| divan::black_box(run_with(&study.block, rec, &spec, stop).unwrap().0.max_theta_over_alpha));
}
