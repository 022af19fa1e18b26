//! A campaign manifest drafted from a folder of logs (`rocklab init`).
//!
//! Each text log (`.csv`, `.txt`, `.tsv`, `.dat`, `.asc`) is surveyed: its
//! delimiter and decimal mark (the reader's own detection,
//! [`LogReader::resolve_format`]), the time and displacement columns (by name:
//! `time…`/`t_…`, and `disp…`/`lvdt…`, or the only other column), their units (from
//! the column's name, `time_s`, `disp [mm]`, else from a `# … name [unit]` metadata
//! line; a time unit named nowhere is inferred from the step: a step of 1e-4–0.05
//! is seconds, 0.1–50 milliseconds), the sampling rate (median step), and the
//! outward sign when the header says `positive = outward` (or inward). The log is
//! then read with what was detected, so a log that `reduce` could not read is
//! listed as skipped with the reader's message instead of becoming a test.
//!
//! What a log cannot say (the wall's geometry, the sensor's height, one- or
//! two-sided rocking, an outward sign the header does not state) is written as a
//! string that starts with [`FILL_IN`]. TOML parses it; [`check_filled`] (called by
//! the manifest's parser) refuses the manifest, naming the key and its line, until
//! each is replaced by a value.

use std::path::Path;

use super::log::{Decimal, Delimiter, LogFormat, LogReader};
use crate::error::FileError;

/// How a value left for the user starts.
pub const FILL_IN: &str = "fill in";

/// Extensions of the text logs `init` reads.
const TEXT_LOGS: &[&str] = &["csv", "txt", "tsv", "dat", "asc"];

/// Extensions of logs in other formats: listed in the manifest as not drafted.
const OTHER_LOGS: &[&str] = &["xlsx", "xls", "tdms", "mat", "parquet", "h5", "hdf5"];

/// A column and its unit (`None`: not detected).
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub column: String,
    pub unit: Option<&'static str>,
    /// Where the unit came from ("the column's name", "a header line", "the step").
    pub unit_from: &'static str,
}

/// What one log says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSurvey {
    /// File name, relative to the folder.
    pub file: String,
    /// Test id: the file's stem.
    pub id: String,
    pub delimiter: Delimiter,
    pub decimal: Decimal,
    pub columns: Vec<String>,
    pub time: Channel,
    /// `None` when no column could be told to be the displacement.
    pub displacement: Option<Channel>,
    /// +1 / −1 when a header line says `positive = outward` / `inward`.
    pub outward_sign: Option<i8>,
    pub rows: usize,
    pub t_first_s: f64,
    pub t_last_s: f64,
    /// Median time step, s.
    pub step_s: f64,
    /// A rate stated in the header (`sampling_rate_Hz: 200`), Hz.
    pub stated_rate_hz: Option<f64>,
    /// The `#` metadata lines.
    pub metadata: Vec<String>,
}

/// A file of the folder that is not drafted as a test, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    pub file: String,
    pub reason: String,
}

/// Survey every log of `dir` (sorted by name): the text logs read, the others listed.
pub fn survey_dir(dir: &Path) -> std::io::Result<(Vec<LogSurvey>, Vec<Skipped>)> {
    let mut names: Vec<String> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .filter_map(|e| e.file_name().to_str().map(str::to_string))
        .collect();
    names.sort();
    let (mut logs, mut skipped) = (Vec::new(), Vec::new());
    for name in names {
        let ext = Path::new(&name).extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if TEXT_LOGS.contains(&ext.as_str()) {
            match survey_log(&name, &std::fs::read(dir.join(&name))?) {
                Ok(s) => logs.push(s),
                Err(reason) => skipped.push(Skipped { file: name, reason }),
            }
        } else if OTHER_LOGS.contains(&ext.as_str()) {
            skipped.push(Skipped {
                file: name,
                reason: format!("a .{ext} log: `init` drafts text logs only; add its [[test]] by hand"),
            });
        }
    }
    Ok((logs, skipped))
}

