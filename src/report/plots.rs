//! Plots in PNG and SVG (plotters). Text is drawn with the DejaVu Sans font shipped
//! in `fixtures/fonts` through plotters' `ab_glyph` backend, so no system font
//! library is needed. Rendering returns bytes ([`Figure`]); [`super::write_files`]
//! writes them.

use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
pub use plotters::style::RGBColor;

use super::{Files, ReportError};

type Result<T> = std::result::Result<T, ReportError>;

static FONT: &[u8] = include_bytes!("../../fixtures/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Register the shipped font as "sans-serif" (once per process).
pub fn register_font() {
    REGISTER.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic, FontStyle::Oblique] {
            let _ = plotters::style::register_font("sans-serif", style, FONT);
        }
    });
}

fn err<E: std::fmt::Debug>(e: E) -> ReportError {
    ReportError::Plot(format!("{e:?}"))
}

/// A line series: label, colour, points.
pub struct Series {
    pub label: String,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
    /// Draw as markers instead of a line.
    pub markers: bool,
}

impl Series {
    /// A line through `points`.
    pub fn line(label: &str, color: RGBColor, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            color,
            points,
            markers: false,
        }
    }
    /// A marker at each of `points`.
    pub fn dots(label: &str, color: RGBColor, points: Vec<(f64, f64)>) -> Series {
        Series {
            markers: true,
            ..Series::line(label, color, points)
        }
    }
}

/// One panel: title, axis labels, series, optional horizontal line (value, label).
#[derive(Default)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub hline: Option<(f64, String)>,
    /// Fixed x range (otherwise from the data).
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range (otherwise from the data), e.g. to leave the legend room.
    pub y_range: Option<(f64, f64)>,
    /// Names of the categories at x = 1, 2, … (the x axis shows them instead of numbers).
    pub x_names: Vec<String>,
}

impl Panel {
    /// A panel of `series` with its title and axis labels (ranges from the data).
    pub fn new(title: impl Into<String>, x_label: &str, y_label: &str, series: Vec<Series>) -> Panel {
        Panel {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series,
            ..Panel::default()
        }
    }
}

/// The x-axis label at `x`: the name of the category at that integer, else nothing.
fn category(names: &[String], x: f64) -> String {
    let i = x.round();
    if (x - i).abs() < 1e-6 && i >= 1.0 && i as usize <= names.len() {
        names[i as usize - 1].clone()
    } else {
        String::new()
    }
}

fn bounds(panel: &Panel) -> ((f64, f64), (f64, f64)) {
    let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ys = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &panel.series {
        for &(x, y) in &s.points {
            if x.is_finite() && y.is_finite() {
                xs = (xs.0.min(x), xs.1.max(x));
                ys = (ys.0.min(y), ys.1.max(y));
            }
        }
    }
    if let Some((h, _)) = panel.hline {
        ys = (ys.0.min(h), ys.1.max(h));
    }
    if !xs.0.is_finite() {
        xs = (0.0, 1.0);
        ys = (0.0, 1.0);
    }
    let pad = |(a, b): (f64, f64), f: f64| {
        let w = (b - a).abs().max(1e-9);
        (a - f * w, b + f * w)
    };
    (pad(xs, 0.02), pad(ys, 0.08))
}

/// One legend entry: its label, colour, and whether the series is markers.
struct Entry<'a> {
    label: &'a str,
    color: RGBColor,
    marker: bool,
}

/// The legend of a panel: every labelled series, then the horizontal line.
fn entries(panel: &Panel) -> Vec<Entry<'_>> {
    let mut out: Vec<Entry> = panel
        .series
        .iter()
        .filter(|s| !s.label.is_empty())
        .map(|s| Entry {
            label: &s.label,
            color: s.color,
            marker: s.markers,
        })
        .collect();
    if let Some((_, label)) = &panel.hline {
        out.push(Entry {
            label,
            color: HLINE,
            marker: false,
        });
    }
    out
}

const LEGEND_FONT: u32 = 13;
const LEGEND_ROW: i32 = 20;

