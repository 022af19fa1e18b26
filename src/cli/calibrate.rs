//! `rocklab calibrate MANIFEST --out DIR`: reduce, then fit e_in/e_out by replaying
//! each test with the solver; write the reduce outputs with the calibration.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;

use super::{load, say};
use rocklab::calibrate::Calibration;
use rocklab::ingest::Campaign;
use rocklab::law_replay::calibrate_with_law;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::CampaignResult;
use rocklab::report::calibration::{calibration_files, calibration_table};
use rocklab::report::campaign::Sources;
use rocklab::report::{table::to_markdown, write_files};

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  rocklab calibrate fixtures/campaigns/one-sided-demo/campaign.toml --out out/cal\n  # writes out/cal/calibration.toml, for `simulate --calibration` and a façade study"
)]
pub struct CalibrateArgs {
    /// Campaign manifest, or the directory that holds it as `campaign.toml`.
    pub manifest: PathBuf,
    #[arg(long)]
    pub out: PathBuf,
    /// Number of impacts in the fitted window (the tables use 6 peaks).
    #[arg(long, default_value_t = 6)]
    pub impacts: usize,
}

pub fn run(a: CalibrateArgs) -> anyhow::Result<ExitCode> {
    // Before the reduction: `--impacts 0` once left every test out as having
    // "fewer than 0 impacts".
    rocklab::limits::CALIBRATION_IMPACTS
        .check("--impacts", a.impacts as f64)
        .map_err(anyhow::Error::msg)?;
    let campaign = Campaign::load(&a.manifest)?;
    let sources = load::campaign_sources(&campaign);
    let res = super::reduce::reduce_with_progress(campaign, PeakOptions::default());
    let cal = calibrate_and_write(&res, &sources, &a.out, a.impacts)?;
    Ok(if cal.failed.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// Calibrate a reduced campaign, write everything `reduce` writes with the
/// calibration on top, then print the reduction and the calibration table.
pub fn calibrate_and_write(res: &CampaignResult, sources: &Sources, out: &Path, n: usize) -> anyhow::Result<Calibration> {
    let start = std::time::Instant::now();
    let (cal, law) = calibrate_with_law(&res.calibration_input(), n);
    let wall = start.elapsed().as_secs_f64();
    let files = calibration_files(res, &cal, Some(&law), n, wall, sources)?;
    write_files(out, &files).with_context(|| format!("writing {}", out.display()))?;
    super::reduce::print_reduction(res);
    say(&format!(
        "calibration of {} ({} rocking), {} impacts per test, {:.2} s:",
        cal.campaign, cal.rocking, n, wall
    ));
    say(&to_markdown(&calibration_table(&cal)));
    if let Some(j) = &cal.joint {
        say(&format!(
            "joint fit: e_in = {}, e_out = {} (95 %), RMS {:.3} mm",
            rocklab::report::tables::value_u(j.e_in, 1.96 * j.se_e_in),
            rocklab::report::tables::value_u(j.e_out, 1.96 * j.se_e_out),
            j.rms_mm
        ));
    }
    if let Some(a) = &cal.agreement {
        say(&format!("joint fit: {}", a.describe()));
    }
    for n in &law.notes {
        say(&format!("law by replay, {n}"));
    }
    for (id, why) in &law.failed {
        super::tell(&format!("test {id}: no law by replay: {why}"));
    }
    for (id, e) in &cal.failed {
        super::tell(&format!("test {id}: {e}"));
    }
    say(&format!("wrote {}", out.display()));
    Ok(cal)
}
