//! The outputs of `rocklab facade`: summary.json, the tables (ensembles with
//! P(overturn), nominal runs, fragility) in Markdown, HTML and the data CSVs, the
//! response, fragility and IDA plots, and report.html with its provenance.

use super::docs::{facade_summary, EnsembleDoc, FragilityDoc};
use super::plots::{self, Captioned, Panel, Series};
use super::table::{to_html, to_markdown, Align, Cell, Column, Table};
use super::{csv_bytes, Files, InputFile, ReportError};
use crate::facade::{CoefficientSet, EnsembleRow, IdaPoint, SampleRun, SetFragility, Study, StudyRun};
use crate::outcomes::{find_run, ida_curve, ida_fractions, polarity_key};
use crate::restitution_law::LawReading;

type Result<T> = std::result::Result<T, ReportError>;

/// The x axis of the IDA plots.
const SCALE_AXIS: &str = "scale factor (× record, magnification included)";

const COLORS: [plots::RGBColor; 9] = plots::SETS;

/// What the study's core step computed.
#[derive(Debug, Default)]
pub struct FacadeResults {
    /// The nominal runs at scale 1 (with their histories).
    pub runs: Vec<StudyRun>,
    /// The ensembles' rows and every sample.
    pub ensemble: Option<(Vec<EnsembleRow>, Vec<SampleRun>)>,
    /// The fragility fits and where their runs came from ([`ida_source`], [`ensemble_source`]).
    pub fragility: Option<(String, Vec<SetFragility>)>,
    /// The IDA's scales and points.
    pub ida: Option<(Vec<f64>, Vec<IdaPoint>)>,
    pub wall_s: f64,
    /// How long the fragility's own runs (an IDA) took; summary.json's `timing`.
    pub fragility_wall_s: Option<f64>,
}

/// The fragility's source when it comes from an IDA over `scales` with `n`
/// samples per point (`runs` runs). No time in it: summary.json keeps times under
/// `timing`, so that two runs with the same seed give the same document.
pub fn ida_source(scales: &[f64], n: usize, runs: usize) -> String {
    format!(
        "IDA over {} scale factors ({:.3}–{:.3} × the magnification), {} sample{} per record × polarity × set at each ({} runs)",
        scales.len(),
        scales.first().copied().unwrap_or(f64::NAN),
        scales.last().copied().unwrap_or(f64::NAN),
        n,
        if n == 1 { "" } else { "s" },
        runs
    )
}

/// The fragility's source when it comes from the ensembles at scale 1.
pub fn ensemble_source(runs: usize, records: usize) -> String {
    format!("the ensembles at scale 1 ({runs} runs over {records} records)")
}

/// Every file of the study, and the Markdown of its tables (results.md, also
/// printed on the terminal).
pub fn facade_files(study: &Study, res: &FacadeResults, inputs: &[InputFile]) -> Result<(Files, String)> {
    let mut files = Files::default();
    for f in inputs.iter().map(|i| &i.path).chain(&study.coefficient_files) {
        files.input(f);
    }
    let mut tables = Vec::new();
    if let Some((rows, samples)) = &res.ensemble {
        tables.push(ensemble_table(study, rows, &res.runs));
        files.add("ensemble.csv", ensemble_csv(rows, &res.runs)?);
        files.add("samples.csv", samples_csv(samples)?);
    }
    tables.push(results_table(study, &res.runs));
    files.add("results.csv", results_csv(study, &res.runs)?);
    if let Some(t) = law_reach_table(study, &res.runs, res.ensemble.as_ref().map(|(rows, _)| &rows[..])) {
        tables.push(t);
    }
    let mut figs = Figs::default();
    if let Some((source, fits)) = &res.fragility {
        tables.push(fragility_table(study, fits, source));
        files.add("fragility.csv", fragility_csv(fits)?);
        files.add("fragility_observed.csv", observed_csv(fits)?);
        figs.fragility.push(fragility_figure(study, fits, source)?);
    }
    figs.responses = response_figures(study, &res.runs)?;
    if let Some((scales, pts)) = &res.ida {
        figs.ida = ida_figures(study, scales, pts, &mut files)?;
    }
    for f in figs.fragility.iter().chain(&figs.responses).chain(&figs.ida) {
        f.figure.add_to(&mut files, &f.stem);
    }
    let ensemble = res.ensemble.as_ref().map(|(rows, _)| EnsembleDoc {
        samples: study.samples,
        seed: study.seed,
        polarity: study.polarity_mode,
        uncertainty: &study.uncertainty,
        rows,
    });
    let fragility = res.fragility.as_ref().map(|(source, sets)| FragilityDoc {
        im: study.im,
        source,
        sets,
        wall_s: res.fragility_wall_s,
    });
    let doc = facade_summary(study, &res.runs, res.wall_s, ensemble, fragility)?;
    files.add("summary.json", serde_json::to_vec_pretty(&doc)?);
    let md = tables.iter().map(to_markdown).collect::<Vec<_>>().join("\n");
    files.add("results.md", md.as_bytes());
    files.add("report.html", facade_page(study, &tables, &figs, inputs));
    Ok((files, md))
}

