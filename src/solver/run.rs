//! The event-driven rocking loop: integrate on the current pivot, locate impacts
//! and overturning on the dense output, apply θ' ← e θ' at impacts, go to rest when
//! the impacts have taken the speed below a threshold, and uplift again when
//! |ü_g| > g tan α. The loop returns why it stopped. It tracks the apex max |θ| of
//! each half-cycle, at which a restitution law is read at the impact that ends it.

use super::integrator::{find_root, next_h, step, Dense, State, Tolerances};
use super::model::{Ground, RockingModel};
use crate::wall::Side;

/// Settings, an initial state or a record the solver cannot run with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolverError {
    #[error("tolerances rtol = {rtol}, atol = {atol}: expected values from 1e-15 to 0.1")]
    Tolerances { rtol: f64, atol: f64 },
    #[error("{what} = {value}: expected a positive number")]
    NotPositive { what: &'static str, value: f64 },
    #[error("end time t_end = {t_end}: expected a finite number")]
    EndTime { t_end: f64 },
    #[error("initial state (θ, θ') = ({theta}, {omega}): expected finite numbers")]
    Initial { theta: f64, omega: f64 },
    #[error("ground motion: time step dt = {dt} and start t0 = {t0}: expected dt > 0 and finite t0")]
    Ground { dt: f64, t0: f64 },
    /// A ground acceleration that is not a finite number (a record scaled
    /// past the largest float: 10^309.4, found by `tests/fuzz.rs`).
    #[error("ground motion: acceleration {value} m/s² at sample {sample}: expected finite numbers (a scale out of the physical range?)")]
    Acceleration { sample: usize, value: f64 },
    /// The integrator rejected [`MAX_REJECTIONS`] steps in a row (issue 22: a
    /// record scaled by 10³⁰⁰ or a tolerance of 10⁻³⁰⁸ used to retry for ever).
    #[error("the integrator did not converge at t = {t} s: {rejections} steps rejected in a row, the last of {h:e} s (a ground motion or a tolerance out of the physical range?)")]
    Rejections { t: f64, h: f64, rejections: usize },
    /// The run took more than [`MAX_STEPS`] integration steps.
    #[error("the integrator did not finish: {steps} steps reached at t = {t} s of {t_end} s (a ground motion out of the physical range?)")]
    Steps { t: f64, t_end: f64, steps: usize },
}

/// Steps rejected in a row after which a run fails ([`SolverError::Rejections`]):
/// a rejection at least halves the step (Dormand–Prince's factor ≤ 0.2 or the
/// hop retry's 0.25), so 200 take any step to the 10⁻¹² s floor and well past it.
pub const MAX_REJECTIONS: usize = 200;

/// Integration steps (accepted or not) after which a run fails
/// ([`SolverError::Steps`]): the façade records (≤ 60 s) take ~10⁴–10⁵.
pub const MAX_STEPS: usize = 20_000_000;

/// Settings of a run; defaults: rtol 1e-9, atol 1e-12, rest below 1e-7 rad/s,
/// history kept, steps at most 10 ms.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    pub tol: Tolerances,
    /// End of the run (s).
    pub t_end: f64,
    /// Speed (rad/s) below which an impact ends in rest.
    pub rest_speed: f64,
    pub max_step: f64,
    /// Keep the time history (off for batch runs).
    pub keep_history: bool,
    /// Stop at rest once no later sample can uplift the wall (|ü_g| ≤ g tan α
    /// from there on): it stays at rest, so the run's result is already known.
    pub stop_at_rest: bool,
    /// Integration steps after which the run ends with [`SolverError::Steps`]
    /// ([`MAX_STEPS`] by default; a replay inside a fit sets a budget of its own).
    pub max_steps: usize,
}

impl Settings {
    pub fn new(t_end: f64) -> Settings {
        Settings {
            tol: Tolerances { rtol: 1e-9, atol: 1e-12 },
            t_end,
            rest_speed: 1e-7,
            max_step: 0.01,
            keep_history: true,
            stop_at_rest: true,
            max_steps: MAX_STEPS,
        }
    }
    /// Relative and absolute tolerances (checked by [`Settings::validate`]).
    pub fn with_tolerances(mut self, rtol: f64, atol: f64) -> Settings {
        self.tol = Tolerances { rtol, atol };
        self
    }