/// Survey one text log from its bytes; the error is why it cannot be a test.
pub fn survey_log(name: &str, bytes: &[u8]) -> Result<LogSurvey, String> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let text = String::from_utf8_lossy(bytes);
    let metadata: Vec<String> = text
        .lines()
        .filter(|l| l.trim_start().starts_with('#'))
        .map(|l| l.trim().to_string())
        .collect();
    let mut notes = Vec::new();
    let (delimiter, decimal) = LogReader::new(name).resolve_format(bytes, &mut notes).map_err(|e| e.to_string())?;
    let header = bytes
        .split(|&b| b == b'\n')
        .find(|l| {
            let l = String::from_utf8_lossy(l);
            !l.trim().is_empty() && !l.trim_start().starts_with('#')
        })
        .unwrap_or_default();
    let sep = match delimiter {
        Delimiter::Comma => b',',
        Delimiter::Semicolon => b';',
        Delimiter::Tab => b'\t',
    };
    // Each name as the log reader reads it (UTF-8, else Latin-1).
    let columns: Vec<String> = header
        .split(|&b| b == sep)
        .map(|c| crate::ingest::log::header_name(c).trim().trim_matches('"').to_string())
        .collect();
    let time_col = columns
        .iter()
        .find(|c| is_time(c))
        .ok_or_else(|| format!("{name}: no time column (columns: {}): name it time_s or time_ms", columns.join(", ")))?;
    let displacement = displacement_column(&columns, time_col, &metadata);
    let mut time = channel(time_col, &metadata, time_unit);
    // Read with what was detected: a log `reduce` cannot read is not a test.
    let disp_col = displacement.as_ref().map_or_else(
        || columns.iter().find(|c| *c != time_col).cloned().unwrap_or_default(),
        |d| d.column.clone(),
    );
    // A time unit named nowhere: read as seconds, else as milliseconds (the reader
    // refuses a rate outside its physical range); the step decides below.
    let scales: &[f64] = match time.unit {
        Some("ms") => &[1e-3],
        Some(_) => &[1.0],
        None => &[1.0, 1e-3],
    };
    let read = |to_s: f64| {
        LogReader::new(name)
            .format(LogFormat {
                delimiter: Some(delimiter),
                decimal: Some(decimal),
            })
            .time(&time.column, to_s)
            .displacement(&disp_col, 1.0)
            .parse(bytes)
            .map(|d| (to_s, d))
            .map_err(|e| e.to_string())
    };
    let (to_s, data) = scales[1..].iter().fold(read(scales[0]), |got, &k| got.or_else(|_| read(k)))?;
    let raw_step = median_step(&data.time_s) / to_s;
    if time.unit.is_none() {
        (time.unit, time.unit_from) = match raw_step {
            s if (1e-4..=0.05).contains(&s) => (Some("s"), "the step"),
            s if (0.1..=50.0).contains(&s) => (Some("ms"), "the step"),
            _ => (None, "nowhere"),
        };
    }
    let step_s = raw_step * if time.unit == Some("ms") { 1e-3 } else { 1.0 };
    let scale = step_s / raw_step.max(f64::MIN_POSITIVE);
    Ok(LogSurvey {
        file: name.to_string(),
        id: Path::new(name).file_stem().and_then(|s| s.to_str()).unwrap_or(name).to_string(),
        delimiter,
        decimal,
        columns: columns.clone(),
        time,
        displacement,
        outward_sign: outward_sign(&metadata),
        rows: data.time_s.len(),
        t_first_s: data.time_s.first().copied().unwrap_or(0.0) / to_s * scale,
        t_last_s: data.time_s.last().copied().unwrap_or(0.0) / to_s * scale,
        step_s,
        stated_rate_hz: stated_rate(&metadata),
        metadata,
    })
}

/// Whether a column's name says it is time.
fn is_time(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.contains("time") || n == "t" || ["t_", "t ", "t[", "t("].iter().any(|p| n.starts_with(p))
}

/// The displacement column: by name, else the only one in a length unit, else the
/// only column beside time.
fn displacement_column(columns: &[String], time: &str, metadata: &[String]) -> Option<Channel> {
    let others: Vec<&String> = columns.iter().filter(|c| *c != time && !c.is_empty()).collect();
    let named = others.iter().find(|c| {
        let n = c.to_ascii_lowercase();
        ["disp", "lvdt", "spost", "x_mm", "d_mm"].iter().any(|k| n.contains(k))
    });
    let lengths: Vec<&&String> = others.iter().filter(|c| channel(c, metadata, length_unit).unit.is_some()).collect();
    let col = named
        .copied()
        .or(if lengths.len() == 1 { Some(*lengths[0]) } else { None })
        .or(if others.len() == 1 { Some(others[0]) } else { None })?;
    Some(channel(col, metadata, length_unit))
}

