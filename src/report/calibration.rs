//! The outputs of `rocklab calibrate`: the calibration table, the per-impact
//! coefficients from the data, the replay plots (measured against the solver's
//! replay, the residual, and the late half-cycles zoomed) and the plot of the
//! fitted coefficients per test; all added to the reduce outputs.

use super::campaign::{reduce_files, Extras, Sources};
use super::html::escape;
use super::plots::{self, Captioned, Figure, Panel, Series};
use super::table::{to_html, Align, Cell, Column, Table};
use super::{Files, ReportError};
use crate::calibrate::{Calibration, TestFit, TestWindow};
use crate::law_replay::LawReplay;
use crate::reduce::CampaignResult;

/// Everything `calibrate` writes: calibration.toml, the reduce outputs with the
/// calibration in summary.json and report.html, and its plots. `n` is the number
/// of impacts in the fitted window; `wall_s` how long the calibration took.
pub fn calibration_files(
    res: &CampaignResult,
    cal: &Calibration,
    law: Option<&LawReplay>,
    n: usize,
    wall_s: f64,
    sources: &Sources,
) -> Result<Files, ReportError> {
    let figs = figures(res, cal, n)?;
    let extra = Extras {
        summary: [("calibration".to_string(), super::docs::calibration_summary(cal, law, wall_s)?)]
            .into_iter()
            .collect(),
        html_sections: vec![calibration_html(cal, law, n, &figs)],
    };
    let mut files = Files::default();
    files.add("calibration.toml", crate::calibrate::to_toml(cal)?);
    for f in &figs {
        f.figure.add_to(&mut files, &format!("plots/{}", f.stem));
    }
    files.append(reduce_files(res, sources, true, &extra)?);
    Ok(files)
}

/// " (left out: 50_1 (exclude_from_mean), …)", or nothing when every test is in.
fn left_out_clause(cal: &Calibration) -> String {
    if cal.left_out.is_empty() {
        String::new()
    } else {
        format!(" (left out: {})", cal.left_out_text())
    }
}

/// The calibration per test: e_in and e_out with their 95 % intervals, the fit's
/// residual and how it stopped.
pub fn calibration_table(cal: &Calibration) -> Table {
    let col = |k: &str, l: &str| Column::new(k, l, Align::Right);
    let columns = vec![
        Column::new("test", "test", Align::Left),
        col("e_in", "e_in"),
        col("ci95_e_in", "95 % interval"),
        col("e_out", "e_out"),
        col("ci95_e_out", "95 % interval"),
        col("rms_mm", "RMS (mm)"),
        col("nrmse", "NRMSE"),
        col("iterations", "iterations"),
        Column::new("stop", "stop", Align::Left),
    ];
    let caption = format!(
        "Calibration of {} ({} rocking): e_in and e_out fitted per test by replaying it with the solver; means over {}{}: e_in = {:.3} (r_in {:.3}), e_out = {:.3} (r_out {:.3}).",
        cal.campaign,
        cal.rocking,
        cal.included.join(", "),
        left_out_clause(cal),
        cal.e_in,
        cal.r_in,
        cal.e_out,
        cal.r_out
    );
    let mut t = Table::new("calibration", caption, columns);
    t.nowrap = true;
    for f in &cal.tests {
        let ci = |c: [f64; 2]| Cell::text(format!("{:.3}–{:.3}", c[0], c[1]));
        t.push(
            Some(f.id.clone()),
            vec![
                Cell::text(&f.id),
                Cell::num(f.e_in, format!("{:.3}", f.e_in)),
                ci(f.ci95_e_in),
                Cell::num(f.e_out, format!("{:.3}", f.e_out)),
                ci(f.ci95_e_out),
                Cell::num(f.rms_mm, format!("{:.3}", f.rms_mm)),
                Cell::num(f.nrmse, format!("{:.4}", f.nrmse)),
                Cell::text(f.iterations.to_string()),
                Cell::text(format!("{:?}", f.stop)),
            ],
        );
    }
    t
}

/// The per-impact coefficients straight from the data, one row per test, the
/// impacts entering the inward side beside those entering the outward side.
pub fn per_impact_table(cal: &Calibration) -> Table {
    let n_in = cal.per_impact.iter().map(|p| p.1.len()).max().unwrap_or(0);
    let n_out = cal.per_impact.iter().map(|p| p.2.len()).max().unwrap_or(0);
    let mut columns = vec![Column::new("test", "test", Align::Left)];
    for (side, n) in [("inward", n_in), ("outward", n_out)] {
        columns.extend((1..=n).map(|k| Column::new(&format!("{side}_{k}"), &format!("{side} {k}"), Align::Right)));
    }
    let caption = "Per-impact coefficients from the data (speed after ÷ speed before at each impact of the fitted window), \
                   numbered per side in time order: impacts entering the inward side, then those entering the outward side; — no such impact."
        .to_string();
    let mut t = Table::new("per-impact", caption, columns);
    for (id, inward, outward) in &cal.per_impact {
        let mut cells = vec![Cell::text(id)];
        for (v, n) in [(inward, n_in), (outward, n_out)] {
            cells.extend((0..n).map(|k| v.get(k).map_or(Cell::text("—"), |e| Cell::num(*e, format!("{e:.2}")))));
        }
        t.push(Some(id.clone()), cells);
    }
    t
}