    /// Every setting usable: positive tolerances, step and rest speed ≥ 0, a
    /// finite end. [`simulate`] checks it before it runs.
    pub fn validate(&self) -> Result<(), SolverError> {
        let Tolerances { rtol, atol } = self.tol;
        if !(crate::limits::SOLVER_TOL.contains(rtol) && crate::limits::SOLVER_TOL.contains(atol)) {
            return Err(SolverError::Tolerances { rtol, atol });
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return Err(SolverError::NotPositive {
                what: "max_step",
                value: self.max_step,
            });
        }
        if self.rest_speed.is_nan() || self.rest_speed < 0.0 {
            return Err(SolverError::NotPositive {
                what: "rest_speed",
                value: self.rest_speed,
            });
        }
        if self.t_end.is_nan() || self.t_end.is_infinite() {
            return Err(SolverError::EndTime { t_end: self.t_end });
        }
        Ok(())
    }
    pub fn without_history(mut self) -> Settings {
        self.keep_history = false;
        self
    }
    /// Scan the record for the next uplift even after the last sample that could
    /// cause one (for the test that the early stop changes nothing).
    pub fn without_stop_at_rest(mut self) -> Settings {
        self.stop_at_rest = false;
        self
    }
}

/// Something that happened.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// θ crossed 0 into side `entering` (serialised +1 outward, −1 inward).
    Impact {
        t: f64,
        #[serde(serialize_with = "Side::serialize_as_sign")]
        entering: Side,
        v_before: f64,
        v_after: f64,
        /// a = apex/α of the half-cycle the impact ends (max |θ| since the last
        /// impact, uplift or release, over α): the amplitude at which a law's
        /// coefficient was read when it is read by amplitude.
        amplitude_over_alpha: f64,
        /// The a at which a law's coefficient was read: `amplitude_over_alpha`,
        /// or, a law read by speed, the amplitude of the campaign's impacts of
        /// this impact's speed ([`super::ImpactLaw::read_at`]).
        law_amplitude_over_alpha: f64,
    },
    /// Rocking started from rest towards `side` (serialised ±1).
    Uplift {
        t: f64,
        #[serde(serialize_with = "Side::serialize_as_sign")]
        side: Side,
    },
    /// The impacts took the speed below the rest threshold.
    Rest {
        t: f64,
    },
    Overturned {
        t: f64,
    },
}

/// Why the loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    End,
    Overturned { t: f64 },
}

/// A point of the time history.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Sample {
    pub t: f64,
    pub theta: f64,
    pub omega: f64,
    pub ag: f64,
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct Simulation {
    pub stop: Stop,
    pub events: Vec<Event>,
    pub history: Vec<Sample>,
    pub max_theta: f64,
    pub min_theta: f64,
    pub impacts: usize,
    pub steps: usize,
}

/// At rest, or rocking on a pivot.
#[derive(Debug, Clone, Copy)]
enum Phase {
    Rest,
    Rocking(Side),
}

/// θ at requested output times, filled as the run advances (dense output inside
/// steps, 0 at rest, the last value after the run stops).
struct Outputs<'a> {
    times: &'a [f64],
    values: Vec<f64>,
}

impl Outputs<'_> {
    /// Fill every requested time < `upto` with `f(t)`.
    fn fill(&mut self, upto: f64, f: impl Fn(f64) -> f64) {
        while self.values.len() < self.times.len() && self.times[self.values.len()] < upto {
            let t = self.times[self.values.len()];
            self.values.push(f(t));
        }
    }
}

/// Run the model from `t0`, at rest unless `initial` = (θ0, θ0') is given.
pub fn simulate(model: &RockingModel, ground: &Ground, t0: f64, initial: Option<State>, settings: &Settings) -> Result<Simulation, SolverError> {
    simulate_at(model, ground, t0, initial, settings, &[]).map(|r| r.0)
}

