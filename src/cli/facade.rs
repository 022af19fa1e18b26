//! `rocklab facade STUDY --out DIR [--scales FROM:TO:N]`.

use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use super::say;
use super::simulate::response_panels;
use rocklab::atomic::write_atomic;
use rocklab::facade::{
    fragility_by_set, parse_scales, run_ensembles, run_ida, run_ida_samples, run_study, EnsembleRow, IdaPoint, SampleRun, SetFragility, Study,
    StudyRun,
};
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
    #[command(flatten)]
    pub ensemble: EnsembleArgs,
}

/// Ensemble options shared by `facade` and `demo`.
#[derive(Args, Debug, Clone, Default)]
pub struct EnsembleArgs {
    /// Ensemble size per record × coefficient set × polarity (overrides [study].samples; 0: none).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the ensembles (overrides [study].seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Samples per record × polarity × set at each IDA scale (overrides [study].ida_samples).
    #[arg(long)]
    pub ida_samples: Option<usize>,
}

impl EnsembleArgs {
    pub fn apply(&self, study: &mut Study) {
        if let Some(n) = self.samples {
            study.samples = n;
        }
        if let Some(s) = self.seed {
            study.seed = s;
        }
        if let Some(n) = self.ida_samples {
            study.ida_samples = n.max(1);
        }
    }
}

use super::progress;

pub fn run(a: FacadeArgs) -> anyhow::Result<ExitCode> {
    let mut study = Study::load(&a.study)?;
    a.ensemble.apply(&mut study);
    let scales = a.scales.as_deref().map(parse_scales).transpose()?;
    std::fs::create_dir_all(&a.out)?;
    let report = run_all(&study, scales.as_deref(), &a.out)?;
    write_report(&study, &report, &a.out)?;
    say(&format!("wrote {}", a.out.display()));
    Ok(ExitCode::SUCCESS)
}

/// Figures for the HTML report: (caption, SVG).
pub type Figures = Vec<(String, String)>;

/// What the façade report shows: Markdown tables (with their HTML ids) and figures.
#[derive(Default)]
pub struct FacadeReport {
    pub tables: Vec<(String, String)>,
    pub figs: Figures,
    pub fragility_figs: Figures,
    pub ida_figs: Figures,
}

/// The whole study: the ensembles (when `samples` > 0), the nominal runs, the
/// IDA (with `scales`) and the fragility curves; writes every output but report.html.
pub fn run_all(study: &Study, scales: Option<&[f64]>, out: &Path) -> anyhow::Result<FacadeReport> {
    let mut rep = FacadeReport::default();
    let start = std::time::Instant::now();
    let (runs, figs, md) = study_outputs(study, out)?;
    rep.figs = figs;
    // The nominal study's document (shared with the Python binding), then the
    // ensemble and fragility sections; wall_s is the whole study's.
    let mut doc = rocklab::report::docs::facade_summary(study, &runs, 0.0);
    let mut ens_samples = Vec::new();
    if study.samples > 0 {
        let (table, rows, samples) = ensemble_outputs(study, &runs, out)?;
        rep.tables.push(("ensemble".into(), table));
        doc["ensemble"] = json!({
            "samples": study.samples,
            "seed": study.seed,
            "polarity": study.polarity_mode,
            "uncertainty": study.uncertainty,
            "rows": rows,
        });
        ens_samples = samples;
    }
    rep.tables.push(("results".into(), md));
    let frag = fragility_runs(study, scales, &ens_samples, out, &mut rep)?;
    if let Some((source, fits)) = frag {
        doc["fragility"] = json!({ "im": study.im, "source": source, "sets": fits });
    }
    rep.ida_figs = match scales {
        Some(sc) => ida_outputs(study, sc, out)?,
        None => Vec::new(),
    };
    doc["wall_s"] = json!(start.elapsed().as_secs_f64());
    write_atomic(&out.join("summary.json"), &serde_json::to_vec_pretty(&doc)?)?;
    let all_md = rep.tables.iter().map(|(_, m)| m.as_str()).collect::<Vec<_>>().join("\n");
    write_atomic(&out.join("results.md"), all_md.as_bytes())?;
    say(&all_md);
    Ok(rep)
}

