//! `ARCHIVE/archive.html`: a self-contained page (SVG inline) plotting every
//! archived test's r⁺ and r⁻ against the wall's slenderness h/t, by rocking type,
//! each with its band r ± 2u (u: the test's standard uncertainty, `_u`), every
//! archived impact's r against the amplitude of the half-cycle it ends (the
//! restitution law's data across campaigns, issue 20), and a table of the campaigns.

use std::collections::BTreeMap;
use std::path::Path;

use polars::prelude::*;

use super::ArchiveError;
use crate::report::html::Page;
use crate::report::plots::{self, Panel, Series};

/// One archived test, as the page needs it.
struct Point {
    campaign: String,
    sha: String,
    rocking: String,
    slenderness: f64,
    r_plus: (f64, Option<f64>),
    r_minus: (f64, Option<f64>),
    /// In its campaign's means (not `exclude_from_mean`).
    in_mean: bool,
}

fn text(df: &DataFrame, name: &str) -> PolarsResult<Vec<Option<String>>> {
    Ok(df.column(name)?.str()?.iter().map(|s| s.map(str::to_string)).collect())
}

fn numbers(df: &DataFrame, name: &str) -> PolarsResult<Vec<Option<f64>>> {
    Ok(df.column(name)?.f64()?.iter().collect())
}

/// The plotted tests: status "ok", slenderness and both ratios known.
fn points(df: &DataFrame) -> PolarsResult<(Vec<Point>, usize)> {
    let (campaign, rocking, status) = (text(df, "campaign")?, text(df, "rocking")?, text(df, "status")?);
    let sha = text(df, "manifest_sha256")?;
    let (sl, rp, rpu, rm, rmu) = (
        numbers(df, "slenderness")?,
        numbers(df, "r_plus")?,
        numbers(df, "r_plus_u")?,
        numbers(df, "r_minus")?,
        numbers(df, "r_minus_u")?,
    );
    let excluded: Vec<Option<bool>> = df.column("exclude_from_mean")?.bool()?.iter().collect();
    let mut out = Vec::new();
    for i in 0..df.height() {
        if status[i].as_deref() != Some("ok") {
            continue;
        }
        if let (Some(s), Some(p), Some(m)) = (sl[i], rp[i], rm[i]) {
            out.push(Point {
                campaign: campaign[i].clone().unwrap_or_default(),
                sha: sha[i].clone().unwrap_or_default(),
                rocking: rocking[i].clone().unwrap_or_default(),
                slenderness: s,
                r_plus: (p, rpu[i]),
                r_minus: (m, rmu[i]),
                in_mean: excluded[i] != Some(true),
            });
        }
    }
    let left_out = df.height() - out.len();
    Ok((out, left_out))
}

/// One panel: dots by rocking type, an unlabelled bar r ± 2u per test.
fn panel(points: &[Point], title: &str, y_label: &str, pick: fn(&Point) -> (f64, Option<f64>)) -> Panel {
    let colors = [("one-sided", plots::BLUE), ("two-sided", plots::ORANGE)];
    let mut series = Vec::new();
    for (rocking, color) in colors {
        let pts: Vec<&Point> = points.iter().filter(|p| p.rocking == rocking).collect();
        for p in &pts {
            if let (v, Some(u)) = pick(p) {
                series.push(Series::line("", color, vec![(p.slenderness, v - 2.0 * u), (p.slenderness, v + 2.0 * u)]));
            }
        }
        if !pts.is_empty() {
            series.push(Series::dots(
                &format!("{rocking} rocking"),
                color,
                pts.iter().map(|p| (p.slenderness, pick(p).0)).collect(),
            ));
        }
    }
    let mut panel = Panel::new(title, "slenderness h/t", y_label, series);
    let xs: Vec<f64> = points.iter().map(|p| p.slenderness).collect();
    let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if lo.is_finite() {
        let pad = ((hi - lo) * 0.1).max(0.5);
        panel.x_range = Some((lo - pad, hi + pad));
    }
    panel
}