/// As [`simulate`], and θ at the sorted `outputs` times (before `t0`: the initial θ).
pub fn simulate_at(
    model: &RockingModel,
    ground: &Ground,
    t0: f64,
    initial: Option<State>,
    settings: &Settings,
    outputs: &[f64],
) -> Result<(Simulation, Vec<f64>), SolverError> {
    settings.validate()?;
    if let Some([theta, omega]) = initial.filter(|s| !(s[0].is_finite() && s[1].is_finite())) {
        return Err(SolverError::Initial { theta, omega });
    }
    if !(ground.dt > 0.0 && ground.t0.is_finite()) {
        return Err(SolverError::Ground {
            dt: ground.dt,
            t0: ground.t0,
        });
    }
    if let Some((sample, &value)) = ground.acc.iter().enumerate().find(|(_, a)| !a.is_finite()) {
        return Err(SolverError::Acceleration { sample, value });
    }
    let mut out = Outputs {
        times: outputs,
        values: Vec::with_capacity(outputs.len()),
    };
    let th0 = initial.map_or(0.0, |s| s[0]);
    out.fill(t0, |_| th0);
    let sim = simulate_inner(model, ground, t0, initial, settings, &mut out)?;
    // After the run: its final θ (known from the history when kept), else the last
    // value output.
    let fill_value = match sim.history.last() {
        Some(s) => s.theta,
        None => out.values.last().copied().unwrap_or(th0),
    };
    out.fill(f64::INFINITY, |_| fill_value);
    Ok((sim, out.values))
}

/// The event loop: [`Loop::step`] until it says the run stopped.
/// Bounded: [`MAX_REJECTIONS`] rejections in a row or [`Settings::max_steps`]
/// (at most [`MAX_STEPS`]) steps end it with an error.
fn simulate_inner(
    model: &RockingModel,
    ground: &Ground,
    t0: f64,
    initial: Option<State>,
    settings: &Settings,
    out: &mut Outputs,
) -> Result<Simulation, SolverError> {
    let mut run = Loop::new(model, ground, t0, initial, settings, out);
    let mut rejections = 0;
    loop {
        match run.step() {
            StepOutcome::Stopped(stop) => {
                run.sim.stop = stop;
                return Ok(run.sim);
            }
            StepOutcome::Rejected => rejections += 1,
            _ => rejections = 0,
        }
        if rejections >= MAX_REJECTIONS {
            return Err(SolverError::Rejections {
                t: run.t,
                h: run.h,
                rejections,
            });
        }
        if run.sim.steps >= settings.max_steps.min(MAX_STEPS) {
            return Err(SolverError::Steps {
                t: run.t,
                t_end: settings.t_end,
                steps: run.sim.steps,
            });
        }
    }
}

/// What one [`Loop::step`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
enum StepOutcome {
    /// An accepted integration step, or a move onto the next record sample.
    Advanced,
    /// A step rejected (error above tolerance, or a hop hidden inside it): it is
    /// retried smaller.
    Rejected,
    /// An impact (rocking goes on from the other pivot, or the wall came to rest).
    Impact,
    /// The wall left rest.
    Uplift,
    /// The run is over: the end time reached, or the wall overturned.
    Stopped(Stop),
}

/// The state of the event loop between steps.
struct Loop<'a, 'o> {
    model: &'a RockingModel,
    ground: &'a Ground,
    settings: &'a Settings,
    out: &'a mut Outputs<'o>,
    sim: Simulation,
    /// Plastic elongations of the tie-rods.
    plastic: Vec<f64>,
    t: f64,
    y: State,
    phase: Phase,
    /// The derivative at (t, y) carried over from the last accepted step (FSAL) or
    /// the last record sample; None: evaluate it afresh.
    k1: Option<State>,
    /// The step size to try next.
    h: f64,
    /// |ü_g| above which the wall uplifts from rest.
    threshold: f64,
    /// After this time |ü_g| ≤ threshold everywhere (found on the first rest).
    quiet: Option<f64>,
    /// max |θ| since the last impact or uplift: the apex of the current half-cycle.
    apex: f64,
}

