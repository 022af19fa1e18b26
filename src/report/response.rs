//! The response plots of `simulate` and of the façade study (paper Fig. 8/9):
//! θ/α of one or more runs over time above the scaled ground acceleration.

use super::plots::{self, Figure, Panel, RGBColor, Series, BLACKISH};
use super::ReportError;
use crate::ground_motion::Record;
use crate::solver::run::Sample;
use crate::study::RunSpec;

/// One run in a response plot: its label, its history and its colour.
pub type Run<'a> = (&'a str, &'a [Sample], RGBColor);

/// The response figure of `simulate`: one run, then the scaled record.
pub fn simulate_figure(name: &str, history: &[Sample], alpha: f64, record: &Record, spec: &RunSpec) -> Result<Figure, ReportError> {
    let panels = response_panels(name, &[("response", history, plots::RED)], alpha, &record_points(record, spec));
    plots::render(&panels, 1000, 320)
}

/// history.csv of `simulate`: time, θ, θ/α, θ', the ground acceleration.
pub fn history_csv(history: &[Sample], alpha: f64) -> Result<Vec<u8>, ReportError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["t_s", "theta_rad", "theta_over_alpha", "theta_dot_rad_s", "ag_m_s2"])?;
    for s in history {
        w.write_record([s.t, s.theta, s.theta / alpha, s.omega, s.ag].iter().map(|v| v.to_string()))?;
    }
    super::csv_bytes(w)
}

/// The scaled ground acceleration in g for plots.
pub fn record_points(record: &Record, spec: &RunSpec) -> Vec<(f64, f64)> {
    let k = spec.scale * spec.polarity / crate::G;
    record
        .acc_m_s2
        .iter()
        .enumerate()
        .map(|(i, a)| (record.t0 + i as f64 * record.dt, a * k))
        .collect()
}

/// Paper Fig. 8/9 style: θ/α of one or more runs over time, then the scaled ground
/// acceleration.
pub fn response_panels(title: &str, runs: &[Run], alpha: f64, ag: &[(f64, f64)]) -> Vec<Panel> {
    let span = ag.first().zip(ag.last()).map(|(a, b)| (a.0, b.0));
    let series = runs
        .iter()
        .map(|(label, h, color)| Series::line(label, *color, h.iter().map(|s| (s.t, s.theta / alpha)).collect()))
        .collect();
    vec![
        Panel {
            x_range: span,
            ..Panel::new(format!("{title}: normalised rotation"), "time (s)", "θ/α", series)
        },
        Panel {
            x_range: span,
            ..Panel::new(
                "ground acceleration (scaled)",
                "time (s)",
                "ü_g (g)",
                vec![Series::line("ü_g", BLACKISH, ag.to_vec())],
            )
        },
    ]
}
