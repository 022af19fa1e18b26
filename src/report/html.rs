//! The HTML page every report is built on: inline CSS, inline SVG plots, no network,
//! tables from the one table model ([`super::table`]), a provenance table. Prints on
//! A4. The pages themselves (campaign, calibration, façade) are written on top of it
//! in their own modules.

use super::table::{to_html, Table};

pub use super::table::escape;

const CSS: &str = r#"
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 10.5pt; color: #222; max-width: 190mm; margin: 1.5em auto; line-height: 1.35; }
body.wide { max-width: 250mm; }
h1 { font-size: 17pt; margin-bottom: 0.2em; } h2 { font-size: 13.5pt; border-bottom: 1px solid #999; margin-top: 1.6em; } h3 { font-size: 11.5pt; }
table { border-collapse: collapse; margin: 0.8em 0; } caption { caption-side: bottom; text-align: left; font-size: 9pt; padding-top: 0.3em; }
table.paper { border-top: 2px solid #222; border-bottom: 2px solid #222; } table.paper thead th { border-bottom: 1px solid #222; }
th, td { padding: 0.15em 0.8em; text-align: right; } th:first-child, td:first-child, th.l, td.l { text-align: left; }
table.wide { font-size: 8.5pt; } table.wide th, table.wide td { padding: 0.15em 0.45em; }
tr.mean td { border-top: 1px solid #222; font-weight: bold; } td.error { color: #a00; text-align: left; font-size: 9pt; } td.suspect { color: #a60; text-align: left; font-size: 9pt; } td.ok { color: #060; text-align: left; }
figure { margin: 0.8em 0; page-break-inside: avoid; } figure svg { width: 100%; height: auto; } figcaption { font-size: 9pt; }
pre { background: #f4f4f4; padding: 0.6em; font-size: 8.5pt; white-space: pre-wrap; } .meta td, .meta th { font-size: 9pt; overflow-wrap: anywhere; } .meta td:first-child { overflow-wrap: normal; } .peaks td { white-space: nowrap; } .peaks td, .peaks th { padding: 0.15em 0.45em; }
.warn { color: #8a5a00; }
@page { size: A4; margin: 15mm; }
@media print { body { max-width: none; margin: 0; } h2 { page-break-after: avoid; } }
"#;

/// Marks every inline plot with `data-rendered="yes"` once the browser has laid it
/// out with a non-empty box (the browser test reads it back from the DOM).
const CHECK: &str = r#"<script>
window.addEventListener('load', function () {
  document.querySelectorAll('figure svg').forEach(function (s) {
    var b = s.getBBox();
    s.setAttribute('data-rendered', (b.width > 0 && b.height > 0 && s.querySelectorAll('path,polyline,circle,line,rect').length > 2) ? 'yes' : 'no');
  });
  document.body.setAttribute('data-checked', 'yes');
});
</script>"#;

/// A page under construction.
pub struct Page {
    title: String,
    body: String,
    wide: bool,
}

impl Page {
    pub fn new(title: &str) -> Page {
        Page {
            title: title.to_string(),
            body: format!("<h1>{}</h1>\n", escape(title)),
            wide: false,
        }
    }
    /// A wider page (on screen) for tables of many columns.
    pub fn widen(&mut self) {
        self.wide = true;
    }
    pub fn h2(&mut self, s: &str) {
        self.body.push_str(&format!("<h2>{}</h2>\n", escape(s)));
    }
    pub fn h3(&mut self, s: &str) {
        self.body.push_str(&format!("<h3>{}</h3>\n", escape(s)));
    }
    pub fn p(&mut self, s: &str) {
        self.body.push_str(&format!("<p>{}</p>\n", escape(s)));
    }
    pub fn raw(&mut self, html: &str) {
        self.body.push_str(html);
    }
    pub fn pre(&mut self, s: &str) {
        self.body.push_str(&format!("<pre>{}</pre>\n", escape(s)));
    }
    pub fn figure(&mut self, svg: &str, caption: &str) {
        self.body
            .push_str(&format!("<figure>{svg}<figcaption>{}</figcaption></figure>\n", escape(caption)));
    }
    /// A table of text (notes, provenance) in the one table model, class `class`
    /// ("meta", plus "peaks" for the velocity peaks, whose columns after the first
    /// are numbers and are right-aligned).
    pub fn table(&mut self, class: &'static str, head: &[&str], rows: &[Vec<String>]) {
        use super::table::{Align, Cell, Column};
        let numbers = class.contains("peaks");
        let align = |i: usize| if numbers && i > 0 { Align::Right } else { Align::Left };
        let columns = head.iter().enumerate().map(|(i, h)| Column::new(h, h, align(i))).collect();
        let mut t = Table::new("", String::new(), columns);
        t.class = class;
        for r in rows {
            t.push(None, r.iter().map(Cell::text).collect());
        }
        self.body.push_str(&to_html(&t));
    }
    /// The provenance table: every input with its path, size and SHA-256.
    pub fn provenance(&mut self, inputs: &[super::InputFile]) {
        let rows: Vec<Vec<String>> = inputs.iter().map(|f| f.row()).collect();
        self.table("meta", &["input", "file", "size", "SHA-256"], &rows);
    }
    pub fn finish(self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{CSS}</style></head>\n<body{}>\n{}\n<p class=\"meta\">rocklab {} — Giresini &amp; Croce, COMPDYN 2021.</p>\n{CHECK}\n</body></html>\n",
            escape(&self.title),
            if self.wide { " class=\"wide\"" } else { "" },
            self.body,
            env!("CARGO_PKG_VERSION")
        )
    }
}