impl<'a, 'o> Loop<'a, 'o> {
    fn new(model: &'a RockingModel, ground: &'a Ground, t0: f64, initial: Option<State>, settings: &'a Settings, out: &'a mut Outputs<'o>) -> Self {
        let phase = match initial {
            Some([th, om]) if th != 0.0 || om != 0.0 => Phase::Rocking(Side::of(if th != 0.0 { th } else { om })),
            _ => Phase::Rest,
        };
        let mut run = Loop {
            model,
            ground,
            settings,
            out,
            sim: Simulation {
                stop: Stop::End,
                events: Vec::new(),
                history: Vec::new(),
                max_theta: 0.0,
                min_theta: 0.0,
                impacts: 0,
                steps: 0,
            },
            plastic: vec![0.0; model.ties.len()],
            t: t0,
            y: initial.unwrap_or([0.0, 0.0]),
            phase,
            k1: None,
            h: 1e-3f64.min(settings.max_step),
            threshold: model.uplift_threshold(),
            quiet: None,
            apex: 0.0,
        };
        run.push(t0, run.y);
        run
    }

    /// Record a point: the extremes, and the history when kept.
    fn push(&mut self, t: f64, y: State) {
        self.apex = self.apex.max(y[0].abs());
        self.sim.max_theta = self.sim.max_theta.max(y[0]);
        self.sim.min_theta = self.sim.min_theta.min(y[0]);
        if self.settings.keep_history {
            self.sim.history.push(Sample {
                t,
                theta: y[0],
                omega: y[1],
                ag: self.ground.at(t),
            });
        }
    }

    /// One step of the loop, and what it did.
    fn step(&mut self) -> StepOutcome {
        if self.t >= self.settings.t_end {
            return StepOutcome::Stopped(Stop::End);
        }
        match self.phase {
            Phase::Rest => self.rest(),
            Phase::Rocking(side) => self.rock(side),
        }
    }

    /// At rest: jump to the next uplift (or to the end: nothing uplifts the wall
    /// before it, or nothing can any more once the record is quiet).
    fn rest(&mut self) -> StepOutcome {
        let (ground, settings) = (self.ground, self.settings);
        self.y = [0.0, 0.0];
        let thr = self.threshold;
        let q = *self.quiet.get_or_insert_with(|| quiet_after(ground, thr));
        let next = if settings.stop_at_rest && self.t >= q {
            None
        } else {
            next_uplift(ground, self.t, settings.t_end, thr)
        };
        self.out.fill(next.map_or(settings.t_end, |n| n.0), |_| 0.0);
        match next {
            Some((tu, side)) => {
                if tu > self.t {
                    self.push(tu, self.y);
                }
                self.t = tu;
                self.sim.events.push(Event::Uplift { t: tu, side });
                self.apex = 0.0;
                self.phase = Phase::Rocking(side);
                self.k1 = None;
                StepOutcome::Uplift
            }
            None => {
                self.t = settings.t_end;
                self.push(self.t, self.y);
                StepOutcome::Stopped(Stop::End)
            }
        }
    }

