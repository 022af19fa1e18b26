//! `rocklab facade STUDY --out DIR [--scales FROM:TO:N]`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use super::say;
use super::simulate::response_panels;
use rocklab::atomic::write_atomic;
use rocklab::facade::{parse_scales, run_ida, run_study, IdaPoint, Study, StudyRun};
use rocklab::report::plots::{self, Panel, Series};

#[derive(Args, Debug)]
pub struct FacadeArgs {
    /// Study file (TOML, see README).
    pub study: PathBuf,
    #[arg(long)]
    pub out: PathBuf,
    /// Incremental dynamic analysis over scale factors FROM:TO:N (×magnification).
    #[arg(long)]
    pub scales: Option<String>,
}

use super::progress;

pub fn run(a: FacadeArgs) -> anyhow::Result<ExitCode> {
    let study = Study::load(&a.study)?;
    let scales = a.scales.as_deref().map(parse_scales).transpose()?;
    std::fs::create_dir_all(&a.out)?;
    let (figs, md) = study_outputs(&study, &a.out)?;
    let ida_figs = match scales {
        Some(sc) => ida_outputs(&study, &sc, &a.out)?,
        None => Vec::new(),
    };
    write_report(&study, &md, &figs, &ida_figs, &a.out)?;
    say(&format!("wrote {}", a.out.display()));
    Ok(ExitCode::SUCCESS)
}

/// Figures for the HTML report: (caption, SVG).
pub type Figures = Vec<(String, String)>;

/// The façade report.html: results, response plots, IDA plots, provenance.
pub fn write_report(study: &Study, md: &str, figs: &[(String, String)], ida: &[(String, String)], out: &Path) -> anyhow::Result<()> {
    use rocklab::report::html::{file_facts, Page};
    let mut page = Page::new(&format!("{} — Housner against calibrated coefficients", study.name));
    page.p(&format!(
        "Block: {} (α = {} rad, R = {} m, I_0 = {:.4e} kg m², p² = {:.4} s⁻²). Ground motions ×{}; polarities {}; overturning at θ = {} rad; integration rtol {:e}. Housner's e_H by Eq. 2 with α = {}: {:.3}.",
        study.block.name, study.block.block.alpha, study.block.block.r_m, study.block.block.i0, study.block.block.p2(),
        study.magnification, study.polarities.iter().map(|p| format!("{:+}", *p as i8)).collect::<Vec<_>>().join(", "), study.overturn_limit, study.rtol, study.block.block.alpha, study.e_housner_eq2
    ));
    page.h2("Results");
    page.raw(&md_table_to_html(md));
    page.h2("Responses");
    for (c, svg) in figs {
        page.figure(svg, c);
    }
    if !ida.is_empty() {
        page.h2("Incremental dynamic analysis");
        for (c, svg) in ida {
            page.figure(svg, c);
        }
    }
    page.h2("Provenance");
    let mut files = Vec::new();
    for (what, p) in [
        ("study", study.path.clone()),
        ("block", study.path.parent().unwrap_or(Path::new(".")).join("block.toml")),
    ] {
        if p.is_file() {
            let (size, sha) = file_facts(&p);
            files.push(vec![what.to_string(), p.display().to_string(), size, sha]);
        }
    }
    for r in &study.records {
        let (size, sha) = file_facts(&r.record.path);
        files.push(vec![r.name.clone(), r.record.path.display().to_string(), size, sha]);
    }
    page.table("meta", &["input", "file", "size", "SHA-256"], &files);
    for r in &study.records {
        if !r.record.notes.is_empty() {
            page.p(&format!("{}: {}", r.name, r.record.notes.join("; ")));
        }
    }
    page.p(&format!("Tool: rocklab {}.", env!("CARGO_PKG_VERSION")));
    write_atomic(&out.join("report.html"), page.finish().as_bytes())?;
    Ok(())
}

