//! Issue #21: how far off are the values of a test the estimator flags, by kind
//! of reason? The figures the report's quality section quotes
//! (`rocklab::report::quality`, docs/accuracy.md) come from this draw:
//! `cargo test --release --test suspect_reasons -- --ignored --nocapture`.

use std::collections::BTreeMap;

use rayon::prelude::*;
use rocklab::report::quality::{kind, split, Kind};
use rocklab::synth::{draw, score, Family, Scored};

/// Per kind: the worst table error (pp) of every flagged test that gave values.
fn by_kind(scored: &[Scored]) -> BTreeMap<Kind, Vec<f64>> {
    let mut out: BTreeMap<Kind, Vec<f64>> = BTreeMap::new();
    for s in scored {
        let (Some(reasons), Ok(w)) = (s.status.strip_prefix("suspect: "), &s.worst_pp) else {
            continue;
        };
        for k in split(reasons).into_iter().map(kind).collect::<std::collections::BTreeSet<_>>() {
            out.entry(k).or_default().push(*w);
        }
    }
    out
}

#[test]
#[ignore = "the full random draws (release build, about a minute); prints the table of docs/accuracy.md"]
fn errors_of_flagged_tests_by_reason() {
    for (name, family, n) in [("idealised", Family::Rigid, 1000..1500u64), ("compliant", Family::Compliant, 1000..1200)] {
        let scored: Vec<Scored> = n.clone().into_par_iter().map(|s| score(&draw(s, family))).collect();
        let flagged = scored.iter().filter(|s| s.status.starts_with("suspect")).count();
        println!(
            "{name}: {} tests (seeds {n:?}, as tests/random_draw.rs), {flagged} suspect",
            n.end - n.start
        );
        for (k, mut errs) in by_kind(&scored) {
            errs.sort_by(f64::total_cmp);
            let med = errs[errs.len() / 2];
            println!("| {name} | {k:?} | {} | {med:.2} pp | {:.2} pp |", errs.len(), errs[errs.len() - 1]);
            assert_ne!(k, Kind::Other, "a reason the report cannot explain");
        }
    }
}

/// The seeds of the compliant draw whose tests are suspect, with their kinds (the
/// report test of tests/cli.rs takes two of them).
#[test]
#[ignore = "a search over the compliant draw; prints seeds"]
fn suspect_seeds() {
    let found: Vec<(u64, String)> = (1000..1060u64)
        .into_par_iter()
        .filter_map(|s| {
            let sc = score(&draw(s, Family::Compliant));
            let r = sc.status.strip_prefix("suspect: ")?.to_string();
            Some((s, format!("{:?}", split(&r).into_iter().map(kind).collect::<Vec<_>>())))
        })
        .collect();
    for (s, k) in &found {
        println!("seed {s}: {k}");
    }
    assert!(!found.is_empty());
}

/// A one-sided engine-made wall logged at 100 Hz (`fixtures/campaigns/mujoco-100hz-one-sided`,
/// made by `tools/mujoco_campaign.py`): its short inward excursions span a few
/// samples, and r₁ once came out 0.76 ± 0.64 with status ok, 7.8 pp from the
/// engine's. A ratio read to more than ± 5 pp is not vouched for
/// (`restitution::RATIO_U_MAX`): the test is suspect, the reason names r₁ and the
/// report explains it; a ratio the reason names is indeed off by more than the
/// 1 pp an ok value is held to.
#[test]
fn ratios_read_too_loosely_are_not_vouched_for() {
    use rocklab::ingest::Campaign;
    use rocklab::peaks::PeakOptions;
    use rocklab::reduce::reduce_campaign;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns/mujoco-100hz-one-sided");
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let res = reduce_campaign(Campaign::load(&dir).unwrap(), PeakOptions::default());
    let r = res.tests[0].result.as_ref().unwrap();
    let status = r.analysis.quality.describe();
    let reasons = status.strip_prefix("suspect: ").unwrap_or_else(|| panic!("{status}"));
    assert!(split(reasons).into_iter().any(|x| kind(x) == Kind::Unresolved), "{status}");
    assert!(reasons.contains("r₁ ± "), "{status}");
    let u = r.uncertainty.as_ref().unwrap();
    assert!(u.r1 > rocklab::restitution::RATIO_U_MAX, "r₁ ± {}", u.r1);
    let off_pp = 100.0 * (r.coefficients.r1 - truth["tests"][0]["r1"].as_f64().unwrap()).abs();
    assert!(off_pp > 1.0, "r₁ {off_pp:.2} pp off: the flag would not be needed");
    assert!(res.means.included.is_empty(), "{:?}", res.means.included);
}