    /// Rocking on pivot `side`: one trial step of the integrator, never past the
    /// next record sample (ü_g is linear on it), and the event it holds.
    fn rock(&mut self, side: Side) -> StepOutcome {
        let (model, ground, settings) = (self.model, self.ground, self.settings);
        let (t, y) = (self.t, self.y);
        let k1 = match self.k1 {
            Some(k) => k,
            None => [y[1], model.accel(side, y[0], ground.at(t), &self.plastic)],
        };
        let pl = &self.plastic;
        let (ta, a0, slope) = ground.linear_piece(t);
        let mut f = |tt: f64, yy: &State| -> State { [yy[1], model.accel(side, yy[0], a0 + slope * (tt - ta), pl)] };
        let boundary = next_sample_after(ground, t).min(settings.t_end);
        let hh = self.h.min(boundary - t).min(settings.max_step);
        if hh <= 1e-14 * t.abs().max(1.0) {
            // At a boundary: move on to it exactly.
            self.t = boundary;
            if boundary >= settings.t_end {
                return StepOutcome::Stopped(Stop::End);
            }
            self.k1 = Some(f(boundary, &y));
            return StepOutcome::Advanced;
        }
        let st = step(&mut f, t, &y, &k1, hh, settings.tol);
        self.sim.steps += 1;
        self.k1 = Some(k1);
        if st.err > 1.0 {
            self.h = next_h(hh, st.err).max(1e-12);
            return StepOutcome::Rejected;
        }
        // A step that ends on the wrong side without a detected crossing hid a
        // short hop: retry smaller.
        let s = side.sign();
        let ev = first_event(model, side, &st.dense, t, hh, &y);
        if ev.is_none() && s * st.y1[0] < 0.0 {
            self.h = 0.25 * hh;
            return StepOutcome::Rejected;
        }
        if let Some(th) = track_extremum(&mut self.sim, &st.dense, t, hh, &y, &st.y1) {
            self.apex = self.apex.max(th.abs());
        }
        let dense = &st.dense;
        self.out.fill(ev.map_or(t + hh, |e| e.0), |x| dense.at(x)[0]);
        match ev {
            None => {
                self.t = t + hh;
                self.y = st.y1;
                self.k1 = Some(st.k7);
                model.update_plastic(self.y[0], &mut self.plastic);
                self.push(self.t, self.y);
                self.h = next_h(hh, st.err);
                if self.t >= settings.t_end {
                    StepOutcome::Stopped(Stop::End)
                } else {
                    StepOutcome::Advanced
                }
            }
            Some((te, EventKind::Overturn)) => {
                self.push(te, st.dense.at(te));
                self.sim.events.push(Event::Overturned { t: te });
                StepOutcome::Stopped(Stop::Overturned { t: te })
            }
            Some((te, EventKind::Impact)) => {
                self.impact(side, te, st.dense.at(te)[1], hh);
                StepOutcome::Impact
            }
        }
    }