/// The figures of the façade report, by section.
#[derive(Default)]
struct Figs {
    fragility: Vec<Captioned>,
    responses: Vec<Captioned>,
    ida: Vec<Captioned>,
}

/// "+1" or "-1".
fn signed(p: i8) -> String {
    format!("{p:+}")
}

/// The façade report.html: ensembles, results, fragility, responses, IDA plots,
/// provenance.
fn facade_page(study: &Study, tables: &[Table], figs: &Figs, inputs: &[InputFile]) -> String {
    let b = &study.block.block;
    let mut page = super::html::Page::new(&format!("{} — Housner against calibrated coefficients", study.name));
    // The ensembles' table has ten columns whose cells stay on one line.
    page.widen();
    page.p(&format!(
        "Block: {} (α = {} rad, R = {} m, I_0 = {:.4e} kg m², p² = {:.4} s⁻²). Ground motions ×{}; polarities {}; overturning at θ = {} rad; integration rtol {:e}. Housner's e_H by Eq. 2 with α = {}: {:.3}.",
        study.block.name, b.alpha, b.r_m, b.i0, b.p2(), study.magnification,
        study.polarities.iter().map(|p| signed(polarity_key(*p))).collect::<Vec<_>>().join(", "),
        study.overturn_limit, study.rtol, b.alpha, study.e_housner_eq2
    ));
    for t in tables {
        page.h2(match t.name.as_str() {
            "ensemble" => "Verdicts with their odds: P(overturn) over the uncertain inputs",
            "results" => "Nominal runs",
            "fragility" => "Fragility curves",
            "law_reach" => "Where the laws reach beyond their data",
            other => other,
        });
        page.raw(&to_html(t));
        if t.name == "fragility" {
            figs.fragility.iter().for_each(|f| page.figure(&f.figure.svg, &f.caption));
        }
    }
    page.h2("Responses");
    figs.responses.iter().for_each(|f| page.figure(&f.figure.svg, &f.caption));
    if !figs.ida.is_empty() {
        page.h2("Incremental dynamic analysis");
        figs.ida.iter().for_each(|f| page.figure(&f.figure.svg, &f.caption));
    }
    page.h2("Provenance");
    page.provenance(inputs);
    for r in study.records.iter().filter(|r| !r.record.notes.is_empty()) {
        page.p(&format!("{}: {}", r.name, r.record.notes.join("; ")));
    }
    page.p(&format!("Tool: rocklab {}.", env!("CARGO_PKG_VERSION")));
    page.finish()
}

/// What a nominal run shows in a table: its peak θ/α, or when it overturned; a
/// dagger when the outcome depends on the integration tolerance.
fn outcome_text(r: &StudyRun) -> String {
    let mark = if r.well_conditioned { "" } else { " †" };
    match r.summary.overturn_time_s {
        Some(t) => format!("overturns at {t:.2} s{mark}"),
        None => format!("{:.3}{mark}", r.summary.max_theta_over_alpha),
    }
}

/// The runs of one record and polarity, one per coefficient set (in the study's order).
fn row_runs<'a>(study: &Study, runs: &'a [StudyRun], record: &str, polarity: i8) -> Vec<&'a StudyRun> {
    study.sets.iter().filter_map(|s| find_run(runs, record, &s.name, polarity)).collect()
}

