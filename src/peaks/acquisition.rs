//! The data logger's filter in the forward model (issue #18): a stated causal
//! low-pass, and the detection and estimation of an unstated one.
//!
//! # A stated filter
//! The logger samples r_i = (h ∗ y)(t_i), y the wall's motion (L sin θ) and h
//! the impulse response of its analogue low-pass ([`crate::signal::filter`]).
//! The model's y is piecewise smooth: closed-form arcs joined at kinks (the
//! impacts: a jump of y'; the release: a jump of y''). Between nodes (the
//! samples and every kink: the release, the onsets and ends of contact, the
//! impacts) y is replaced by the cubic Hermite interpolant of its value and
//! one-sided slopes, and the filter's modal states are advanced exactly over
//! each piece ([`Modal::advance`]). The interpolation error is
//! h⁴ max|y⁗| / 384 per node spacing h ≤ Δt: below 10⁻⁴ mm for the stiffest
//! restraint arcs of the draws at 100 Hz (ω ≈ 60 rad/s, 50 mm), so a stated
//! filter costs no accuracy. The filter starts in the steady state of the
//! held wall (the model is constant before its release).
//!
//! Cost: one more pass over the window per model evaluation (a few complex
//! multiply-adds per pole and sample); only a stated or estimated filter takes
//! it, the plain path of a log without one is unchanged.
//!
//! # An unstated filter
//! See [`estimate`]: a generic low-pass (Bessel, order 4, the family whose
//! smooth rounding and delay are those of most analogue front ends) with its
//! cut-off free is fitted where the plain model misses the samples around its
//! impacts, and kept where the data ask for it (Bayesian information
//! criterion, one parameter).

use std::sync::Arc;

use nalgebra::Complex;

use super::model::Model;
use crate::signal::filter::{hermite_cubic, LowPass, Modal, StepCoefficients};

/// What the manifest says of the logger's filter (SPEC, `[acquisition]`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Acquisition {
    /// `filter = "none"`: the samples are the sensor's instantaneous readings.
    None,
    /// A causal analogue low-pass, stated: modelled exactly.
    Stated(LowPass),
    /// `filter = "unknown"`, or no `[acquisition]` at all: detected and
    /// estimated from the log ([`estimate`]).
    #[default]
    Unknown,
}

/// Which response the reduction of one test used, and where it came from
/// (reported per test in `summary.json` and the report).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ResponseUsed {
    /// "stated", "stated none", "estimated" or "not detected".
    pub source: &'static str,
    /// The low-pass the model was seen through, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filter: Option<LowPass>,
}

impl ResponseUsed {
    pub fn describe(&self) -> String {
        match self.filter {
            Some(f) => format!("{} ({})", self.source, f.describe()),
            None => self.source.to_string(),
        }
    }
}

/// A filter as the model carries it: the modal form and what it was made from.
#[derive(Debug, Clone)]
pub struct ModelFilter {
    pub modal: Modal,
    /// Group delay at DC (s): a smooth arc comes out of the filter this late.
    pub delay: f64,
}

impl ModelFilter {
    pub fn new(modal: Modal) -> Arc<ModelFilter> {
        let delay = modal.group_delay();
        Arc::new(ModelFilter { modal, delay })
    }
}

/// The filter a stated acquisition puts in the model, and how the report names it.
pub fn stated(acq: &Acquisition) -> (Option<Arc<ModelFilter>>, ResponseUsed) {
    match acq {
        Acquisition::Stated(lp) => (
            Some(ModelFilter::new(lp.modal())),
            ResponseUsed {
                source: "stated",
                filter: Some(*lp),
            },
        ),
        Acquisition::None => (
            None,
            ResponseUsed {
                source: "stated none",
                filter: None,
            },
        ),
        Acquisition::Unknown => (
            None,
            ResponseUsed {
                source: "not detected",
                filter: None,
            },
        ),
    }
}

/// One node of the piecewise-cubic input: its time, the sample it is (if any),
/// and whether the model has a kink there (slopes differ on either side).
#[derive(Debug, Clone, Copy)]
struct Node {
    t: f64,
    sample: Option<usize>,
    kink: bool,
}

/// The times where the model's slope or curvature jumps: the release, the
/// onset of each contact (the impact without contact phases) and its end.
fn kinks(model: &Model) -> Vec<f64> {
    let mut out = vec![model.release_time()];
    for k in 0..model.m() {
        out.push(model.onset(k));
        let end = model.release_from_contact(k);
        if end > model.onset(k) && k + 1 < model.m() {
            out.push(end);
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// The samples and the kinks in time order, from the release (or the first
/// sample, whichever is earlier).
fn nodes(model: &Model, t: &[f64]) -> Vec<Node> {
    let kinks = kinks(model);
    let start = t[0].min(kinks[0]);
    let mut out = Vec::with_capacity(t.len() + kinks.len() + 1);
    if start < t[0] {
        out.push(Node {
            t: start,
            sample: None,
            kink: false,
        });
    }
    let mut j = 0;
    // A kink within this of a sample is taken at the sample (its left slope kept).
    let tol = 1e-9 * (t[t.len() - 1] - t[0]).max(1.0);
    for (i, &ti) in t.iter().enumerate() {
        while j < kinks.len() && kinks[j] < ti - tol {
            if kinks[j] > start + tol {
                out.push(Node {
                    t: kinks[j],
                    sample: None,
                    kink: true,
                });
            }
            j += 1;
        }
        let kink = j < kinks.len() && (kinks[j] - ti).abs() <= tol;
        if kink {
            j += 1;
        }
        out.push(Node {
            t: ti,
            sample: Some(i),
            kink,
        });
    }
    out
}

/// The model seen through the filter at the samples `t` (sorted): None where the
/// model is undefined (past its last impact).
pub fn through_filter(model: &Model, filter: &ModelFilter, t: &[f64]) -> Vec<Option<f64>> {
    let mut out = vec![None; t.len()];
    if t.is_empty() {
        return out;
    }
    let nodes = nodes(model, t);
    // Slopes just left of every kink (ε = 1 ns), values and right slopes at every node.
    const EPS: f64 = 1e-9;
    let mut query = Vec::with_capacity(nodes.len() * 2);
    for n in &nodes {
        if n.kink {
            query.push(n.t - EPS);
        }
        query.push(n.t);
    }
    let evals: Vec<Option<(f64, f64)>> = model.eval_many(&query).collect();
    let modal = &filter.modal;
    let step = if t.len() > 1 { t[1] - t[0] } else { 1.0 };
    let cached: StepCoefficients = modal.step_coefficients(step);
    let mut q = 0;
    let mut state: Vec<Complex<f64>> = Vec::new();
    let mut prev: Option<(f64, f64, f64)> = None;
    for n in &nodes {
        let left = if n.kink {
            q += 1;
            evals[q - 1]
        } else {
            None
        };
        let Some((y, v)) = evals[q] else { break };
        q += 1;
        let v_left = left.map_or(v, |(_, vl)| vl);
        match prev {
            None => state = modal.steady_state(y),
            Some((t0, y0, v0)) => {
                let h = n.t - t0;
                if h > 0.0 {
                    let c = hermite_cubic(y0, v0, y, v_left, h);
                    if (h - step).abs() <= 1e-9 * step {
                        modal.advance(&mut state, &cached, c);
                    } else {
                        modal.advance(&mut state, &modal.step_coefficients(h), c);
                    }
                }
            }
        }
        prev = Some((n.t, y, v));
        if let Some(i) = n.sample {
            out[i] = Some(modal.output(&state));
        }
    }
    out
}