    /// An impact at `te` with θ' = `vb` coming from pivot `from`: θ' ← e θ' with
    /// the coefficient of the side entered (a law's at the apex of the half-cycle
    /// that ends); rest when that leaves the wall slower than the rest speed.
    fn impact(&mut self, from: Side, te: f64, vb: f64, hh: f64) {
        let entering = from.opposite();
        let (e, law_amplitude_over_alpha) = self.model.coefficient(entering, self.apex, vb);
        let amplitude_over_alpha = self.apex / self.model.alpha;
        self.apex = 0.0;
        let va = e * vb;
        self.push(te, [0.0, vb]);
        self.sim.impacts += 1;
        self.sim.events.push(Event::Impact {
            t: te,
            entering,
            v_before: vb,
            v_after: va,
            amplitude_over_alpha,
            law_amplitude_over_alpha,
        });
        self.t = te;
        self.y = [0.0, va];
        self.h = hh.max(1e-6);
        self.k1 = None;
        if va.abs() < self.settings.rest_speed {
            self.sim.events.push(Event::Rest { t: te });
            self.phase = Phase::Rest;
        } else {
            self.phase = Phase::Rocking(entering);
        }
        self.push(te, self.y);
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum EventKind {
    Impact,
    Overturn,
}

/// The first event inside an accepted step: θ returning to 0 from side s, or θ
/// reaching the overturning level. The dense output is sampled at 8 points so
/// that a short excursion inside one step is not missed.
fn first_event(model: &RockingModel, side: Side, d: &Dense, t: f64, h: f64, y0: &State) -> Option<(f64, EventKind)> {
    let level = model.overturn_level(side);
    let s = side.sign();
    // Quick exclusion: on the step θ stays within h·(|ω₀| + |ω₁|) + h²·(|θ''|max)
    // of its end values (Taylor bound; |θ''| taken generously from the change of ω
    // across the step plus p²), so a step far from 0 and from the limit holds no event.
    let y1 = d.at(t + h);
    let acc = (y1[1] - y0[1]).abs() / h;
    let reach = h * (y0[1].abs() + y1[1].abs()) + h * h * (2.0 * acc + 2.0 * model.p2);
    let near_zero = s * y0[0] <= reach || s * y1[0] <= reach;
    let near_limit = level.is_some_and(|lv| (lv - y0[0]).abs() <= reach || (lv - y1[0]).abs() <= reach);
    if !near_zero && !near_limit {
        return None;
    }
    let n = 8;
    let mut prev_t = t;
    let mut prev = *y0;
    for q in 1..=n {
        let tq = t + h * q as f64 / n as f64;
        let yq = d.at(tq);
        if let Some(lv) = level {
            if (prev[0] - lv) * s < 0.0 && (yq[0] - lv) * s >= 0.0 {
                let te = find_root(|x| d.at(x)[0] - lv, prev_t, tq, 1e-13);
                // An impact cannot come first inside the same sub-interval: θ is
                // beyond the level, far from 0.
                return Some((te, EventKind::Overturn));
            }
        }
        if s * prev[0] > 0.0 && s * yq[0] <= 0.0 {
            let te = find_root(|x| d.at(x)[0], prev_t, tq, 1e-13);
            return Some((te, EventKind::Impact));
        }
        if s * prev[0] == 0.0 && q > 1 && s * yq[0] <= 0.0 {
            return Some((prev_t, EventKind::Impact));
        }
        prev_t = tq;
        prev = yq;
    }
    None
}

/// Record θ at a turning point inside the step (θ' changes sign), and return it.
fn track_extremum(sim: &mut Simulation, d: &Dense, t: f64, h: f64, y0: &State, y1: &State) -> Option<f64> {
    if y0[1] * y1[1] < 0.0 {
        let te = find_root(|x| d.at(x)[1], t, t + h, 1e-12);
        let th = d.at(te)[0];
        sim.max_theta = sim.max_theta.max(th);
        sim.min_theta = sim.min_theta.min(th);
        return Some(th);
    }
    None
}

/// The first record sample strictly after t (or +∞ past the record).
fn next_sample_after(ground: &Ground, t: f64) -> f64 {
    if ground.acc.len() < 2 || t >= ground.end() {
        return f64::INFINITY;
    }
    if t < ground.t0 {
        return ground.t0;
    }
    let k = ((t - ground.t0) / ground.dt * (1.0 + 1e-12) + 1e-9).floor() + 1.0;
    ground.t0 + ground.dt * k
}

/// The time after which |ü_g| ≤ threshold for good: the end of the interval after
/// the last sample above it (ü_g is linear between samples, so it can only exceed
/// the threshold next to such a sample); the record's start if none is.
fn quiet_after(ground: &Ground, thr: f64) -> f64 {
    match ground.acc.iter().rposition(|a| a.abs() > thr) {
        Some(i) => ground.time((i + 1).min(ground.acc.len().saturating_sub(1))),
        None => ground.t0,
    }
}

/// Next time ≥ t when |ü_g| exceeds the threshold (exact on the piecewise-linear
/// record), and the side the wall rocks towards (the sign of ü_g).
fn next_uplift(ground: &Ground, t: f64, t_end: f64, thr: f64) -> Option<(f64, Side)> {
    let a_now = ground.at(t);
    if a_now.abs() > thr {
        return Some((t, Side::of(a_now)));
    }
    if ground.acc.len() < 2 || t >= ground.end() {
        return None;
    }
    let start = ground.interval(t.max(ground.t0));
    for i in start..ground.acc.len() - 1 {
        let (ta, tb) = (ground.time(i), ground.time(i + 1));
        if ta > t_end {
            return None;
        }
        let (a, b) = (ground.acc[i], ground.acc[i + 1]);
        for sgn in [1.0, -1.0] {
            let (fa, fb) = (sgn * a - thr, sgn * b - thr);
            if fb > 0.0 && fa <= 0.0 {
                let tc = ta + (tb - ta) * (-fa) / (fb - fa);
                let tc = tc.max(t);
                if tc <= t_end {
                    // Just past the crossing, so that |ü_g| > threshold strictly.
                    let tu = (tc + 1e-12).min(tb);
                    return Some((tu, Side::of(sgn)));
                }
                return None;
            }
        }
    }
    None
}