/// The fragility fit: from an IDA over `scales` (with the study's IDA samples),
/// else from the scale-1 ensembles when there are two records or more.
fn fragility_runs(
    study: &Study,
    scales: Option<&[f64]>,
    ens_samples: &[SampleRun],
    out: &Path,
    rep: &mut FacadeReport,
) -> anyhow::Result<Option<(String, Vec<SetFragility>)>> {
    let (source, samples_owned);
    let samples: &[SampleRun] = if let Some(sc) = scales {
        let n = study.ida_samples;
        let pb = progress(
            sc.len() * study.records.len() * study.rows().len() * study.sets.len() * n,
            "fragility runs",
        );
        let start = std::time::Instant::now();
        samples_owned = run_ida_samples(study, sc, n, &|| pb.inc(1))?;
        pb.finish_and_clear();
        source = format!(
            "IDA over {} scale factors ({:.3}–{:.3} × the magnification), {} sample{} per record × polarity × set at each ({} runs, {:.2} s)",
            sc.len(),
            sc[0],
            sc[sc.len() - 1],
            n,
            if n == 1 { "" } else { "s" },
            samples_owned.len(),
            start.elapsed().as_secs_f64()
        );
        &samples_owned
    } else if !ens_samples.is_empty() && study.records.len() >= 2 {
        source = format!(
            "the ensembles at scale 1 ({} runs over {} records)",
            ens_samples.len(),
            study.records.len()
        );
        ens_samples
    } else {
        return Ok(None);
    };
    let fits = fragility_by_set(study, samples);
    let (md, figs) = fragility_outputs(study, &fits, &source, out)?;
    rep.tables.push(("fragility".into(), md));
    rep.fragility_figs = figs;
    Ok(Some((source, fits)))
}

