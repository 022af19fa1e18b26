//! The `summary.json` documents of `simulate`, `calibrate` and `facade`, built in
//! one place so that the CLI and the Python binding return the same values (the
//! reduce summary is [`super::summary::summary`]). Each is a `Serialize` view that
//! borrows the core's own `Serialize` types (run summary, test fits, study runs)
//! instead of listing their fields again.

use serde::Serialize;
use serde_json::Value;

use super::ReportError;
use crate::calibrate::{Calibration, JointFit, TestFit};
use crate::facade::{CoefficientSet, EnsembleRow, SetFragility, Study, StudyRun};
use crate::ground_motion::Record;
use crate::ingest::block::BlockSpec;
use crate::solver::run::Event;
use crate::solver::Simulation;
use crate::study::{RunSpec, RunSummary};

#[derive(Serialize)]
struct SimulateDoc<'a> {
    block: &'a str,
    record: &'a str,
    record_notes: &'a [String],
    alpha_rad: f64,
    p2_per_s2: f64,
    i0_kg_m2: f64,
    mass_kg: f64,
    r_m: f64,
    e_in: f64,
    e_out: f64,
    scale: f64,
    polarity: i32,
    overturn_limit_rad: f64,
    rtol: f64,
    atol: f64,
    #[serde(flatten)]
    summary: &'a RunSummary,
    events: &'a [Event],
}

/// `summary.json` of `rocklab simulate`: the block's properties, the run's
/// settings, its summary and every event. `record_name` is how the record is
/// named (the path the user gave). `spec.polarity` is written as an integer.
pub fn simulate_summary(
    block: &BlockSpec,
    record_name: &str,
    record: &Record,
    spec: &RunSpec,
    summary: &RunSummary,
    sim: &Simulation,
) -> Result<Value, ReportError> {
    let b = &block.block;
    let mut doc = super::json_value(&SimulateDoc {
        block: &block.name,
        record: record_name,
        record_notes: &record.notes,
        alpha_rad: b.alpha,
        p2_per_s2: b.p2(),
        i0_kg_m2: b.i0,
        mass_kg: b.mass_kg,
        r_m: b.r_m,
        e_in: spec.e_in,
        e_out: spec.e_out,
        scale: spec.scale,
        polarity: spec.polarity as i32,
        overturn_limit_rad: spec.overturn_limit,
        rtol: spec.rtol,
        atol: spec.atol,
        summary,
        events: &sim.events,
    })?;
    gather_timing(&mut doc);
    Ok(doc)
}

#[derive(Serialize)]
struct PerImpact<'a> {
    id: &'a str,
    inward: &'a [f64],
    outward: &'a [f64],
}

#[derive(Serialize)]
struct Failure<'a> {
    id: &'a str,
    error: &'a crate::calibrate::TestFailure,
}

#[derive(Serialize)]
struct CalibrationDoc<'a> {
    e_in: f64,
    e_out: f64,
    r_in: f64,
    r_out: f64,
    e_housner: f64,
    included: &'a [String],
    /// Every test the means leave out, with why (suspect tests included).
    left_out: Vec<super::summary::LeftOut<'a>>,
    joint: &'a Option<JointFit>,
    /// Whether the included tests share the one pair the joint fit assumes
    /// ([`crate::calibrate::Agreement`]); absent with fewer than two tests.
    #[serde(skip_serializing_if = "Option::is_none")]
    joint_agreement: Option<crate::calibrate::Agreement>,
    tests: &'a [TestFit],
    per_impact: Vec<PerImpact<'a>>,
    failed: Vec<Failure<'a>>,
    wall_s: f64,
    /// How the restitution law is fitted by replay (issue 20).
    law_by_replay: &'static str,
    /// The law by replay ([`crate::law_replay::LawReplay`]), absent where not fitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    law_replay: Option<&'a crate::law_replay::LawReplay>,
}

/// The `"calibration"` entry that `rocklab calibrate` adds to `summary.json`;
/// `wall_s` is how long the calibration took. Each test is its [`TestFit`].
pub fn calibration_summary(cal: &Calibration, law: Option<&crate::law_replay::LawReplay>, wall_s: f64) -> Result<Value, ReportError> {
    super::json_value(&CalibrationDoc {
        e_in: cal.e_in,
        e_out: cal.e_out,
        r_in: cal.r_in,
        r_out: cal.r_out,
        e_housner: cal.e_housner,
        included: &cal.included,
        left_out: cal.left_out.iter().map(|(id, why)| super::summary::LeftOut { id, why }).collect(),
        joint: &cal.joint,
        joint_agreement: cal.agreement,
        tests: &cal.tests,
        per_impact: cal.per_impact.iter().map(|(id, i, o)| PerImpact { id, inward: i, outward: o }).collect(),
        failed: cal.failed.iter().map(|(id, e)| Failure { id, error: e }).collect(),
        wall_s,
        law_by_replay: if law.is_some() {
            crate::law_replay::LAW_BY_REPLAY
        } else {
            "not fitted by replay in this run"
        },
        law_replay: law,
    })
}