/// The calibration section of report.html.
fn calibration_html(cal: &Calibration, law: Option<&LawReplay>, n: usize, figs: &[Captioned]) -> String {
    let mut s = format!(
        "<h2>Calibration: e_in and e_out replaying each test with the solver</h2>\n<p>Each test is replayed with the rocking solver (Eq. 1, free rocking) from the release and fitted to the displacement over its first {n} impacts (Levenberg–Marquardt; release time, zero offset, p² factor{} free). Means over {}{}: <b>e_in = {:.3}</b> (r_in = {:.3}), <b>e_out = {:.3}</b> (r_out = {:.3}); e_H = {:.4}.</p>\n",
        if cal.rocking == crate::wall::Rocking::OneSided { " and inward spring" } else { "" },
        escape(&cal.included.join(", ")),
        escape(&left_out_clause(cal)),
        cal.e_in,
        cal.r_in,
        cal.e_out,
        cal.r_out,
        cal.e_housner
    );
    s.push_str(&law_replay_html(law));
    if let Some(j) = &cal.joint {
        s.push_str(&format!(
            "<p>One joint fit over the same tests: e_in = {}, e_out = {} (95 %), RMS {:.3} mm, {} iterations, {:?}.</p>\n",
            super::tables::value_u(j.e_in, 1.96 * j.se_e_in),
            super::tables::value_u(j.e_out, 1.96 * j.se_e_out),
            j.rms_mm,
            j.iterations,
            j.stop
        ));
        if let Some(a) = &cal.agreement {
            s.push_str(&format!("<p>{}.</p>\n", escape(&a.describe())));
        }
    }
    s.push_str(&to_html(&calibration_table(cal)));
    s.push_str(&to_html(&per_impact_table(cal)));
    for f in figs {
        s.push_str(&format!(
            "<figure>{}<figcaption>{}</figcaption></figure>\n",
            f.figure.svg,
            escape(&f.caption)
        ));
    }
    s
}

/// The coefficient plot first, then each test's replay.
fn figures(res: &CampaignResult, cal: &Calibration, n_impacts: usize) -> Result<Vec<Captioned>, ReportError> {
    let mut figs = vec![Captioned {
        stem: "coefficients".into(),
        caption: "Fitted e_in (red) and e_out (blue) per test with their 95 % intervals.".into(),
        figure: coefficients_figure(cal)?,
    }];
    for f in &cal.tests {
        let Some(t) = res.tests.iter().find(|t| t.spec.id == f.id) else {
            continue;
        };
        let Ok(r) = &t.result else { continue };
        let Some(w) = crate::calibrate::window(&f.id, r, t.spec.lever_arm_m * 1e3, n_impacts) else {
            continue;
        };
        // The late half-cycles: every arc after the first two impacts.
        let late_from = r.analysis.impacts.get(1).map(|i| i.time_s);
        figs.push(Captioned {
            stem: format!("{}_replay", super::file_stem(&f.id)),
            caption: format!(
                "Test {}: measured displacement and the solver's replay with the fitted coefficients, the residual, and the late half-cycles enlarged.",
                f.id
            ),
            figure: replay_figure(f, &w, late_from)?,
        });
    }
    Ok(figs)
}

/// Measured against replayed, the residual, and (from `late_from` on) the late
/// half-cycles on their own scale, where millimetre misses are visible.
pub fn replay_figure(f: &TestFit, w: &TestWindow, late_from: Option<f64>) -> Result<Figure, ReportError> {
    let n = w.t.len().min(f.replay_mm.len());
    let pts = |y: &dyn Fn(usize) -> f64, keep: &dyn Fn(f64) -> bool| -> Vec<(f64, f64)> {
        (0..n).filter(|&i| keep(w.t[i])).map(|i| (w.t[i], y(i))).collect()
    };
    let both = |keep: &dyn Fn(f64) -> bool| {
        vec![
            Series::line("measured", plots::GREY, pts(&|i| w.x_mm[i], keep)),
            Series::line("solver replay", plots::RED, pts(&|i| f.replay_mm[i], keep)),
        ]
    };
    let all = |_: f64| true;
    let title = format!("Test {}: measured and replayed (e_in {:.3}, e_out {:.3})", f.id, f.e_in, f.e_out);
    let residual = vec![Series::line("measured − replay", plots::BLUE, pts(&|i| w.x_mm[i] - f.replay_mm[i], &all))];
    let mut panels = vec![
        Panel::new(title, "time (s)", "displacement (mm)", both(&all)),
        Panel::new(format!("residual (RMS {:.3} mm)", f.rms_mm), "time (s)", "mm", residual),
    ];
    if let Some(t0) = late_from {
        let late = move |t: f64| t >= t0;
        panels.push(Panel::new(
            format!("late half-cycles (from {t0:.2} s), enlarged"),
            "time (s)",
            "displacement (mm)",
            both(&late),
        ));
    }
    plots::render(&panels, 1000, 320)
}

