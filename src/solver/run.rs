//! The event-driven rocking loop: integrate on the current pivot, locate impacts
//! and overturning on the dense output, apply θ' ← e θ' at impacts, go to rest when
//! the impacts have taken the speed below a threshold, and uplift again when
//! |ü_g| > g tan α. The loop returns why it stopped.

use super::integrator::{find_root, next_h, step, Dense, State, Tolerances};
use super::model::{Ground, RockingModel};

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
        }
    }
    pub fn with_tolerances(mut self, rtol: f64, atol: f64) -> Settings {
        assert!(rtol > 0.0 && atol > 0.0, "tolerances must be positive");
        self.tol = Tolerances { rtol, atol };
        self
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
    /// θ crossed 0; `entering` is +1 (outward side) or −1 (inward side).
    Impact {
        t: f64,
        entering: i8,
        v_before: f64,
        v_after: f64,
    },
    /// Rocking started from rest towards `side`.
    Uplift {
        t: f64,
        side: i8,
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

enum Phase {
    Rest,
    Rocking(f64),
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
pub fn simulate(model: &RockingModel, ground: &Ground, t0: f64, initial: Option<State>, settings: &Settings) -> Simulation {
    simulate_at(model, ground, t0, initial, settings, &[]).0
}

/// As [`simulate`], and θ at the sorted `outputs` times (before `t0`: the initial θ).
pub fn simulate_at(
    model: &RockingModel,
    ground: &Ground,
    t0: f64,
    initial: Option<State>,
    settings: &Settings,
    outputs: &[f64],
) -> (Simulation, Vec<f64>) {
    let mut out = Outputs {
        times: outputs,
        values: Vec::with_capacity(outputs.len()),
    };
    let th0 = initial.map_or(0.0, |s| s[0]);
    out.fill(t0, |_| th0);
    let sim = simulate_inner(model, ground, t0, initial, settings, &mut out);
    // After the run: its final θ (known from the history when kept), else the last
    // value output.
    let fill_value = match sim.history.last() {
        Some(s) => s.theta,
        None => out.values.last().copied().unwrap_or(th0),
    };
    out.fill(f64::INFINITY, |_| fill_value);
    (sim, out.values)
}

fn simulate_inner(model: &RockingModel, ground: &Ground, t0: f64, initial: Option<State>, settings: &Settings, out: &mut Outputs) -> Simulation {
    let mut sim = Simulation {
        stop: Stop::End,
        events: Vec::new(),
        history: Vec::new(),
        max_theta: 0.0,
        min_theta: 0.0,
        impacts: 0,
        steps: 0,
    };
    let mut plastic = vec![0.0; model.ties.len()];
    let mut t = t0;
    let mut y: State = initial.unwrap_or([0.0, 0.0]);
    let mut phase = match initial {
        Some([th, om]) if th != 0.0 || om != 0.0 => Phase::Rocking(if th != 0.0 { th.signum() } else { om.signum() }),
        _ => Phase::Rest,
    };
    let thr = model.uplift_threshold();
    // After `quiet`, |ü_g| ≤ threshold everywhere (found on the first rest).
    let mut quiet: Option<f64> = None;
    let mut h = 1e-3f64.min(settings.max_step);
    let push = |sim: &mut Simulation, t: f64, y: &State| {
        sim.max_theta = sim.max_theta.max(y[0]);
        sim.min_theta = sim.min_theta.min(y[0]);
        if settings.keep_history {
            sim.history.push(Sample {
                t,
                theta: y[0],
                omega: y[1],
                ag: ground.at(t),
            });
        }
    };
    push(&mut sim, t, &y);
    while t < settings.t_end {
        match phase {
            Phase::Rest => {
                y = [0.0, 0.0];
                let q = *quiet.get_or_insert_with(|| quiet_after(ground, thr));
                let next = if settings.stop_at_rest && t >= q {
                    None
                } else {
                    next_uplift(ground, t, settings.t_end, thr)
                };
                out.fill(next.map_or(settings.t_end, |n| n.0), |_| 0.0);
                match next {
                    Some((tu, side)) => {
                        if tu > t {
                            push(&mut sim, tu, &y);
                        }
                        t = tu;
                        sim.events.push(Event::Uplift { t, side: side as i8 });
                        phase = Phase::Rocking(side);
                    }
                    None => {
                        t = settings.t_end;
                        push(&mut sim, t, &y);
                        break;
                    }
                }
            }
            Phase::Rocking(s) => {
                let mut k1: State = [y[1], model.accel(s, y[0], ground.at(t), &plastic)];
                loop {
                    let pl = &plastic;
                    // The step never crosses a record sample, so ü_g is linear on it.
                    let (ta, a0, slope) = ground.linear_piece(t);
                    let mut f = |tt: f64, yy: &State| -> State { [yy[1], model.accel(s, yy[0], a0 + slope * (tt - ta), pl)] };
                    let boundary = next_sample_after(ground, t).min(settings.t_end);
                    let hh = h.min(boundary - t).min(settings.max_step);
                    if hh <= 1e-14 * t.abs().max(1.0) {
                        // At a boundary: move on to it exactly.
                        t = boundary;
                        if t >= settings.t_end {
                            break;
                        }
                        k1 = f(t, &y);
                        continue;
                    }
                    let st = step(&mut f, t, &y, &k1, hh, settings.tol);
                    sim.steps += 1;
                    if st.err > 1.0 {
                        h = next_h(hh, st.err).max(1e-12);
                        continue;
                    }
                    // A step that ends on the wrong side without a detected crossing
                    // hid a short hop: retry smaller.
                    let ev = first_event(model, s, &st.dense, t, hh, &y);
                    if ev.is_none() && s * st.y1[0] < 0.0 {
                        h = 0.25 * hh;
                        continue;
                    }
                    track_extremum(&mut sim, &st.dense, t, hh, &y, &st.y1);
                    let dense = st.dense;
                    out.fill(ev.map_or(t + hh, |e| e.0), |x| dense.at(x)[0]);
                    match ev {
                        None => {
                            t += hh;
                            y = st.y1;
                            k1 = st.k7;
                            model.update_plastic(y[0], &mut plastic);
                            push(&mut sim, t, &y);
                            h = next_h(hh, st.err);
                            if t >= settings.t_end {
                                break;
                            }
                        }
                        Some((te, EventKind::Overturn)) => {
                            let ye = st.dense.at(te);
                            push(&mut sim, te, &ye);
                            sim.events.push(Event::Overturned { t: te });
                            sim.stop = Stop::Overturned { t: te };
                            return sim;
                        }
                        Some((te, EventKind::Impact)) => {
                            let ye = st.dense.at(te);
                            let vb = ye[1];
                            let entering = -s;
                            let e = if entering < 0.0 { model.e_in } else { model.e_out };
                            let va = e * vb;
                            push(&mut sim, te, &[0.0, vb]);
                            sim.impacts += 1;
                            sim.events.push(Event::Impact {
                                t: te,
                                entering: entering as i8,
                                v_before: vb,
                                v_after: va,
                            });
                            t = te;
                            y = [0.0, va];
                            h = hh.max(1e-6);
                            if va.abs() < settings.rest_speed {
                                sim.events.push(Event::Rest { t });
                                phase = Phase::Rest;
                            } else {
                                phase = Phase::Rocking(entering);
                            }
                            push(&mut sim, t, &y);
                            break;
                        }
                    }
                }
                if t >= settings.t_end {
                    break;
                }
            }
        }
    }
    sim
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum EventKind {
    Impact,
    Overturn,
}

/// The first event inside an accepted step: θ returning to 0 from side s, or θ
/// reaching the overturning level. The dense output is sampled at 8 points so
/// that a short excursion inside one step is not missed.
fn first_event(model: &RockingModel, s: f64, d: &Dense, t: f64, h: f64, y0: &State) -> Option<(f64, EventKind)> {
    let level = model.overturn_level(s);
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

/// Record θ at a turning point inside the step (θ' changes sign).
fn track_extremum(sim: &mut Simulation, d: &Dense, t: f64, h: f64, y0: &State, y1: &State) {
    if y0[1] * y1[1] < 0.0 {
        let te = find_root(|x| d.at(x)[1], t, t + h, 1e-12);
        let th = d.at(te)[0];
        sim.max_theta = sim.max_theta.max(th);
        sim.min_theta = sim.min_theta.min(th);
    }
}

/// The first record sample strictly after t (or +∞ past the record).
fn next_sample_after(g: &Ground, t: f64) -> f64 {
    if g.acc.len() < 2 || t >= g.end() {
        return f64::INFINITY;
    }
    if t < g.t0 {
        return g.t0;
    }
    let k = ((t - g.t0) / g.dt * (1.0 + 1e-12) + 1e-9).floor() + 1.0;
    g.t0 + g.dt * k
}

/// The time after which |ü_g| ≤ threshold for good: the end of the interval after
/// the last sample above it (ü_g is linear between samples, so it can only exceed
/// the threshold next to such a sample); the record's start if none is.
fn quiet_after(g: &Ground, thr: f64) -> f64 {
    match g.acc.iter().rposition(|a| a.abs() > thr) {
        Some(i) => g.time((i + 1).min(g.acc.len().saturating_sub(1))),
        None => g.t0,
    }
}

/// Next time ≥ t when |ü_g| exceeds the threshold (exact on the piecewise-linear
/// record), and the side (sign of ü_g).
fn next_uplift(g: &Ground, t: f64, t_end: f64, thr: f64) -> Option<(f64, f64)> {
    let a_now = g.at(t);
    if a_now.abs() > thr {
        return Some((t, a_now.signum()));
    }
    if g.acc.len() < 2 || t >= g.end() {
        return None;
    }
    let start = g.interval(t.max(g.t0));
    for i in start..g.acc.len() - 1 {
        let (ta, tb) = (g.time(i), g.time(i + 1));
        if ta > t_end {
            return None;
        }
        let (a, b) = (g.acc[i], g.acc[i + 1]);
        for sgn in [1.0, -1.0] {
            let (fa, fb) = (sgn * a - thr, sgn * b - thr);
            if fb > 0.0 && fa <= 0.0 {
                let tc = ta + (tb - ta) * (-fa) / (fb - fa);
                let tc = tc.max(t);
                if tc <= t_end {
                    // Just past the crossing, so that |ü_g| > threshold strictly.
                    let tu = (tc + 1e-12).min(tb);
                    return Some((tu, sgn));
                }
                return None;
            }
        }
    }
    None
}
