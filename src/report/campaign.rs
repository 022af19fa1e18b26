//! The outputs of `rocklab reduce` (and the base of `calibrate`'s): summary.json,
//! Tables 1–3 as CSV, Markdown and LaTeX, the per-test plots (paper Fig. 3/4 and
//! Fig. 5) and report.html.

use rayon::prelude::*;

use super::html::{escape, Page};
use super::plots::{self, Figure, Panel, Series};
use super::quality::{advice, kind};
use super::tables::{self, to_html, Table};
use super::{Files, InputFile, ReportError};
use crate::peaks::Quality;
use crate::reduce::{CampaignResult, Reduced};
use crate::restitution::local_ratios;

/// What a later step (the calibration) adds to the reduce outputs: keys of
/// summary.json and sections of report.html.
#[derive(Debug, Default)]
pub struct Extras {
    pub summary: serde_json::Map<String, serde_json::Value>,
    pub html_sections: Vec<String>,
}

/// The inputs as the load step read them: the manifest's text and every input
/// file's size and SHA-256 (the manifest first, then the logs).
#[derive(Debug, Clone, Default)]
pub struct Sources {
    pub manifest: String,
    pub files: Vec<InputFile>,
}

/// The figures of one test: its id, the motion (Fig. 3/4) and the ratios (Fig. 5).
pub type TestFigures = Vec<(String, Figure, Figure)>;

/// Everything `reduce` produces: summary.json, tables (CSV, Markdown, LaTeX),
/// per-test plots (PNG and SVG in `plots/`) unless `with_plots` is false, and the
/// self-contained report.html, with what `extra` adds.
pub fn reduce_files(res: &CampaignResult, sources: &Sources, with_plots: bool, extra: &Extras) -> Result<Files, ReportError> {
    let mut files = Files::default();
    for f in &sources.files {
        files.input(&f.path);
    }
    let mut doc = super::summary::summary(res)?;
    if let Some(map) = doc.as_object_mut() {
        map.extend(extra.summary.clone());
    }
    super::docs::gather_timing(&mut doc);
    files.add("summary.json", serde_json::to_vec_pretty(&doc)?);
    impacts_file(&doc, &mut files)?;
    let tabs = tables::tables(res);
    table_files(res, &tabs, &mut files)?;
    let figs: TestFigures = if with_plots {
        res.tests
            .par_iter()
            .filter_map(|t| t.result.as_ref().ok().map(|r| (t.spec.id.as_str(), r)))
            .map(|(id, r)| test_plots(id, r, res.campaign.e_housner).map(|(m, q)| (id.to_string(), m, q)))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        Vec::new()
    };
    for (id, motion, ratios) in &figs {
        let stem = super::file_stem(id);
        motion.add_to(&mut files, &format!("plots/{stem}_motion"));
        ratios.add_to(&mut files, &format!("plots/{stem}_ratios"));
    }
    let mut sections = vec![super::law::law_files(res, with_plots, &mut files)?];
    sections.extend(extra.html_sections.iter().cloned());
    let page = reduce_page(res, &tabs, &figs, &sections, sources);
    files.add("report.html", page);
    Ok(files)
}

/// `impacts.parquet`: one row per impact of summary.json's tests, in the archive's
/// layout (`rocklab::archive`), when the tests carry per-impact coefficients in
/// SPEC's shape.
fn impacts_file(doc: &serde_json::Value, files: &mut Files) -> Result<(), ReportError> {
    let Ok(mut r) = crate::archive::rows::reduction(doc, "summary.json") else {
        return Ok(()); // no manifest hash (unreadable manifest): no archive rows either
    };
    if r.impacts.height() > 0 {
        files.add("impacts.parquet", super::parquet::bytes(&mut r.impacts)?);
    }
    Ok(())
}