/// One archived impact of a test with status ok: (campaign, side, amplitude, r).
type ImpactPoint = (String, String, f64, f64);

/// The impacts of the tests with status ok, with amplitude and r known.
fn impact_points(tests: &DataFrame, impacts: &DataFrame) -> PolarsResult<Vec<ImpactPoint>> {
    let ok: std::collections::HashSet<(String, String)> = text(tests, "manifest_sha256")?
        .into_iter()
        .zip(text(tests, "test")?)
        .zip(text(tests, "status")?)
        .filter_map(|((sha, t), st)| (st.as_deref() == Some("ok")).then_some((sha?, t?)))
        .collect();
    let (sha, test, campaign, side) = (
        text(impacts, "manifest_sha256")?,
        text(impacts, "test")?,
        text(impacts, "campaign")?,
        text(impacts, "side")?,
    );
    let (a, r) = (numbers(impacts, "amplitude_over_alpha")?, numbers(impacts, "r")?);
    let mut out = Vec::new();
    for i in 0..impacts.height() {
        let key = (sha[i].clone().unwrap_or_default(), test[i].clone().unwrap_or_default());
        if let (true, Some(a), Some(r), Some(side)) = (ok.contains(&key), a[i], r[i], side[i].clone()) {
            out.push((campaign[i].clone().unwrap_or_default(), side, a, r));
        }
    }
    Ok(out)
}

