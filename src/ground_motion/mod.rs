//! Ground-motion records: ESM ASCII, PEER NGA `.AT2` (old and NGA-West2 headers),
//! COSMOS V2, two columns (time, acceleration) and one column with a given dt;
//! units g, m/s², cm/s². Readers parse text (`rocklab::ingest::record` reads the
//! file) and name the line of every defect.

use std::path::{Path, PathBuf};

use crate::error::InputError;
use crate::limits;
use crate::G;

/// Acceleration units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Units {
    G,
    MetresPerS2,
    CmPerS2,
}

impl Units {
    /// Factor to m/s².
    pub fn to_m_s2(self) -> f64 {
        match self {
            Units::G => G,
            Units::MetresPerS2 => 1.0,
            Units::CmPerS2 => 0.01,
        }
    }
    pub fn parse(s: &str) -> Option<Units> {
        match s.trim().to_ascii_lowercase().as_str() {
            "g" => Some(Units::G),
            "m/s2" | "m/s^2" | "m/s²" => Some(Units::MetresPerS2),
            "cm/s2" | "cm/s^2" | "cm/s²" | "gal" | "cm/sec2" => Some(Units::CmPerS2),
            _ => None,
        }
    }
}

/// Record formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Format {
    Esm,
    At2,
    Cosmos,
    TwoColumn,
    OneColumn,
}

impl Format {
    /// The names a study file or the Python API uses for a format: `Ok(None)` for
    /// "auto" (detect it), an error naming the accepted names otherwise.
    pub fn from_name(name: &str) -> Result<Option<Format>, UnknownFormat> {
        match name {
            "auto" => Ok(None),
            "esm" => Ok(Some(Format::Esm)),
            "at2" => Ok(Some(Format::At2)),
            "cosmos" => Ok(Some(Format::Cosmos)),
            "two-column" => Ok(Some(Format::TwoColumn)),
            "one-column" => Ok(Some(Format::OneColumn)),
            other => Err(UnknownFormat(other.to_string())),
        }
    }
}

/// A format name that is none of [`Format::from_name`]'s.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("format = {0:?}: expected auto, esm, at2, cosmos, two-column or one-column")]
pub struct UnknownFormat(pub String);

/// A uniformly sampled record, in m/s².
#[derive(Debug, Clone)]
pub struct Record {
    pub path: PathBuf,
    pub format: Format,
    pub units: Units,
    pub t0: f64,
    pub dt: f64,
    pub acc_m_s2: Vec<f64>,
    /// Header facts worth printing (station, event, licence, …).
    pub notes: Vec<String>,
}

impl Record {
    /// Duration of the record (s).
    pub fn duration(&self) -> f64 {
        self.dt * self.acc_m_s2.len().saturating_sub(1) as f64
    }
    /// Peak ground acceleration in g (of the record times `scale`).
    pub fn pga_g(&self, scale: f64) -> f64 {
        self.acc_m_s2.iter().fold(0.0f64, |m, a| m.max(a.abs())) * scale.abs() / G
    }
    /// Peak ground velocity in cm/s, by trapezoidal integration of the record.
    pub fn pgv_cm_s(&self, scale: f64) -> f64 {
        let mut v = 0.0f64;
        let mut peak = 0.0f64;
        for w in self.acc_m_s2.windows(2) {
            v += 0.5 * (w[0] + w[1]) * self.dt;
            peak = peak.max(v.abs());
        }
        peak * 100.0 * scale.abs()
    }
}

/// What the user told about a record.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    pub format: Option<Format>,
    pub dt: Option<f64>,
    pub units: Option<Units>,
}

/// A defect at a line; the message is cut to 300 characters (issue 22: it may
/// quote a header line or a token of any length).
fn err(path: &Path, line: usize, message: impl Into<String>) -> InputError {
    InputError::Line {
        file: path.to_path_buf(),
        line: line as u64,
        message: crate::error::excerpt_text(&message.into(), 300),
    }
}

/// Lines of a text with any of LF, CRLF, CR CR LF or CR line ends (1-based numbers).
fn lines(text: &str) -> Vec<&str> {
    let t = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out: Vec<&str> = t.split('\n').map(|l| l.trim_end_matches('\r')).collect();
    if out.len() == 1 && t.contains('\r') {
        out = t.split('\r').collect();
    }
    while out.last().is_some_and(|l| l.trim().is_empty()) {
        out.pop();
    }
    out
}