/// The nominal runs: per record and polarity, PGA, PGV, each set's peak θ/α or
/// overturning time, and the ratio of the second set's peak to the first's.
pub fn results_table(study: &Study, runs: &[StudyRun]) -> Table {
    let r = |k: &str, l: &str| Column::new(k, l, Align::Right);
    let mut columns = vec![
        Column::new("record", "record", Align::Left),
        r("polarity", "polarity"),
        r("pga_g", "PGA (g)"),
        r("pgv_cm_s", "PGV (cm/s)"),
    ];
    columns.extend(study.sets.iter().map(|s| r(&s.name, &format!("{} max θ/α", s.name))));
    let two = study.sets.len() >= 2;
    if two {
        columns.push(r("ratio", &format!("{} / {}", study.sets[1].name, study.sets[0].name)));
    }
    let sets: Vec<String> = study
        .sets
        .iter()
        .map(|s| {
            let law = match s.law_at(study.block.block.alpha) {
                Some((law, e_h)) => {
                    let range = law_range(&law, e_h, s.law_reading(), study.block.push_speed_ratio());
                    format!(", the law's e at a = 1{}{range}", if range.is_empty() { "" } else { "; " })
                }
                None => String::new(),
            };
            format!(
                "{} (e_in {}, e_out {}{law}, {})",
                s.name,
                crate::ensemble::short(s.e_in),
                crate::ensemble::short(s.e_out),
                s.source
            )
        })
        .collect();
    let caption = format!(
        "Coefficient sets: {}. Housner by Eq. 2 with α = {}: e_H = {:.3}. Ground motions ×{}. † the outcome or the peak changes when the integration tolerance is tightened or loosened 100× (a knife-edge result).",
        sets.join("; "), study.block.block.alpha, study.e_housner_eq2, study.magnification
    );
    let mut t = Table::new("results", caption, columns);
    t.nowrap = true;
    for rec in &study.records {
        for p in study.polarities.iter().map(|p| polarity_key(*p)) {
            let row = row_runs(study, runs, &rec.name, p);
            let Some(first) = row.first() else { continue };
            let s = &first.summary;
            let mut cells = vec![
                Cell::text(&rec.name),
                Cell::text(signed(p)),
                Cell::num(s.pga_g, format!("{:.3}", s.pga_g)),
                Cell::num(s.pgv_cm_s, format!("{:.2}", s.pgv_cm_s)),
            ];
            cells.extend(row.iter().map(|r| Cell::text(outcome_text(r))));
            if two {
                let ratio = (row.len() >= 2).then(|| row[1].summary.max_theta_over_alpha / row[0].summary.max_theta_over_alpha);
                cells.push(match ratio {
                    // The ratio of the first two sets' peaks, where neither overturned
                    // (a set further along the row has no say in it).
                    Some(x) if row[..2].iter().all(|r| !r.summary.overturned) => Cell::num(x, format!("{:.0}%", 100.0 * x)),
                    _ => Cell::text("—"),
                });
            }
            t.push(Some(format!("{}{}", rec.name, signed(p))), cells);
        }
    }
    t
}

/// Per law set and side, where the impacts of its runs fell: those of its
/// ensembles' samples where the study ran ensembles (where its odds come
/// from), else those of its nominal runs (every record and polarity): the
/// amplitudes the campaign observed on the side and those the runs read the
/// law at, the impacts, how many below and above the observed ones with their
/// share of the energy, how many at the cap e = 1, and the mean e. None when
/// no set is a law.
pub fn law_reach_table(study: &Study, runs: &[StudyRun], ensemble: Option<&[EnsembleRow]>) -> Option<Table> {
    use crate::facade::LawReach;
    use crate::wall::Side;
    let alpha = study.block.block.alpha;
    let laws: Vec<_> = study.sets.iter().filter_map(|s| s.law_at(alpha).map(|(law, _)| (s, law))).collect();
    if laws.is_empty() {
        return None;
    }
    let r = |k: &str, l: &str| Column::new(k, l, Align::Right);
    let columns = vec![
        Column::new("coefficients", "coefficients", Align::Left),
        Column::new("side", "impacts entering", Align::Left),
        r("observed", "campaign's a"),
        r("read", "runs' a"),
        r("impacts", "impacts"),
        r("below", "below the data (energy)"),
        r("above", "above the data (energy)"),
        r("elastic", "at e = 1"),
        r("mean_e", "mean e"),
    ];
    let from_samples = ensemble.is_some_and(|rows| rows.iter().any(|r| r.law_reach.is_some()));
    let whose = if from_samples {
        "in its ensembles' samples (every record and polarity row, each sample with its drawn inputs)"
    } else {
        "in its nominal runs (every record and polarity)"
    };
    let caption = format!("Where each law set's impacts fell {whose}, by the side they enter:") + " the amplitudes a = |θ|/α of the campaign's impacts the law was fitted on, those of the runs' impacts, and how many of these ended a half-cycle smaller or larger than any the campaign observed on that side (there the law's coefficient comes from its form, extrapolated or held, not from a measured impact), with in brackets their share of the kinetic energy the side's impacts met (Σ θ'² before impact: most impacts of a run that comes to rest are tiny and carry almost none), or were capped at e = 1 (an elastic impact), and the mean e the side's impacts applied, weighted by that energy. A verdict whose impacts lie beyond the data rests on the law's form there, not on the campaign.";
    // A set read by the impact's speed reads its law at the amplitude of the
    // campaign's impacts of that speed, not at the run's apex: say so.
    let by_speed: Vec<&str> = study
        .sets
        .iter()
        .filter(|s| s.law_reading() == LawReading::Speed)
        .map(|s| s.name.as_str())
        .collect();
    let caption = if by_speed.is_empty() {
        caption
    } else {
        caption
            + &format!(
                " For {} (read by the impact's speed), a is the amplitude each impact read the law at: that of the campaign's impacts of its speed, not the run's apex.",
                by_speed.join(", ")
            )
    };
    let mut t = Table::new("law_reach", caption, columns);
    t.nowrap = true;
    // n of `of` impacts, with a share in brackets (of the impacts or of the energy).
    let counted = |n: usize, of: usize, share: f64| {
        let text = if of == 0 {
            "—".to_string()
        } else {
            format!("{n} ({:.0} %)", 100.0 * share)
        };
        Cell::num(n as f64, text)
    };
    let ratio = |x: f64, total: f64| x / total.max(f64::MIN_POSITIVE);
    let a = |x: f64| match x {
        0.0 => "0".to_string(),
        x if x >= 0.01 => format!("{x:.3}"),
        x => format!("{x:.2e}"),
    };
    // Each run's set and reach: the samples' where the study ran ensembles.
    let reaches: Vec<(&str, &LawReach)> = match ensemble.filter(|_| from_samples) {
        Some(rows) => rows
            .iter()
            .filter_map(|r| Some((r.coefficients.as_str(), r.law_reach.as_ref()?)))
            .collect(),
        None => runs
            .iter()
            .filter_map(|r| Some((r.coefficients.as_str(), r.law_reach.as_ref()?)))
            .collect(),
    };
    for (set, law) in laws {
        let mut reach = LawReach::default();
        reaches.iter().filter(|(name, _)| *name == set.name).for_each(|(_, x)| reach.add(x));
        for (side, name, x) in [(Side::Inward, "inward", &reach.inward), (Side::Outward, "outward", &reach.outward)] {
            let (lo, hi) = law.observed(side);
            let read = if x.impacts == 0 {
                "—".to_string()
            } else {
                format!("{}–{}", a(x.smallest_amplitude), a(x.largest_amplitude))
            };
            t.push(
                Some(format!("{} {name}", set.name)),
                vec![
                    Cell::text(&set.name),
                    Cell::text(name),
                    Cell::text(format!("{}–{}", a(lo), a(hi))),
                    Cell::text(read),
                    Cell::num(x.impacts as f64, x.impacts.to_string()),
                    counted(x.below_observed, x.impacts, ratio(x.energy_below, x.energy)),
                    counted(x.above_observed, x.impacts, ratio(x.energy_above, x.energy)),
                    counted(x.elastic, x.impacts, ratio(x.elastic as f64, x.impacts as f64)),
                    match x.mean_e() {
                        Some(e) => Cell::num(e, format!("{e:.3}")),
                        None => Cell::text("—"),
                    },
                ],
            );
        }
    }
    Some(t)
}

