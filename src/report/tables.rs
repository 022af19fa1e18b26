//! Tables 1–3 in the paper's layout, built on the one table model
//! ([`super::table`]): CSV at full precision (values, their standard
//! uncertainties, the status with its reason), Markdown and HTML in percent rounded
//! like the paper with a quality column (HTML: a short mark, the reasons are in the
//! page's quality section), LaTeX with a dagger on suspect tests.

pub use super::table::{latex_escape, to_csv, to_html, to_latex, to_markdown, Table};
use super::table::{Align, Cell, Column, CsvField};
use crate::campaign_means::{CampaignMeans, Means};
use crate::reduce::CampaignResult;
use crate::restitution::Coefficients;

/// "59%" or "59 ± 1%" (the uncertainty to one significant digit, at least 1 %
/// resolution unless it is below 1 %).
pub fn percent_u(v: f64, u: Option<f64>) -> String {
    match u {
        Some(u) if u.is_finite() => {
            let up = 100.0 * u;
            if up < 0.95 {
                format!("{:.1} ± {:.1}%", 100.0 * v, up.max(0.1))
            } else {
                format!("{:.0} ± {:.0}%", 100.0 * v, up)
            }
        }
        _ => percent(v),
    }
}

/// "0.916 ± 0.012", or with as many decimals as the uncertainty's first
/// significant digit needs ("0.9160 ± 0.0004"), so that a small u never reads
/// "± 0.000"; at least three decimals, at most nine. A u that is not finite
/// is said, never printed as NaN.
pub fn value_u(v: f64, u: f64) -> String {
    if !u.is_finite() {
        return format!("{v:.3} (u not computed)");
    }
    let d = if u.is_finite() && u > 0.0 { (-u.log10().floor()) as i64 } else { 3 };
    let d = d.clamp(3, 9) as usize;
    format!("{v:.d$} ± {u:.d$}")
}

type Pick = fn(&Coefficients) -> f64;

/// The columns of one campaign table: (CSV key, label, pick).
type Cols<'a> = &'a [(&'static str, &'static str, Pick)];

/// One test's row (paper layout): values in percent with their uncertainty and
/// the quality, or dashes and the error.
fn test_row(cols: Cols, id: &str, values: Result<(&Coefficients, Option<&Coefficients>, Option<String>), &str>) -> Vec<Cell> {
    let mut cells = vec![Cell::text(id)];
    match values {
        Ok((q, u, suspect)) => {
            for c in cols {
                let (v, ui) = ((c.2)(q), u.map(|u| (c.2)(u)));
                let tex = latex_escape(&percent_u(v, ui)).replace(" ± ", " $\\pm$ ");
                cells.push(Cell {
                    u: ui,
                    tex: Some(tex),
                    ..Cell::num(v, percent_u(v, ui))
                });
            }
            if suspect.is_some() {
                cells[0].tex = Some(format!("{}$^\\dagger$", latex_escape(id)));
            }
            // HTML shows a short mark (the page explains the reasons once, in its
            // quality section); CSV keeps the whole reason, Markdown its first words.
            cells.push(match suspect {
                Some(why) => Cell {
                    md: Some(format!("suspect: {}", first_words(&why))),
                    csv: Some(format!("suspect: {why}")),
                    ..Cell::text("suspect").class("suspect")
                },
                None => Cell::text("ok").class("ok"),
            });
        }
        Err(e) => {
            for _ in cols {
                cells.push(Cell {
                    tex: Some("--".into()),
                    ..Cell::text("—")
                });
            }
            cells.push(Cell {
                md: Some(format!("error: {}", first_words(e))),
                csv: Some(format!("error: {e}")),
                ..Cell::text("error").class("error")
            });
        }
    }
    cells
}

/// The mean row: bold in Markdown, without uncertainty in LaTeX, "mean" as status in CSV.
fn mean_row(cols: Cols, label: &str, m: &Means, u: Option<&Means>) -> Vec<Cell> {
    let (q, qu) = (as_coefficients(m), u.map(as_coefficients));
    let mut cells = vec![Cell::text(label).strong()];
    for c in cols {
        let (v, ui) = ((c.2)(&q), qu.as_ref().map(|u| (c.2)(u)));
        cells.push(Cell {
            u: ui,
            tex: Some(format!("{:.0}\\%", 100.0 * v)),
            ..Cell::num(v, percent_u(v, ui)).strong()
        });
    }
    cells.push(Cell {
        csv: Some("mean".into()),
        ..Cell::default()
    });
    cells
}