/// Each table as `NAME.csv` and `NAME.md`, all of them in tables.md and tables.tex.
fn table_files(res: &CampaignResult, tabs: &[Table], files: &mut Files) -> Result<(), ReportError> {
    let mut md = format!("# {} — coefficients of restitution\n\n", res.campaign.name);
    let mut tex = String::from("% Tables 1-3 written by rocklab (needs \\usepackage{booktabs})\n");
    for t in tabs {
        files.add(format!("{}.csv", t.name), tables::to_csv(t)?);
        files.add(format!("{}.parquet", t.name), super::parquet::table(t)?);
        let one = tables::to_markdown(t);
        files.add(format!("{}.md", t.name), one.as_bytes());
        md.push_str(&one);
        md.push('\n');
        tex.push_str(&tables::to_latex(t));
        tex.push('\n');
    }
    md.push_str(&format!("Velocity peaks: {}.\n", res.options.method.describe()));
    files.add("tables.md", md);
    files.add("tables.tex", tex);
    Ok(())
}

/// Paper Fig. 3/4 (displacement and velocity with the peaks) and Fig. 5 (local
/// ratios with their mean) for one test.
fn test_plots(id: &str, r: &Reduced, e_h: f64) -> Result<(Figure, Figure), ReportError> {
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
    let mut disp = vec![Series::line("measured (zero: final rest line)", plots::GREY, measured)];
    let mut vel = vec![Series::line("velocity (per sample)", plots::GREY, velocity)];
    if !fit_x.is_empty() {
        disp.push(Series::line("free-rocking fit", plots::RED, fit_x));
        vel.push(Series::line("free-rocking fit", plots::BLUE, fit_v));
    }
    vel.push(Series::dots("peaks v_k", plots::RED, peaks));
    let motion = [
        Panel::new(
            format!("Test {id}: displacement at the sensor (outward +)"),
            "time (s)",
            "displacement (mm)",
            disp,
        ),
        Panel::new(format!("Test {id}: velocity and its peaks"), "time (s)", "velocity (mm/s)", vel),
    ];
    let motion_fig = plots::render(&motion, 1000, 340)?;
    let v: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let local: Vec<(f64, f64)> = local_ratios(&v).iter().enumerate().map(|(k, q)| ((k + 1) as f64, q / e_h)).collect();
    let n = local.len();
    let ratios = [Panel {
        hline: Some((r.coefficients.r, format!("mean r = {:.2}", r.coefficients.r))),
        // Impacts are counted: the axis names 1, 2, … (no ticks between them).
        x_names: (1..=n).map(|k| k.to_string()).collect(),
        x_range: Some((0.5, n as f64 + 0.5)),
        ..Panel::new(
            format!("Test {id}: local ratios |v_k+1 / v_k| / e_H (Eq. 3)"),
            "impact",
            "ratio",
            vec![Series::dots("local ratio", plots::RED, local)],
        )
    }];
    let ratios_fig = plots::render(&ratios, 800, 400)?;
    Ok((motion_fig, ratios_fig))
}

/// The reduce report (plus extra sections, e.g. the calibration).
fn reduce_page(res: &CampaignResult, tabs: &[Table], figs: &TestFigures, extra: &[String], sources: &Sources) -> String {
    let c = &res.campaign;
    let mut page = Page::new(&format!("{} — coefficients of restitution ({} rocking)", c.name, c.rocking.as_str()));
    page.p(&format!(
        "α = {:.4} rad ({}); e_H = {:.4} ({}). Ratios are divided by e_H. Velocity peaks: {}.",
        c.alpha_rad,
        c.alpha_source,
        c.e_housner,
        c.e_housner_source,
        res.options.method.describe()
    ));
    page.h2("Tables");
    if let Some(none) = super::quality::none_vouched_in(res) {
        page.raw(&format!(
            "<p class=\"none-vouched\"><strong>{}</strong> See Quality below.</p>\n",
            escape(&none)
        ));
    }
    if !res.means.left_out.is_empty() {
        page.p(&format!("Means leave out: {}.", res.means.left_out_text()));
    }
    for t in tabs {
        page.raw(&to_html(t));
    }
    quality_section(&mut page, res, !figs.is_empty());
    peaks_section(&mut page, res);
    for x in extra {
        page.raw(x);
    }
    page.h2("Plots");
    for (id, motion, ratios) in figs {
        page.raw(&format!("<h3 id=\"plots-{0}\">Test {0}</h3>\n", escape(id)));
        page.figure(
            &motion.svg,
            &format!("Test {id}: displacement and velocity with the velocity peaks marked (paper Fig. 3/4)."),
        );
        page.figure(&ratios.svg, &format!("Test {id}: local ratios of Eq. 3 and their mean (paper Fig. 5)."));
    }
    provenance(&mut page, res, sources);
    page.finish()
}