/// The width of the legend column: the widest label and its key, at most 40 %
/// of the panel (longer labels are cut with "…").
fn legend_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[Entry]) -> u32 {
    if entries.is_empty() {
        return 0;
    }
    let font = ("sans-serif", LEGEND_FONT).into_text_style(area);
    let widest = entries
        .iter()
        .filter_map(|e| {
            let head: String = e.label.chars().take(LABEL_CHARS + 1).collect();
            area.estimate_text_size(&head, &font).ok()
        })
        .map(|(w, _)| w)
        .max()
        .unwrap_or(0);
    (widest + 44).min(area.dim_in_pixel().0 * 2 / 5)
}

/// The legend drawn in its own column beside the plot, so that it never covers
/// a point: a marker or a line segment in the series' colour, then the label.
fn draw_legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[Entry], top: i32) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", LEGEND_FONT).into_text_style(area);
    let room = area.dim_in_pixel().0.saturating_sub(40);
    for (i, e) in entries.iter().enumerate() {
        let y = top + LEGEND_ROW * i as i32;
        if e.marker {
            area.draw(&Circle::new((16, y), 4, e.color.filled())).map_err(err)?;
        } else {
            area.draw(&PathElement::new(vec![(6, y), (26, y)], e.color.stroke_width(2)))
                .map_err(err)?;
        }
        let label = fit_label(area, e.label, &font, room);
        area.draw(&Text::new(label, (34, y - 7), font.clone())).map_err(err)?;
    }
    Ok(())
}

/// Labels longer than this are cut before they are measured: no legend column
/// shows as many characters, and measuring a label costs its length.
const LABEL_CHARS: usize = 200;

/// `label`, cut with "…" to the longest prefix that is at most `room` pixels
/// wide with it (a binary search on the prefix's length: a test id of 100,000
/// characters once took minutes, cut one character at a time).
fn fit_label<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, label: &str, font: &TextStyle, room: u32) -> String {
    let wide = |s: &str| area.estimate_text_size(s, font).map(|(w, _)| w > room).unwrap_or(false);
    let chars: Vec<char> = label.chars().take(LABEL_CHARS + 1).collect();
    if chars.len() <= LABEL_CHARS && !wide(label) {
        return label.to_string();
    }
    let cut = |n: usize| format!("{}…", chars[..n].iter().collect::<String>());
    // The longest n in 0..=LABEL_CHARS with cut(n) narrow enough (0 if none is).
    let (mut lo, mut hi) = (0, chars.len().min(LABEL_CHARS));
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if wide(&cut(mid)) {
            hi = mid - 1;
        } else {
            lo = mid;
        }
    }
    cut(lo)
}

/// The colour of a panel's horizontal line.
const HLINE: RGBColor = BLUE;

/// One panel: its title over the whole width, the chart, and its legend in a
/// column `lw` pixels wide at the right (the same for every panel of a figure,
/// so that stacked panels share their x axis).
fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel, lw: u32) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let title_font = ("sans-serif", 18).into_text_style(area);
    let title = fit_label(area, &panel.title, &title_font, area.dim_in_pixel().0.saturating_sub(10));
    let area = area.titled(&title, title_font).map_err(err)?;
    let legend = entries(panel);
    let (plot, side) = area.split_horizontally(area.dim_in_pixel().0 - lw);
    draw_chart(&plot, panel)?;
    draw_legend(&side, &legend, 14)
}