/// The Markdown results table as HTML (first table of the text; the caption after it).
fn md_table_to_html(md: &str) -> String {
    use rocklab::report::html::escape;
    let mut s = String::from("<table class=\"paper\" id=\"results\">");
    let mut caption = String::new();
    for (i, line) in md.lines().enumerate() {
        if !line.starts_with('|') {
            if !line.trim().is_empty() {
                caption.push_str(line);
            }
            continue;
        }
        if i == 1 {
            continue;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(|c| c.trim()).collect();
        let tag = if i == 0 { "th" } else { "td" };
        s.push_str("<tr>");
        for c in cells {
            s.push_str(&format!("<{tag}>{}</{tag}>", escape(c)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str(&format!("<caption>{}</caption></table>\n", escape(&caption)));
    s
}

/// Run the study at scale 1 and write summary.json, results.{csv,md} and plots;
/// returns the figures and the Markdown table for the report.
pub fn study_outputs(study: &Study, out: &Path) -> anyhow::Result<(Figures, String)> {
    let pb = progress(study.combinations().len(), "façade runs");
    let start = std::time::Instant::now();
    let runs = run_study(study, 1.0, true, &|| pb.inc(1));
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let doc = rocklab::report::docs::facade_summary(study, &runs, wall);
    write_atomic(&out.join("summary.json"), &serde_json::to_vec_pretty(&doc)?)?;
    let (csv, md) = results_table(study, &runs)?;
    write_atomic(&out.join("results.csv"), &csv)?;
    write_atomic(&out.join("results.md"), md.as_bytes())?;
    say(&md);
    let mut figs = Figures::new();
    for rec in &study.records {
        let ag = rec
            .record
            .acc_m_s2
            .iter()
            .enumerate()
            .map(|(i, a)| (rec.record.t0 + i as f64 * rec.record.dt, a * study.magnification / rocklab::G))
            .collect::<Vec<_>>();
        let colors = [plots::RED, plots::BLUE, plots::GREEN, plots::ORANGE];
        let mut panels = Vec::new();
        for &p in &study.polarities {
            let these: Vec<&StudyRun> = runs.iter().filter(|r| r.record == rec.name && r.polarity as f64 == p).collect();
            let series: Vec<(&str, &[rocklab::solver::run::Sample], plots::RGBColor)> = these
                .iter()
                .enumerate()
                .map(|(i, r)| (r.coefficients.as_str(), r.history.as_slice(), colors[i % colors.len()]))
                .collect();
            let mut ps = response_panels(&format!("{} polarity {:+}", rec.name, p as i8), &series, study.block.block.alpha, &ag);
            // One θ/α panel per polarity, the ground acceleration once, last.
            if panels.is_empty() {
                panels.append(&mut ps);
            } else {
                panels.insert(panels.len() - 1, ps.remove(0));
            }
        }
        let svg = plots::render(&out.join(format!("response_{}", rec.name)), &panels, 1000, 300)?;
        figs.push((
            format!(
                "{}: θ/α under each coefficient set, per polarity, and the scaled ground acceleration (paper Fig. 8/9).",
                rec.name
            ),
            svg,
        ));
    }
    Ok((figs, md))
}

fn results_table(study: &Study, runs: &[StudyRun]) -> anyhow::Result<(Vec<u8>, String)> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head = vec!["record".to_string(), "polarity".into(), "pga_g".into(), "pgv_cm_s".into()];
    for s in &study.sets {
        for k in [
            "max_theta_over_alpha",
            "min_theta_over_alpha",
            "overturned",
            "overturn_time_s",
            "well_conditioned",
        ] {
            head.push(format!("{}_{k}", s.name));
        }
    }
    let ratio_name = (study.sets.len() >= 2).then(|| format!("ratio_{}_over_{}", study.sets[1].name, study.sets[0].name));
    if let Some(r) = &ratio_name {
        head.push(r.clone());
    }
    w.write_record(&head)?;
    let mut md = format!(
        "| record | polarity | PGA (g) | PGV (cm/s) | {} |{}\n|---|---:|---:|---:|{}{}\n",
        study.sets.iter().map(|s| format!("{} max θ/α", s.name)).collect::<Vec<_>>().join(" | "),
        if study.sets.len() >= 2 {
            format!(" {} / {} |", study.sets[1].name, study.sets[0].name)
        } else {
            String::new()
        },
        "---:|".repeat(study.sets.len()),
        if study.sets.len() >= 2 { "---:|" } else { "" }
    );
    for rec in &study.records {
        for &p in &study.polarities {
            let row: Vec<&StudyRun> = study
                .sets
                .iter()
                .filter_map(|s| {
                    runs.iter()
                        .find(|r| r.record == rec.name && r.polarity as f64 == p && r.coefficients == s.name)
                })
                .collect();
            let first = row[0];
            let mut rec_csv = vec![
                rec.name.clone(),
                format!("{}", p as i8),
                first.summary.pga_g.to_string(),
                first.summary.pgv_cm_s.to_string(),
            ];
            let mut cells = Vec::new();
            for r in &row {
                let s = &r.summary;
                rec_csv.extend([
                    s.max_theta_over_alpha.to_string(),
                    s.min_theta_over_alpha.to_string(),
                    s.overturned.to_string(),
                    s.overturn_time_s.map(|t| t.to_string()).unwrap_or_default(),
                    r.well_conditioned.to_string(),
                ]);
                let mark = if r.well_conditioned { "" } else { " †" };
                cells.push(match s.overturn_time_s {
                    Some(t) => format!("overturns at {t:.2} s{mark}"),
                    None => format!("{:.3}{mark}", s.max_theta_over_alpha),
                });
            }
            let ratio = (row.len() >= 2).then(|| row[1].summary.max_theta_over_alpha / row[0].summary.max_theta_over_alpha);
            if ratio_name.is_some() {
                rec_csv.push(ratio.map(|r| r.to_string()).unwrap_or_default());
            }
            w.write_record(&rec_csv)?;
            md.push_str(&format!(
                "| {} | {:+} | {:.3} | {:.2} | {} |{}\n",
                rec.name,
                p as i8,
                first.summary.pga_g,
                first.summary.pgv_cm_s,
                cells.join(" | "),
                match ratio {
                    Some(r) if row.iter().all(|x| !x.summary.overturned) => format!(" {:.0}% |", 100.0 * r),
                    Some(_) => " — |".into(),
                    None => String::new(),
                }
            ));
        }
    }
    md.push_str(&format!(
        "\nCoefficient sets: {}. Housner by Eq. 2 with α = {}: e_H = {:.3}. Ground motions ×{}. † the outcome or the peak changes when the integration tolerance is tightened or loosened 100× (a knife-edge result).\n",
        study.sets.iter().map(|s| format!("{} (e_in {}, e_out {}, {})", s.name, s.e_in, s.e_out, s.source)).collect::<Vec<_>>().join("; "),
        study.block.block.alpha,
        study.e_housner_eq2,
        study.magnification
    ));
    Ok((w.into_inner()?, md))
}

/// IDA: per point CSV, fraction overturning per scale and set, plots.
fn ida_outputs(study: &Study, scales: &[f64], out: &Path) -> anyhow::Result<Figures> {
    let mut figs = Figures::new();
    let n = scales.len() * study.combinations().len();
    let pb = progress(n, "IDA runs");
    let start = std::time::Instant::now();
    let pts = run_ida(study, scales, &|| pb.inc(1));
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let mut w = csv::Writer::from_writer(Vec::new());
    for p in &pts {
        w.serialize(p)?;
    }
    write_atomic(&out.join("ida.csv"), &w.into_inner()?)?;
    let mut f = csv::Writer::from_writer(Vec::new());
    f.write_record(["coefficients", "scale", "fraction_overturned", "runs"])?;
    let mut frac_series = Vec::new();
    let colors = [plots::RED, plots::BLUE, plots::GREEN, plots::ORANGE];
    for (si, set) in study.sets.iter().enumerate() {
        let mut pts_f = Vec::new();
        for &sc in scales {
            let here: Vec<&IdaPoint> = pts.iter().filter(|p| p.coefficients == set.name && p.scale == sc).collect();
            let frac = here.iter().filter(|p| p.overturned).count() as f64 / here.len().max(1) as f64;
            f.write_record([set.name.clone(), sc.to_string(), frac.to_string(), here.len().to_string()])?;
            pts_f.push((sc * study.magnification, frac));
        }
        frac_series.push(Series {
            label: set.name.clone(),
            color: colors[si % colors.len()],
            points: pts_f,
            markers: false,
        });
        let mut series = Vec::new();
        for (ri, rec) in study.records.iter().enumerate() {
            for &p in &study.polarities {
                let line: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|x| x.coefficients == set.name && x.record == rec.name && x.polarity as f64 == p)
                    .map(|x| (x.scale * study.magnification, x.max_theta_over_alpha.min(1.0)))
                    .collect();
                series.push(Series {
                    label: format!("{} {:+}", rec.name, p as i8),
                    color: colors[ri % colors.len()],
                    points: line,
                    markers: p < 0.0,
                });
            }
        }
        let panel = Panel {
            title: format!("IDA, {}: max θ/α against scale (1 = overturned)", set.name),
            x_label: "scale factor (× record, magnification included)".into(),
            y_label: "max θ/α".into(),
            series,
            hline: None,
            x_range: None,
        };
        let svg = plots::render(&out.join(format!("ida_{}", set.name)), &[panel], 900, 450)?;
        figs.push((
            format!(
                "IDA with the {} coefficients: max θ/α against the scale factor per record and polarity.",
                set.name
            ),
            svg,
        ));
    }
    write_atomic(&out.join("ida_fraction.csv"), &f.into_inner()?)?;
    let panel = Panel {
        title: "Fraction of records × polarities that overturn".into(),
        x_label: "scale factor (× record, magnification included)".into(),
        y_label: "fraction overturned".into(),
        series: frac_series,
        hline: None,
        x_range: None,
    };
    let svg = plots::render(&out.join("ida_fraction"), &[panel], 900, 450)?;
    figs.push(("Fraction of the records × polarities that overturn at each scale.".to_string(), svg));
    say(&format!(
        "IDA: {} runs ({} scales × {} combinations) in {:.2} s",
        pts.len(),
        scales.len(),
        study.combinations().len(),
        wall
    ));
    Ok(figs)
}