fn as_coefficients(m: &Means) -> Coefficients {
    Coefficients {
        e: f64::NAN,
        e_plus: f64::NAN,
        e_minus: f64::NAN,
        r: m.r,
        r_plus: m.r_plus,
        r_minus: m.r_minus,
        r1: m.r1,
        r1_plus: m.r1_plus,
        r1_minus: m.r1_minus,
        r2: m.r2,
    }
}

/// The columns of a campaign table and its CSV layout: test, values, uncertainties, status.
fn layout(name: &str, caption: String, cols: Cols) -> Table {
    let mut columns = vec![Column {
        tex: Some("Test".into()),
        ..Column::new("test", "test#", Align::Left)
    }];
    columns.extend(cols.iter().map(|c| Column {
        tex: Some(latex_label(c.0)),
        ..Column::new(c.0, c.1, Align::Right)
    }));
    columns.push(Column {
        tex: None,
        ..Column::new("status", "quality", Align::Left)
    });
    let mut t = Table::new(name, caption, columns);
    let n = cols.len();
    t.csv = std::iter::once(("test".to_string(), CsvField::Text(0)))
        .chain(cols.iter().enumerate().map(|(i, c)| (c.0.to_string(), CsvField::Value(i + 1))))
        .chain(cols.iter().enumerate().map(|(i, c)| (format!("{}_u", c.0), CsvField::U(i + 1))))
        .chain(std::iter::once(("status".to_string(), CsvField::Text(n + 1))))
        .collect();
    t
}

/// What a campaign table shows of one test: its coefficients, their standard
/// uncertainties and why the tool cannot vouch for them, or why there are none.
pub struct TestValues<'a> {
    pub id: &'a str,
    pub values: Result<(&'a Coefficients, Option<&'a Coefficients>, Option<String>), String>,
}

/// What the campaign tables are built from: the captions' context (rocking,
/// e_H and its source), every test, and the means.
pub struct CampaignView<'a> {
    pub rocking: &'a str,
    pub e_housner: f64,
    pub e_housner_source: String,
    pub tests: Vec<TestValues<'a>>,
    pub means: &'a CampaignMeans,
}