fn draw_chart<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (x, y) = bounds(panel);
    let ((x0, x1), (y0, y1)) = (panel.x_range.unwrap_or(x), panel.y_range.unwrap_or(y));
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let names = |x: &f64| category(&panel.x_names, *x);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style(("sans-serif", 13))
        .light_line_style(RGBColor(235, 235, 235));
    if !panel.x_names.is_empty() {
        mesh.x_labels(panel.x_names.len() + 1).x_label_formatter(&names);
    }
    mesh.draw().map_err(err)?;
    for s in &panel.series {
        let color = s.color;
        if s.markers {
            chart
                .draw_series(s.points.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(err)?;
        } else {
            // Thick polylines of dense series render with gaps in the bitmap
            // backend: one pixel is enough there.
            let width = if s.points.len() > 1500 { 1 } else { 2 };
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), color.stroke_width(width)))
                .map_err(err)?;
        }
    }
    if let Some((h, _)) = &panel.hline {
        chart
            .draw_series(LineSeries::new(vec![(x0, *h), (x1, *h)], HLINE.stroke_width(2)))
            .map_err(err)?;
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, panels: &[Panel]) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let lw = panels.iter().map(|p| legend_width(&root, &entries(p))).max().unwrap_or(0);
    let areas = root.split_evenly((panels.len(), 1));
    for (a, p) in areas.iter().zip(panels) {
        draw_panel(a, p, lw)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// A rendered figure: the SVG text (inlined in the HTML reports) and the PNG bytes.
#[derive(Debug, Clone)]
pub struct Figure {
    pub svg: String,
    pub png: Vec<u8>,
}

impl Figure {
    /// Add `stem.svg` and `stem.png` to the files to write.
    pub fn add_to(&self, files: &mut Files, stem: &str) {
        files.add(format!("{stem}.svg"), self.svg.as_bytes());
        files.add(format!("{stem}.png"), self.png.clone());
    }
}

/// A figure with its caption and the file stem it is written under.
pub struct Captioned {
    pub stem: String,
    pub caption: String,
    pub figure: Figure,
}

/// Render stacked panels as SVG and PNG, `width` wide and `height_per_panel`
/// high per panel.
pub fn render(panels: &[Panel], width: u32, height_per_panel: u32) -> Result<Figure> {
    register_font();
    let size = (width, height_per_panel * panels.len() as u32);
    let mut svg = String::new();
    draw_figure(SVGBackend::with_string(&mut svg, size).into_drawing_area(), panels)?;
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    draw_figure(BitMapBackend::with_buffer(&mut buf, size).into_drawing_area(), panels)?;
    let png = encode_png(&buf, size.0, size.1)?;
    Ok(Figure { svg, png })
}

/// Encode an RGB buffer as PNG (through the `image` crate that plotters' bitmap
/// encoder already brings).
fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, w, h, image::ColorType::Rgb8)
        .map_err(err)?;
    Ok(out)
}

pub const BLACKISH: RGBColor = RGBColor(40, 40, 40);
pub const GREY: RGBColor = RGBColor(150, 150, 150);
pub const RED: RGBColor = RGBColor(214, 39, 40);
pub const BLUE: RGBColor = RGBColor(31, 119, 180);
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
pub const GREEN: RGBColor = RGBColor(44, 160, 44);

pub const PURPLE: RGBColor = RGBColor(148, 103, 189);
pub const BROWN: RGBColor = RGBColor(140, 86, 75);
pub const PINK: RGBColor = RGBColor(227, 119, 194);
pub const OLIVE: RGBColor = RGBColor(188, 189, 34);
pub const CYAN: RGBColor = RGBColor(23, 190, 207);

/// Colours of the tests in a plot of many (cycled; pink is kept for a plot's
/// reference line).
pub const PALETTE: [RGBColor; 6] = [BLUE, RED, GREEN, ORANGE, PURPLE, BROWN];

/// Nine distinct colours for sets that must not share one (a figure of up to
/// nine coefficient sets).
pub const SETS: [RGBColor; 9] = [RED, BLUE, GREEN, ORANGE, PURPLE, BROWN, PINK, OLIVE, CYAN];

/// A law that is not the constant: black with its ±u band over the amplitudes
/// `fitted` (its side's impacts), olive where it is extrapolated (no ±u there:
/// the band is the fit's, not the form's, and nothing vouches for the form
/// beyond its impacts).
fn law_lines(law: &[(f64, f64, f64)], fitted: (f64, f64)) -> Vec<Series> {
    let lg = |a: f64| a.max(1e-9).log10();
    // The curve's samples inside the span, and the parts outside it joined to
    // their neighbouring sample inside (so that the lines meet).
    let i0 = law.iter().position(|p| p.0 >= fitted.0).unwrap_or(law.len());
    let i1 = law.iter().rposition(|p| p.0 <= fitted.1).map_or(0, |i| i + 1);
    let xy = |part: &[(f64, f64, f64)]| -> Vec<(f64, f64)> { part.iter().map(|&(a, r, _)| (lg(a), r)).collect() };
    let inside: &[(f64, f64, f64)] = if i0 < i1 { &law[i0..i1] } else { &[] };
    let below = xy(&law[..(i0 + 1).min(law.len())]);
    let above = xy(&law[i1.saturating_sub(1).min(law.len())..]);
    let mut out = Vec::new();
    let mut label = "law r(a), extrapolated";
    for part in [below, above] {
        if part.len() >= 2 {
            out.push(Series::line(label, OLIVE, part));
            label = "";
        }
    }
    out.push(Series::line("law r(a)", BLACKISH, inside.iter().map(|&(a, r, _)| (lg(a), r)).collect()));
    out.push(Series::line("law ± u", GREY, inside.iter().map(|&(a, r, u)| (lg(a), r + u)).collect()));
    out.push(Series::line("", GREY, inside.iter().map(|&(a, r, u)| (lg(a), r - u)).collect()));
    out
}

