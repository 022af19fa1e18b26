//! One table model for every table rocklab prints (the campaign's Tables 1–3, the
//! calibration, the façade's ensembles, nominal runs and fragility), rendered to
//! Markdown, HTML, LaTeX (booktabs) and CSV by the four functions below. A builder
//! says what each cell shows; the renderers only lay it out.

use super::ReportError;

/// How a column is aligned (Markdown's `---:` and the HTML style sheet).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// A column: `key` names it in CSV and in the HTML `data-col` attribute, `label`
/// heads it in Markdown and HTML, `tex` in LaTeX (None: left out of LaTeX).
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    pub key: String,
    pub label: String,
    pub tex: Option<String>,
    pub align: Align,
}

impl Column {
    /// A column with the same text as key, label and LaTeX head.
    pub fn new(key: &str, label: &str, align: Align) -> Column {
        Column {
            key: key.into(),
            label: label.into(),
            tex: Some(latex_escape(label)),
            align,
        }
    }
}

/// One cell: the text shown, the number behind it (CSV and HTML `data-value`), its
/// standard uncertainty, and per-format overrides.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cell {
    pub text: String,
    pub value: Option<f64>,
    pub u: Option<f64>,
    /// Shorter text for Markdown (e.g. a reason cut to a few words).
    pub md: Option<String>,
    /// LaTeX source (not escaped again).
    pub tex: Option<String>,
    /// CSV text when it differs from `text` (e.g. "mean" in an otherwise empty cell).
    pub csv: Option<String>,
    /// HTML class (`ok`, `suspect`, `error`).
    pub class: Option<&'static str>,
    pub strong: bool,
}

impl Cell {
    pub fn text(s: impl Into<String>) -> Cell {
        Cell {
            text: s.into(),
            ..Cell::default()
        }
    }
    /// A number shown as `text`.
    pub fn num(value: f64, text: impl Into<String>) -> Cell {
        Cell {
            text: text.into(),
            value: Some(value),
            ..Cell::default()
        }
    }
    pub fn strong(mut self) -> Cell {
        self.strong = true;
        self
    }
    pub fn class(mut self, c: &'static str) -> Cell {
        self.class = Some(c);
        self
    }
}

/// A row: its key (HTML `data-test`), whether it is a mean row, its cells.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Row {
    pub key: Option<String>,
    pub mean: bool,
    pub cells: Vec<Cell>,
}

/// What a CSV column holds, taken from the cells of one table column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvField {
    /// The cell's CSV text, else its text.
    Text(usize),
    /// The number at full precision (empty when there is none).
    Value(usize),
    /// Its standard uncertainty (empty when there is none).
    U(usize),
}

/// A table: `name` (file stem, HTML id, LaTeX label), caption, columns, rows,
/// and how the CSV is laid out (by default every column's text).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub name: String,
    pub caption: String,
    pub columns: Vec<Column>,
    pub rows: Vec<Row>,
    pub csv: Vec<(String, CsvField)>,
    /// A note LaTeX prints above the label (e.g. what a dagger means).
    pub tex_note: Option<String>,
    /// Markdown and HTML cells stay on one line (the façade's ranges and times).
    pub nowrap: bool,
    /// The HTML class: "paper" (the paper's rules) or "meta" (provenance, notes).
    pub class: &'static str,
}

impl Table {
    pub fn new(name: &str, caption: String, columns: Vec<Column>) -> Table {
        let csv = columns.iter().enumerate().map(|(i, c)| (c.key.clone(), CsvField::Text(i))).collect();
        Table {
            name: name.into(),
            caption,
            columns,
            rows: Vec::new(),
            csv,
            tex_note: None,
            nowrap: false,
            class: "paper",
        }
    }
    pub fn push(&mut self, key: Option<String>, cells: Vec<Cell>) {
        self.rows.push(Row { key, mean: false, cells });
    }
}

/// Markdown: header, alignment line, rows (`**strong**` cells), a blank line and the caption.
pub fn to_markdown(t: &Table) -> String {
    let head: Vec<&str> = t.columns.iter().map(|c| c.label.as_str()).collect();
    let align: String = t.columns.iter().map(|c| if c.align == Align::Right { "---:|" } else { "---|" }).collect();
    let mut s = format!("| {} |\n|{align}\n", head.join(" | "));
    for row in &t.rows {
        let cells: Vec<String> = row.cells.iter().map(md_cell).collect();
        // An empty cell is written as "| |", as the paper-layout tables always were.
        let line = cells
            .iter()
            .map(|c| if c.is_empty() { " ".to_string() } else { format!(" {c} ") })
            .collect::<Vec<_>>();
        s.push_str(&format!("|{}|\n", line.join("|")));
    }
    s.push_str(&format!("\n{}\n", t.caption));
    s
}