/// results.csv: per record and polarity, every set's outcome at full precision.
fn results_csv(study: &Study, runs: &[StudyRun]) -> Result<Vec<u8>> {
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
    let two = study.sets.len() >= 2;
    if two {
        head.push(format!("ratio_{}_over_{}", study.sets[1].name, study.sets[0].name));
    }
    w.write_record(&head)?;
    for rec in &study.records {
        for p in study.polarities.iter().map(|p| polarity_key(*p)) {
            let row = row_runs(study, runs, &rec.name, p);
            let Some(first) = row.first() else { continue };
            let mut fields = vec![
                rec.name.clone(),
                p.to_string(),
                first.summary.pga_g.to_string(),
                first.summary.pgv_cm_s.to_string(),
            ];
            for r in &row {
                let s = &r.summary;
                fields.extend([
                    s.max_theta_over_alpha.to_string(),
                    s.min_theta_over_alpha.to_string(),
                    s.overturned.to_string(),
                    s.overturn_time_s.map(|t| t.to_string()).unwrap_or_default(),
                    r.well_conditioned.to_string(),
                ]);
            }
            if two {
                let ratio = (row.len() >= 2).then(|| row[1].summary.max_theta_over_alpha / row[0].summary.max_theta_over_alpha);
                fields.push(ratio.map(|r| r.to_string()).unwrap_or_default());
            }
            w.write_record(&fields)?;
        }
    }
    csv_bytes(w)
}

/// The θ/α responses per record: one panel per polarity with every set, then the
/// scaled ground acceleration (paper Fig. 8/9).
fn response_figures(study: &Study, runs: &[StudyRun]) -> Result<Vec<Captioned>> {
    let mut figs = Vec::new();
    for rec in &study.records {
        let r = &rec.record;
        let ag: Vec<(f64, f64)> = r
            .acc_m_s2
            .iter()
            .enumerate()
            .map(|(i, a)| (r.t0 + i as f64 * r.dt, a * study.magnification / crate::G))
            .collect();
        let mut panels = Vec::new();
        for p in study.polarities.iter().map(|p| polarity_key(*p)) {
            let these = row_runs(study, runs, &rec.name, p);
            let series: Vec<super::response::Run> = these
                .iter()
                .enumerate()
                .map(|(i, r)| (r.coefficients.as_str(), r.history.as_slice(), COLORS[i % COLORS.len()]))
                .collect();
            let mut ps = super::response::response_panels(&format!("{} polarity {}", rec.name, signed(p)), &series, study.block.block.alpha, &ag);
            // One θ/α panel per polarity, the ground acceleration once, last.
            if panels.is_empty() {
                panels.append(&mut ps);
            } else {
                panels.insert(panels.len() - 1, ps.remove(0));
            }
        }
        figs.push(Captioned {
            stem: format!("response_{}", super::file_stem(&rec.name)),
            caption: format!(
                "{}: θ/α under each coefficient set, per polarity, and the scaled ground acceleration (paper Fig. 8/9).",
                rec.name
            ),
            figure: plots::render(&panels, 1000, 300)?,
        });
    }
    Ok(figs)
}