/// Detect the format from the text.
pub fn detect(text: &str) -> Option<Format> {
    let ls = lines(text);
    if ls.iter().take(100).any(|l| l.starts_with("SAMPLING_INTERVAL_S:")) {
        return Some(Format::Esm);
    }
    if ls
        .first()
        .is_some_and(|l| l.contains("(Format v") || l.to_ascii_lowercase().contains("text lines"))
    {
        return Some(Format::Cosmos);
    }
    if ls.get(3).is_some_and(|l| l.to_ascii_uppercase().contains("NPTS")) {
        return Some(Format::At2);
    }
    let first_data = ls.iter().find(|l| !l.trim().is_empty() && numbers(l).is_ok())?;
    match numbers(first_data).ok()?.len() {
        1 => Some(Format::OneColumn),
        2 => Some(Format::TwoColumn),
        _ => None,
    }
}

/// Parse record text.
pub fn parse(path: &Path, text: &str, opts: &ReadOptions) -> Result<Record, InputError> {
    let format = match opts.format {
        Some(f) => f,
        None => detect(text).ok_or_else(|| InputError::File {
            file: path.to_path_buf(),
            message: "format not recognised (expected ESM ASCII, PEER .AT2, COSMOS V2, two columns or one column): pass --format".into(),
        })?,
    };
    let ls = lines(text);
    let mut rec = match format {
        Format::Esm => esm(path, &ls)?,
        Format::At2 => at2(path, &ls)?,
        Format::Cosmos => cosmos(path, &ls)?,
        Format::TwoColumn => two_column(path, &ls)?,
        Format::OneColumn => {
            let dt = opts.dt.ok_or_else(|| InputError::File {
                file: path.to_path_buf(),
                message: "a one-column record has no time step: pass --dt".into(),
            })?;
            let (vals, _) = column_values(path, &ls, 0)?;
            Record {
                path: path.into(),
                format,
                units: Units::G,
                t0: 0.0,
                dt,
                acc_m_s2: vals,
                notes: Vec::new(),
            }
        }
    };
    if let Some(dt) = opts.dt {
        if format != Format::OneColumn && (dt - rec.dt).abs() > 1e-9 * rec.dt {
            return Err(InputError::File {
                file: path.to_path_buf(),
                message: format!("--dt {dt} disagrees with the file's time step {}", rec.dt),
            });
        }
    }
    let header_units = matches!(format, Format::Esm | Format::At2 | Format::Cosmos);
    let units = match (opts.units, header_units) {
        (Some(u), _) => u,
        (None, true) => rec.units,
        (None, false) => {
            return Err(InputError::File {
                file: path.to_path_buf(),
                message: "the units of a column record are not in the file: pass --units g|m/s2|cm/s2".into(),
            })
        }
    };
    if !(rec.dt > 0.0 && rec.dt.is_finite()) {
        return Err(InputError::File {
            file: path.to_path_buf(),
            message: format!("time step {} is not positive", rec.dt),
        });
    }
    if rec.acc_m_s2.len() < 2 {
        return Err(InputError::File {
            file: path.to_path_buf(),
            message: "fewer than two samples".into(),
        });
    }
    let k = units.to_m_s2();
    for a in rec.acc_m_s2.iter_mut() {
        *a *= k;
    }
    rec.units = units;
    check_ranges(path, &rec)?;
    Ok(rec)
}

/// The record within the physical ranges of [`crate::limits`] (issue 22: a sample
/// of 10³⁰ g or a record scaled by 10³⁰⁰ made the solver retry without end).
fn check_ranges(path: &Path, rec: &Record) -> Result<(), InputError> {
    let fail = |message: String| {
        Err(InputError::File {
            file: path.to_path_buf(),
            message,
        })
    };
    if !limits::RECORD_DT_S.contains(rec.dt) {
        return fail(format!("time step {} s: expected a value {}", rec.dt, limits::RECORD_DT_S.describe()));
    }
    if rec.acc_m_s2.len() > limits::RECORD_SAMPLES {
        return fail(format!("{} samples: expected at most {}", rec.acc_m_s2.len(), limits::RECORD_SAMPLES));
    }
    let max = limits::RECORD_ACCEL_G.hi * G;
    if let Some((i, a)) = rec.acc_m_s2.iter().enumerate().find(|(_, a)| a.abs() > max) {
        return fail(format!(
            "sample {} (t = {} s) is {:e} g: expected |a| ≤ {} g (wrong units? pass --units)",
            i + 1,
            rec.t0 + i as f64 * rec.dt,
            a / G,
            limits::RECORD_ACCEL_G.hi
        ));
    }
    Ok(())
}