/// The ensemble section of the façade summary.
#[derive(Serialize)]
pub struct EnsembleDoc<'a> {
    pub samples: usize,
    pub seed: u64,
    pub polarity: crate::ensemble::PolarityMode,
    pub uncertainty: &'a crate::ensemble::Uncertainty,
    pub rows: &'a [EnsembleRow],
}

/// The fragility section of the façade summary: where the runs came from and the
/// fits; `wall_s`, how long the fragility's own runs took (an IDA), goes to `timing`.
#[derive(Serialize)]
pub struct FragilityDoc<'a> {
    pub im: crate::facade::Im,
    pub source: &'a str,
    pub sets: &'a [SetFragility],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_s: Option<f64>,
}

#[derive(Serialize)]
struct FacadeDoc<'a> {
    study: &'a str,
    block: &'a str,
    alpha_rad: f64,
    magnification: f64,
    overturn_limit_rad: f64,
    rtol: f64,
    e_housner_eq2: f64,
    coefficient_sets: &'a [CoefficientSet],
    wall_s: f64,
    runs: &'a [StudyRun],
    #[serde(skip_serializing_if = "Option::is_none")]
    ensemble: Option<EnsembleDoc<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    fragility: Option<FragilityDoc<'a>>,
}

/// `summary.json` of `rocklab facade`: the study's settings and its runs, with
/// the ensemble and fragility sections when they ran; `wall_s` is how long the
/// study took.
pub fn facade_summary(
    study: &Study,
    runs: &[StudyRun],
    wall_s: f64,
    ensemble: Option<EnsembleDoc>,
    fragility: Option<FragilityDoc>,
) -> Result<Value, ReportError> {
    let mut doc = super::json_value(&FacadeDoc {
        study: &study.name,
        block: &study.block.name,
        alpha_rad: study.block.block.alpha,
        magnification: study.magnification,
        overturn_limit_rad: study.overturn_limit,
        rtol: study.rtol,
        e_housner_eq2: study.e_housner_eq2,
        coefficient_sets: &study.sets,
        wall_s,
        runs,
        ensemble,
        fragility,
    })?;
    gather_timing(&mut doc);
    Ok(doc)
}

/// The key that holds every measured time of a summary document.
pub const TIMING: &str = "timing";

/// Move every measured time of a summary document (a key ending in `wall_s`, at any
/// depth) under one top-level [`TIMING`] object, keyed by its JSON pointer
/// (`/wall_s`, `/runs/3/solve_wall_s`, `/calibration/wall_s`). The rest of the
/// document then depends only on the inputs and the seed: two runs give the same
/// bytes once `timing` is removed. Applied to every summary.json (CLI and Python).
pub fn gather_timing(doc: &mut Value) {
    let mut found = serde_json::Map::new();
    take_timings(doc, "", &mut found);
    if found.is_empty() {
        return;
    }
    if let Some(map) = doc.as_object_mut() {
        match map.get_mut(TIMING).and_then(Value::as_object_mut) {
            Some(t) => t.extend(found),
            None => {
                map.insert(TIMING.into(), Value::Object(found));
            }
        }
    }
}

fn take_timings(v: &mut Value, at: &str, found: &mut serde_json::Map<String, Value>) {
    match v {
        Value::Object(map) => {
            let keys: Vec<String> = map.keys().filter(|k| k.as_str() != TIMING || !at.is_empty()).cloned().collect();
            for k in keys {
                let path = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
                if k.ends_with("wall_s") {
                    if let Some(t) = map.remove(&k) {
                        found.insert(path, t);
                    }
                } else if let Some(child) = map.get_mut(&k) {
                    take_timings(child, &path, found);
                }
            }
        }
        Value::Array(items) => {
            for (i, item) in items.iter_mut().enumerate() {
                take_timings(item, &format!("{at}/{i}"), found);
            }
        }
        _ => {}
    }
}
