//! `rocklab demo`: reduce and calibrate the fixture campaigns and run the façade
//! study, into `reports/demo/`. The façade study gets, beside its constant
//! sets, the restitution laws of the one-sided campaigns (reduce → law in
//! summary.json → façade): the demo's own and the engine-made one with compliant
//! contacts (`mujoco-public-one-sided`), whose coefficient falls with amplitude.

use std::process::ExitCode;

use super::reduce::{print_reduction, reduce_with_progress};
use super::{say, DemoArgs};
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;

pub fn run(args: DemoArgs) -> anyhow::Result<ExitCode> {
    let mut ok = true;
    for name in ["one-sided-demo", "two-sided-demo"] {
        let manifest = args.fixtures.join("campaigns").join(name).join("campaign.toml");
        let campaign = Campaign::load(&manifest)?;
        let sources = super::load::campaign_sources(&campaign);
        let res = reduce_with_progress(campaign, PeakOptions::default());
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
    ok &= reduce_for_law(&args, "mujoco-public-one-sided")?;
    for (campaign, name) in [("one-sided-demo", "campaign"), ("mujoco-public-one-sided", "mujoco")] {
        study.sets.extend(law_sets(&study, &args.out.join(campaign).join("summary.json"), name)?);
    }
    // The engine-made campaign's law read by the impact's speed as well: its push
    // law carries the test wall's restraint in its amplitude (docs/facade.md,
    // "Reading the law by the impact's speed").
    let readable = |s: &&rocklab::facade::CoefficientSet| s.law_at(study.block.block.alpha).is_some_and(|(law, _)| law.readable_by_speed().is_ok());
    if let Some(law_set) = study.sets.iter().find(|s| s.name == "mujoco law").filter(readable) {
        let mut by_speed = law_set.clone().read_by(rocklab::restitution_law::LawReading::Speed);
        by_speed.name = "mujoco law by speed".into();
        study.sets.push(by_speed);
    }
    // The law the engine's own per-impact truth gives (what the readings would give
    // if they reached every impact; tests/law.rs writes and checks it).
    let truth_law = args.fixtures.join("laws").join("mujoco-public-one-sided-truth.json");
    study.sets.extend(law_sets(&study, &truth_law, "mujoco truth")?);
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

/// Reduce a campaign only for its law: its reduce outputs into `out/NAME`.
fn reduce_for_law(args: &DemoArgs, name: &str) -> anyhow::Result<bool> {
    let manifest = args.fixtures.join("campaigns").join(name).join("campaign.toml");
    let campaign = Campaign::load(&manifest)?;
    let sources = super::load::campaign_sources(&campaign);
    let res = reduce_with_progress(campaign, PeakOptions::default());
    let files = rocklab::report::reduce_files(&res, &sources, true, &rocklab::report::Extras::default())?;
    rocklab::report::write_files(&args.out.join(name), &files)?;
    print_reduction(&res);
    say("");
    let ok = res.failed().next().is_none();
    Ok(ok)
}

/// The law sets of a summary.json (the one the demo wrote for a campaign, or a
/// fixture of the same shape): "NAME
/// law" (the fitted law) and "NAME constant" (the best constant pair of the same
/// impacts, `restitution_law.constant`, as a constant law), both as r × e_H by
/// Eq. 2 with the façade's α and drawn from their covariance, so that the two
/// differ only in the law's form (the constant set is left out when the fitted
/// law is itself the constant: the data did not reject it). None, said on the
/// terminal, when the summary holds no law.
fn law_sets(study: &rocklab::facade::Study, path: &std::path::Path, name: &str) -> anyhow::Result<Vec<rocklab::facade::CoefficientSet>> {
    use rocklab::facade::CoefficientSet;
    use rocklab::restitution_law::RestitutionLaw;
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path)?)?;
    let Some(fitted) = doc.get("restitution_law") else {
        say(&format!(
            "{}: no restitution_law, so the façade study has no \"{name} law\" set",
            path.display()
        ));
        return Ok(Vec::new());
    };
    let alpha = study.block.block.alpha;
    let law = rocklab::ingest::law::read(path)?;
    let mut sets = vec![CoefficientSet::law(
        &format!("{name} law"),
        law,
        None,
        alpha,
        true,
        format!("law {} ({})", path.display(), law.form.as_str()),
    )];
    let c = &fitted["constant"];
    let num = |k: &str| {
        c[k].as_f64()
            .ok_or_else(|| anyhow::anyhow!("{}: restitution_law.constant.{k}: expected a number", path.display()))
    };
    if law.form != rocklab::restitution_law::LawForm::Constant {
        let mut constant = RestitutionLaw::constant(num("r_in")?, num("r_in_u")?, num("r_out")?, num("r_out_u")?);
        // The best constant of the same impacts: the same amplitudes observed.
        constant.parameters.amplitude_min = law.parameters.amplitude_min;
        constant.parameters.amplitude_max = law.parameters.amplitude_max;
        constant.parameters.observed = Some(law.observed_amplitudes());
        constant.parameters.push_speed = law.parameters.push_speed;
        let source = format!("the constant pair of {}", path.display());
        sets.push(CoefficientSet::law(&format!("{name} constant"), constant, None, alpha, true, source));
    }
    Ok(sets)
}
