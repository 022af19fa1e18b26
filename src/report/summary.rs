//! `summary.json` of `rocklab reduce`, exactly as SPEC defines it.

use serde_json::{json, Map, Value};

use crate::reduce::CampaignResult;

/// Build the summary document (SPEC "the output contract").
pub fn summary(res: &CampaignResult) -> Value {
    let c = &res.campaign;
    let tests: Vec<Value> = res
        .tests
        .iter()
        .map(|t| {
            let mut m = Map::new();
            m.insert("id".into(), json!(t.spec.id));
            match &t.result {
                Ok(r) => {
                    match r.suspect_reason() {
                        None => m.insert("status".into(), json!("ok")),
                        Some(why) => {
                            m.insert("status".into(), json!("suspect"));
                            m.insert("reason".into(), json!(why))
                        }
                    };
                    m.insert("peaks".into(), json!(r.analysis.peaks));
                    m.insert("contact_phases".into(), json!(r.analysis.contact_phases));
                    if let Some(u) = &r.uncertainty {
                        let names = ["e", "e_plus", "e_minus", "r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2"];
                        for (k, v) in names.iter().zip(u.to_array()) {
                            m.insert(format!("{k}_u"), json!(v));
                        }
                    }
                    let q = &r.coefficients;
                    for (k, v) in [
                        ("e", q.e),
                        ("e_plus", q.e_plus),
                        ("e_minus", q.e_minus),
                        ("r", q.r),
                        ("r_plus", q.r_plus),
                        ("r_minus", q.r_minus),
                        ("r1", q.r1),
                        ("r1_plus", q.r1_plus),
                        ("r1_minus", q.r1_minus),
                        ("r2", q.r2),
                    ] {
                        m.insert(k.into(), json!(v));
                    }
                    m.insert("release_time_s".into(), json!(r.analysis.release_time_s));
                    m.insert("impacts".into(), json!(r.analysis.impacts));
                }
                Err(e) => {
                    m.insert("status".into(), json!("error"));
                    m.insert("error".into(), json!(e));
                }
            }
            m.insert("exclude_from_mean".into(), json!(t.spec.exclude_from_mean));
            if !t.warnings.is_empty() {
                m.insert("warnings".into(), json!(t.warnings));
            }
            Value::Object(m)
        })
        .collect();
    let mean = res.means.means.map(|m| {
        json!({"r": m.r, "r_plus": m.r_plus, "r_minus": m.r_minus, "r1": m.r1,
               "r1_plus": m.r1_plus, "r1_minus": m.r1_minus, "r2": m.r2})
    });
    let mean_u = res.means.means_u.map(|m| serde_json::to_value(m).unwrap_or(Value::Null));
    json!({
        "campaign": c.name,
        "rocking": c.rocking.as_str(),
        "alpha_rad": c.alpha_rad,
        "alpha_source": c.alpha_source.to_string(),
        "e_housner": c.e_housner,
        "e_housner_source": c.e_housner_source.to_string(),
        "method": res.options.method.describe(),
        "tests": tests,
        "mean": mean.unwrap_or(Value::Null),
        "mean_u": mean_u.unwrap_or(Value::Null),
        "mean_included": res.means.included,
        "mean_left_out": res.means.left_out.iter().map(|(id, why)| json!({"id": id, "why": why})).collect::<Vec<_>>(),
    })
}