/// ida.csv, ida_fraction.csv and the plots: per set, max θ/α against the scale
/// per record and polarity; the fraction overturning per set.
fn ida_figures(study: &Study, scales: &[f64], pts: &[IdaPoint], files: &mut Files) -> Result<Vec<Captioned>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for p in pts {
        w.serialize(p)?;
    }
    files.add("ida.csv", csv_bytes(w)?);
    let names: Vec<&str> = study.sets.iter().map(|s| s.name.as_str()).collect();
    let fractions = ida_fractions(pts, &names, scales);
    let mut f = csv::Writer::from_writer(Vec::new());
    f.write_record(["coefficients", "scale", "fraction_overturned", "runs"])?;
    for x in &fractions {
        f.write_record([
            x.coefficients.clone(),
            x.scale.to_string(),
            x.fraction_overturned.to_string(),
            x.runs.to_string(),
        ])?;
    }
    files.add("ida_fraction.csv", csv_bytes(f)?);
    let m = study.magnification;
    let mut figs = Vec::new();
    let mut frac_series = Vec::new();
    for (si, set) in study.sets.iter().enumerate() {
        let points = fractions
            .iter()
            .filter(|x| x.coefficients == set.name)
            .map(|x| (x.scale * m, x.fraction_overturned))
            .collect();
        frac_series.push(Series::line(&set.name, COLORS[si % COLORS.len()], points));
        figs.push(ida_set_figure(study, set, pts)?);
    }
    let panel = Panel::new(
        "Fraction of records × polarities that overturn",
        SCALE_AXIS,
        "fraction overturned",
        frac_series,
    );
    figs.push(Captioned {
        stem: "ida_fraction".into(),
        caption: "Fraction of the records × polarities that overturn at each scale.".into(),
        figure: plots::render(&[panel], 900, 450)?,
    });
    Ok(figs)
}

/// One set's IDA: max θ/α against the scale per record (colour) and polarity
/// (line +, markers −).
fn ida_set_figure(study: &Study, set: &CoefficientSet, pts: &[IdaPoint]) -> Result<Captioned> {
    let mut series = Vec::new();
    for (ri, rec) in study.records.iter().enumerate() {
        for p in study.polarities.iter().map(|p| polarity_key(*p)) {
            let points = ida_curve(pts, &set.name, &rec.name, p)
                .into_iter()
                .map(|(s, y)| (s * study.magnification, y))
                .collect();
            let (label, color) = (format!("{} {}", rec.name, signed(p)), COLORS[ri % COLORS.len()]);
            series.push(if p < 0 {
                Series::dots(&label, color, points)
            } else {
                Series::line(&label, color, points)
            });
        }
    }
    let panel = Panel::new(
        format!("IDA, {}: max θ/α against scale (1 = overturned)", set.name),
        SCALE_AXIS,
        "max θ/α",
        series,
    );
    Ok(Captioned {
        stem: format!("ida_{}", super::file_stem(&set.name)),
        caption: format!(
            "IDA with the {} coefficients: max θ/α against the scale factor per record and polarity.",
            set.name
        ),
        figure: plots::render(&[panel], 900, 450)?,
    })
}

fn pct(p: f64) -> String {
    format!("{:.1} %", 100.0 * p)
}

/// The nominal run beside an ensemble row ("—" for a random-polarity row).
fn nominal_of(r: &EnsembleRow, nominal: &[StudyRun]) -> String {
    let Some(p) = r.polarity else { return "—".into() };
    find_run(nominal, &r.record, &r.coefficients, p).map(outcome_text).unwrap_or_default()
}

/// The share of one side's impact energy met beyond a law's data (summed over
/// an ensemble row's samples) above which the ensembles' table marks a law
/// set's verdict (‡): most of it.
pub const BEYOND_THE_DATA: f64 = 0.5;