/// The velocity peaks v_k with their standard uncertainties (mm/s), and their
/// times (s) in a table of their own, so that every cell stays on one line.
fn peaks_section(page: &mut Page, res: &CampaignResult) {
    page.h2("Velocity peaks");
    let reduced: Vec<(&str, &Reduced)> = res
        .tests
        .iter()
        .filter_map(|t| Some((t.spec.id.as_str(), t.result.as_ref().ok()?)))
        .collect();
    let row = |id: &str, cells: Vec<String>| std::iter::once(id.to_string()).chain(cells).collect::<Vec<String>>();
    let velocities: Vec<Vec<String>> = reduced
        .iter()
        .map(|(id, r)| {
            let v = r.analysis.peaks.iter().map(|p| match p.velocity_u_mm_s {
                Some(u) => format!("{:.1} ± {u:.1}", p.velocity_mm_s),
                None => format!("{:.1}", p.velocity_mm_s),
            });
            row(id, v.collect())
        })
        .collect();
    let times: Vec<Vec<String>> = reduced
        .iter()
        .map(|(id, r)| row(id, r.analysis.peaks.iter().map(|p| format!("{:.3}", p.time_s)).collect()))
        .collect();
    page.p("Each peak v_k ± its standard uncertainty (outward +), in mm/s:");
    page.table("meta peaks", &["test", "v0", "v1", "v2", "v3", "v4", "v5"], &velocities);
    page.p("and the time of each peak, s:");
    page.table("meta peaks", &["test", "t0", "t1", "t2", "t3", "t4", "t5"], &times);
}

/// The quality section: each test the tool cannot vouch for, once, with its
/// reasons in the lab's words ([`super::quality`]): what is wrong, the plot to look
/// at, how far off the values may be, what to re-run; then the estimator's own
/// words. Tests that could not be reduced are listed with their error.
fn quality_section(page: &mut Page, res: &CampaignResult, with_plots: bool) {
    page.h2("Quality");
    let suspect: Vec<(&str, &[String])> = res
        .tests
        .iter()
        .filter_map(|t| match &t.result.as_ref().ok()?.analysis.quality {
            Quality::Suspect(reasons) => Some((t.spec.id.as_str(), reasons.as_slice())),
            Quality::Ok => None,
        })
        .collect();
    let failed: Vec<_> = res.failed().collect();
    if suspect.is_empty() && failed.is_empty() {
        page.p("Every test passed the estimator's checks (docs/estimator.md): the tables' ± are their standard uncertainties.");
        return;
    }
    page.p("A suspect test is left out of the means. Its values are in the tables, but the estimator cannot vouch for them:");
    let mut html = String::from("<dl class=\"quality\">\n");
    for (id, reasons) in &suspect {
        let plot = if with_plots {
            format!("<a href=\"#plots-{0}\">plots/{0}_motion</a>", escape(id))
        } else {
            format!("plots/{}_motion (not drawn: --no-plots)", escape(id))
        };
        html.push_str(&format!("<dt id=\"quality-{0}\" data-test=\"{0}\">{0}: suspect</dt>\n", escape(id)));
        let mut kinds: Vec<_> = reasons.iter().map(|r| kind(r)).collect();
        kinds.sort();
        kinds.dedup();
        for k in kinds {
            let a = advice(k);
            let details: Vec<String> = reasons.iter().filter(|r| kind(r) == k).map(|r| escape(r)).collect();
            html.push_str(&format!(
                "<dd><strong>{}</strong><br><em>Look at</em> {plot}: {}<br><em>How far off:</em> {}<br><em>What to do:</em> {}<br><span class=\"detail\">The estimator: {}.</span></dd>\n",
                escape(a.title),
                escape(a.look),
                escape(a.how_far),
                escape(a.rerun),
                details.join("; ")
            ));
        }
    }
    for (id, e) in &failed {
        html.push_str(&format!(
            "<dt id=\"quality-{0}\" data-test=\"{0}\">{0}: not reduced</dt>\n<dd>{1}<br>Fix the log or the manifest at the place named and run reduce again.</dd>\n",
            escape(id),
            escape(&e.to_string())
        ));
    }
    html.push_str("</dl>\n");
    page.raw(&html);
}