/// A column with its unit from its name, else from a `# … name [unit]` line.
fn channel(column: &str, metadata: &[String], unit: fn(&str) -> Option<&'static str>) -> Channel {
    if let Some(u) = unit_in_name(column).and_then(unit) {
        return Channel {
            column: column.into(),
            unit: Some(u),
            unit_from: "the column's name",
        };
    }
    // `name [unit]`, the name standing as a word of its own.
    let stated = metadata.iter().find_map(|l| {
        l.match_indices(column).find_map(|(i, _)| {
            let word_start = !l[..i].chars().next_back().is_some_and(|c| c.is_alphanumeric() || c == '_');
            let inner = l[i + column.len()..].trim_start().strip_prefix('[')?.split(']').next()?;
            unit(inner.trim()).filter(|_| word_start)
        })
    });
    match stated {
        Some(u) => Channel {
            column: column.into(),
            unit: Some(u),
            unit_from: "a header line",
        },
        None => Channel {
            column: column.into(),
            unit: None,
            unit_from: "nowhere",
        },
    }
}

/// The unit a column's name carries: `time_s`, `disp (mm)`, `x [m]`.
fn unit_in_name(name: &str) -> Option<&str> {
    let n = name.trim();
    if let Some(open) = n.rfind(['[', '(']) {
        return Some(n[open + 1..].trim_end_matches([']', ')']).trim());
    }
    n.rsplit_once('_').map(|(_, u)| u)
}

fn time_unit(u: &str) -> Option<&'static str> {
    match u.to_ascii_lowercase().as_str() {
        "s" | "sec" => Some("s"),
        "ms" | "msec" => Some("ms"),
        _ => None,
    }
}

fn length_unit(u: &str) -> Option<&'static str> {
    match u.to_ascii_lowercase().as_str() {
        "mm" => Some("mm"),
        "m" => Some("m"),
        _ => None,
    }
}

/// +1 or −1 from a header line that says `positive = outward` / `inward`.
fn outward_sign(metadata: &[String]) -> Option<i8> {
    let said = |word: &str| {
        metadata.iter().any(|l| {
            let l = l.to_ascii_lowercase().replace(' ', "");
            l.contains(&format!("positive={word}")) || l.contains(&format!("positive:{word}"))
        })
    };
    match (said("outward"), said("inward")) {
        (true, false) => Some(1),
        (false, true) => Some(-1),
        _ => None,
    }
}

/// A rate the header states: a line with "rate" or "hz" and a number.
fn stated_rate(metadata: &[String]) -> Option<f64> {
    metadata.iter().find_map(|l| {
        let low = l.to_ascii_lowercase();
        if !(low.contains("rate") || low.contains("hz")) {
            return None;
        }
        low.split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .find_map(|w| w.parse::<f64>().ok().filter(|v| *v > 0.0))
    })
}

/// Median of the steps of an increasing time series.
fn median_step(t: &[f64]) -> f64 {
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return f64::NAN;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

/// A TOML basic string.
fn quoted(s: &str) -> String {
    format!("{s:?}")
}

fn fill(what: &str) -> String {
    quoted(&format!("{FILL_IN}: {what}"))
}

fn delimiter_toml(d: Delimiter) -> &'static str {
    match d {
        Delimiter::Comma => "\",\"",
        Delimiter::Semicolon => "\";\"",
        Delimiter::Tab => "\"\\t\"",
    }
}

fn decimal_toml(d: Decimal) -> &'static str {
    match d {
        Decimal::Point => "\".\"",
        Decimal::Comma => "\",\"",
    }
}

const SENSOR_HEIGHT: &str = "height of the displacement sensor above the base, m";

fn time_toml(c: &Channel) -> String {
    let unit = c.unit.map_or_else(|| fill("s or ms"), quoted);
    format!("{{ column = {}, unit = {unit} }}", quoted(&c.column))
}

fn displacement_toml(c: Option<&Channel>, columns: &[String]) -> String {
    match c {
        Some(c) => format!(
            "{{ column = {}, unit = {}, height_m = {} }}",
            quoted(&c.column),
            c.unit.map_or_else(|| fill("mm or m"), quoted),
            fill(SENSOR_HEIGHT)
        ),
        None => format!(
            "{{ column = {}, unit = {}, height_m = {} }}",
            fill(&format!("the displacement column, one of {}", columns.join(", "))),
            fill("mm or m"),
            fill(SENSOR_HEIGHT)
        ),
    }
}