/// The ensembles' table: P(overturn) first with its interval and verdict, the
/// nominal run last as the numerical check.
fn ensemble_table(study: &Study, rows: &[EnsembleRow], nominal: &[StudyRun]) -> Table {
    let (l, r) = (
        |k: &str, x: &str| Column::new(k, x, Align::Left),
        |k: &str, x: &str| Column::new(k, x, Align::Right),
    );
    let columns = vec![
        l("record", "record"),
        r("polarity", "polarity"),
        l("coefficients", "coefficients"),
        r("p_overturn", "P(overturn)"),
        r("p_overturn_ci95", "95 % CI"),
        l("verdict", "verdict"),
        r("max_theta_over_alpha_median", "max θ/α median"),
        r("max_theta_over_alpha_p05_p95", "max θ/α 5–95 %"),
        r("overturn_time_median_s", "median overturning time (s)"),
        r("nominal_run", "nominal run"),
    ];
    let mut caption = ensemble_caption(study);
    let beyond = |row: &EnsembleRow| row.law_reach.is_some_and(|x| x.beyond_share() > BEYOND_THE_DATA);
    if rows.iter().any(beyond) {
        caption.push_str(&format!(
            " ‡ a law set whose samples met, together, more than {:.0} % of one side's impact energy at amplitudes the campaign did not observe on that side (\"Where the laws reach beyond their data\"): its odds rest on the law's form there, not on measured impacts.",
            100.0 * BEYOND_THE_DATA
        ));
    }
    let mut t = Table::new("ensemble", caption, columns);
    t.nowrap = true;
    for row in rows {
        let st = &row.stats;
        let mark = if beyond(row) { " ‡" } else { "" };
        let pol = row.polarity.map_or("random".to_string(), signed);
        t.push(
            Some(format!("{}{}/{}", row.record, pol, row.coefficients)),
            vec![
                Cell::text(&row.record),
                Cell::text(&pol),
                Cell::text(&row.coefficients),
                Cell::num(st.p_overturn, pct(st.p_overturn)).strong(),
                Cell::text(format!("{}–{}", pct(st.p_overturn_ci95[0]), pct(st.p_overturn_ci95[1]))),
                Cell::text(format!("{}{mark}", st.verdict)),
                Cell::num(st.max_theta_over_alpha_median, format!("{:.3}", st.max_theta_over_alpha_median)),
                Cell::text(format!("{:.3}–{:.3}", st.max_theta_over_alpha_p05, st.max_theta_over_alpha_p95)),
                Cell::text(st.overturn_time_median_s.map_or("—".to_string(), |t| format!("{t:.2}"))),
                Cell::text(nominal_of(row, nominal)),
            ],
        );
    }
    t
}

fn ensemble_caption(study: &Study) -> String {
    let unc = study.uncertainty.describe();
    let inputs = if unc.is_empty() {
        "none".to_string()
    } else {
        unc.iter().map(|(k, d)| format!("{k} {d}")).collect::<Vec<_>>().join(", ")
    };
    let sets = study
        .sets
        .iter()
        .map(|s| format!("{} {}", s.name, describe_set(s, &study.block)))
        .collect::<Vec<_>>()
        .join("; ");
    format!(
        "P(overturn) over {} samples per row (seed {}), with its 95 % Wilson interval; the verdict is robust only when P < 5 % (survives) or P > 95 % (overturns), else uncertain. Uncertain inputs: {inputs}; coefficients: {sets}. An overturned sample counts with max θ/α = limit/α. Nominal run: the deterministic run at the nominal inputs († the outcome or peak changes at 100× tighter or looser tolerances).",
        study.samples, study.seed
    )
}

/// Where a law set's coefficients sit at the cap: per side, the amplitude from which
/// the solver's e = min(1, r(a) e_H) is 1 (a perfectly elastic impact), beside the
/// amplitudes of the campaign's impacts (a speed-loss law; a constant has none).
///
/// Where the law's outward side ends pushes and carries the campaign's Ω/p, it
/// also says how the block's restraint compares (`block_push`, the block's Ω/p):
/// read at the apex, a push of the block reads the law where the campaign's pushes
/// were (Ω/p)_block/(Ω/p)_campaign times slower (docs/facade.md, "Reading the law
/// by the impact's speed").
fn law_range(law: &crate::restitution_law::RestitutionLaw, e_h: f64, reading: LawReading, block_push: Option<f64>) -> String {
    use crate::restitution_law::LawForm;
    use crate::wall::Side;
    let (lo, hi) = (law.parameters.amplitude_min, law.parameters.amplitude_max);
    let mut parts = Vec::new();
    if law.form != LawForm::Constant {
        parts.push(format!("the campaign's impacts span a = |θ|/α = {lo:.3}–{hi:.3}"));
    }
    for (side, name) in [(Side::Inward, "inward"), (Side::Outward, "outward")] {
        if let Some(a) = law.elastic_from(side, e_h) {
            parts.push(format!("{name} e = 1 (the cap: an elastic impact) from a = {a:.3}"));
        }
    }
    // (A constant reads the same e at every amplitude: nothing to say.)
    let pushes = law.form != LawForm::Constant && law.ends_a_push(Side::Outward);
    if let (true, Some(q), Some(qb)) = (pushes, law.parameters.push_speed, block_push) {
        let measured = format!(
            "its pushes were measured at Ω/p = {:.1} ({:.1}–{:.1}), this block's restraint gives {qb:.1}",
            q.median, q.range[0], q.range[1]
        );
        parts.push(match reading {
            LawReading::Amplitude => {
                let (x, how) = if qb >= q.median { (qb / q.median, "slower") } else { (q.median / qb, "faster") };
                format!("{measured}: read at the apex, an outward impact reads the law where the campaign's pushes were {x:.1} times {how} (reading = \"speed\" reads it at its speed)")
            }
            LawReading::Speed => format!("{measured}: each impact reads the law at its speed"),
        });
    }
    parts.join("; ")
}

