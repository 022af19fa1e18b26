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
        let (r, s) = run_ensembles(&study, n, &|| {});
        divan::black_box((r.len(), s.len()))
    });
}
