//! `summary.json` of `rocklab reduce`, exactly as SPEC defines it, derived from
//! the `Serialize` types of the core (coefficients, peaks, impacts, means).

use serde::ser::{Serialize, SerializeMap, Serializer};
use serde_json::Value;

use crate::campaign_means::Means;
use crate::impacts::{ImpactCoefficient, ImpactTable};
use crate::law_fit::{LawFit, SideFit};
use crate::peaks::{Impact, Peak};
use crate::reduce::{CampaignResult, TestOutcome};
use crate::restitution::Coefficients;
use crate::restitution_law::{CurvePoint, RestitutionLaw};

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
    impacts: Vec<ImpactDoc<'a>>,
    /// Why `impacts` ends where it does (the first impact not reported and the
    /// reason), where the late readings extended it ([`ImpactTable::end`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    impacts_end: Option<&'a str>,
    /// The logger's filter the model was seen through: stated, estimated, or
    /// none (issue #18).
    acquisition: &'a crate::peaks::acquisition::ResponseUsed,
    /// Where an unstated filter was estimated and then dropped as the wall's
    /// contacts' rounding, why.
    #[serde(skip_serializing_if = "Option::is_none")]
    acquisition_note: Option<&'a str>,
    /// One-sided walls: the peaks (k) read by the contact model instead of the
    /// global fit ([`crate::peaks::inward`]): the pushes into the transverse
    /// walls (k odd) and the late landings whose fit's residuals stand out
    /// (k even, from 4 on).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    peaks_read_by_contact_model: Vec<usize>,
    /// Where the fit's model misses the log without that being a reason (a
    /// one-sided wall's exits), what and what was done about it.
    #[serde(skip_serializing_if = "Option::is_none")]
    model_note: Option<&'a str>,
}

/// One entry of a test's `"impacts"`: the analysis' impact (time, side entered,
/// signed speeds) and, where the next peak was fitted, its coefficient (SPEC).
#[derive(serde::Serialize)]
struct ImpactDoc<'a> {
    #[serde(flatten)]
    impact: &'a Impact,
    #[serde(flatten)]
    coefficient: Option<&'a ImpactCoefficient>,
    /// One-sided walls: why a reported coefficient is kept out of the campaign's
    /// law (the wall lifts off for less than half of a half-cycle around it).
    #[serde(skip_serializing_if = "Option::is_none")]
    not_in_law: Option<&'a str>,
}

fn impact_docs<'a>(t: &'a ImpactTable, law_end: Option<&'a (usize, String)>) -> Vec<ImpactDoc<'a>> {
    t.raw
        .iter()
        .enumerate()
        .map(|(k, impact)| {
            let coefficient = t.impacts.get(k);
            ImpactDoc {
                impact,
                coefficient,
                not_in_law: law_end
                    .filter(|(from, _)| coefficient.is_some_and(|c| c.k >= *from))
                    .map(|(_, why)| why.as_str()),
            }
        })
        .collect()
}

/// `"restitution_law"`: the law (form, parameters), its curve, and its test against
/// the constant pair; or why there is none.
#[derive(serde::Serialize)]
#[serde(untagged)]
enum LawDoc<'a> {
    Fitted {
        #[serde(flatten)]
        law: &'a RestitutionLaw,
        curve: Vec<CurvePoint>,
        constant: ConstantDoc,
        fits: Vec<FitDoc<'a>>,
        rejects_constant: bool,
        speed_loss_fit: &'a RestitutionLaw,
        tests: &'a [String],
        notes: &'a [String],
    },
    Missing {
        error: String,
    },
}

#[derive(serde::Serialize)]
struct ConstantDoc {
    r_in: f64,
    r_in_u: f64,
    r_out: f64,
    r_out_u: f64,
}

#[derive(serde::Serialize)]
struct FitDoc<'a> {
    side: &'a str,
    #[serde(flatten)]
    fit: &'a SideFit,
}

/// The number of points of the law's curve in summary.json (SPEC: at least 20).
pub const CURVE_POINTS: usize = 25;

fn law_doc(law: &Result<LawFit, crate::law_fit::LawFitError>) -> LawDoc<'_> {
    match law {
        Ok(f) => {
            let c = &f.constant.parameters;
            LawDoc::Fitted {
                law: &f.law,
                curve: f.law.curve(CURVE_POINTS),
                constant: ConstantDoc {
                    r_in: c.inward.r_inf,
                    r_in_u: c.inward.cov[0][0].sqrt(),
                    r_out: c.outward.r_inf,
                    r_out_u: c.outward.cov[0][0].sqrt(),
                },
                fits: f.sides.iter().map(|(side, fit)| FitDoc { side, fit }).collect(),
                rejects_constant: f.rejects_constant,
                speed_loss_fit: &f.speed_loss,
                tests: &f.tests_used,
                notes: &f.notes,
            }
        }
        Err(e) => LawDoc::Missing { error: e.to_string() },
    }
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
                impacts: impact_docs(&r.impacts, r.law_end.as_ref()),
                impacts_end: r.impacts.end.as_deref(),
                acquisition: &r.analysis.response,
                acquisition_note: r.analysis.acquisition_note.as_deref(),
                peaks_read_by_contact_model: r.analysis.contact_model_peaks(),
                model_note: r.analysis.model_note.as_deref(),
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
pub(super) struct LeftOut<'a> {
    pub(super) id: &'a str,
    pub(super) why: &'a str,
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
    restitution_law: LawDoc<'a>,
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
        restitution_law: law_doc(&res.law),
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
