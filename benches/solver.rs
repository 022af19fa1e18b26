//! Issue #3 benchmarks: the façade (fixtures/facade/block.toml) under the 30 Oct
//! 2016 Norcia east record ×1.27, one run; and the 3 records × 2 coefficient sets ×
//! 2 polarities as a parallel batch (rayon).

use std::path::Path;

use rayon::prelude::*;
use rocklab::ground_motion::{ReadOptions, Record};
use rocklab::ingest::block::BlockSpec;
use rocklab::ingest::record::read;
use rocklab::study::{run, RunSpec};

fn main() {
    divan::main();
}

fn fixtures() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures"))
}

fn record(name: &str) -> Record {
    read(
        &fixtures().join("ground-motions/esm-central-italy-2016").join(name),
        &ReadOptions::default(),
    )
    .unwrap()
}

fn spec(e_in: f64, e_out: f64, polarity: f64) -> RunSpec {
    RunSpec {
        e_in,
        e_out,
        law: None,
        law_reading: Default::default(),
        scale: 1.27,
        polarity,
        overturn_limit: 0.10,
        t_extra: 0.0,
        rtol: 1e-8,
        atol: 1e-10,
        keep_history: false,
    }
}

#[divan::bench]
fn facade_nrc_20161030_one_run(bencher: divan::Bencher) {
    let block = BlockSpec::load(&fixtures().join("facade/block.toml")).unwrap();
    let rec = record("IT.NRC..HGE.D.20161030.064018.C.ACC.ASC");
    let s = spec(0.59, 0.68, -1.0);
    bencher.bench(|| divan::black_box(run(&block, &rec, &s).unwrap().0.max_theta_over_alpha));
}

/// Issue 20: the same run with the pair given as a constant restitution law
/// (r = e/e_H, e_H = 0.985): the same trajectory bit for bit, so the difference is
/// the law's cost (the apex tracked at every step, r read at each impact).
#[divan::bench(args = ["pair", "constant law"])]
fn facade_nrc_20161030_pair_or_law(bencher: divan::Bencher, how: &str) {
    use rocklab::restitution_law::RestitutionLaw;
    let block = BlockSpec::load(&fixtures().join("facade/block.toml")).unwrap();
    let rec = record("IT.NRC..HGE.D.20161030.064018.C.ACC.ASC");
    let e_h = 0.985;
    let (r_in, r_out) = (0.59 / e_h, 0.68 / e_h);
    let mut s = spec(r_in * e_h, r_out * e_h, -1.0);
    if how != "pair" {
        s.law = Some((RestitutionLaw::constant(r_in, 0.0, r_out, 0.0), e_h));
    }
    bencher.bench(|| divan::black_box(run(&block, &rec, &s).unwrap().0.max_theta_over_alpha));
}

#[divan::bench(sample_count = 20)]
fn facade_batch_3_records_2_sets_2_polarities(bencher: divan::Bencher) {
    let block = BlockSpec::load(&fixtures().join("facade/block.toml")).unwrap();
    let recs: Vec<Record> = [
        "IT.NRC..HGE.D.20161030.064018.C.ACC.ASC",
        "IT.NRC..HGE.D.20160824.013632.C.ACC.ASC",
        "IT.ACC..HGE.D.20161030.064018.C.ACC.ASC",
    ]
    .iter()
    .map(|n| record(n))
    .collect();
    let mut jobs = Vec::new();
    for r in &recs {
        for (ei, eo) in [(0.980, 0.980), (0.59, 0.68)] {
            for pol in [1.0, -1.0] {
                jobs.push((r, spec(ei, eo, pol)));
            }
        }
    }
    bencher.bench(|| jobs.par_iter().map(|(r, s)| run(&block, r, s).unwrap().0.impacts).sum::<usize>());
}
