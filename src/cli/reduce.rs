//! `rocklab reduce MANIFEST --out DIR`: load the campaign, reduce it, write the
//! report.

use std::process::ExitCode;

use anyhow::Context;

use super::{load, say, EstimatorArgs, MethodArg, ReduceArgs};
use rocklab::ingest::Campaign;
use rocklab::peaks::{Method, PeakOptions};
use rocklab::reduce::{reduce_campaign_with, CampaignResult};
use rocklab::report::{self, tables};
use rocklab::signal::savgol::SavGol;

pub fn options(e: &EstimatorArgs) -> anyhow::Result<PeakOptions> {
    let method = match e.method {
        MethodArg::Segments => Method::Segments,
        MethodArg::Savgol => Method::SavGol(SavGol::new(e.window, e.order).map_err(anyhow::Error::msg)?),
    };
    Ok(PeakOptions {
        method,
        ..PeakOptions::default()
    })
}

pub fn run(args: ReduceArgs) -> anyhow::Result<ExitCode> {
    let opts = options(&args.estimator)?;
    let campaign = Campaign::load(&args.manifest)?;
    let sources = load::campaign_sources(&campaign);
    let res = reduce_with_progress(campaign, opts);
    let files = report::reduce_files(&res, &sources, !args.estimator.no_plots, &report::Extras::default())?;
    report::write_files(&args.out, &files).with_context(|| format!("writing {}", args.out.display()))?;
    print_reduction(&res);
    say(&format!("wrote {}", args.out.display()));
    Ok(exit_code(&res))
}

/// Reduce a campaign, saying which campaign and showing progress; shared by
/// `calibrate` and `demo`. What it found is printed by [`print_reduction`] once
/// the outputs are written (a refused write prints no table of values that were
/// not written).
pub fn reduce_with_progress(campaign: Campaign, opts: PeakOptions) -> CampaignResult {
    say(&format!(
        "campaign {} ({}), {} tests; α = {:.4} rad ({}); e_H = {:.4} ({})",
        campaign.name,
        campaign.rocking.as_str(),
        campaign.tests.len(),
        campaign.alpha_rad,
        campaign.alpha_source,
        campaign.e_housner,
        campaign.e_housner_source
    ));
    let pb = super::progress(campaign.tests.len(), "reducing tests");
    let res = reduce_campaign_with(campaign, opts, &|| pb.inc(1));
    pb.finish_and_clear();
    res
}

/// What a user reads on the terminal of a reduction: warnings, Table 1, the
/// tests the means leave out, suspect tests and failures.
pub fn print_reduction(res: &CampaignResult) {
    for t in &res.tests {
        for w in &t.warnings {
            super::tell(&format!("warning: test {}: {w}", t.spec.id));
        }
    }
    say(&tables::to_markdown(&tables::tables(res)[0]));
    if !res.means.left_out.is_empty() {
        say(&format!("means leave out: {}", res.means.left_out_text()));
    }
    for t in &res.tests {
        if let Some(why) = t.result.as_ref().ok().and_then(|r| r.suspect_reason()) {
            super::tell(&format!(
                "suspect: test {}: {why} (its values are printed but left out of the means)",
                t.spec.id
            ));
        }
    }
    if let Some(none) = report::quality::none_vouched_in(res) {
        super::tell(&none);
    }
    let failed: Vec<_> = res.failed().collect();
    if !failed.is_empty() {
        super::tell(&format!("{} of {} tests failed:", failed.len(), res.tests.len()));
        for (id, e) in failed {
            super::tell(&format!("  test {id}: {e}"));
        }
    }
}

pub fn exit_code(res: &CampaignResult) -> ExitCode {
    if res.failed().next().is_some() {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
