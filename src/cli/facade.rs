//! `rocklab facade STUDY --out DIR [--scales FROM:TO:N]`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

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

/// A progress bar on a terminal, hidden otherwise (indicatif draws to stderr only
/// when it is a terminal).
fn progress(n: usize, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(n as u64);
    pb.set_style(ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})").unwrap_or_else(|_| ProgressStyle::default_bar()));
    pb.set_message(what.to_string());
    pb
}

pub fn run(a: FacadeArgs) -> anyhow::Result<ExitCode> {
    let study = Study::load(&a.study)?;
    let scales = a.scales.as_deref().map(parse_scales).transpose()?;
    std::fs::create_dir_all(&a.out)?;
    study_outputs(&study, &a.out)?;
    if let Some(sc) = scales {
        ida_outputs(&study, &sc, &a.out)?;
    }
    say(&format!("wrote {}", a.out.display()));
    Ok(ExitCode::SUCCESS)
}

/// Run the study at scale 1 and write summary.json, results.{csv,md} and plots.
pub fn study_outputs(study: &Study, out: &Path) -> anyhow::Result<Vec<StudyRun>> {
    let pb = progress(study.combinations().len(), "façade runs");
    let start = std::time::Instant::now();
    let runs = run_study(study, 1.0, true, &|| pb.inc(1));
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let doc = json!({
        "study": study.name,
        "block": study.block.name,
        "alpha_rad": study.block.block.alpha,
        "magnification": study.magnification,
        "overturn_limit_rad": study.overturn_limit,
        "rtol": study.rtol,
        "e_housner_eq2": study.e_housner_eq2,
        "coefficient_sets": study.sets,
        "wall_s": wall,
        "runs": runs,
    });
    write_atomic(&out.join("summary.json"), &serde_json::to_vec_pretty(&doc)?)?;
    let (csv, md) = results_table(study, &runs)?;
    write_atomic(&out.join("results.csv"), &csv)?;
    write_atomic(&out.join("results.md"), md.as_bytes())?;
    say(&md);
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
            if panels.is_empty() {
                panels.push(ps.remove(0));
                panels.push(ps.remove(0));
                panels.swap(0, 1);
                panels.rotate_left(1);
            } else {
                panels.insert(panels.len() - 1, ps.remove(0));
            }
        }
        plots::render(&out.join(format!("response_{}", rec.name)), &panels, 1000, 300)?;
    }
    Ok(runs)
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
fn ida_outputs(study: &Study, scales: &[f64], out: &Path) -> anyhow::Result<()> {
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
        plots::render(&out.join(format!("ida_{}", set.name)), &[panel], 900, 450)?;
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
    plots::render(&out.join("ida_fraction"), &[panel], 900, 450)?;
    say(&format!(
        "IDA: {} runs ({} scales × {} combinations) in {:.2} s",
        pts.len(),
        scales.len(),
        study.combinations().len(),
        wall
    ));
    Ok(())
}