/// Numbers of a line; Fortran fields that run together ("-.12E-03-.34E-03") are
/// split at a sign that does not follow an exponent mark.
fn numbers(line: &str) -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    let mut tok = String::new();
    let flush = |tok: &mut String, out: &mut Vec<f64>| -> Result<(), String> {
        if !tok.is_empty() {
            let v: f64 = tok
                .replace(['D', 'd'], "E")
                .parse()
                .map_err(|_| format!("'{}' is not a number", crate::error::excerpt(tok, 60)))?;
            if !v.is_finite() {
                return Err(format!("'{}' is not a finite number", crate::error::excerpt(tok, 60)));
            }
            out.push(v);
            tok.clear();
        }
        Ok(())
    };
    let mut prev = ' ';
    for c in line.chars() {
        if c.is_whitespace() || c == ',' || c == ';' {
            flush(&mut tok, &mut out)?;
        } else if (c == '-' || c == '+') && !tok.is_empty() && !matches!(prev, 'E' | 'e' | 'D' | 'd') {
            flush(&mut tok, &mut out)?;
            tok.push(c);
        } else {
            tok.push(c);
        }
        prev = c;
    }
    flush(&mut tok, &mut out)?;
    Ok(out)
}

/// All numbers from line `from` (0-based) to the end, with the line of each.
fn values_from(path: &Path, ls: &[&str], from: usize, stop_at: Option<&str>) -> Result<Vec<f64>, InputError> {
    let mut out = Vec::new();
    for (i, l) in ls.iter().enumerate().skip(from) {
        if stop_at.is_some_and(|s| l.starts_with(s)) {
            break;
        }
        out.extend(numbers(l).map_err(|m| err(path, i + 1, format!("{m}: expected acceleration values")))?);
    }
    Ok(out)
}

fn header_value<'a>(ls: &[&'a str], key: &str) -> Option<(usize, &'a str)> {
    ls.iter().enumerate().find_map(|(i, l)| l.strip_prefix(key).map(|v| (i, v.trim())))
}

fn esm(path: &Path, ls: &[&str]) -> Result<Record, InputError> {
    let (li, dt_s) = header_value(ls, "SAMPLING_INTERVAL_S:").ok_or_else(|| err(path, 1, "no SAMPLING_INTERVAL_S header"))?;
    let dt: f64 = dt_s
        .parse()
        .map_err(|_| err(path, li + 1, format!("SAMPLING_INTERVAL_S '{dt_s}' is not a number")))?;
    let units = match header_value(ls, "UNITS:") {
        Some((ui, u)) => Units::parse(u).ok_or_else(|| err(path, ui + 1, format!("UNITS '{u}': expected cm/s^2, m/s^2 or g")))?,
        None => return Err(err(path, 1, "no UNITS header")),
    };
    let first = ls
        .iter()
        .position(|l| !l.contains(':') && !l.trim().is_empty())
        .ok_or_else(|| err(path, ls.len(), "no data after the header"))?;
    let vals = values_from(path, ls, first, None)?;
    if let Some((ni, n)) = header_value(ls, "NDATA:") {
        if n.parse::<usize>().ok() != Some(vals.len()) {
            return Err(err(path, ni + 1, format!("NDATA {n} but {} values follow (truncated file?)", vals.len())));
        }
    }
    let mut notes = Vec::new();
    for key in [
        "EVENT_NAME:",
        "EVENT_DATE_YYYYMMDD:",
        "STATION_CODE:",
        "STREAM:",
        "DATA_LICENSE:",
        "DATA_CITATION:",
    ] {
        if let Some((_, v)) = header_value(ls, key) {
            notes.push(format!("{} {v}", key.trim_end_matches(':')));
        }
    }
    Ok(Record {
        path: path.into(),
        format: Format::Esm,
        units,
        t0: 0.0,
        dt,
        acc_m_s2: vals,
        notes,
    })
}

fn at2(path: &Path, ls: &[&str]) -> Result<Record, InputError> {
    if ls.len() < 5 {
        return Err(err(path, ls.len().max(1), "an AT2 file has 4 header lines, then values"));
    }
    let units = if ls[2].to_ascii_uppercase().contains("UNITS OF G") {
        Units::G
    } else if let Some(u) = ls[2]
        .to_ascii_uppercase()
        .split("UNITS OF")
        .nth(1)
        .and_then(|s| Units::parse(s.split_whitespace().next().unwrap_or("")))
    {
        u
    } else {
        return Err(err(path, 3, "expected 'UNITS OF G' on the third header line"));
    };
    let h = ls[3].to_ascii_uppercase();
    let (npts, dt) = if h.contains("NPTS=") || h.contains("NPTS =") {
        let grab = |key: &str| -> Option<f64> {
            let rest = h.split(key).nth(1)?;
            let rest = rest.trim_start_matches([' ', '=']);
            let num: String = rest
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == 'E' || *c == '-' || *c == '+')
                .collect();
            num.parse().ok()
        };
        (grab("NPTS"), grab("DT"))
    } else {
        let n = numbers(h.split("NPTS").next().unwrap_or("")).unwrap_or_default();
        (n.first().copied(), n.get(1).copied())
    };
    let (npts, dt) = match (npts, dt) {
        (Some(n), Some(d)) => (n as usize, d),
        _ => return Err(err(path, 4, format!("cannot read NPTS and DT from '{}'", ls[3].trim()))),
    };
    let vals = values_from(path, ls, 4, None)?;
    if vals.len() != npts {
        return Err(err(path, ls.len(), format!("NPTS = {npts} but {} values were read", vals.len())));
    }
    Ok(Record {
        path: path.into(),
        format: Format::At2,
        units,
        t0: 0.0,
        dt,
        acc_m_s2: vals,
        notes: vec![ls[1].trim().to_string()],
    })
}

