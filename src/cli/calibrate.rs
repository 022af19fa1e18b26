//! `rocklab calibrate MANIFEST --out DIR`: reduce, then fit e_in/e_out by replaying
//! each test with the solver.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use super::say;
use rocklab::atomic::write_atomic;
use rocklab::calibrate::{calibrate, to_toml, Calibration};
use rocklab::ingest::Campaign;
use rocklab::peaks::PeakOptions;
use rocklab::reduce::CampaignResult;
use rocklab::report::plots::{self, Panel, Series};
use rocklab::report::{write_reduce_outputs, Extras};

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Campaign manifest.
    pub manifest: PathBuf,
    #[arg(long)]
    pub out: PathBuf,
    /// Number of impacts in the fitted window (the tables use 6 peaks).
    #[arg(long, default_value_t = 6)]
    pub impacts: usize,
}

pub fn run(a: CalibrateArgs) -> anyhow::Result<ExitCode> {
    let campaign = Campaign::load(&a.manifest)?;
    let res = super::reduce::reduce_and_print(campaign, PeakOptions::default());
    let cal = calibrate_and_write(&res, &a.out, a.impacts)?;
    Ok(if cal.failed.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

pub fn calibrate_and_write(res: &CampaignResult, out: &Path, n: usize) -> anyhow::Result<Calibration> {
    let start = std::time::Instant::now();
    let cal = calibrate(&res.calibration_input(), n);
    let wall = start.elapsed().as_secs_f64();
    std::fs::create_dir_all(out)?;
    write_atomic(&out.join("calibration.toml"), to_toml(&cal)?.as_bytes())?;
    let calibration = rocklab::report::docs::calibration_summary(&cal, wall);
    // Everything reduce writes, with the calibration in summary.json and report.html.
    let figs = plots_for(res, &cal, out, n)?;
    let extra = Extras {
        summary: [("calibration".to_string(), calibration)].into_iter().collect(),
        html_sections: vec![calibration_html(&cal, n, &figs)],
    };
    write_reduce_outputs(res, out, true, &extra)?;
    say(&format!(
        "calibration of {} ({} rocking), {} impacts per test, {:.2} s:",
        cal.campaign, cal.rocking, n, wall
    ));
    say("| test | e_in | ±95 % | e_out | ±95 % | RMS (mm) | NRMSE | iterations | stop |");
    say("|---|---:|---:|---:|---:|---:|---:|---:|---|");
    for t in &cal.tests {
        say(&format!(
            "| {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} | {} | {:?} |",
            t.id,
            t.e_in,
            1.96 * t.se_e_in,
            t.e_out,
            1.96 * t.se_e_out,
            t.rms_mm,
            t.nrmse,
            t.iterations,
            t.stop
        ));
    }
    say(&format!(
        "mean over {}: e_in = {:.3} (r_in {:.3}), e_out = {:.3} (r_out {:.3})",
        cal.included.join(", "),
        cal.e_in,
        cal.r_in,
        cal.e_out,
        cal.r_out
    ));
    if let Some(j) = &cal.joint {
        say(&format!(
            "joint fit: e_in = {:.3} ± {:.3}, e_out = {:.3} ± {:.3} (95 %), RMS {:.3} mm",
            j.e_in,
            1.96 * j.se_e_in,
            j.e_out,
            1.96 * j.se_e_out,
            j.rms_mm
        ));
    }
    for (id, e) in &cal.failed {
        eprintln!("test {id}: {e}");
    }
    say(&format!("wrote {}", out.display()));
    Ok(cal)
}

/// The calibration section of report.html.
fn calibration_html(cal: &Calibration, n: usize, figs: &[(String, String)]) -> String {
    use rocklab::report::html::escape;
    let mut s = format!(
        "<h2>Calibration: e_in and e_out replaying each test with the solver</h2>\n<p>Each test is replayed with the rocking solver (Eq. 1, free rocking) from the release and fitted to the displacement over its first {n} impacts (Levenberg–Marquardt; release time, zero offset, p² factor{} free). Means over {}: <b>e_in = {:.3}</b> (r_in = {:.3}), <b>e_out = {:.3}</b> (r_out = {:.3}); e_H = {:.4}.</p>\n",
        if cal.rocking == rocklab::wall::Rocking::OneSided { " and inward spring" } else { "" },
        escape(&cal.included.join(", ")),
        cal.e_in,
        cal.r_in,
        cal.e_out,
        cal.r_out,
        cal.e_housner
    );
    if let Some(j) = &cal.joint {
        s.push_str(&format!(
            "<p>One joint fit over the same tests: e_in = {:.3} ± {:.3}, e_out = {:.3} ± {:.3} (95 %), RMS {:.3} mm, {} iterations, {:?}.</p>\n",
            j.e_in,
            1.96 * j.se_e_in,
            j.e_out,
            1.96 * j.se_e_out,
            j.rms_mm,
            j.iterations,
            j.stop
        ));
    }
    s.push_str("<table class=\"paper\" id=\"calibration\"><thead><tr><th>test</th><th>e_in</th><th>95 % interval</th><th>e_out</th><th>95 % interval</th><th>RMS (mm)</th><th>NRMSE</th><th>iterations</th><th>stop</th><th>per-impact e from the data (in / out)</th></tr></thead><tbody>\n");
    for t in &cal.tests {
        let per = cal.per_impact.iter().find(|p| p.0 == t.id).map(|(_, i, o)| {
            let f = |v: &Vec<f64>| v.iter().map(|x| format!("{x:.2}")).collect::<Vec<_>>().join(" ");
            format!("{} / {}", f(i), f(o))
        });
        s.push_str(&format!(
            "<tr data-test=\"{}\"><td>{}</td><td>{:.3}</td><td>{:.3}–{:.3}</td><td>{:.3}</td><td>{:.3}–{:.3}</td><td>{:.3}</td><td>{:.4}</td><td>{}</td><td>{:?}</td><td>{}</td></tr>\n",
            escape(&t.id), escape(&t.id), t.e_in, t.ci95_e_in[0], t.ci95_e_in[1], t.e_out, t.ci95_e_out[0], t.ci95_e_out[1], t.rms_mm, t.nrmse, t.iterations, t.stop, per.unwrap_or_default()
        ));
    }
    s.push_str("</tbody></table>\n");
    for (caption, svg) in figs {
        s.push_str(&format!("<figure>{svg}<figcaption>{}</figcaption></figure>\n", escape(caption)));
    }
    s
}

fn plots_for(res: &CampaignResult, cal: &Calibration, out: &Path, n_impacts: usize) -> anyhow::Result<Vec<(String, String)>> {
    let mut figs = Vec::new();
    let dir = out.join("plots");
    std::fs::create_dir_all(&dir)?;
    for f in &cal.tests {
        let Some(t) = res.tests.iter().find(|t| t.spec.id == f.id) else {
            continue;
        };
        let Ok(r) = &t.result else { continue };
        let Some(w) = rocklab::calibrate::window(&f.id, r, t.spec.lever_arm_m * 1e3, n_impacts) else {
            continue;
        };
        let n = w.t.len().min(f.replay_mm.len());
        let measured: Vec<(f64, f64)> = (0..n).map(|i| (w.t[i], w.x_mm[i])).collect();
        let replay: Vec<(f64, f64)> = (0..n).map(|i| (w.t[i], f.replay_mm[i])).collect();
        let resid: Vec<(f64, f64)> = (0..n).map(|i| (w.t[i], w.x_mm[i] - f.replay_mm[i])).collect();
        let panels = [
            Panel {
                title: format!("Test {}: measured and replayed (e_in {:.3}, e_out {:.3})", f.id, f.e_in, f.e_out),
                x_label: "time (s)".into(),
                y_label: "displacement (mm)".into(),
                series: vec![
                    Series {
                        label: "measured".into(),
                        color: plots::GREY,
                        points: measured,
                        markers: false,
                    },
                    Series {
                        label: "solver replay".into(),
                        color: plots::RED,
                        points: replay,
                        markers: false,
                    },
                ],
                hline: None,
                x_range: None,
            },
            Panel {
                title: format!("residual (RMS {:.3} mm)", f.rms_mm),
                x_label: "time (s)".into(),
                y_label: "mm".into(),
                series: vec![Series {
                    label: "measured − replay".into(),
                    color: plots::BLUE,
                    points: resid,
                    markers: false,
                }],
                hline: None,
                x_range: None,
            },
        ];
        let svg = plots::render(&dir.join(format!("{}_replay", f.id)), &panels, 1000, 320)?;
        figs.push((
            format!(
                "Test {}: measured displacement and the solver's replay with the fitted coefficients, and the residual.",
                f.id
            ),
            svg,
        ));
    }
    // Fitted coefficients per test with their 95 % intervals (interval ends as
    // small markers joined by the point).
    let mut series = Vec::new();
    for (label, color, pick) in [
        (
            "e_in",
            plots::RED,
            (|t: &rocklab::calibrate::TestFit| (t.e_in, t.ci95_e_in)) as fn(&rocklab::calibrate::TestFit) -> (f64, [f64; 2]),
        ),
        ("e_out", plots::BLUE, |t| (t.e_out, t.ci95_e_out)),
    ] {
        let pts: Vec<(f64, f64)> = cal.tests.iter().enumerate().map(|(i, t)| (i as f64 + 1.0, pick(t).0)).collect();
        series.push(Series {
            label: label.into(),
            color,
            points: pts,
            markers: true,
        });
        for (i, t) in cal.tests.iter().enumerate() {
            let (_, ci) = pick(t);
            let x = i as f64 + 1.0 + if label == "e_in" { -0.05 } else { 0.05 };
            series.push(Series {
                label: String::new(),
                color,
                points: vec![(x, ci[0]), (x, ci[1])],
                markers: false,
            });
        }
    }
    let panel = Panel {
        title: format!(
            "{}: fitted coefficients per test ({}), 95 % intervals",
            cal.campaign,
            cal.tests.iter().map(|t| t.id.as_str()).collect::<Vec<_>>().join(", ")
        ),
        x_label: "test (in the order listed)".into(),
        y_label: "coefficient of restitution".into(),
        series,
        hline: Some((cal.e_in, format!("mean e_in {:.3}", cal.e_in))),
        x_range: Some((0.5, cal.tests.len() as f64 + 0.5)),
    };
    let svg = plots::render(&dir.join("coefficients"), &[panel], 900, 450)?;
    figs.insert(
        0,
        ("Fitted e_in (red) and e_out (blue) per test with their 95 % intervals.".to_string(), svg),
    );
    Ok(figs)
}
