//! Self-contained HTML reports: inline CSS, inline SVG plots, no network. Tables in
//! the paper's layout with captions, every test's plots, and a provenance section
//! (manifest, input files with size and SHA-256, e_H and its source, the
//! differentiation method, the tool's version, every warning). Prints on A4.

use super::campaign::{Sources, TestFigures};
use super::tables::{to_html, Table};
use crate::reduce::CampaignResult;

/// Escape text for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

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

/// The reduce report (plus extra sections, e.g. the calibration).
pub fn reduce_page(res: &CampaignResult, tabs: &[Table], figs: &TestFigures, extra: &[String], sources: &Sources) -> String {
    let c = &res.campaign;
    let mut page = Page::new(&format!("{} — coefficients of restitution ({} rocking)", c.name, c.rocking.as_str()));
    page.p(&format!(
        "α = {:.4} rad ({}); e_H = {:.4} ({}). Ratios are divided by e_H. Velocity peaks: {}.",
        c.alpha_rad,
        c.alpha_source,
        c.e_housner,
        c.e_housner_source,
        res.options.method.describe()
    ));
    let failed: Vec<_> = res.failed().collect();
    if !failed.is_empty() {
        page.h2("Tests that could not be reduced");
        page.table(
            "meta",
            &["test", "reason"],
            &failed.iter().map(|(id, e)| vec![id.to_string(), e.to_string()]).collect::<Vec<_>>(),
        );
    }
    page.h2("Tables");
    if !res.means.left_out.is_empty() {
        page.p(&format!("Means leave out: {}.", res.means.left_out_text()));
    }
    for t in tabs {
        page.raw(&to_html(t));
    }
    page.h2("Velocity peaks");
    let mut rows = Vec::new();
    for t in &res.tests {
        if let Ok(r) = &t.result {
            rows.push(
                std::iter::once(t.spec.id.clone())
                    .chain(r.analysis.peaks.iter().map(|p| format!("{:.1} @ {:.3} s", p.velocity_mm_s, p.time_s)))
                    .collect(),
            );
        }
    }
    page.table("meta peaks", &["test", "v0 (mm/s)", "v1", "v2", "v3", "v4", "v5"], &rows);
    for x in extra {
        page.raw(x);
    }
    page.h2("Plots");
    for (id, motion, ratios) in figs {
        page.h3(&format!("Test {id}"));
        page.figure(
            &motion.svg,
            &format!("Test {id}: displacement and velocity with the velocity peaks marked (paper Fig. 3/4)."),
        );
        page.figure(&ratios.svg, &format!("Test {id}: local ratios of Eq. 3 and their mean (paper Fig. 5)."));
    }
    provenance(&mut page, res, sources);
    page.finish()
}

/// The provenance section of the reduce report: the inputs with their checksums,
/// what reading and fitting each log noted, every warning, the tool, the manifest.
fn provenance(page: &mut Page, res: &CampaignResult, sources: &Sources) {
    page.h2("Provenance");
    page.provenance(&sources.files);
    let mut notes = Vec::new();
    for t in &res.tests {
        if let Ok(r) = &t.result {
            for n in &r.log.notes {
                notes.push(vec![t.spec.id.clone(), n.clone()]);
            }
            if let (Some(p), Some(rms)) = (r.analysis.p_fit, r.analysis.rms_mm) {
                notes.push(vec![
                    t.spec.id.clone(),
                    format!(
                        "fit: p_e = {p:.4} rad/s, λ = {}, RMS {rms:.4} mm, noise {:.4} mm, spikes removed {}",
                        r.analysis.lambda_fit.map_or("—".to_string(), |l| format!("{l:.2} s⁻²")),
                        r.analysis.noise_mm,
                        r.analysis.spikes_removed
                    ),
                ]);
                notes.push(vec![
                    t.spec.id.clone(),
                    format!("data logger's filter: {}", r.analysis.response.describe()),
                ]);
            }
        }
    }
    page.table("meta", &["test", "reading and fit"], &notes);
    let warnings: Vec<Vec<String>> = res
        .tests
        .iter()
        .flat_map(|t| t.warnings.iter().map(move |w| vec![t.spec.id.clone(), w.clone()]))
        .collect();
    if warnings.is_empty() {
        page.p("No warnings were raised while reading.");
    } else {
        page.raw("<p class=\"warn\">Warnings raised while reading:</p>");
        page.table("meta", &["test", "warning"], &warnings);
    }
    page.p(&format!(
        "Tool: rocklab {}; method: {}.",
        env!("CARGO_PKG_VERSION"),
        res.options.method.describe()
    ));
    page.h3("Manifest");
    page.pre(&sources.manifest);
}
