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
        let res = reduce_and_print(campaign, PeakOptions::default());
        ok &= res.failed().next().is_none();
        // Writes everything `reduce` writes, then the calibration on top.
        let cal = super::calibrate::calibrate_and_write(&res, &args.out.join(name), 6)?;
        ok &= cal.failed.is_empty();
        say("");
    }
    let study = rocklab::facade::Study::load(&args.fixtures.join("facade/study.toml"))?;
    say(&format!("façade study: {}", study.name));
    let out = args.out.join("facade");
    std::fs::create_dir_all(&out)?;
    let (figs, md) = super::facade::study_outputs(&study, &out)?;
    super::facade::write_report(&study, &md, &figs, &[], &out)?;
    say(&format!("wrote {}", out.display()));
    Ok(if ok { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