impl<'a> CampaignView<'a> {
    pub fn of(res: &'a CampaignResult) -> CampaignView<'a> {
        let c = &res.campaign;
        let tests = res
            .tests
            .iter()
            .map(|t| TestValues {
                id: &t.spec.id,
                values: t
                    .result
                    .as_ref()
                    .map(|r| (&r.coefficients, r.uncertainty.as_ref(), r.suspect_reason()))
                    .map_err(|e| e.reason()),
            })
            .collect();
        CampaignView {
            rocking: c.rocking.as_str(),
            e_housner: c.e_housner,
            e_housner_source: c.e_housner_source.to_string(),
            tests,
            means: &res.means,
        }
    }
}

fn build(v: &CampaignView, name: &'static str, caption: String, cols: Cols) -> Table {
    let mut t = layout(name, caption, cols);
    for test in &v.tests {
        t.push(
            Some(test.id.to_string()),
            test_row(cols, test.id, test.values.as_ref().cloned().map_err(|e| e.as_str())),
        );
    }
    if t.rows.iter().any(|r| r.cells[0].tex.as_deref().is_some_and(|x| x.contains("dagger"))) {
        t.tex_note = Some("$^\\dagger$ suspect: the estimator cannot vouch for these values (left out of the mean).".into());
    }
    if let Some(m) = &v.means.means {
        t.rows.push(super::table::Row {
            key: Some("mean".into()),
            mean: true,
            cells: mean_row(cols, &mean_label(v.means), m, v.means.means_u.as_ref()),
        });
    }
    t
}

fn mean_label(means: &CampaignMeans) -> String {
    if let (None, [only]) = (&means.means_u, means.included.as_slice()) {
        // One test: the "mean" is its values, and there is no spread between
        // tests to give it a ± (the row would read as a bare, exact-looking 82%).
        format!("mean = {only} alone (one test: no spread between tests, so no ±)")
    } else if means.left_out.is_empty() {
        "mean".to_string()
    } else {
        let ids: Vec<&str> = means.left_out.iter().map(|(id, _)| id.as_str()).collect();
        format!("mean (without {})", ids.join(", "))
    }
}

/// Tables 1–3 of a campaign (Table 2's layout is the two-sided one of the paper:
/// r⁺, r⁻, r, r over two impacts; it is produced for every campaign).
pub fn tables(res: &CampaignResult) -> Vec<Table> {
    campaign_tables(&CampaignView::of(res))
}

/// Tables 1–3 from a [`CampaignView`].
pub fn campaign_tables(v: &CampaignView) -> Vec<Table> {
    let eh = format!("e_H = {:.4} ({})", v.e_housner, v.e_housner_source);
    vec![
        build(
            v,
            "table1",
            format!(
                "Table 1: mean experimental ratios of coefficients of restitution, {} rocking (r⁺ outward, r⁻ inward); {eh}.",
                v.rocking
            ),
            &[("r_plus", "r⁺", |q| q.r_plus), ("r_minus", "r⁻", |q| q.r_minus), ("r", "r", |q| q.r)],
        ),
        build(
            v,
            "table2",
            format!("Table 2: ratios over consecutive peaks and peaks of the same sign, and over the first two impacts; {eh}."),
            &[
                ("r_plus", "r⁺", |q| q.r_plus),
                ("r_minus", "r⁻", |q| q.r_minus),
                ("r", "r", |q| q.r),
                ("r2", "r (2 impacts)", |q| q.r2),
            ],
        ),
        build(
            v,
            "table3",
            format!("Table 3: ratios for the first impacts (r₁⁺ outward, r₁⁻ inward); {eh}."),
            &[
                ("r1_plus", "r₁⁺", |q| q.r1_plus),
                ("r1_minus", "r₁⁻", |q| q.r1_minus),
                ("r1", "r₁", |q| q.r1),
            ],
        ),
    ]
}

/// Percent rounded to the unit, as the paper prints them ("67%").
pub fn percent(v: f64) -> String {
    format!("{:.0}%", 100.0 * v)
}

/// The reason in a few words for a table cell (the file path of an error dropped).
fn first_words(e: &str) -> String {
    let e = match e.split_once(".csv: ") {
        Some((_, rest)) => rest,
        None => e,
    };
    let short: String = e.chars().take(60).collect();
    let short = if e.chars().count() > 60 { format!("{short}…") } else { short };
    short.replace('|', "/")
}

fn latex_label(name: &str) -> String {
    match name {
        "r_plus" => "$r^+$".into(),
        "r_minus" => "$r^-$".into(),
        "r" => "$r$".into(),
        "r2" => "$r$ (2 impacts)".into(),
        "r1_plus" => "$r_1^+$".into(),
        "r1_minus" => "$r_1^-$".into(),
        "r1" => "$r_1$".into(),
        other => latex_escape(other),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_u_shows_the_first_digit_of_a_small_u() {
        assert_eq!(value_u(0.91612, 0.00037), "0.9161 ± 0.0004");
        assert_eq!(value_u(0.916, 0.012), "0.916 ± 0.012");
        assert_eq!(value_u(0.5, 0.0), "0.500 ± 0.000");
        assert_eq!(value_u(0.5, f64::NAN), "0.500 (u not computed)");
    }

    // Session 13: on the engine campaign fresh-one-default four of five tests are
    // suspect, and the mean row read "mean (without …) 82% 81% 80%": one test's
    // values, without ± and without saying so.
    #[test]
    fn a_mean_of_one_test_says_so() {
        let m = CampaignMeans {
            means: None,
            means_u: None,
            included: vec!["F1_180_1".into()],
            left_out: vec![("F1_190_1".into(), "suspect".into())],
        };
        assert_eq!(mean_label(&m), "mean = F1_180_1 alone (one test: no spread between tests, so no ±)");
        let two = CampaignMeans {
            included: vec!["a".into(), "b".into()],
            ..m.clone()
        };
        assert_eq!(mean_label(&two), "mean (without F1_190_1)");
    }
}
