//! Issue #2: every table value of every test of both fixture campaigns within 1.0
//! percentage point of the truth the logs were generated with (`truth.json`).
//!
//! Tolerance: 1.0 pp is the issue's acceptance bound. The estimator's noise floor
//! on these logs is ≈ 0.2 pp std (SPEC, 20 noise draws, σ = 0.02 mm), so 1.0 pp is
//! about five standard deviations: a pass is not luck, a biased estimator fails.

use std::path::Path;

use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::reduce_campaign;

const KEYS: [&str; 7] = ["r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2"];

fn max_errors(name: &str) -> Vec<(String, f64)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/campaigns")
        .join(name);
    let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let res = reduce_campaign(campaign, PeakOptions::default());
    let mut worst = vec![0.0f64; KEYS.len()];
    for t in &res.tests {
        let r = t
            .result
            .as_ref()
            .unwrap_or_else(|e| panic!("{}: {e}", t.spec.id));
        let tt = truth["tests"]
            .as_array()
            .unwrap()
            .iter()
            .find(|x| x["id"] == t.spec.id.as_str())
            .unwrap();
        let c = serde_json::to_value(r.coefficients).unwrap();
        let mut line = format!("{:8}", t.spec.id);
        for (i, k) in KEYS.iter().enumerate() {
            let err = 100.0 * (c[k].as_f64().unwrap() - tt[k].as_f64().unwrap());
            worst[i] = worst[i].max(err.abs());
            line.push_str(&format!(" {k}={err:+.2}"));
        }
        println!("{line}");
    }
    KEYS.iter().map(|k| k.to_string()).zip(worst).collect()
}

fn check(name: &str) {
    let worst = max_errors(name);
    println!("{name}: max |error| per column (pp): {worst:?}");
    for (k, e) in worst {
        assert!(e <= 1.0, "{name}: column {k} off by {e:.2} pp (> 1.0)");
    }
}

#[test]
fn one_sided_demo_within_one_point() {
    check("one-sided-demo");
}

#[test]
fn two_sided_demo_within_one_point() {
    check("two-sided-demo");
}
