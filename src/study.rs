//! One seismic run of a block under a record (shared by `simulate` and the façade
//! study): build the model, scale the record, integrate, summarise.

use std::sync::Arc;

use crate::ground_motion::Record;
use crate::restitution_law::{LawReading, RestitutionLaw};
use crate::solver::run::SolverError;
use crate::solver::{simulate, BlockSpec, Ground, ImpactLaw, RockingModel, Settings, Simulation, Stop};

/// Everything a run needs besides the block and the record.
#[derive(Debug, Clone, Copy)]
pub struct RunSpec {
    pub e_in: f64,
    pub e_out: f64,
    /// A restitution law and the e_H it is applied with, instead of (e_in, e_out).
    pub law: Option<(RestitutionLaw, f64)>,
    /// Where the solver reads the law: at the apex (SPEC) or at the impact's speed.
    pub law_reading: LawReading,
    /// Magnification × user scale.
    pub scale: f64,
    /// ±1.
    pub polarity: f64,
    /// Overturning limit on θ (rad).
    pub overturn_limit: f64,
    /// Seconds simulated past the end of the record.
    pub t_extra: f64,
    pub rtol: f64,
    pub atol: f64,
    pub keep_history: bool,
}

impl RunSpec {
    /// The run's settings within `crate::limits` (magnification, tolerances,
    /// t_extra, overturning limit) and polarity ±1, or a message naming the first
    /// that is not; `name` gives each setting's name as its caller spells it
    /// (`--scale` on the command line, `scale` in Python).
    pub fn check(&self, name: impl Fn(&str) -> String) -> Result<(), String> {
        use crate::limits;
        if self.polarity != 1.0 && self.polarity != -1.0 {
            return Err(format!("{} = {}: expected 1 or -1", name("polarity"), self.polarity));
        }
        for (key, v, range) in [
            ("scale", self.scale, limits::MAGNIFICATION),
            ("rtol", self.rtol, limits::RTOL),
            ("atol", self.atol, limits::ATOL),
            ("t_extra", self.t_extra, limits::T_EXTRA_S),
            ("overturn_limit", self.overturn_limit, limits::ANGLE_RAD),
        ] {
            range.check(&name(key), v)?;
        }
        Ok(())
    }
}

/// The summary of a run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    pub max_theta_over_alpha: f64,
    pub min_theta_over_alpha: f64,
    pub overturned: bool,
    pub overturn_time_s: Option<f64>,
    pub impacts: usize,
    pub pga_g: f64,
    pub pgv_cm_s: f64,
    pub solve_wall_s: f64,
    pub steps: usize,
}

/// Build the rocking model of a block with the given coefficients.
pub fn model(block: &BlockSpec, spec: &RunSpec) -> RockingModel {
    RockingModel {
        alpha: block.block.alpha,
        p2: block.block.p2(),
        i0: block.block.i0,
        restraint: block.restraint,
        ties: block.ties.clone(),
        e_in: spec.e_in,
        e_out: spec.e_out,
        law: spec.law.map(|(law, e_h)| ImpactLaw::new(Arc::new(law), e_h).read_by(spec.law_reading)),
        overturn_limit: spec.overturn_limit,
        linearized: false,
    }
}

/// The scaled ground motion (m/s²).
pub fn ground(record: &Record, spec: &RunSpec) -> Ground {
    let k = spec.scale * spec.polarity;
    Ground {
        t0: record.t0,
        dt: record.dt,
        acc: record.acc_m_s2.iter().map(|a| a * k).collect(),
    }
}

/// Run one simulation from rest at the record's first sample.
pub fn run(block: &BlockSpec, record: &Record, spec: &RunSpec) -> Result<(RunSummary, Simulation), SolverError> {
    run_with(block, record, spec, true)
}

/// As [`run`], choosing whether a wall at rest after the last sample that could
/// uplift it stops the run ([`Settings::stop_at_rest`]; `run` always does).
pub fn run_with(block: &BlockSpec, record: &Record, spec: &RunSpec, stop_at_rest: bool) -> Result<(RunSummary, Simulation), SolverError> {
    let m = model(block, spec);
    let ag = ground(record, spec);
    let mut settings = Settings::new(record.t0 + record.duration() + spec.t_extra).with_tolerances(spec.rtol, spec.atol);
    if !spec.keep_history {
        settings = settings.without_history();
    }
    if !stop_at_rest {
        settings = settings.without_stop_at_rest();
    }
    let start = std::time::Instant::now();
    let sim = simulate(&m, &ag, record.t0, None, &settings)?;
    let wall = start.elapsed().as_secs_f64();
    let alpha = block.block.alpha;
    let (overturned, t_ov) = match sim.stop {
        Stop::Overturned { t } => (true, Some(t)),
        Stop::End => (false, None),
    };
    let summary = RunSummary {
        max_theta_over_alpha: sim.max_theta / alpha,
        min_theta_over_alpha: sim.min_theta / alpha,
        overturned,
        overturn_time_s: t_ov,
        impacts: sim.impacts,
        pga_g: record.pga_g(spec.scale),
        pgv_cm_s: record.pgv_cm_s(spec.scale),
        solve_wall_s: wall,
        steps: sim.steps,
    };
    Ok((summary, sim))
}
