//! Tables 1–3 in the paper's layout: CSV at full precision (written through a polars
//! DataFrame) and Markdown in percent rounded like the paper. One table builder
//! feeds both renderers.

use polars::prelude::*;

use crate::reduce::CampaignResult;
use crate::restitution::Coefficients;

/// A table: title, caption, column headers (CSV name, Markdown label), rows.
#[derive(Debug, Clone)]
pub struct Table {
    pub name: &'static str,
    pub caption: String,
    pub columns: Vec<(&'static str, &'static str)>,
    pub rows: Vec<TableRow>,
    /// Mean row over the included tests, its label and its standard uncertainty.
    pub mean: Option<(String, Vec<f64>, Option<Vec<f64>>)>,
}

/// One test's row: values or the reason there are none, their standard
/// uncertainties, and why the tool cannot vouch for them (a suspect test).
#[derive(Debug, Clone)]
pub struct TableRow {
    pub id: String,
    pub values: Result<Vec<f64>, String>,
    pub u: Option<Vec<f64>>,
    pub suspect: Option<String>,
}

impl TableRow {
    /// "ok", "suspect: …" or "error: …".
    pub fn quality(&self) -> String {
        match (&self.values, &self.suspect) {
            (Err(e), _) => format!("error: {e}"),
            (Ok(_), Some(why)) => format!("suspect: {why}"),
            (Ok(_), None) => "ok".into(),
        }
    }
}

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

type Pick = fn(&Coefficients) -> f64;

fn build(res: &CampaignResult, name: &'static str, caption: String, cols: &[(&'static str, &'static str, Pick)]) -> Table {
    let rows = res
        .tests
        .iter()
        .map(|t| TableRow {
            id: t.spec.id.clone(),
            values: t
                .result
                .as_ref()
                .map(|r| cols.iter().map(|c| (c.2)(&r.coefficients)).collect())
                .map_err(|e| e.reason()),
            u: t.result
                .as_ref()
                .ok()
                .and_then(|r| r.uncertainty.as_ref())
                .map(|u| cols.iter().map(|c| (c.2)(u)).collect()),
            suspect: t.result.as_ref().ok().and_then(|r| r.suspect_reason()),
        })
        .collect();
    let as_coefficients = |m: &crate::campaign_means::Means| Coefficients {
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
    };
    let mean_u = res.means.means_u.map(|m| {
        let c = as_coefficients(&m);
        cols.iter().map(|col| (col.2)(&c)).collect::<Vec<f64>>()
    });
    let mean = res.means.means.map(|m| {
        let as_c = as_coefficients(&m);
        let label = if res.means.left_out.is_empty() {
            "mean".to_string()
        } else {
            format!(
                "mean (without {})",
                res.means.left_out.iter().map(|(id, _)| id.as_str()).collect::<Vec<_>>().join(", ")
            )
        };
        (label, cols.iter().map(|c| (c.2)(&as_c)).collect(), mean_u)
    });
    Table {
        name,
        caption,
        columns: cols.iter().map(|c| (c.0, c.1)).collect(),
        rows,
        mean,
    }
}