/// The y range of the coefficient plot: every interval and the mean.
fn y_range(cal: &Calibration) -> (f64, f64) {
    let ends = cal
        .tests
        .iter()
        .flat_map(|t| t.ci95_e_in.into_iter().chain(t.ci95_e_out))
        .chain([cal.e_in]);
    let (lo, hi) = ends
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(0.05);
    (lo - 0.08 * span, hi + 0.08 * span)
}

/// The fitted coefficients per test (named on the x axis) with their 95 %
/// intervals (a bar through each point; e_in left of the test's name, e_out
/// right of it) and the mean e_in in e_in's colour.
pub fn coefficients_figure(cal: &Calibration) -> Result<Figure, ReportError> {
    type Pick = fn(&TestFit) -> (f64, [f64; 2]);
    let mut series = Vec::new();
    let sides: [(&str, plots::RGBColor, Pick, f64); 2] = [
        ("e_in", plots::RED, |t| (t.e_in, t.ci95_e_in), -0.08),
        ("e_out", plots::BLUE, |t| (t.e_out, t.ci95_e_out), 0.08),
    ];
    for (label, color, pick, dx) in sides {
        let x = |i: usize| i as f64 + 1.0;
        series.push(Series::dots(
            label,
            color,
            cal.tests.iter().enumerate().map(|(i, t)| (x(i) + dx, pick(t).0)).collect(),
        ));
        for (i, t) in cal.tests.iter().enumerate() {
            let ci = pick(t).1;
            series.push(Series::line("", color, vec![(x(i) + dx, ci[0]), (x(i) + dx, ci[1])]));
        }
    }
    let n = cal.tests.len() as f64;
    series.push(Series::line(
        &format!("mean e_in {:.3}", cal.e_in),
        plots::RED,
        vec![(0.5, cal.e_in), (n + 0.5, cal.e_in)],
    ));
    let panel = Panel {
        title: format!("{}: fitted coefficients per test, 95 % intervals", cal.campaign),
        x_label: "test".into(),
        y_label: "coefficient of restitution".into(),
        series,
        x_range: Some((0.5, n + 0.5)),
        y_range: Some(y_range(cal)),
        hline: None,
        x_names: cal.tests.iter().map(|t| t.id.clone()).collect(),
    };
    plots::render(&[panel], 900, 450)
}

/// The law by replay in report.html: how it was fitted, then its notes.
fn law_replay_html(law: Option<&LawReplay>) -> String {
    let Some(l) = law else {
        return "<p>Restitution law: not fitted by replay in this run.</p>\n".into();
    };
    let mut s = format!("<p>Restitution law {}.</p>\n<ul>\n", escape(crate::law_replay::LAW_BY_REPLAY));
    for n in &l.notes {
        s.push_str(&format!("<li>{}</li>\n", escape(n)));
    }
    for t in &l.tests {
        let v: Vec<String> = t
            .sides
            .iter()
            .map(|x| match &x.reason {
                None => format!("{}: r_inf {:.4}, c {:.4} ± {:.4}", x.side, x.r_inf, x.c, x.cov[1][1].max(0.0).sqrt()),
                Some(_) => format!(
                    "{}: constant {:.4} (c {:.4} ± {:.4} not separated)",
                    x.side,
                    x.constant_r,
                    x.c,
                    x.cov[1][1].max(0.0).sqrt()
                ),
            })
            .collect();
        s.push_str(&format!(
            "<li>test {}: {} impacts over a = {:.3}–{:.3}, RMS {:.3} mm (constant pair {:.3} mm); {}</li>\n",
            escape(&t.id),
            t.impacts,
            t.amplitude_min,
            t.amplitude_max,
            t.law_rms_mm,
            t.constant_rms_mm,
            escape(&v.join("; "))
        ));
    }
    for (id, why) in &l.failed {
        s.push_str(&format!("<li>test {}: no law by replay: {}</li>\n", escape(id), escape(why)));
    }
    s + "</ul>\n"
}