fn cosmos(path: &Path, ls: &[&str]) -> Result<Record, InputError> {
    // 13 text lines; integer-header count line; ints; real-header count line; reals;
    // comment count line; comments; data count line; data; "End-of-data".
    let count_of = |i: usize, what: &str| -> Result<usize, InputError> {
        ls.get(i)
            .and_then(|l| l.split_whitespace().next())
            .and_then(|n| n.parse().ok())
            .ok_or_else(|| err(path, i + 1, format!("expected the number of {what}")))
    };
    let mut i = 13;
    let nint = count_of(i, "integer-header values")?;
    i += 1 + nint.div_ceil(10);
    let nreal = count_of(i, "real-header values")?;
    let reals = values_from(path, &ls[..(i + 1 + nreal.div_ceil(5)).min(ls.len())], i + 1, None)?;
    i += 1 + nreal.div_ceil(5);
    let dt_ms = *reals.get(61).ok_or_else(|| err(path, i, "real header #62 (sampling interval) missing"))?;
    let ncom = count_of(i, "comment lines")?;
    i += 1 + ncom;
    let npts = count_of(i, "acceleration points")?;
    let units_line = ls[i].to_ascii_lowercase();
    let units = if units_line.contains("cm/sec2") || units_line.contains("cm/s2") {
        Units::CmPerS2
    } else if units_line.contains("units=g") {
        Units::G
    } else {
        return Err(err(path, i + 1, "units not recognised (expected cm/sec2 or g)"));
    };
    let vals = values_from(path, ls, i + 1, Some("End-of-data"))?;
    if vals.len() != npts {
        return Err(err(path, i + 1, format!("{npts} points announced but {} read", vals.len())));
    }
    Ok(Record {
        path: path.into(),
        format: Format::Cosmos,
        units,
        t0: 0.0,
        dt: dt_ms / 1000.0,
        acc_m_s2: vals,
        notes: vec![ls[1].trim().to_string()],
    })
}

/// Values of column `col` of numeric lines, skipping leading non-numeric header
/// lines; every later line must be numeric.
fn column_values(path: &Path, ls: &[&str], col: usize) -> Result<(Vec<f64>, Vec<f64>), InputError> {
    let first = ls
        .iter()
        .position(|l| numbers(l).is_ok_and(|v| !v.is_empty()))
        .ok_or_else(|| err(path, 1, "no numeric lines"))?;
    let mut a = Vec::new();
    let mut other = Vec::new();
    let width = numbers(ls[first]).unwrap_or_default().len();
    for (i, l) in ls.iter().enumerate().skip(first) {
        if l.trim().is_empty() {
            continue;
        }
        let v = numbers(l).map_err(|m| err(path, i + 1, format!("{m}: expected {width} number(s)")))?;
        if v.len() != width {
            return Err(err(path, i + 1, format!("{} values: expected {width}", v.len())));
        }
        a.push(v[col]);
        if width > 1 {
            other.push(v[1 - col]);
        }
    }
    Ok((a, other))
}

fn two_column(path: &Path, ls: &[&str]) -> Result<Record, InputError> {
    let (t, acc) = column_values(path, ls, 0)?;
    if t.len() < 2 {
        return Err(err(path, ls.len(), "fewer than two samples"));
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    for (k, w) in t.windows(2).enumerate() {
        if ((w[1] - w[0]) - dt).abs() > 1e-6 * dt.max(1e-12) + 1e-9 {
            return Err(InputError::File {
                file: path.to_path_buf(),
                message: format!(
                    "time step changes at sample {} ({} s, expected {dt} s): uniform sampling expected",
                    k + 2,
                    w[1] - w[0]
                ),
            });
        }
    }
    Ok(Record {
        path: path.into(),
        format: Format::TwoColumn,
        units: Units::G,
        t0: t[0],
        dt,
        acc_m_s2: acc,
        notes: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_together_fortran_numbers() {
        assert_eq!(numbers("-.12E-03-.34E+02 .5").unwrap(), vec![-0.12e-3, -0.34e2, 0.5]);
        assert!(numbers("1.2.3").is_err());
    }
}