fn describe_set(s: &CoefficientSet, block: &crate::solver::BlockSpec) -> String {
    use crate::ensemble::CoefficientDist;
    let alpha = block.block.alpha;
    let range = match s
        .law_at(alpha)
        .map(|(law, e_h)| law_range(&law, e_h, s.law_reading(), block.push_speed_ratio()))
    {
        Some(r) if !r.is_empty() => format!("; {r}"),
        _ => String::new(),
    };
    match s.dist {
        CoefficientDist::Single(d) => format!("(e {}, {})", d.describe(), s.source),
        CoefficientDist::Pair { e_in, e_out } => format!("(e_in {}, e_out {}, {})", e_in.describe(), e_out.describe(), s.source),
        CoefficientDist::Law { drawn, .. } => format!(
            "(law, {}; e at a = 1: in {}, out {}{range}; {})",
            if drawn {
                "parameters drawn from their covariance"
            } else {
                "nominal parameters"
            },
            crate::ensemble::short(s.e_in),
            crate::ensemble::short(s.e_out),
            s.source
        ),
    }
}

/// ensemble.csv: one row per record × polarity × set, at full precision.
fn ensemble_csv(rows: &[EnsembleRow], nominal: &[StudyRun]) -> Result<Vec<u8>> {
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
    for r in rows {
        let st = &r.stats;
        let mut fields = place(&r.record, r.polarity, &r.coefficients);
        fields.extend([st.samples, st.overturned].map(|n| n.to_string()));
        fields.extend(texts(&[st.p_overturn, st.p_overturn_ci95[0], st.p_overturn_ci95[1]]));
        fields.push(st.verdict.to_string());
        fields.extend(texts(&[
            st.max_theta_over_alpha_median,
            st.max_theta_over_alpha_p05,
            st.max_theta_over_alpha_p95,
        ]));
        fields.extend([optional(st.overturn_time_median_s), nominal_of(r, nominal)]);
        w.write_record(&fields)?;
    }
    csv_bytes(w)
}

/// The first fields of an ensemble's row: record, polarity ("random" when drawn
/// per sample), coefficient set.
fn place(record: &str, polarity: Option<i8>, set: &str) -> Vec<String> {
    vec![
        record.to_string(),
        polarity.map_or("random".to_string(), |p| p.to_string()),
        set.to_string(),
    ]
}

/// Numbers at full precision.
fn texts(v: &[f64]) -> impl Iterator<Item = String> + '_ {
    v.iter().map(|x| x.to_string())
}

/// A number at full precision, or an empty field.
fn optional(v: Option<f64>) -> String {
    v.map(|t| t.to_string()).unwrap_or_default()
}

/// samples.csv: every sample, where it sits, its drawn inputs and its outcome.
fn samples_csv(samples: &[SampleRun]) -> Result<Vec<u8>> {
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
        let mut fields = place(&s.record, s.row_polarity, &s.coefficients);
        fields.push(s.scale.to_string());
        fields.push(s.sample.to_string());
        fields.extend(texts(&[s.im, x.magnification, x.polarity, x.r_m, x.alpha, x.i0]));
        fields.extend([optional(x.spring_bed.map(|b| b.0)), optional(x.spring_bed.map(|b| b.1))]);
        fields.extend(texts(&[x.e_in, x.e_out]));
        fields.push(s.outcome.overturned.to_string());
        fields.extend([optional(s.outcome.overturn_time_s), s.outcome.max_theta_over_alpha.to_string()]);
        w.write_record(&fields)?;
    }
    csv_bytes(w)
}

