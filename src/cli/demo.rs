//! `rocklab demo`: reduce and calibrate the fixture campaigns and run the façade
//! study, into `reports/demo/`.

use std::process::ExitCode;

use super::reduce::reduce_and_print;
use super::{say, DemoArgs};
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;

pub fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let mut ok = true;
    for name in ["one-sided-demo", "two-sided-demo"] {
        let manifest = args.fixtures.join("campaigns").join(name).join("campaign.toml");
        let campaign = Campaign::load(&manifest)?;
        let sources = super::load::campaign_sources(&campaign);
        let res = reduce_and_print(campaign, PeakOptions::default());
        ok &= res.failed().next().is_none();
        // Writes everything `reduce` writes, with the calibration on top.
        let cal = super::calibrate::calibrate_and_write(&res, &sources, &args.out.join(name), 6)?;
        ok &= cal.failed.is_empty();
        say("");
    }
    let mut study = rocklab::facade::Study::load(&args.fixtures.join("facade/study.toml"))?;
    args.ensemble.apply(&mut study);
    // reduce → calibrate → façade: this campaign's calibration joins the study as
    // a coefficient set, read back from the calibration.toml just written.
    let cal_path = args.out.join("one-sided-demo").join("calibration.toml");
    let cal = rocklab::ingest::calibration::read(&cal_path)?.calibration;
    let set = rocklab::facade::calibration_set("campaign", &cal_path.display().to_string(), &cal, "tests").map_err(|e| anyhow::anyhow!(e))?;
    study.sets.push(set);
    let scales = rocklab::facade::parse_scales(&args.scales)?;
    say(&format!(
        "façade study: {} ({} samples per record × polarity × set, seed {}; fragility from {} scales × {} samples)",
        study.name,
        study.samples,
        study.seed,
        scales.len(),
        study.ida_samples
    ));
    super::facade::run_and_write(&study, Some(&scales), &args.out.join("facade"))?;
    Ok(if ok { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
