//! The output edge: the `summary.json` contract, the tables as CSV and Markdown,
//! and the plots. Renderers return bytes; [`crate::atomic::write_atomic`] writes.

pub mod docs;
pub mod html;
pub mod plots;
pub mod summary;
pub mod tables;

use std::path::Path;

use anyhow::Result;
use rayon::prelude::*;

use crate::atomic::write_atomic;
use crate::reduce::{CampaignResult, Reduced};
use crate::restitution::local_ratios;
use plots::{Panel, Series};

/// SVG texts of the plots of one test: (id, motion, ratios).
pub type TestSvgs = Vec<(String, String, String)>;

/// What a later step (the calibration) adds to the reduce outputs: keys of
/// summary.json and sections of report.html.
#[derive(Debug, Default)]
pub struct Extras {
    pub summary: serde_json::Map<String, serde_json::Value>,
    pub html_sections: Vec<String>,
}

/// Write everything `reduce` produces into `out`: summary.json, tables (CSV,
/// Markdown, LaTeX), per-test plots (PNG and SVG) unless `with_plots` is false, and
/// the self-contained report.html, with what `extra` adds.
pub fn write_reduce_outputs(res: &CampaignResult, out: &Path, with_plots: bool, extra: &Extras) -> Result<()> {
    std::fs::create_dir_all(out)?;
    let mut doc = summary::summary(res);
    if let Some(map) = doc.as_object_mut() {
        map.extend(extra.summary.clone());
    }
    let json = serde_json::to_vec_pretty(&doc)?;
    write_atomic(&out.join("summary.json"), &json)?;
    let mut md = format!("# {} — coefficients of restitution\n\n", res.campaign.name);
    let mut tex = String::from("% Tables 1-3 written by rocklab (needs \\usepackage{booktabs})\n");
    let tabs = tables::tables(res);
    for t in &tabs {
        write_atomic(&out.join(format!("{}.csv", t.name)), &tables::to_csv(t)?)?;
        let one = tables::to_markdown(t);
        write_atomic(&out.join(format!("{}.md", t.name)), one.as_bytes())?;
        md.push_str(&one);
        md.push('\n');
        tex.push_str(&tables::to_latex(t));
        tex.push('\n');
    }
    md.push_str(&format!("Velocity peaks: {}.\n", res.options.method.describe()));
    write_atomic(&out.join("tables.md"), md.as_bytes())?;
    write_atomic(&out.join("tables.tex"), tex.as_bytes())?;
    let mut svgs: TestSvgs = Vec::new();
    if with_plots {
        let dir = out.join("plots");
        std::fs::create_dir_all(&dir)?;
        svgs = res
            .tests
            .par_iter()
            .filter_map(|t| t.result.as_ref().ok().map(|r| (t.spec.id.as_str(), r)))
            .map(|(id, r)| test_plots(&dir, id, r, res.campaign.e_housner).map(|(m, q)| (id.to_string(), m, q)))
            .collect::<Result<Vec<_>>>()?;
    }
    let page = html::reduce_page(res, &tabs, &svgs, &extra.html_sections);
    write_atomic(&out.join("report.html"), page.as_bytes())?;
    Ok(())
}

/// Paper Fig. 3/4 (displacement and velocity with the peaks) and Fig. 5 (local
/// ratios with their mean) for one test.
fn test_plots(dir: &Path, id: &str, r: &Reduced, e_h: f64) -> Result<(String, String)> {
    let a = &r.analysis;
    let t = &r.log.time_s;
    let last = a.impacts.last().map_or(a.release_time_s + 1.0, |i| i.time_s);
    let span = last - a.release_time_s;
    let (t0, t1) = (a.release_time_s - 0.15 * span, last + 0.25 * span);
    let window = |i: &usize| t[*i] >= t0 && t[*i] <= t1;
    let idx: Vec<usize> = (0..t.len()).filter(window).collect();
    let measured: Vec<(f64, f64)> = idx.iter().map(|&i| (t[i], a.displacement_mm[i])).collect();
    let velocity: Vec<(f64, f64)> = idx.iter().map(|&i| (t[i], a.velocity_mm_s[i])).collect();
    let fit_x: Vec<(f64, f64)> = a.fit_curve.iter().map(|p| (p.0, p.1)).collect();
    let fit_v: Vec<(f64, f64)> = a.fit_curve.iter().map(|p| (p.0, p.2)).collect();
    let peaks: Vec<(f64, f64)> = a.peaks.iter().map(|p| (p.time_s, p.velocity_mm_s)).collect();
    let mut disp = vec![Series {
        label: "measured (zero: final rest line)".into(),
        color: plots::GREY,
        points: measured,
        markers: false,
    }];
    let mut vel = vec![Series {
        label: "velocity (per sample)".into(),
        color: plots::GREY,
        points: velocity,
        markers: false,
    }];
    if !fit_x.is_empty() {
        disp.push(Series {
            label: "free-rocking fit".into(),
            color: plots::RED,
            points: fit_x,
            markers: false,
        });
        vel.push(Series {
            label: "fit, one-sided at impacts".into(),
            color: plots::BLUE,
            points: fit_v,
            markers: false,
        });
    }
    vel.push(Series {
        label: "peaks v_k".into(),
        color: plots::RED,
        points: peaks,
        markers: true,
    });
    let motion = [
        Panel {
            title: format!("Test {id}: displacement at the sensor (outward +)"),
            x_label: "time (s)".into(),
            y_label: "displacement (mm)".into(),
            series: disp,
            hline: None,
            x_range: None,
        },
        Panel {
            title: format!("Test {id}: velocity and its peaks"),
            x_label: "time (s)".into(),
            y_label: "velocity (mm/s)".into(),
            series: vel,
            hline: None,
            x_range: None,
        },
    ];
    let motion_svg = plots::render(&dir.join(format!("{id}_motion")), &motion, 1000, 340)?;
    let v: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let local: Vec<(f64, f64)> = local_ratios(&v).iter().enumerate().map(|(k, q)| ((k + 1) as f64, q / e_h)).collect();
    let ratios = [Panel {
        title: format!("Test {id}: local ratios |v_k+1 / v_k| / e_H (Eq. 3)"),
        x_label: "impact".into(),
        y_label: "ratio".into(),
        series: vec![Series {
            label: "local ratio".into(),
            color: plots::RED,
            points: local,
            markers: true,
        }],
        hline: Some((r.coefficients.r, format!("mean r = {:.2}", r.coefficients.r))),
        x_range: None,
    }];
    let ratios_svg = plots::render(&dir.join(format!("{id}_ratios")), &ratios, 800, 400)?;
    Ok((motion_svg, ratios_svg))
}
