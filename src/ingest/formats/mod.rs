//! Readers of the loggers' own file formats, chosen by the log's extension: Excel
//! workbooks (`.xlsx`), NI TDMS (`.tdms`), MATLAB v5 and v7.3 (`.mat`) and Parquet
//! (`.parquet`). Each produces the two columns the text reader produces (time in s,
//! displacement in outward mm, [`LogData`]) through [`to_log`], which applies the same
//! checks: finite values, strictly increasing time, at least one row.
//!
//! Crates, and why each (`docs/formats.md` has the details):
//! - Excel: `calamine`, the pure-Rust reader of xlsx/xls/ods, kept up (releases
//!   every few months, wide use).
//! - TDMS: `tdms`, the one pure-Rust TDMS parser on crates.io. It is young and its
//!   parser has a few `unwrap`s, so it is called inside `catch_unwind` and a panic
//!   becomes a located error (tests/formats.rs corrupts files to check it).
//! - MAT v5: `matfile`, a small pure-Rust (nom) parser of v5 numeric arrays.
//! - MAT v7.3 (HDF5 with a 512-byte user block): `hdf5-pure`, a pure-Rust HDF5
//!   reader (no libhdf5, so it builds on a fresh machine), which skips the user block.
//! - Parquet: polars' Parquet reader (polars is already the archive's table engine).
//!
//! Errors name the file and where in it: the sheet, row and column of a workbook; the
//! channel (and group) of a TDMS file; the variable of a MAT file; the column of a
//! Parquet file; and the 1-based row (sample) of a bad value.

use std::path::Path;

use crate::error::InputError;
use crate::reduction::LogData;

mod mat;
mod parquet;
mod tdms;
mod xlsx;

/// A log format other than delimited text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Xlsx,
    Tdms,
    Mat,
    Parquet,
}

impl Kind {
    /// The format of `path` by its extension (case-insensitive); `None` for text.
    pub fn of(path: &Path) -> Option<Kind> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "xlsx" | "xlsm" => Some(Kind::Xlsx),
            "tdms" => Some(Kind::Tdms),
            "mat" => Some(Kind::Mat),
            "parquet" => Some(Kind::Parquet),
            _ => None,
        }
    }
}

/// Where in a structured file the channels are: the sheet of a workbook, the group
/// of a TDMS file (both optional).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Source {
    pub sheet: Option<String>,
    pub group: Option<String>,
}

/// What to read: the file, the channel names and their factors.
#[derive(Debug, Clone)]
pub struct Request<'a> {
    pub file: &'a Path,
    pub time_column: &'a str,
    pub time_scale: f64,
    pub disp_column: &'a str,
    pub disp_scale: f64,
    pub source: &'a Source,
}

/// Two channels as read, in the file's units, and how to name a sample in messages.
pub struct Channels {
    pub time: Vec<f64>,
    pub disp: Vec<f64>,
    /// The time is already in seconds (computed from waveform properties), not in
    /// the manifest's time unit.
    pub time_in_s: bool,
    /// Row (1-based, as the user sees it in the file) of the first sample.
    pub first_row: usize,
    /// "sheet 'log'", "group 'demo'", "" …: the location before the row.
    pub place: String,
    /// What was read and how.
    pub notes: Vec<String>,
}

/// Read a log of format `kind`.
pub fn read(kind: Kind, req: &Request) -> Result<LogData, InputError> {
    if !req.file.exists() {
        return Err(InputError::Missing {
            file: req.file.to_path_buf(),
        });
    }
    if kind != Kind::Xlsx && req.source.sheet.is_some() {
        return Err(err(req.file, "'sheet' is given but the file is not a workbook (.xlsx): remove it".into()));
    }
    if kind != Kind::Tdms && req.source.group.is_some() {
        return Err(err(
            req.file,
            "'group' is given but the file is not a TDMS file (.tdms): remove it".into(),
        ));
    }
    // The format crates parse untrusted bytes; a panic in one of them (a damaged
    // file it did not expect) becomes an error naming the file, never a crash.
    let read = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match kind {
        Kind::Xlsx => xlsx::read(req),
        Kind::Tdms => tdms::read(req),
        Kind::Mat => mat::read(req),
        Kind::Parquet => parquet::read(req),
    }));
    let channels = read.unwrap_or_else(|_| Err(err(req.file, format!("the file is damaged: the {kind:?} reader stopped on it"))))?;
    to_log(req, channels)
}

/// The log from two channels: lengths equal, values finite, time strictly
/// increasing, each error naming the row; then the unit factors applied.
pub fn to_log(req: &Request, ch: Channels) -> Result<LogData, InputError> {
    let file = req.file;
    let place = if ch.place.is_empty() { String::new() } else { format!("{}, ", ch.place) };
    if ch.time.len() != ch.disp.len() {
        return Err(err(
            file,
            format!(
                "{place}time '{}' has {} values, displacement '{}' has {}: expected equal lengths",
                req.time_column,
                ch.time.len(),
                req.disp_column,
                ch.disp.len()
            ),
        ));
    }
    if ch.time.is_empty() {
        return Err(err(file, format!("{place}no data: the channels are empty")));
    }
    for (name, values) in [(req.time_column, &ch.time), (req.disp_column, &ch.disp)] {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(err(
                file,
                format!(
                    "{place}row {}: '{name}' is {}: expected a finite measured value",
                    ch.first_row + i,
                    crate::limits::show(values[i])
                ),
            ));
        }
    }
    if let Some(i) = (1..ch.time.len()).find(|&i| ch.time[i] <= ch.time[i - 1]) {
        let what = if ch.time[i] == ch.time[i - 1] { "duplicated" } else { "decreasing" };
        return Err(err(
            file,
            format!(
                "{place}row {}: '{}' {} is {what} (previous row {}): expected strictly increasing time",
                ch.first_row + i,
                req.time_column,
                crate::limits::show(ch.time[i]),
                crate::limits::show(ch.time[i - 1])
            ),
        ));
    }
    Ok(LogData {
        time_s: if ch.time_in_s {
            ch.time
        } else {
            ch.time.iter().map(|t| t * req.time_scale).collect()
        },
        disp_mm: ch.disp.iter().map(|x| x * req.disp_scale).collect(),
        notes: ch.notes,
        warnings: Vec::new(),
    })
}

/// An error about the whole file (or a place in it that the message names).
pub(crate) fn err(file: &Path, message: String) -> InputError {
    InputError::File {
        file: file.to_path_buf(),
        message,
    }
}

/// "'x' not found (… : a, b, c)": a channel that is not there.
pub(crate) fn not_found(file: &Path, what: &str, name: &str, place: &str, names: &[String]) -> InputError {
    let place = if place.is_empty() { String::new() } else { format!(" in {place}") };
    err(
        file,
        format!(
            "{what} '{name}' not found{place} (there: {}). Set [channels].time/displacement.column or override it in this [[test]]",
            if names.is_empty() { "none".to_string() } else { names.join(", ") }
        ),
    )
}
