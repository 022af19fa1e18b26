//! `rocklab demo`: reduce the fixture campaigns into `reports/demo/`.

use std::process::ExitCode;

use super::reduce::reduce_and_write;
use super::{say, DemoArgs};
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;

pub fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let mut ok = true;
    for name in ["one-sided-demo", "two-sided-demo"] {
        let manifest = args.fixtures.join("campaigns").join(name).join("campaign.toml");
        let campaign = Campaign::load(&manifest)?;
        let res = reduce_and_write(campaign, PeakOptions::default(), &args.out.join(name), true)?;
        ok &= res.failed().next().is_none();
        let cal = super::calibrate::calibrate_and_write(&res, &args.out.join(name), 6)?;
        ok &= cal.failed.is_empty();
        say("");
    }
    let study = rocklab::facade::Study::load(&args.fixtures.join("facade/study.toml"))?;
    say(&format!("façade study: {}", study.name));
    let out = args.out.join("facade");
    std::fs::create_dir_all(&out)?;
    let (runs, figs, md) = super::facade::study_outputs(&study, &out)?;
    super::facade::write_report(&study, &runs, &md, &figs, &Vec::new(), &out)?;
    say(&format!("wrote {}", out.display()));
    Ok(if ok { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