/// r of every impact against its amplitude, a panel per side, a colour per campaign.
fn impact_panels(points: &[ImpactPoint]) -> Vec<Panel> {
    let campaigns: Vec<&str> = points
        .iter()
        .map(|p| p.0.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    [("in", "entering the inward side"), ("out", "entering the outward side")]
        .iter()
        .map(|(side, title)| {
            let series = campaigns
                .iter()
                .enumerate()
                .filter_map(|(k, c)| {
                    let pts: Vec<(f64, f64)> = points.iter().filter(|p| p.0 == *c && p.1 == *side).map(|p| (p.2, p.3)).collect();
                    (!pts.is_empty()).then(|| Series::dots(c, plots::SETS[k % plots::SETS.len()], pts))
                })
                .collect();
            Panel::new(
                format!("impacts {title}: r against amplitude"),
                "amplitude |θ|/α of the half-cycle ended",
                "r = e/e_H",
                series,
            )
        })
        .collect()
}

/// Render the page from the `tests` and `impacts` tables.
pub fn render(tests: &DataFrame, impacts: &DataFrame) -> Result<String, ArchiveError> {
    let (pts, left_out) = points(tests).map_err(|e| ArchiveError::Page(e.to_string()))?;
    let mut page = Page::new("Lab archive — coefficients of restitution of every campaign");
    page.p(&format!(
        "{} tests plotted (status ok); {left_out} left out (suspect, error, or without r⁺/r⁻ or the wall's size). Bars: r ± 2u, u the test's standard uncertainty. Ratios r = e/e_H (paper Eqs. 5–6).",
        pts.len()
    ));
    let panels = [
        panel(&pts, "r⁺ (outward) against slenderness", "r⁺", |p| p.r_plus),
        panel(&pts, "r⁻ (inward) against slenderness", "r⁻", |p| p.r_minus),
    ];
    let fig = plots::render(&panels, 900, 380).map_err(|e| ArchiveError::Page(e.to_string()))?;
    page.figure(&fig.svg, "Every archived test's r⁺ and r⁻ with its band (± 2u), by rocking type.");
    let ipts = impact_points(tests, impacts).map_err(|e| ArchiveError::Page(e.to_string()))?;
    if ipts.is_empty() {
        page.p("No archived impact of a test with status ok carries a coefficient (side, e, r): no impact plot.");
    } else {
        let fig = plots::render(&impact_panels(&ipts), 900, 380).map_err(|e| ArchiveError::Page(e.to_string()))?;
        page.figure(
            &fig.svg,
            &format!(
                "r = e/e_H of every archived impact ({} impacts of the tests with status ok) against the amplitude of the half-cycle it ends, by campaign: the data a restitution law r(a) is fitted to (docs/restitution-law.md).",
                ipts.len()
            ),
        );
    }
    // Every archived campaign has a row, also one whose tests are all suspect
    // (it was missing from the table, as if not archived).
    let page_err = |e: PolarsError| ArchiveError::Page(e.to_string());
    let (campaign, rocking) = (text(tests, "campaign").map_err(page_err)?, text(tests, "rocking").map_err(page_err)?);
    let slenderness = numbers(tests, "slenderness").map_err(page_err)?;
    let sha = text(tests, "manifest_sha256").map_err(page_err)?;
    // A row per reduction (campaign and manifest): a campaign reduced again from a
    // corrected manifest is two reductions, never merged into one mean.
    type Group<'a> = (usize, Option<f64>, Vec<&'a Point>);
    let mut by: BTreeMap<(String, String, String), Group> = BTreeMap::new();
    for i in 0..tests.height() {
        let key = (
            campaign[i].clone().unwrap_or_default(),
            sha[i].clone().unwrap_or_default(),
            rocking[i].clone().unwrap_or_default(),
        );
        let g = by.entry(key).or_insert((0, None, Vec::new()));
        g.0 += 1;
        g.1 = g.1.or(slenderness[i]);
    }
    for p in &pts {
        if let Some(g) = by.get_mut(&(p.campaign.clone(), p.sha.clone(), p.rocking.clone())) {
            g.2.push(p);
        }
    }
    let mut names: BTreeMap<&str, usize> = BTreeMap::new();
    for (c, _, _) in by.keys() {
        *names.entry(c.as_str()).or_default() += 1;
    }
    // The campaign's means: its tests with status ok that the manifest does not
    // leave out (`exclude_from_mean`), as its Table 1 has them.
    let mean = |v: &[&&Point], f: fn(&Point) -> f64| (!v.is_empty()).then(|| format!("{:.3}", v.iter().map(|p| f(p)).sum::<f64>() / v.len() as f64));
    let rows: Vec<Vec<String>> = by
        .iter()
        .map(|((c, sha, r), (n, sl, v))| {
            let inc: Vec<&&Point> = v.iter().filter(|p| p.in_mean).collect();
            let none = || "— (no test in the means)".to_string();
            let name = if names[c.as_str()] > 1 {
                format!("{c} (manifest {}…)", &sha[..sha.len().min(12)])
            } else {
                c.clone()
            };
            vec![
                name,
                r.clone(),
                sl.map_or_else(|| "—".to_string(), |x| format!("{x:.2}")),
                n.to_string(),
                v.len().to_string(),
                inc.len().to_string(),
                mean(&inc, |p| p.r_plus.0).unwrap_or_else(none),
                mean(&inc, |p| p.r_minus.0).unwrap_or_else(none),
            ]
        })
        .collect();
    page.h2("Campaigns");
    page.p("Mean r⁺ and r⁻ of each campaign's tests with status ok that its manifest keeps in the means (not exclude_from_mean): the means of its Table 1.");
    page.table(
        "meta",
        &["campaign", "rocking", "h/t", "tests", "tests ok", "in the mean", "mean r⁺", "mean r⁻"],
        &rows,
    );
    Ok(page.finish())
}

/// Write `archive.html` (atomically).
pub fn write(archive: &Path, tests: &DataFrame, impacts: &DataFrame) -> Result<(), ArchiveError> {
    let mut files = crate::report::Files::default();
    files.add("archive.html", render(tests, impacts)?);
    crate::report::write_files(archive, &files).map_err(|e| ArchiveError::Write(e.to_string()))
}
