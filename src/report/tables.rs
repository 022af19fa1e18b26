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
    /// (test id, values or the reason there are none)
    pub rows: Vec<(String, Result<Vec<f64>, String>)>,
    /// Mean row over the included tests and its label.
    pub mean: Option<(String, Vec<f64>)>,
}

type Pick = fn(&Coefficients) -> f64;

fn build(res: &CampaignResult, name: &'static str, caption: String, cols: &[(&'static str, &'static str, Pick)]) -> Table {
    let rows = res
        .tests
        .iter()
        .map(|t| {
            let vals = t
                .result
                .as_ref()
                .map(|r| cols.iter().map(|c| (c.2)(&r.coefficients)).collect())
                .map_err(|e| e.clone());
            (t.spec.id.clone(), vals)
        })
        .collect();
    let mean = res.means.means.map(|m| {
        let as_c = Coefficients {
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
        let label = if res.means.left_out.is_empty() {
            "mean".to_string()
        } else {
            format!(
                "mean (without {})",
                res.means.left_out.iter().map(|(id, _)| id.as_str()).collect::<Vec<_>>().join(", ")
            )
        };
        (label, cols.iter().map(|c| (c.2)(&as_c)).collect())
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

/// CSV at full precision: `test,<columns>,status`; failed tests have empty values
/// and their error in `status`; the mean row is last.
pub fn to_csv(t: &Table) -> anyhow::Result<Vec<u8>> {
    let mut ids: Vec<String> = Vec::new();
    let mut status: Vec<String> = Vec::new();
    let mut cols: Vec<Vec<Option<f64>>> = vec![Vec::new(); t.columns.len()];
    for (id, vals) in &t.rows {
        ids.push(id.clone());
        match vals {
            Ok(v) => {
                status.push("ok".into());
                for (c, x) in cols.iter_mut().zip(v) {
                    c.push(Some(*x));
                }
            }
            Err(e) => {
                status.push(format!("error: {e}"));
                for c in cols.iter_mut() {
                    c.push(None);
                }
            }
        }
    }
    if let Some((label, v)) = &t.mean {
        ids.push(label.clone());
        status.push("mean".into());
        for (c, x) in cols.iter_mut().zip(v) {
            c.push(Some(*x));
        }
    }
    let mut columns: Vec<Column> = vec![Column::new("test".into(), ids)];
    for ((name, _), c) in t.columns.iter().zip(cols) {
        columns.push(Column::new((*name).into(), c));
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

/// Markdown: the caption, then the table in percent.
pub fn to_markdown(t: &Table) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "| test# | {} |\n",
        t.columns.iter().map(|c| c.1).collect::<Vec<_>>().join(" | ")
    ));
    s.push_str(&format!("|---|{}\n", "---:|".repeat(t.columns.len())));
    for (id, vals) in &t.rows {
        match vals {
            Ok(v) => s.push_str(&format!("| {id} | {} |\n", v.iter().map(|x| percent(*x)).collect::<Vec<_>>().join(" | "))),
            Err(e) => s.push_str(&format!(
                "| {id} | {} |\n",
                vec![format!("— ({})", first_words(e))]
                    .into_iter()
                    .chain(std::iter::repeat_n("—".to_string(), t.columns.len() - 1))
                    .collect::<Vec<_>>()
                    .join(" | ")
            )),
        }
    }
    if let Some((label, v)) = &t.mean {
        s.push_str(&format!(
            "| **{label}** | {} |\n",
            v.iter().map(|x| format!("**{}**", percent(*x))).collect::<Vec<_>>().join(" | ")
        ));
    }
    s.push_str(&format!("\n{}\n", t.caption));
    s
}

fn first_words(e: &str) -> String {
    let e = e.rsplit(": ").next().unwrap_or(e);
    e.chars().take(40).collect::<String>().replace('|', "/")
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
    for (id, vals) in &t.rows {
        let cells = match vals {
            Ok(v) => v.iter().map(|x| format!("{:.0}\\%", 100.0 * x)).collect::<Vec<_>>(),
            Err(_) => vec!["--".to_string(); cols],
        };
        s.push_str(&format!("    {} & {} \\\\\n", latex_escape(id), cells.join(" & ")));
    }
    if let Some((label, v)) = &t.mean {
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
    s.push_str("</tr></thead>\n<tbody>\n");
    for (id, vals) in &t.rows {
        s.push_str(&format!("<tr data-test=\"{}\"><td>{}</td>", escape(id), escape(id)));
        match vals {
            Ok(v) => {
                for (c, x) in t.columns.iter().zip(v) {
                    s.push_str(&format!("<td data-col=\"{}\" data-value=\"{x}\">{}</td>", c.0, percent(*x)));
                }
            }
            Err(e) => s.push_str(&format!("<td colspan=\"{}\" class=\"error\">{}</td>", t.columns.len(), escape(e))),
        }
        s.push_str("</tr>\n");
    }
    if let Some((label, v)) = &t.mean {
        s.push_str(&format!("<tr class=\"mean\" data-test=\"mean\"><td>{}</td>", escape(label)));
        for (c, x) in t.columns.iter().zip(v) {
            s.push_str(&format!("<td data-col=\"{}\" data-value=\"{x}\">{}</td>", c.0, percent(*x)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody></table>\n");
    s
}