/// Tables 1–3 of a campaign (Table 2's layout is the two-sided one of the paper:
/// r⁺, r⁻, r, r over two impacts; it is produced for every campaign).
pub fn tables(res: &CampaignResult) -> Vec<Table> {
    let c = &res.campaign;
    let eh = format!("e_H = {:.4} ({})", c.e_housner, c.e_housner_source);
    vec![
        build(
            res,
            "table1",
            format!(
                "Table 1: mean experimental ratios of coefficients of restitution, {} rocking (r⁺ outward, r⁻ inward); {eh}.",
                c.rocking.as_str()
            ),
            &[("r_plus", "r⁺", |q| q.r_plus), ("r_minus", "r⁻", |q| q.r_minus), ("r", "r", |q| q.r)],
        ),
        build(
            res,
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
            res,
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

/// CSV at full precision: `test,<columns>,<columns>_u,status`; failed tests have
/// empty values and their error in `status`, suspect tests "suspect: reason";
/// the mean row is last (its `_u` the test-to-test standard error).
pub fn to_csv(t: &Table) -> anyhow::Result<Vec<u8>> {
    let mut ids: Vec<String> = Vec::new();
    let mut status: Vec<String> = Vec::new();
    let nc = t.columns.len();
    let mut cols: Vec<Vec<Option<f64>>> = vec![Vec::new(); nc];
    let mut ucols: Vec<Vec<Option<f64>>> = vec![Vec::new(); nc];
    let push = |vals: Option<&Vec<f64>>, u: Option<&Vec<f64>>, cols: &mut Vec<Vec<Option<f64>>>, ucols: &mut Vec<Vec<Option<f64>>>| {
        for i in 0..nc {
            cols[i].push(vals.map(|v| v[i]));
            ucols[i].push(u.map(|v| v[i]));
        }
    };
    for row in &t.rows {
        ids.push(row.id.clone());
        status.push(row.quality());
        push(row.values.as_ref().ok(), row.u.as_ref(), &mut cols, &mut ucols);
    }
    if let Some((label, v, u)) = &t.mean {
        ids.push(label.clone());
        status.push("mean".into());
        push(Some(v), u.as_ref(), &mut cols, &mut ucols);
    }
    let mut columns: Vec<Column> = vec![Column::new("test".into(), ids)];
    for ((name, _), c) in t.columns.iter().zip(cols) {
        columns.push(Column::new((*name).into(), c));
    }
    for ((name, _), c) in t.columns.iter().zip(ucols) {
        columns.push(Column::new(format!("{name}_u").into(), c));
    }
    columns.push(Column::new("status".into(), status));
    let mut df = DataFrame::new_infer_height(columns)?;
    let mut buf = Vec::new();
    CsvWriter::new(&mut buf).include_header(true).finish(&mut df)?;
    Ok(buf)
}

/// Percent rounded to the unit, as the paper prints them ("67%").
pub fn percent(v: f64) -> String {
    format!("{:.0}%", 100.0 * v)
}

/// Markdown: the table in percent with standard uncertainties ("59 ± 1%"), a
/// quality column (ok / suspect / error with the reason), then the caption.
pub fn to_markdown(t: &Table) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "| test# | {} | quality |\n",
        t.columns.iter().map(|c| c.1).collect::<Vec<_>>().join(" | ")
    ));
    s.push_str(&format!("|---|{}---|\n", "---:|".repeat(t.columns.len())));
    for row in &t.rows {
        let id = &row.id;
        match &row.values {
            Ok(v) => {
                let cells: Vec<String> = v.iter().enumerate().map(|(i, x)| percent_u(*x, row.u.as_ref().map(|u| u[i]))).collect();
                let q = match &row.suspect {
                    Some(why) => format!("suspect: {}", first_words(why)),
                    None => "ok".into(),
                };
                s.push_str(&format!("| {id} | {} | {q} |\n", cells.join(" | ")));
            }
            Err(e) => s.push_str(&format!(
                "| {id} | {} | error: {} |\n",
                vec!["—".to_string(); t.columns.len()].join(" | "),
                first_words(e)
            )),
        }
    }
    if let Some((label, v, u)) = &t.mean {
        s.push_str(&format!(
            "| **{label}** | {} | |\n",
            v.iter()
                .enumerate()
                .map(|(i, x)| format!("**{}**", percent_u(*x, u.as_ref().map(|u| u[i]))))
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    s.push_str(&format!("\n{}\n", t.caption));
    s
}

/// The reason in a few words for a table cell (an error's reason comes without
/// the file's path: `TestError::reason`).
fn first_words(e: &str) -> String {
    let short: String = e.chars().take(60).collect();
    let short = if e.chars().count() > 60 { format!("{short}…") } else { short };
    short.replace('|', "/")
}

/// LaTeX (booktabs): percent rounded like the paper, caption, label.
pub fn to_latex(t: &Table) -> String {
    let cols = t.columns.len();
    let mut s = format!(
        "\\begin{{table}}[htbp]\n  \\centering\n  \\caption{{{}}}\n  \\label{{tab:{}}}\n  \\begin{{tabular}}{{l{}}}\n    \\toprule\n",
        latex_escape(&t.caption),
        t.name,
        "r".repeat(cols)
    );
    s.push_str(&format!(
        "    Test & {} \\\\\n    \\midrule\n",
        t.columns.iter().map(|c| latex_label(c.0)).collect::<Vec<_>>().join(" & ")
    ));
    let mut any_suspect = false;
    for row in &t.rows {
        let cells = match &row.values {
            Ok(v) => v
                .iter()
                .enumerate()
                .map(|(i, x)| latex_escape(&percent_u(*x, row.u.as_ref().map(|u| u[i]))).replace(" ± ", " $\\pm$ "))
                .collect::<Vec<_>>(),
            Err(_) => vec!["--".to_string(); cols],
        };
        let mark = if row.suspect.is_some() {
            any_suspect = true;
            "$^\\dagger$"
        } else {
            ""
        };
        s.push_str(&format!("    {}{mark} & {} \\\\\n", latex_escape(&row.id), cells.join(" & ")));
    }
    if any_suspect {
        s = s.replace(
            "\\label{",
            "\\footnotesize{$^\\dagger$ suspect: the estimator cannot vouch for these values (left out of the mean).}\n  \\label{",
        );
    }
    if let Some((label, v, _)) = &t.mean {
        s.push_str("    \\midrule\n");
        s.push_str(&format!(
            "    {} & {} \\\\\n",
            latex_escape(label),
            v.iter().map(|x| format!("{:.0}\\%", 100.0 * x)).collect::<Vec<_>>().join(" & ")
        ));
    }
    s.push_str("    \\bottomrule\n  \\end{tabular}\n\\end{table}\n");
    s
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

/// Escape LaTeX's special characters (and spell the Unicode the captions use).
pub fn latex_escape(s: &str) -> String {
    let mut o = String::new();
    for c in s.chars() {
        match c {
            '_' | '%' | '&' | '#' | '$' | '{' | '}' => {
                o.push('\\');
                o.push(c);
            }
            '⁺' => o.push_str("$^+$"),
            '⁻' => o.push_str("$^-$"),
            '₁' => o.push_str("$_1$"),
            'α' => o.push_str("$\\alpha$"),
            '−' => o.push('-'),
            '²' => o.push_str("$^2$"),
            _ => o.push(c),
        }
    }
    o
}

/// HTML: caption, then the table in percent (a failed test shows its reason).
pub fn to_html(t: &Table) -> String {
    use super::html::escape;
    let mut s = format!(
        "<table class=\"paper\" id=\"{}\">\n<caption>{}</caption>\n<thead><tr><th>test#</th>",
        t.name,
        escape(&t.caption)
    );
    for c in &t.columns {
        s.push_str(&format!("<th data-col=\"{}\">{}</th>", c.0, escape(c.1)));
    }
    s.push_str("<th>quality</th></tr></thead>\n<tbody>\n");
    for row in &t.rows {
        let id = &row.id;
        s.push_str(&format!("<tr data-test=\"{}\"><td>{}</td>", escape(id), escape(id)));
        match &row.values {
            Ok(v) => {
                for (i, (c, x)) in t.columns.iter().zip(v).enumerate() {
                    let u = row.u.as_ref().map(|u| u[i]);
                    s.push_str(&format!(
                        "<td data-col=\"{}\" data-value=\"{x}\" data-u=\"{}\">{}</td>",
                        c.0,
                        u.map_or(String::new(), |u| u.to_string()),
                        percent_u(*x, u)
                    ));
                }
                match &row.suspect {
                    Some(why) => s.push_str(&format!("<td class=\"suspect\">suspect: {}</td>", escape(why))),
                    None => s.push_str("<td class=\"ok\">ok</td>"),
                }
            }
            Err(e) => s.push_str(&format!(
                "<td colspan=\"{}\" class=\"error\">error: {}</td>",
                t.columns.len() + 1,
                escape(e)
            )),
        }
        s.push_str("</tr>\n");
    }
    if let Some((label, v, u)) = &t.mean {
        s.push_str(&format!("<tr class=\"mean\" data-test=\"mean\"><td>{}</td>", escape(label)));
        for (i, (c, x)) in t.columns.iter().zip(v).enumerate() {
            let ui = u.as_ref().map(|u| u[i]);
            s.push_str(&format!("<td data-col=\"{}\" data-value=\"{x}\">{}</td>", c.0, percent_u(*x, ui)));
        }
        s.push_str("<td></td></tr>\n");
    }
    s.push_str("</tbody></table>\n");
    s
}
