//! `summary.json` of `rocklab reduce`, exactly as SPEC defines it, derived from
//! the `Serialize` types of the core (coefficients, peaks, impacts, means).

use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::Value;

use crate::campaign_means::Means;
use crate::peaks::{Impact, Peak};
use crate::reduce::{CampaignResult, TestOutcome};
use crate::restitution::Coefficients;

/// The standard uncertainties of a test's coefficients, each key with `_u`
/// appended (`r_plus_u` beside `r_plus`).
struct Uncertainties<'a>(&'a Coefficients);

impl Serialize for Uncertainties<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let Value::Object(fields) = serde_json::to_value(self.0).map_err(serde::ser::Error::custom)? else {
            return Err(serde::ser::Error::custom("coefficients are not a map"));
        };
        let mut m = s.serialize_map(Some(fields.len()))?;
        for (k, v) in &fields {
            m.serialize_entry(&format!("{k}_u"), v)?;
        }
        m.end()
    }
}

/// What a reduced test adds to its entry.
#[derive(serde::Serialize)]
struct Reduction<'a> {
    peaks: &'a [Peak],
    contact_phases: bool,
    #[serde(flatten)]
    coefficients: &'a Coefficients,
    #[serde(flatten)]
    u: Option<Uncertainties<'a>>,
    release_time_s: f64,
    impacts: &'a [Impact],
}

/// One entry of `"tests"`.
#[derive(serde::Serialize)]
struct TestDoc<'a> {
    id: &'a str,
    status: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<&'a crate::reduce::TestError>,
    #[serde(flatten)]
    reduction: Option<Reduction<'a>>,
    exclude_from_mean: bool,
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    warnings: &'a [String],
}

fn test_doc(t: &TestOutcome) -> TestDoc<'_> {
    let (status, reason, error, reduction) = match &t.result {
        Ok(r) => {
            let reason = r.suspect_reason();
            let reduction = Reduction {
                peaks: &r.analysis.peaks,
                contact_phases: r.analysis.contact_phases,
                coefficients: &r.coefficients,
                u: r.uncertainty.as_ref().map(Uncertainties),
                release_time_s: r.analysis.release_time_s,
                impacts: &r.analysis.impacts,
            };
            (if reason.is_some() { "suspect" } else { "ok" }, reason, None, Some(reduction))
        }
        Err(e) => ("error", None, Some(e), None),
    };
    TestDoc {
        id: &t.spec.id,
        status,
        reason,
        error,
        reduction,
        exclude_from_mean: t.spec.exclude_from_mean,
        warnings: &t.warnings,
    }
}

#[derive(serde::Serialize)]
struct LeftOut<'a> {
    id: &'a str,
    why: &'a str,
}

/// The whole document.
#[derive(serde::Serialize)]
struct SummaryDoc<'a> {
    campaign: &'a str,
    rocking: &'a str,
    alpha_rad: f64,
    alpha_source: String,
    e_housner: f64,
    e_housner_source: String,
    method: String,
    tests: Vec<TestDoc<'a>>,
    mean: Option<&'a Means>,
    mean_u: Option<&'a Means>,
    mean_included: &'a [String],
    mean_left_out: Vec<LeftOut<'a>>,
}

/// Build the summary document (SPEC "the output contract"); its keys sorted as
/// `serde_json::Value` keeps them.
pub fn summary(res: &CampaignResult) -> Result<Value, super::ReportError> {
    let c = &res.campaign;
    let doc = SummaryDoc {
        campaign: &c.name,
        rocking: c.rocking.as_str(),
        alpha_rad: c.alpha_rad,
        alpha_source: c.alpha_source.to_string(),
        e_housner: c.e_housner,
        e_housner_source: c.e_housner_source.to_string(),
        method: res.options.method.describe(),
        tests: res.tests.iter().map(test_doc).collect(),
        mean: res.means.means.as_ref(),
        mean_u: res.means.means_u.as_ref(),
        mean_included: &res.means.included,
        mean_left_out: res.means.left_out.iter().map(|(id, why)| LeftOut { id, why }).collect(),
    };
    let mut v = super::json_value(&doc)?;
    if let Value::Object(m) = &mut v {
        m.extend(identity(c));
    }
    Ok(v)
}

/// Keys that identify a reduction in a lab's archive (`rocklab archive`): the
/// wall's size, the manifest's SHA-256 (the archive's key) and the rocklab version.
fn identity(c: &crate::ingest::Campaign) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    m.insert(
        "wall".into(),
        serde_json::json!({
            "height_m": c.height_m, "thickness_m": c.thickness_m, "width_m": c.width_m,
            "weight_kN": c.weight_kn, "hinge_height_m": c.hinge_height_m,
        }),
    );
    m.insert("manifest_sha256".into(), c.manifest_sha256.clone().into());
    m.insert("rocklab_version".into(), env!("CARGO_PKG_VERSION").into());
    m
}
