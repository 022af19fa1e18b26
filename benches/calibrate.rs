//! Issue #4 benchmark: calibrate the five-test one-sided fixture campaign (the
//! reduction is done once outside the timed part).

use std::path::Path;

use rocklab::calibrate::calibrate;
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::reduce_campaign;

fn main() {
    divan::main();
}

#[divan::bench(sample_count = 20)]
fn calibrate_one_sided_demo(bencher: divan::Bencher) {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns/one-sided-demo/campaign.toml");
    let res = reduce_campaign(Campaign::load(&m).unwrap(), PeakOptions::default());
    let input = res.calibration_input();
    bencher.bench(|| divan::black_box(calibrate(&input, 6).e_in));
}