/// Where each detected value came from, as a comment.
fn detected(c: &Channel) -> String {
    match c.unit {
        Some(_) => format!("unit from {}", c.unit_from),
        None => "unit not stated in the log".into(),
    }
}

/// The manifest's text: the campaign's tables from the first log, a `[[test]]` per
/// log (overriding what differs from the first), the skipped files as comments.
pub fn manifest_text(name: &str, logs: &[LogSurvey], skipped: &[Skipped]) -> String {
    let mut o = String::new();
    o.push_str("# Campaign manifest drafted by `rocklab init` from the logs in this folder.\n");
    o.push_str("# Replace every \"fill in: …\" by a value (`rocklab reduce` refuses the manifest,\n");
    o.push_str("# naming the key, until then), check what was detected, then run\n");
    o.push_str("#   rocklab reduce campaign.toml --out report\n\n");
    o.push_str(&format!(
        "[campaign]\nname = {}\nrocking = {}\n\n",
        quoted(name),
        fill("one-sided or two-sided")
    ));
    o.push_str("[wall]\n");
    o.push_str(&format!("height_m = {}\n", fill("height of the wall above its base, m")));
    o.push_str(&format!("thickness_m = {}\n", fill("thickness of the wall, m")));
    o.push_str(&format!(
        "hinge_height_m = {}\n",
        fill("height of the hinge (the rocking crack) above the base, m; 0 at the base")
    ));
    o.push_str("# width_m = 0.0      # optional, reported only\n# weight_kN = 0.0    # optional, reported only\n\n");
    let Some(first) = logs.first() else {
        o.push_str("# No text log (.csv, .txt, .tsv, .dat, .asc) was found in this folder.\n");
        push_skipped(&mut o, skipped);
        return o;
    };
    o.push_str("[channels]\n");
    o.push_str(&format!("time = {}    # {}\n", time_toml(&first.time), detected(&first.time)));
    let disp_note = first.displacement.as_ref().map_or("column not told apart".into(), detected);
    o.push_str(&format!(
        "displacement = {}    # {disp_note}\n",
        displacement_toml(first.displacement.as_ref(), &first.columns)
    ));
    match first.outward_sign {
        Some(s) => o.push_str(&format!(
            "outward_sign = {s}    # the log's header says positive = {}\n",
            if s > 0 { "outward" } else { "inward" }
        )),
        None => o.push_str(&format!(
            "outward_sign = {}\n",
            fill("1 if a positive reading means outward (away from the transverse walls), -1 if inward")
        )),
    }
    o.push_str(&format!(
        "\n[format]    # detected from {}\ndelimiter = {}\ndecimal = {}\n",
        first.file,
        delimiter_toml(first.delimiter),
        decimal_toml(first.decimal)
    ));
    o.push_str(ACQUISITION_HINT);
    if !first.metadata.is_empty() {
        o.push_str(&format!("\n# The header of {}:\n", first.file));
        first.metadata.iter().take(12).for_each(|l| o.push_str(&format!("#   {l}\n")));
    }
    for log in logs {
        o.push_str(&test_entry(log, first));
    }
    push_skipped(&mut o, skipped);
    o
}

/// The logger's filter, commented out: `init` cannot read it from a log, and
/// stating it is what makes it cost no accuracy (SPEC `[acquisition]`).
const ACQUISITION_HINT: &str = "
# The data logger's low-pass on the displacement channel, if you know it (its
# datasheet or settings): a stated filter is modelled exactly; without one, each
# log is searched for a filter's signature and the report says what was assumed.
# [acquisition]
# filter = \"bessel\"     # \"bessel\" | \"butterworth\" | \"none\" | \"unknown\"
# order = 4             # 2–8
# cutoff_hz = 50.0      # the −3 dB frequency
";