/// The façade report.html: ensembles, results, fragility, responses, IDA plots,
/// provenance.
pub fn write_report(study: &Study, rep: &FacadeReport, out: &Path) -> anyhow::Result<()> {
    use rocklab::report::html::{file_facts, Page};
    let mut page = Page::new(&format!("{} — Housner against calibrated coefficients", study.name));
    page.p(&format!(
        "Block: {} (α = {} rad, R = {} m, I_0 = {:.4e} kg m², p² = {:.4} s⁻²). Ground motions ×{}; polarities {}; overturning at θ = {} rad; integration rtol {:e}. Housner's e_H by Eq. 2 with α = {}: {:.3}.",
        study.block.name, study.block.block.alpha, study.block.block.r_m, study.block.block.i0, study.block.block.p2(),
        study.magnification, study.polarities.iter().map(|p| format!("{:+}", *p as i8)).collect::<Vec<_>>().join(", "), study.overturn_limit, study.rtol, study.block.block.alpha, study.e_housner_eq2
    ));
    for (id, md) in &rep.tables {
        page.h2(match id.as_str() {
            "ensemble" => "Verdicts with their odds: P(overturn) over the uncertain inputs",
            "results" => "Nominal runs",
            "fragility" => "Fragility curves",
            _ => id,
        });
        page.raw(&md_table_to_html(md, id));
        if id == "fragility" {
            for (c, svg) in &rep.fragility_figs {
                page.figure(svg, c);
            }
        }
    }
    page.h2("Responses");
    for (c, svg) in &rep.figs {
        page.figure(svg, c);
    }
    if !rep.ida_figs.is_empty() {
        page.h2("Incremental dynamic analysis");
        for (c, svg) in &rep.ida_figs {
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

/// A Markdown table as HTML (first table of the text; the text after it is the caption).
fn md_table_to_html(md: &str, id: &str) -> String {
    use rocklab::report::html::escape;
    let mut s = format!("<table class=\"paper\" id=\"{id}\">");
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
            // Markdown's **bold** (the P(overturn) column) as <strong>, not as asterisks.
            let cell = match c.strip_prefix("**").and_then(|x| x.strip_suffix("**")) {
                Some(inner) => format!("<strong>{}</strong>", escape(inner)),
                None => escape(c),
            };
            // Cells stay on one line (ranges such as "98.1 %–100.0 %" and times
            // broke into three-line rows); the headers wrap.
            let style = if tag == "td" { " style=\"white-space: nowrap\"" } else { "" };
            s.push_str(&format!("<{tag}{style}>{cell}</{tag}>"));
        }
        s.push_str("</tr>\n");
    }
    s.push_str(&format!("<caption>{}</caption></table>\n", escape(&caption)));
    s
}

/// Run the nominal study at scale 1 and write results.csv and the plots; returns
/// the runs, the figures and the Markdown table.
pub fn study_outputs(study: &Study, out: &Path) -> anyhow::Result<(Vec<StudyRun>, Figures, String)> {
    let pb = progress(study.combinations().len(), "façade runs");
    let start = std::time::Instant::now();
    let runs = run_study(study, 1.0, true, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    say(&format!("{} nominal runs (each at 3 tolerances) in {wall:.2} s", runs.len()));
    let (csv, md) = results_table(study, &runs)?;
    write_atomic(&out.join("results.csv"), &csv)?;
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
    Ok((runs, figs, md))
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
        study.sets.iter().map(|s| format!("{} (e_in {}, e_out {}, {})", s.name, rocklab::ensemble::short(s.e_in), rocklab::ensemble::short(s.e_out), s.source)).collect::<Vec<_>>().join("; "),
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
    let pts = run_ida(study, scales, &|| pb.inc(1))?;
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

fn pct(p: f64) -> String {
    format!("{:.1} %", 100.0 * p)
}

/// The ensembles: ensemble.csv (one row per record × polarity × set), samples.csv
/// (every sample's inputs and outcome) and the Markdown table that leads the
/// results (P(overturn) first, the nominal run last as the numerical check).
fn ensemble_outputs(study: &Study, nominal: &[StudyRun], out: &Path) -> anyhow::Result<(String, Vec<EnsembleRow>, Vec<SampleRun>)> {
    let n = study.samples;
    let pb = progress(study.records.len() * study.rows().len() * study.sets.len() * n, "ensemble runs");
    let start = std::time::Instant::now();
    let (rows, samples) = run_ensembles(study, n, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    say(&format!(
        "{} ensemble runs in {wall:.2} s ({:.2} ms per run)",
        samples.len(),
        1e3 * wall / samples.len().max(1) as f64
    ));
    let nominal_of = |r: &EnsembleRow| -> String {
        let Some(p) = r.polarity else { return "—".into() };
        nominal
            .iter()
            .find(|x| x.record == r.record && x.coefficients == r.coefficients && x.polarity == p)
            .map(|x| {
                let mark = if x.well_conditioned { "" } else { " †" };
                match x.summary.overturn_time_s {
                    Some(t) => format!("overturns at {t:.2} s{mark}"),
                    None => format!("{:.3}{mark}", x.summary.max_theta_over_alpha),
                }
            })
            .unwrap_or_default()
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "record",
        "polarity",
        "coefficients",
        "samples",
        "overturned",
        "p_overturn",
        "p_overturn_ci95_lo",
        "p_overturn_ci95_hi",
        "verdict",
        "max_theta_over_alpha_median",
        "max_theta_over_alpha_p05",
        "max_theta_over_alpha_p95",
        "overturn_time_median_s",
        "nominal_run",
    ])?;
    let mut md = String::from(
        "| record | polarity | coefficients | P(overturn) | 95 % CI | verdict | max θ/α median | max θ/α 5–95 % | median overturning time (s) | nominal run |\n|---|---:|---|---:|---:|---|---:|---:|---:|---:|\n",
    );
    for r in &rows {
        let st = &r.stats;
        let pol = r.polarity.map_or("random".to_string(), |p| format!("{p:+}"));
        w.write_record([
            r.record.clone(),
            r.polarity.map_or("random".to_string(), |p| p.to_string()),
            r.coefficients.clone(),
            st.samples.to_string(),
            st.overturned.to_string(),
            st.p_overturn.to_string(),
            st.p_overturn_ci95[0].to_string(),
            st.p_overturn_ci95[1].to_string(),
            st.verdict.to_string(),
            st.max_theta_over_alpha_median.to_string(),
            st.max_theta_over_alpha_p05.to_string(),
            st.max_theta_over_alpha_p95.to_string(),
            st.overturn_time_median_s.map(|t| t.to_string()).unwrap_or_default(),
            nominal_of(r),
        ])?;
        md.push_str(&format!(
            "| {} | {} | {} | **{}** | {}–{} | {} | {:.3} | {:.3}–{:.3} | {} | {} |\n",
            r.record,
            pol,
            r.coefficients,
            pct(st.p_overturn),
            pct(st.p_overturn_ci95[0]),
            pct(st.p_overturn_ci95[1]),
            st.verdict,
            st.max_theta_over_alpha_median,
            st.max_theta_over_alpha_p05,
            st.max_theta_over_alpha_p95,
            st.overturn_time_median_s.map_or("—".to_string(), |t| format!("{t:.2}")),
            nominal_of(r)
        ));
    }
    let unc = study.uncertainty.describe();
    md.push_str(&format!(
        "\nP(overturn) over {n} samples per row (seed {}), with its 95 % Wilson interval; the verdict is robust only when P < 5 % (survives) or P > 95 % (overturns), else uncertain. Uncertain inputs: {}; coefficients: {}. An overturned sample counts with max θ/α = limit/α. Nominal run: the deterministic run at the nominal inputs († the outcome or peak changes at 100× tighter or looser tolerances).\n",
        study.seed,
        if unc.is_empty() {
            "none".to_string()
        } else {
            unc.iter().map(|(k, d)| format!("{k} {d}")).collect::<Vec<_>>().join(", ")
        },
        study
            .sets
            .iter()
            .map(|s| format!("{} {}", s.name, describe_set(s)))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    write_atomic(&out.join("ensemble.csv"), &w.into_inner()?)?;
    write_atomic(&out.join("samples.csv"), &samples_csv(&samples)?)?;
    Ok((md, rows, samples))
}

fn describe_set(s: &rocklab::facade::CoefficientSet) -> String {
    use rocklab::ensemble::CoefficientDist;
    match s.dist {
        CoefficientDist::Single(d) => format!("(e {}, {})", d.describe(), s.source),
        CoefficientDist::Pair { e_in, e_out } => format!("(e_in {}, e_out {}, {})", e_in.describe(), e_out.describe(), s.source),
    }
}

/// Every sample: where it sits, its drawn inputs and its outcome.
fn samples_csv(samples: &[SampleRun]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "record",
        "polarity_row",
        "coefficients",
        "scale",
        "sample",
        "im",
        "magnification",
        "polarity",
        "r_m",
        "alpha_rad",
        "i0_kg_m2",
        "unit_stiffness_mn_m2",
        "contact_height_m",
        "e_in",
        "e_out",
        "overturned",
        "overturn_time_s",
        "max_theta_over_alpha",
    ])?;
    for s in samples {
        let x = &s.inputs;
        w.write_record([
            s.record.clone(),
            s.row_polarity.map_or("random".into(), |p| p.to_string()),
            s.coefficients.clone(),
            s.scale.to_string(),
            s.sample.to_string(),
            s.im.to_string(),
            x.magnification.to_string(),
            x.polarity.to_string(),
            x.r_m.to_string(),
            x.alpha.to_string(),
            x.i0.to_string(),
            x.spring_bed.map(|b| b.0.to_string()).unwrap_or_default(),
            x.spring_bed.map(|b| b.1.to_string()).unwrap_or_default(),
            x.e_in.to_string(),
            x.e_out.to_string(),
            s.outcome.overturned.to_string(),
            s.outcome.overturn_time_s.map(|t| t.to_string()).unwrap_or_default(),
            s.outcome.max_theta_over_alpha.to_string(),
        ])?;
    }
    Ok(w.into_inner()?)
}

/// fragility.csv, fragility_observed.csv, the Markdown table and the plot
/// (fitted curves with the observed fractions per record × scale).
fn fragility_outputs(study: &Study, fits: &[SetFragility], source: &str, out: &Path) -> anyhow::Result<(String, Figures)> {
    let im = study.im.label();
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "coefficients",
        "median",
        "median_ci95_lo",
        "median_ci95_hi",
        "beta",
        "beta_ci95_lo",
        "beta_ci95_hi",
        "runs",
        "note",
    ])?;
    let mut md = format!("| coefficients | median {im} | 95 % CI | β | 95 % CI | runs |\n|---|---:|---:|---:|---:|---:|\n");
    for f in fits {
        let runs: usize = f.observed.iter().map(|t| t.n).sum();
        match &f.fit {
            Ok(x) => {
                w.write_record([
                    f.coefficients.clone(),
                    x.median.to_string(),
                    x.median_ci95[0].to_string(),
                    x.median_ci95[1].to_string(),
                    x.beta.to_string(),
                    x.beta_ci95[0].to_string(),
                    x.beta_ci95[1].to_string(),
                    x.runs.to_string(),
                    String::new(),
                ])?;
                md.push_str(&format!(
                    "| {} | {:.3} | {:.3}–{:.3} | {:.3} | {:.3}–{:.3} | {} |\n",
                    f.coefficients, x.median, x.median_ci95[0], x.median_ci95[1], x.beta, x.beta_ci95[0], x.beta_ci95[1], x.runs
                ));
            }
            Err(e) => {
                w.write_record([
                    f.coefficients.clone(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    runs.to_string(),
                    e.to_string(),
                ])?;
                md.push_str(&format!("| {} | no fit: {e} | | | | {runs} |\n", f.coefficients));
            }
        }
    }
    md.push_str(&format!(
        "\nLognormal fragility P(overturn | IM) = Φ(ln(IM/θ)/β) fitted by maximum likelihood (Baker 2015) to every run of {source}; IM = {im} of the scaled record each run felt. 95 % intervals from the observed information (Wald on ln θ and ln β); they treat the runs as independent, so with {} records they understate the record-to-record uncertainty.\n",
        study.records.len()
    ));
    write_atomic(&out.join("fragility.csv"), &w.into_inner()?)?;
    let mut o = csv::Writer::from_writer(Vec::new());
    o.write_record(["coefficients", "im", "runs", "overturned", "fraction"])?;
    for f in fits {
        for t in &f.observed {
            o.write_record([
                f.coefficients.clone(),
                t.im.to_string(),
                t.n.to_string(),
                t.k.to_string(),
                (t.k as f64 / t.n as f64).to_string(),
            ])?;
        }
    }
    write_atomic(&out.join("fragility_observed.csv"), &o.into_inner()?)?;
    let colors = [plots::RED, plots::BLUE, plots::GREEN, plots::ORANGE];
    let x_max = fits.iter().flat_map(|f| f.observed.iter().map(|t| t.im)).fold(0.0f64, f64::max) * 1.05;
    let mut series = Vec::new();
    for (i, f) in fits.iter().enumerate() {
        let color = colors[i % colors.len()];
        if let Ok(x) = &f.fit {
            let pts: Vec<(f64, f64)> = (1..=200).map(|k| x_max * k as f64 / 200.0).map(|v| (v, x.probability(v))).collect();
            series.push(Series {
                label: format!("{}: θ = {:.3}, β = {:.2}", f.coefficients, x.median, x.beta),
                color,
                points: pts,
                markers: false,
            });
            // The median's 95 % interval as a bar at P = ½ (out of the legend).
            series.push(Series {
                label: String::new(),
                color,
                points: vec![(x.median_ci95[0], 0.5), (x.median_ci95[1], 0.5)],
                markers: false,
            });
        }
        series.push(Series {
            label: format!("{} observed{}", f.coefficients, if f.fit.is_err() { " (no fit)" } else { "" }),
            color,
            points: f.observed.iter().map(|t| (t.im, t.k as f64 / t.n as f64)).collect(),
            markers: true,
        });
    }
    let panel = Panel {
        title: "Fragility: P(overturn) against the intensity of the scaled record".into(),
        x_label: im.into(),
        y_label: "P(overturn)".into(),
        series,
        hline: None,
        x_range: Some((0.0, x_max.max(1e-6))),
    };
    let svg = plots::render(&out.join("fragility"), &[panel], 900, 480)?;
    Ok((
        md,
        vec![(
            format!(
                "Lognormal fragility curves by maximum likelihood per coefficient set (lines; the bar at P = ½ is the median's 95 % interval) and the observed fraction of overturning runs per record × scale (dots), from {source}."
            ),
            svg,
        )],
    ))
}
