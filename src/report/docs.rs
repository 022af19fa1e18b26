//! The `summary.json` documents of `simulate`, `calibrate` and `facade`, built in
//! one place so that the CLI and the Python binding return the same values (the
//! reduce summary is [`super::summary::summary`]).

use serde_json::{json, Value};

use crate::calibrate::Calibration;
use crate::facade::{CoefficientSet, Study, StudyRun};
use crate::ground_motion::Record;
use crate::ingest::block::BlockSpec;
use crate::solver::Simulation;
use crate::study::{RunSpec, RunSummary};

/// `summary.json` of `rocklab simulate`: the block's properties, the run's
/// settings, its summary and every event. `record_name` is how the record is
/// named (the path the user gave). `spec.polarity` is written as an integer.
pub fn simulate_summary(block: &BlockSpec, record_name: &str, record: &Record, spec: &RunSpec, summary: &RunSummary, sim: &Simulation) -> Value {
    let b = &block.block;
    json!({
        "block": block.name,
        "record": record_name,
        "record_notes": record.notes,
        "alpha_rad": b.alpha, "p2_per_s2": b.p2(), "i0_kg_m2": b.i0, "mass_kg": b.mass_kg, "r_m": b.r_m,
        "e_in": spec.e_in, "e_out": spec.e_out, "scale": spec.scale, "polarity": spec.polarity as i32,
        "overturn_limit_rad": spec.overturn_limit,
        "rtol": spec.rtol, "atol": spec.atol,
        "max_theta_over_alpha": summary.max_theta_over_alpha,
        "min_theta_over_alpha": summary.min_theta_over_alpha,
        "overturned": summary.overturned,
        "overturn_time_s": summary.overturn_time_s,
        "impacts": summary.impacts,
        "pga_g": summary.pga_g,
        "pgv_cm_s": summary.pgv_cm_s,
        "solve_wall_s": summary.solve_wall_s,
        "steps": summary.steps,
        "events": sim.events,
    })
}

/// The `"calibration"` entry that `rocklab calibrate` adds to `summary.json`;
/// `wall_s` is how long the calibration took.
pub fn calibration_summary(cal: &Calibration, wall_s: f64) -> Value {
    json!({
        "e_in": cal.e_in, "e_out": cal.e_out, "r_in": cal.r_in, "r_out": cal.r_out,
        "e_housner": cal.e_housner,
        "included": cal.included,
        "joint": cal.joint,
        "tests": cal.tests.iter().map(|t| json!({
            "id": t.id, "e_in": t.e_in, "e_out": t.e_out, "rms_mm": t.rms_mm,
            "se_e_in": t.se_e_in, "se_e_out": t.se_e_out, "ci95_e_in": t.ci95_e_in, "ci95_e_out": t.ci95_e_out,
            "release_offset_s": t.release_offset_s, "zero_offset_mm": t.zero_offset_mm, "p2_factor": t.p2_factor,
            "kappa_per_s2": t.kappa_per_s2, "nrmse": t.nrmse, "iterations": t.iterations, "stop": t.stop,
        })).collect::<Vec<_>>(),
        "per_impact": cal.per_impact.iter().map(|(id, i, o)| json!({"id": id, "inward": i, "outward": o})).collect::<Vec<_>>(),
        "failed": cal.failed.iter().map(|(id, e)| json!({"id": id, "error": e})).collect::<Vec<_>>(),
        "wall_s": wall_s,
    })
}

/// `summary.json` of `rocklab facade`: the study's settings and its runs;
/// `wall_s` is how long the runs took.
pub fn facade_summary(study: &Study, runs: &[StudyRun], wall_s: f64) -> Value {
    let sets: &[CoefficientSet] = &study.sets;
    json!({
        "study": study.name,
        "block": study.block.name,
        "alpha_rad": study.block.block.alpha,
        "magnification": study.magnification,
        "overturn_limit_rad": study.overturn_limit,
        "rtol": study.rtol,
        "e_housner_eq2": study.e_housner_eq2,
        "coefficient_sets": sets,
        "wall_s": wall_s,
        "runs": runs,
    })
}