/// One `[[test]]`: id, file, what differs from the first log, and a comment with
/// its rate, rows and span.
fn test_entry(log: &LogSurvey, first: &LogSurvey) -> String {
    let mut o = format!(
        "\n[[test]]\nid = {}\nfile = {}\nexclude_from_mean = false\n",
        quoted(&log.id),
        quoted(&log.file)
    );
    if log.time != first.time {
        o.push_str(&format!("time = {}    # {}\n", time_toml(&log.time), detected(&log.time)));
    }
    if log.displacement != first.displacement {
        o.push_str(&format!(
            "displacement = {}\n",
            displacement_toml(log.displacement.as_ref(), &log.columns)
        ));
    }
    if log.outward_sign != first.outward_sign {
        match log.outward_sign {
            Some(s) => o.push_str(&format!("outward_sign = {s}    # from the log's header\n")),
            None => o.push_str(&format!("outward_sign = {}\n", fill("1 or -1"))),
        }
    }
    if (log.delimiter, log.decimal) != (first.delimiter, first.decimal) {
        o.push_str(&format!(
            "format = {{ delimiter = {}, decimal = {} }}    # detected\n",
            delimiter_toml(log.delimiter),
            decimal_toml(log.decimal)
        ));
    }
    let stated = log.stated_rate_hz.map_or(String::new(), |r| format!("; the header says {r} Hz"));
    o.push_str(&format!(
        "# {} rows over {:.3}–{:.3} s, {} Hz (median step {} s{stated}); columns: {}\n",
        log.rows,
        log.t_first_s,
        log.t_last_s,
        rate_text(log.step_s),
        (log.step_s * 1e9).round() / 1e9,
        log.columns.join(", ")
    ));
    o
}