fn md_cell(c: &Cell) -> String {
    let text = c.md.as_deref().unwrap_or(&c.text).replace('|', "/");
    if c.strong && !text.is_empty() {
        format!("**{text}**")
    } else {
        text
    }
}

/// HTML: the table with its id, caption, `data-test` on rows and `data-col`,
/// `data-value`, `data-u` on numeric cells.
pub fn to_html(t: &Table) -> String {
    let wide = if t.nowrap { " wide" } else { "" };
    let id = if t.name.is_empty() {
        String::new()
    } else {
        format!(" id=\"{}\"", escape(&t.name))
    };
    let mut s = format!("<table class=\"{}{wide}\"{id}>\n", t.class);
    if !t.caption.is_empty() {
        s.push_str(&format!("<caption>{}</caption>\n", escape(&t.caption)));
    }
    s.push_str("<thead><tr>");
    for c in &t.columns {
        let class = if c.align == Align::Left { " class=\"l\"" } else { "" };
        s.push_str(&format!("<th{class} data-col=\"{}\">{}</th>", escape(&c.key), escape(&c.label)));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for row in &t.rows {
        let class = if row.mean { " class=\"mean\"" } else { "" };
        let key = row.key.as_ref().map_or(String::new(), |k| format!(" data-test=\"{}\"", escape(k)));
        s.push_str(&format!("<tr{class}{key}>"));
        for (c, cell) in t.columns.iter().zip(&row.cells) {
            s.push_str(&html_cell(c, cell, t.nowrap));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody></table>\n");
    s
}

fn html_cell(c: &Column, cell: &Cell, nowrap: bool) -> String {
    let mut attrs = String::new();
    let classes: Vec<&str> = cell.class.into_iter().chain((c.align == Align::Left).then_some("l")).collect();
    if !classes.is_empty() {
        attrs.push_str(&format!(" class=\"{}\"", classes.join(" ")));
    }
    if let Some(v) = cell.value {
        attrs.push_str(&format!(" data-col=\"{}\" data-value=\"{v}\"", escape(&c.key)));
        if let Some(u) = cell.u {
            attrs.push_str(&format!(" data-u=\"{u}\""));
        }
    }
    if nowrap {
        attrs.push_str(" style=\"white-space: nowrap\"");
    }
    let text = if cell.strong {
        format!("<strong>{}</strong>", escape(&cell.text))
    } else {
        escape(&cell.text)
    };
    format!("<td{attrs}>{text}</td>")
}

/// LaTeX (booktabs): caption, label, the columns that have a LaTeX head; mean rows
/// after a rule. Text is escaped, "±" set as `$\pm$`.
pub fn to_latex(t: &Table) -> String {
    let cols: Vec<usize> = (0..t.columns.len()).filter(|&i| t.columns[i].tex.is_some()).collect();
    let spec: String = cols.iter().map(|&i| if t.columns[i].align == Align::Right { 'r' } else { 'l' }).collect();
    let note = t.tex_note.as_ref().map_or(String::new(), |n| format!("\\footnotesize{{{n}}}\n  "));
    let mut s = format!(
        "\\begin{{table}}[htbp]\n  \\centering\n  \\caption{{{}}}\n  {note}\\label{{tab:{}}}\n  \\begin{{tabular}}{{{spec}}}\n    \\toprule\n",
        latex_escape(&t.caption),
        t.name,
    );
    let head: Vec<&str> = cols.iter().filter_map(|&i| t.columns[i].tex.as_deref()).collect();
    s.push_str(&format!("    {} \\\\\n    \\midrule\n", head.join(" & ")));
    for row in &t.rows {
        if row.mean {
            s.push_str("    \\midrule\n");
        }
        let cells: Vec<String> = cols
            .iter()
            .map(|&i| match &row.cells[i].tex {
                Some(x) => x.clone(),
                None => latex_escape(&row.cells[i].text).replace(" ± ", " $\\pm$ "),
            })
            .collect();
        s.push_str(&format!("    {} \\\\\n", cells.join(" & ")));
    }
    s.push_str("    \\bottomrule\n  \\end{tabular}\n\\end{table}\n");
    s
}

/// CSV with the columns of `t.csv`; numbers at full precision.
pub fn to_csv(t: &Table) -> Result<Vec<u8>, ReportError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(t.csv.iter().map(|(h, _)| h.as_str()))?;
    for row in &t.rows {
        let field = |f: &CsvField| -> String {
            match *f {
                CsvField::Text(i) => {
                    let c = &row.cells[i];
                    c.csv.clone().unwrap_or_else(|| c.text.clone())
                }
                CsvField::Value(i) => row.cells[i].value.map(|v| v.to_string()).unwrap_or_default(),
                CsvField::U(i) => row.cells[i].u.map(|v| v.to_string()).unwrap_or_default(),
            }
        };
        w.write_record(t.csv.iter().map(|(_, f)| field(f)))?;
    }
    super::csv_bytes(w)
}

/// Escape text for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
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