/// One panel of the restitution-law plot (issue 20): r of every impact against
/// log₁₀ of its amplitude |θ|/α, one marker colour per test; the law with its ±1 u
/// band; the constant for comparison. `tests`: (legend label, [(a, r)]); `law`: [(a, r, u)].
pub fn law_panel(title: &str, tests: &[(String, Vec<(f64, f64)>)], law: &[(f64, f64, f64)], constant: f64, fitted: (f64, f64)) -> Panel {
    let lg = |a: f64| a.max(1e-9).log10();
    let mut series: Vec<Series> = tests
        .iter()
        .enumerate()
        .map(|(i, (id, pts))| Series::dots(id, PALETTE[i % PALETTE.len()], pts.iter().map(|&(a, r)| (lg(a), r)).collect()))
        .collect();
    // The constant first, so that the law is drawn over it: where the data do not
    // reject the constant the law is that constant and its line must still show.
    // Where the law is that constant, one line says so (the law's would hide it).
    let flat = law.iter().all(|&(_, r, _)| (r - constant).abs() <= 1e-12 * constant.abs().max(1.0));
    let span = law.first().zip(law.last()).map(|(a, b)| (lg(a.0), lg(b.0)));
    if let Some((x0, x1)) = span.filter(|_| !flat) {
        series.push(Series::line(
            &format!("constant r = {constant:.3}"),
            PINK,
            vec![(x0, constant), (x1, constant)],
        ));
    }
    if flat {
        series.push(Series::line(
            &format!("law r(a) = the constant {constant:.3}"),
            BLACKISH,
            law.iter().map(|&(a, r, _)| (lg(a), r)).collect(),
        ));
        series.push(Series::line("law ± u", GREY, law.iter().map(|&(a, r, u)| (lg(a), r + u)).collect()));
        series.push(Series::line("", GREY, law.iter().map(|&(a, r, u)| (lg(a), r - u)).collect()));
    } else {
        series.extend(law_lines(law, fitted));
    }
    Panel::new(
        title,
        "log10 of the amplitude |θ|/α at the apex of the half-cycle the impact ends",
        "r = e / e_H",
        series,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(p: &Panel) -> Vec<&str> {
        p.series.iter().map(|s| s.label.as_str()).filter(|l| !l.is_empty()).collect()
    }

    /// A law that is the constant is one line that says so; a law that is not
    /// is drawn beside the constant.
    #[test]
    fn law_panel_names_a_constant_law_once() {
        let tests = vec![("test t1".to_string(), vec![(0.1, 0.9)])];
        let flat = [(0.01, 0.9, 0.01), (0.3, 0.9, 0.01)];
        assert_eq!(
            labels(&law_panel("x", &tests, &flat, 0.9, (0.01, 0.3))),
            ["test t1", "law r(a) = the constant 0.900", "law ± u"]
        );
        let falling = [(0.01, 0.8, 0.01), (0.3, 0.95, 0.01)];
        assert_eq!(
            labels(&law_panel("x", &tests, &falling, 0.9, (0.01, 0.3))),
            ["test t1", "constant r = 0.900", "law r(a)", "law ± u"]
        );
        // Fitted on a = 0.01–0.03 only: the law above is drawn as extrapolated,
        // without a band, and the band covers the fitted amplitudes alone.
        let curve: Vec<(f64, f64, f64)> = (0..=20)
            .map(|i| 0.01 * 30f64.powf(i as f64 / 20.0))
            .map(|a| (a, 1.0 - 0.01 / a.sqrt(), 0.01))
            .collect();
        let p = law_panel("x", &tests, &curve, 0.9, (0.01, 0.03));
        assert_eq!(
            labels(&p),
            ["test t1", "constant r = 0.900", "law r(a), extrapolated", "law r(a)", "law ± u"]
        );
        let band = p.series.iter().find(|s| s.label == "law ± u").unwrap();
        assert!(band.points.iter().all(|&(x, _)| x <= 0.03f64.log10() + 1e-12));
    }
}