/// A rate from a step, to four significant figures.
fn rate_text(step_s: f64) -> String {
    let r = 1.0 / step_s;
    if !r.is_finite() {
        return "?".into();
    }
    let digits = (3 - r.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{r:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn push_skipped(o: &mut String, skipped: &[Skipped]) {
    if skipped.is_empty() {
        return;
    }
    o.push_str("\n# Not drafted as tests:\n");
    for s in skipped {
        o.push_str(&format!("#   {}: {}\n", s.file, s.reason.replace('\n', " ")));
    }
}

/// Refuse a manifest that still holds a value left for the user: the first string
/// value that starts with [`FILL_IN`], with its table, key, line and column.
pub fn check_filled(text: &str, path: &Path) -> Result<(), FileError> {
    let marker = format!("\"{FILL_IN}");
    let mut table = String::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split('#').next().unwrap_or("");
        let trimmed = code.trim();
        if trimmed.starts_with('[') {
            table = trimmed.to_string();
            continue;
        }
        let Some(at) = code.find(&marker) else { continue };
        let key = code[..at].trim_end().trim_end_matches('=').trim_end();
        let key = key.rsplit(['{', ',', ' ']).find(|k| !k.is_empty()).unwrap_or(key);
        let what = code[at + 1..].split('"').next().unwrap_or("");
        let what = what.strip_prefix(FILL_IN).unwrap_or(what).trim_start_matches(':').trim();
        // In an inline table (`displacement = { …, height_m = "fill in…" }`): its key too.
        let outer = code
            .split_once('=')
            .map(|(k, _)| k.trim())
            .filter(|k| *k != key && code[..at].contains('{'));
        let key_path = outer.map_or_else(|| key.to_string(), |o| format!("{o}.{key}"));
        let name = if table.is_empty() { key_path } else { format!("{table}.{key_path}") };
        let line_key = code[..at].trim_end().trim_end_matches('=').trim_end();
        let column = line_key.rfind(key).map_or(1, |p| code[..p].chars().count() + 1);
        return Err(FileError::Invalid {
            file: path.to_path_buf(),
            line: Some(i + 1),
            column: Some(column),
            message: format!("{name} is not filled in yet ({what}): replace \"{FILL_IN}: …\" by the value"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &[u8] = b"# sampling_rate_Hz: 200\n# channels: t [s]; d1 [mm] LVDT, positive = outward\nt;d1;acc_g\n0,000;1,5;0\n0,005;1,4;0\n0,010;1,3;0\n0,015;1,2;0\n";

    #[test]
    fn a_log_says_its_columns_units_format_rate_and_sign() {
        let s = survey_log("w_1.txt", LOG).unwrap();
        assert_eq!((s.delimiter, s.decimal), (Delimiter::Semicolon, Decimal::Comma));
        assert_eq!(
            s.time,
            Channel {
                column: "t".into(),
                unit: Some("s"),
                unit_from: "a header line"
            }
        );
        assert_eq!(s.displacement.as_ref().unwrap().column, "d1");
        assert_eq!(s.displacement.as_ref().unwrap().unit, Some("mm"));
        assert_eq!((s.outward_sign, s.rows, s.stated_rate_hz), (Some(1), 4, Some(200.0)));
        assert!((s.step_s - 0.005).abs() < 1e-12 && rate_text(s.step_s) == "200", "{}", s.step_s);
        assert_eq!(s.id, "w_1");
    }

    // Session 13: a Latin-1 header 'disp_\xb5m' was drafted as column "disp_\u{fffd}m",
    // which no log reader could then find.
    #[test]
    fn a_latin1_header_is_drafted_as_the_reader_reads_it() {
        let s = survey_log("l.csv", b"# Prova n\xb0 1\ntime_s,disp_\xb5m\n0,1\n0.005,1\n0.01,1\n").unwrap();
        assert_eq!(s.displacement.as_ref().unwrap().column, "disp_µm");
        let reader = LogReader::new("l.csv").displacement(&s.displacement.unwrap().column, 1e-3);
        assert_eq!(reader.parse(b"time_s,disp_\xb5m\n0,1000\n0.005,2000\n").unwrap().disp_mm, vec![1.0, 2.0]);
    }

    #[test]
    fn a_time_unit_named_nowhere_is_taken_from_the_step() {
        let s = survey_log("a.csv", b"time,disp_m\n0,0.1\n2,0.1\n4,0.1\n").unwrap();
        assert_eq!((s.time.unit, s.time.unit_from), (Some("ms"), "the step"));
        assert_eq!(s.displacement.unwrap().unit, Some("m"));
        assert!((s.step_s - 0.002).abs() < 1e-15 && (s.t_last_s - 0.004).abs() < 1e-15);
        let s = survey_log("b.csv", b"time,disp\n0,1\n0.001,1\n0.002,1\n").unwrap();
        assert_eq!(s.time.unit, Some("s"));
        assert_eq!(s.displacement.unwrap().unit, None);
    }

    #[test]
    fn a_log_that_cannot_be_read_says_why() {
        let e = survey_log("c.csv", b"time_s,disp_mm\n0,1\n0,2\n").unwrap_err();
        assert!(e.contains("c.csv:3") && e.contains("duplicated"), "{e}");
        let e = survey_log("d.csv", b"a,b\n1,2\n").unwrap_err();
        assert!(e.contains("no time column"), "{e}");
    }

    #[test]
    fn the_draft_is_toml_and_is_refused_until_filled() {
        let s = survey_log("w_1.txt", LOG).unwrap();
        let text = manifest_text("w", &[s], &[]);
        let table: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(table["channels"]["outward_sign"].as_integer(), Some(1));
        let e = check_filled(&text, Path::new("m.toml")).unwrap_err().to_string();
        assert!(
            e.starts_with("m.toml:8:1: [campaign].rocking is not filled in yet (one-sided or two-sided)"),
            "{e}"
        );
        let text = text.replacen(&fill("one-sided or two-sided"), "\"one-sided\"", 1);
        let e = check_filled(&text, Path::new("m.toml")).unwrap_err().to_string();
        assert!(e.contains("[wall].height_m is not filled in yet"), "{e}");
        let text = text
            .lines()
            .map(|l| {
                if l.starts_with("height_m") || l.starts_with("thickness_m") || l.starts_with("hinge_height_m") {
                    "x = 1"
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let e = check_filled(&text, Path::new("m.toml")).unwrap_err().to_string();
        assert!(
            e.contains("[channels].displacement.height_m is not filled in yet (height of the displacement sensor"),
            "{e}"
        );
        assert!(check_filled(&text.replace(&fill(SENSOR_HEIGHT), "2.5"), Path::new("m.toml")).is_ok());
    }

    /// The logger's filter is offered commented out; uncommented as it stands it is
    /// the SPEC's `[acquisition]` table (a stated Bessel-4 at 50 Hz), ahead of the tests.
    #[test]
    fn the_draft_offers_the_loggers_filter() {
        let s = survey_log("w_1.txt", LOG).unwrap();
        let text = manifest_text("w", &[s], &[]);
        let table: toml::Table = toml::from_str(&text).unwrap();
        assert!(!table.contains_key("acquisition"), "stated without the lab saying so");
        let hint: Vec<&str> = ACQUISITION_HINT
            .lines()
            .filter_map(|l| l.strip_prefix("# "))
            .skip_while(|l| !l.starts_with('['))
            .collect();
        let stated: toml::Table = toml::from_str(&hint.join("\n")).unwrap();
        let a = stated["acquisition"].as_table().unwrap();
        assert_eq!(
            (a["filter"].as_str(), a["order"].as_integer(), a["cutoff_hz"].as_float()),
            (Some("bessel"), Some(4), Some(50.0))
        );
        assert!(text.find("# [acquisition]").unwrap() < text.find("[[test]]").unwrap());
    }
}