/// The fragility fits: median and β with their intervals, or why there is no fit.
fn fragility_table(study: &Study, fits: &[SetFragility], source: &str) -> Table {
    let im = study.im.label();
    let r = |k: &str, x: &str| Column::new(k, x, Align::Right);
    let columns = vec![
        Column::new("coefficients", "coefficients", Align::Left),
        r("median", &format!("median {im}")),
        r("median_ci95", "95 % CI"),
        r("beta", "β"),
        r("beta_ci95", "95 % CI"),
        r("runs", "runs"),
    ];
    let caption = format!(
        "Lognormal fragility P(overturn | IM) = Φ(ln(IM/θ)/β) fitted by maximum likelihood (Baker 2015) to every run of {source}; IM = {im} of the scaled record each run felt. 95 % intervals from the observed information (Wald on ln θ and ln β); they treat the runs as independent, so with {} records they understate the record-to-record uncertainty.",
        study.records.len()
    );
    let beyond = |f: &SetFragility| f.law_reach.is_some_and(|x| x.beyond_share() > BEYOND_THE_DATA);
    let caption = if fits.iter().any(beyond) {
        caption
            + &format!(
                " ‡ a law set whose runs, the larger scales included, met together more than {:.0} % of one side's impact energy at amplitudes the campaign did not observe on that side: its fragility rests on the law's form there, not on measured impacts.",
                100.0 * BEYOND_THE_DATA
            )
    } else {
        caption
    };
    let mut t = Table::new("fragility", caption, columns);
    t.nowrap = true;
    for f in fits {
        let runs: usize = f.observed.iter().map(|t| t.n).sum();
        let name = format!("{}{}", f.coefficients, if beyond(f) { " ‡" } else { "" });
        let cells = match &f.fit {
            Ok(x) => vec![
                Cell::text(&name),
                Cell::num(x.median, format!("{:.3}", x.median)),
                Cell::text(format!("{:.3}–{:.3}", x.median_ci95[0], x.median_ci95[1])),
                Cell::num(x.beta, format!("{:.3}", x.beta)),
                Cell::text(format!("{:.3}–{:.3}", x.beta_ci95[0], x.beta_ci95[1])),
                Cell::text(x.runs.to_string()),
            ],
            Err(e) => vec![
                Cell::text(&name),
                Cell::text(format!("no fit: {e}")),
                Cell::default(),
                Cell::default(),
                Cell::default(),
                Cell::text(runs.to_string()),
            ],
        };
        t.push(Some(f.coefficients.clone()), cells);
    }
    t
}

/// fragility.csv: the fits at full precision (a note where there is none).
fn fragility_csv(fits: &[SetFragility]) -> Result<Vec<u8>> {
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
    for f in fits {
        let runs: usize = f.observed.iter().map(|t| t.n).sum();
        let fields: Vec<String> = match &f.fit {
            Ok(x) => [x.median, x.median_ci95[0], x.median_ci95[1], x.beta, x.beta_ci95[0], x.beta_ci95[1]]
                .iter()
                .map(|v| v.to_string())
                .chain([x.runs.to_string(), String::new()])
                .collect(),
            Err(e) => std::iter::repeat_n(String::new(), 6).chain([runs.to_string(), e.to_string()]).collect(),
        };
        w.write_record(std::iter::once(f.coefficients.clone()).chain(fields))?;
    }
    csv_bytes(w)
}

/// fragility_observed.csv: the observed fraction per set and intensity.
fn observed_csv(fits: &[SetFragility]) -> Result<Vec<u8>> {
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
    csv_bytes(o)
}

/// The fitted curves with the median's 95 % interval as a bar at P = ½, and the
/// observed fractions per record × scale.
fn fragility_figure(study: &Study, fits: &[SetFragility], source: &str) -> Result<Captioned> {
    let x_max = fits.iter().flat_map(|f| f.observed.iter().map(|t| t.im)).fold(0.0f64, f64::max) * 1.05;
    let mut series = Vec::new();
    for (i, f) in fits.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        if let Ok(x) = &f.fit {
            let pts = (1..=200).map(|k| x_max * k as f64 / 200.0).map(|v| (v, x.probability(v))).collect();
            series.push(Series::line(
                &format!("{}: θ = {:.3}, β = {:.2}", f.coefficients, x.median, x.beta),
                color,
                pts,
            ));
            // The median's 95 % interval as a bar at P = ½ (out of the legend).
            series.push(Series::line("", color, vec![(x.median_ci95[0], 0.5), (x.median_ci95[1], 0.5)]));
        }
        let observed = f.observed.iter().map(|t| (t.im, t.k as f64 / t.n as f64)).collect();
        let no_fit = if f.fit.is_err() { " (no fit)" } else { "" };
        series.push(Series::dots(&format!("{} observed{no_fit}", f.coefficients), color, observed));
    }
    let panel = Panel {
        title: "Fragility: P(overturn) against the intensity of the scaled record".into(),
        x_label: study.im.label().into(),
        y_label: "P(overturn)".into(),
        series,
        x_range: Some((0.0, x_max.max(1e-6))),
        ..Panel::default()
    };
    Ok(Captioned {
        stem: "fragility".into(),
        caption: format!("Lognormal fragility curves by maximum likelihood per coefficient set (lines; the bar at P = ½ is the median's 95 % interval) and the observed fraction of overturning runs per record × scale (dots), from {source}."),
        figure: plots::render(&[panel], 900, 480)?,
    })
}