/// The provenance section of the reduce report: the inputs with their checksums,
/// what reading and fitting each log noted, every warning, the tool, the manifest.
fn provenance(page: &mut Page, res: &CampaignResult, sources: &Sources) {
    page.h2("Provenance");
    page.provenance(&sources.files);
    let mut notes = Vec::new();
    for t in &res.tests {
        if let Ok(r) = &t.result {
            for n in &r.log.notes {
                notes.push(vec![t.spec.id.clone(), n.clone()]);
            }
            if let (Some(p), Some(rms)) = (r.analysis.p_fit, r.analysis.rms_mm) {
                notes.push(vec![
                    t.spec.id.clone(),
                    format!(
                        "fit: p_e = {p:.4} rad/s, λ = {}, RMS {rms:.4} mm, noise {:.4} mm, spikes removed {}",
                        r.analysis.lambda_fit.map_or("—".to_string(), |l| format!("{l:.2} s⁻²")),
                        r.analysis.noise_mm,
                        r.analysis.spikes_removed
                    ),
                ]);
                notes.push(vec![
                    t.spec.id.clone(),
                    match &r.analysis.acquisition_note {
                        Some(why) => format!("data logger's filter: {} ({why})", r.analysis.response.describe()),
                        None => format!("data logger's filter: {}", r.analysis.response.describe()),
                    },
                ]);
                if let Some(note) = &r.analysis.model_note {
                    notes.push(vec![t.spec.id.clone(), format!("fit: {note}")]);
                }
                let (pushes, landings): (Vec<usize>, Vec<usize>) = r.analysis.contact_model_peaks().into_iter().partition(|k| k % 2 == 1);
                let list = |ks: &[usize]| ks.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(", ");
                if !pushes.is_empty() {
                    notes.push(vec![
                        t.spec.id.clone(),
                        format!(
                            "peaks {}: read by the contact model of the push into the transverse walls, not the global fit (which reads them 1–5 % low on compliant walls; u the larger of the fit's and the two readings' difference)",
                            list(&pushes)
                        ),
                    ]);
                }
                if !landings.is_empty() {
                    notes.push(vec![
                        t.spec.id.clone(),
                        format!(
                            "{} {}: a late landing read by the contact model, not the global fit, whose residuals stand out there (its one contact shape, set by the fast first landings, runs the free arc on too long and reads it fast; u the larger of the fit's and the two readings' difference)",
                            if landings.len() == 1 { "peak" } else { "peaks" },
                            list(&landings)
                        ),
                    ]);
                }
            }
        }
    }
    page.table("meta", &["test", "reading and fit"], &notes);
    let warnings: Vec<Vec<String>> = res
        .tests
        .iter()
        .flat_map(|t| t.warnings.iter().map(move |w| vec![t.spec.id.clone(), w.clone()]))
        .collect();
    if warnings.is_empty() {
        page.p("No warnings were raised while reading.");
    } else {
        page.raw("<p class=\"warn\">Warnings raised while reading:</p>");
        page.table("meta", &["test", "warning"], &warnings);
    }
    page.p(&format!(
        "Tool: rocklab {}; method: {}.",
        env!("CARGO_PKG_VERSION"),
        res.options.method.describe()
    ));
    page.h3("Manifest");
    page.pre(&sources.manifest);
}
