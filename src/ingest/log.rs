//! Reader of displacement logs: text exports with optional `#` metadata lines, one
//! header row, then numeric rows; delimiter `,` `;` or tab, decimal `.` or `,`
//! (given or detected), UTF-8 BOM, CRLF, extra columns ignored.
//!
//! The csv crate splits the records (it handles quoting and CRLF and reports line
//! numbers); numbers are parsed here so that a decimal comma costs no copy of the
//! file. Every defect is an [`InputError`] naming the file, line and column.
//! Logs in the loggers' own formats (.xlsx, .tdms, .mat, .parquet, by extension)
//! are handed to `ingest::formats` by [`LogReader::read`].
//!
//! Memory (issue 22): the file is streamed, never held whole. The format is
//! detected on its first [`PREFIX_BYTES`], then the csv reader runs over that
//! prefix chained with the rest of the file, and only the two columns used (time
//! and displacement) are kept, reserved by an estimate of the rows from the file's
//! size and the width of its first rows. A 16-channel 2,000,000-row log (242 MB)
//! reduces in about the memory of its two columns (docs/hardening.md).

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{excerpt, InputError};
pub use crate::reduction::LogData;

/// Field delimiter of a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Delimiter {
    Comma,
    Semicolon,
    Tab,
}

impl Delimiter {
    fn byte(self) -> u8 {
        match self {
            Delimiter::Comma => b',',
            Delimiter::Semicolon => b';',
            Delimiter::Tab => b'\t',
        }
    }
    /// The character, for messages.
    pub fn show(self) -> &'static str {
        match self {
            Delimiter::Comma => "','",
            Delimiter::Semicolon => "';'",
            Delimiter::Tab => "tab",
        }
    }
}

/// Decimal mark of a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Decimal {
    Point,
    Comma,
}

/// Delimiter and decimal mark; `None` means detect from the file.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LogFormat {
    pub delimiter: Option<Delimiter>,
    pub decimal: Option<Decimal>,
}

/// Where the channels are in a log: column indices (0-based) and the header.
struct Columns {
    /// Number of columns the header names.
    n_names: usize,
    /// 1-based line of the header row.
    header_line: u64,
    time: usize,
    disp: usize,
}

/// Builder of a log reader: `LogReader::new(path).time("time_s", 1.0)…read()`.
#[derive(Debug, Clone)]
pub struct LogReader {
    path: PathBuf,
    format: LogFormat,
    time_column: String,
    time_scale: f64,
    disp_column: String,
    disp_scale: f64,
    /// Sheet or group of a structured log (`.xlsx`, `.tdms`; see `ingest::formats`).
    source: crate::ingest::formats::Source,
}

impl LogReader {
    /// Defaults: columns `time_s` (s) and `disp_mm` (mm), outward sign +1, format
    /// detected.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        LogReader {
            path: path.into(),
            format: LogFormat::default(),
            time_column: "time_s".into(),
            time_scale: 1.0,
            disp_column: "disp_mm".into(),
            disp_scale: 1.0,
            source: Default::default(),
        }
    }
    /// Sheet (`.xlsx`) or group (`.tdms`) holding the channels.
    pub fn source(mut self, source: crate::ingest::formats::Source) -> Self {
        self.source = source;
        self
    }
    pub fn format(mut self, f: LogFormat) -> Self {
        self.format = f;
        self
    }
    /// Time column and its factor to seconds.
    pub fn time(mut self, column: &str, to_s: f64) -> Self {
        self.time_column = column.into();
        self.time_scale = to_s;
        self
    }
    /// Displacement column and its factor to outward millimetres (unit × outward_sign).
    pub fn displacement(mut self, column: &str, to_outward_mm: f64) -> Self {
        self.disp_column = column.into();
        self.disp_scale = to_outward_mm;
        self
    }

    /// Read the file, streamed (see the module docs).
    pub fn read(&self) -> Result<LogData, InputError> {
        if let Some(kind) = crate::ingest::formats::Kind::of(&self.path) {
            return crate::ingest::formats::read(kind, &self.request());
        }
        let io = |source| InputError::Io {
            file: self.path.clone(),
            source,
        };
        let f = std::fs::File::open(&self.path).map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                InputError::Missing { file: self.path.clone() }
            } else {
                io(e)
            }
        })?;
        let size = f.metadata().map(|m| m.len()).unwrap_or(0);
        let mut f = std::io::BufReader::with_capacity(1 << 16, f);
        let mut prefix = Vec::new();
        (&mut f).take(PREFIX_BYTES as u64).read_to_end(&mut prefix).map_err(io)?;
        self.parse_stream(&prefix, f, size)
    }

    /// What a structured-format reader needs (`ingest::formats`).
    fn request(&self) -> crate::ingest::formats::Request<'_> {
        crate::ingest::formats::Request {
            file: &self.path,
            time_column: &self.time_column,
            time_scale: self.time_scale,
            disp_column: &self.disp_column,
            disp_scale: self.disp_scale,
            source: &self.source,
        }
    }

    /// Parse the bytes of a log (the path only names it in messages).
    pub fn parse(&self, bytes: &[u8]) -> Result<LogData, InputError> {
        self.parse_stream(bytes, std::io::empty(), bytes.len() as u64)
    }

    /// Parse a log whose first bytes are `prefix` and the rest `rest`; `size` is
    /// the whole length (for the reservation only).
    fn parse_stream(&self, prefix: &[u8], rest: impl Read, size: u64) -> Result<LogData, InputError> {
        let file = &self.path;
        let bytes = prefix.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(prefix);
        let mut rest = LastByte { inner: rest, last: None };
        if bytes.iter().all(|b| b.is_ascii_whitespace()) && size <= prefix.len() as u64 {
            return Err(InputError::Empty { file: file.clone() });
        }
        let mut data = LogData::default();
        let (delimiter, decimal) = self.resolve_format(bytes, &mut data.notes)?;
        let mut rdr = csv::ReaderBuilder::new()
            .delimiter(delimiter.byte())
            .has_headers(false)
            .flexible(true)
            .comment(Some(b'#'))
            // No `.trim(csv::Trim::All)`: it rebuilds every record in a new
            // allocation (a fifth of a 2 M-row read); the header's names, the
            // two cells read and the blank-line test trim their own bytes.
            .from_reader(bytes.chain(&mut rest));
        let mut rec = csv::ByteRecord::new();
        let cols = self.header(&mut rdr, &mut rec, bytes)?;
        let approx_rows = approx_rows(bytes, size);
        data.time_s.reserve(approx_rows);
        data.disp_mm.reserve(approx_rows);
        let defect = self.rows(&mut rdr, &mut rec, &cols, decimal, &mut data)?;
        drop(rdr);
        let last = rest.last.or_else(|| bytes.last().copied());
        if let Some((line, e)) = defect {
            // A defect on a last line without a line end: the export was cut off.
            if last.is_some_and(|b| b == b'\n' || b == b'\r') {
                return Err(e);
            }
            data.warnings.push(format!(
                "{}:{line}: truncated last line (no line end, {e_short}) dropped",
                file.display(),
                e_short = short(&e)
            ));
        }
        if data.time_s.is_empty() {
            return Err(InputError::NoData {
                file: file.clone(),
                line: cols.header_line,
            });
        }
        data.time_s.shrink_to_fit();
        data.disp_mm.shrink_to_fit();
        self.check_rate(&data)?;
        Ok(data)
    }

    /// The mean sampling rate within [`crate::limits::LOG_RATE_HZ`] (issue 22: a
    /// time column scaled by 10⁻⁶ made a fit run without end).
    fn check_rate(&self, data: &LogData) -> Result<(), InputError> {
        let (n, t) = (data.time_s.len(), &data.time_s);
        if n < 2 {
            return Ok(());
        }
        let rate = (n - 1) as f64 / (t[n - 1] - t[0]);
        let range = crate::limits::LOG_RATE_HZ;
        if range.contains(rate) {
            return Ok(());
        }
        Err(InputError::File {
            file: self.path.clone(),
            message: format!(
                "column '{}': a mean sampling rate of {rate:.6e} Hz: expected a rate {} (is [channels].time.unit right?)",
                excerpt(&self.time_column, 60),
                range.describe()
            ),
        })
    }

    /// The next record, or false at the end.
    fn next_record<R: Read>(&self, rdr: &mut csv::Reader<R>, rec: &mut csv::ByteRecord) -> Result<bool, InputError> {
        rdr.read_byte_record(rec).map_err(|e| InputError::File {
            file: self.path.clone(),
            message: format!("not readable as delimited text: {e}"),
        })
    }

    /// Read the header row and find the time and displacement columns.
    fn header<R: Read>(&self, rdr: &mut csv::Reader<R>, rec: &mut csv::ByteRecord, bytes: &[u8]) -> Result<Columns, InputError> {
        let file = &self.path;
        if !self.next_record(rdr, rec)? {
            return Err(InputError::File {
                file: file.clone(),
                message: "only '#' metadata lines: expected a header row and numeric rows".into(),
            });
        }
        // The csv reader does not count skipped '#' lines in the header's position.
        let header_line = header_line_number(bytes);
        let names: Vec<String> = rec.iter().map(|f| header_name(f).trim().to_string()).collect();
        let find = |name: &str, what: &str| {
            names.iter().position(|n| n == name).ok_or_else(|| InputError::Line {
                file: file.clone(),
                line: header_line,
                message: format!(
                    "{what} column '{}' not found (columns: {}). Set [channels].{what}.column or override it in this [[test]]",
                    excerpt(name, 60),
                    shown_names(&names)
                ),
            })
        };
        let time = find(&self.time_column, "time")?;
        let disp = find(&self.disp_column, "displacement")?;
        if time == disp {
            // issue 22: this used to read as "no release found" in every test.
            return Err(InputError::Line {
                file: file.clone(),
                line: header_line,
                message: format!(
                    "the time and the displacement channels both name column '{}' (column {}): expected two different columns. Check [channels].time.column and [channels].displacement.column",
                    excerpt(&self.time_column, 60),
                    time + 1
                ),
            });
        }
        Ok(Columns {
            n_names: names.len(),
            header_line,
            time,
            disp,
        })
    }

    /// Read the numeric rows into `data`. A defective row is an error unless it is
    /// the last one: then it is returned (line, error) for the caller to judge.
    fn rows<R: Read>(
        &self,
        rdr: &mut csv::Reader<R>,
        rec: &mut csv::ByteRecord,
        cols: &Columns,
        decimal: Decimal,
        data: &mut LogData,
    ) -> Result<Option<(u64, InputError)>, InputError> {
        let mut pending: Option<(u64, InputError)> = None;
        let mut buf = Vec::with_capacity(32);
        while self.next_record(rdr, rec)? {
            let line = rec.position().map_or(0, |p| p.line());
            if let Some((_, e)) = pending.take() {
                // A defect that was not on the last line is an error.
                return Err(e);
            }
            if rec.len() == 1 && rec.get(0).is_some_and(|f| f.trim_ascii().is_empty()) {
                continue; // blank line
            }
            match self.row(rec, cols, line, decimal, &mut buf) {
                Ok((t, x, t_raw)) => {
                    if let Some(&prev) = data.time_s.last() {
                        if t <= prev {
                            return Err(self.not_increasing(line, cols, t_raw, t == prev, prev));
                        }
                    }
                    data.time_s.push(t);
                    data.disp_mm.push(x);
                }
                Err(e) => pending = Some((line, e)),
            }
        }
        Ok(pending)
    }

    /// One row: (time in s, displacement in outward mm, time as written).
    fn row(&self, rec: &csv::ByteRecord, cols: &Columns, line: u64, decimal: Decimal, buf: &mut Vec<u8>) -> Result<(f64, f64, f64), InputError> {
        let file = &self.path;
        let (it, id) = (cols.time, cols.disp);
        if rec.len() < it.max(id) + 1 {
            return Err(InputError::At {
                file: file.clone(),
                line,
                column: rec.len() + 1,
                message: format!(
                    "row has {} fields, the header has {}: expected a value for column '{}'",
                    rec.len(),
                    cols.n_names,
                    if rec.len() <= it { &self.time_column } else { &self.disp_column }
                ),
            });
        }
        let t = parse_cell(rec.get(it).unwrap_or(b""), decimal, buf).map_err(|m| at(file, line, it, &self.time_column, m))?;
        let x = parse_cell(rec.get(id).unwrap_or(b""), decimal, buf).map_err(|m| at(file, line, id, &self.disp_column, m))?;
        Ok((t * self.time_scale, x * self.disp_scale, t))
    }

    /// A time that does not increase.
    fn not_increasing(&self, line: u64, cols: &Columns, t_raw: f64, duplicated: bool, prev: f64) -> InputError {
        let what = if duplicated { "duplicated" } else { "decreasing" };
        at(
            &self.path,
            line,
            cols.time,
            &self.time_column,
            format!(
                "time {t_raw} is {what} (previous row {}): expected strictly increasing time",
                prev / self.time_scale
            ),
        )
    }

    /// The delimiter and decimal mark: the manifest's, or detected from the header and
    /// the first rows, each with a note saying which.
    pub fn resolve_format(&self, bytes: &[u8], notes: &mut Vec<String>) -> Result<(Delimiter, Decimal), InputError> {
        let mut lines = bytes
            .split(|b| *b == b'\n')
            .map(|l| l.strip_suffix(b"\r").unwrap_or(l))
            .filter(|l| !l.is_empty() && l[0] != b'#');
        let header = lines.next().unwrap_or(b"");
        let sample: Vec<&[u8]> = lines.take(50).collect();
        let delimiter = match self.format.delimiter {
            Some(d) => {
                notes.push(format!("delimiter {} (manifest)", d.show()));
                d
            }
            None => {
                let d = if header.contains(&b'\t') {
                    Delimiter::Tab
                } else if header.contains(&b';') {
                    Delimiter::Semicolon
                } else if header.contains(&b',') {
                    Delimiter::Comma
                } else {
                    return Err(InputError::File {
                        file: self.path.clone(),
                        message: "cannot detect the delimiter: the header row has no ',', ';' or tab. Set [format].delimiter".into(),
                    });
                };
                notes.push(format!("delimiter {} (detected from the header)", d.show()));
                d
            }
        };
        let decimal = match self.format.decimal {
            Some(d) => {
                notes.push(format!("decimal {:?} (manifest)", d));
                d
            }
            None => {
                let d = if delimiter != Delimiter::Comma && sample.iter().any(|l| l.contains(&b',')) {
                    Decimal::Comma
                } else {
                    Decimal::Point
                };
                notes.push(format!("decimal {:?} (detected from the first rows)", d));
                d
            }
        };
        Ok((delimiter, decimal))
    }
}

/// Bytes of a log read before its format is detected: the header and the first
/// rows the detection samples are in them unless the metadata is unusually long.
pub const PREFIX_BYTES: usize = 1 << 20;

/// A reader that remembers the last byte it gave (whether the file ends with a
/// line end, without holding the file).
struct LastByte<R> {
    inner: R,
    last: Option<u8>,
}

impl<R: Read> Read for LastByte<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n > 0 {
            self.last = Some(buf[n - 1]);
        }
        Ok(n)
    }
}

/// Rows to reserve per kept column: the file's size over the mean length of the
/// prefix's data lines (after the first 8 lines), +5 %; at most 10⁸ rows.
fn approx_rows(prefix: &[u8], size: u64) -> usize {
    let lines: Vec<usize> = prefix.split(|b| *b == b'\n').skip(8).take(200).map(|l| l.len() + 1).collect();
    if lines.len() < 2 {
        return 0;
    }
    let mean = lines.iter().sum::<usize>() as f64 / lines.len() as f64;
    ((size as f64 / mean.max(2.0)) * 1.05).min(1e8) as usize
}

/// The header's names for a message: each at most 40 characters, at most 20 of them.
fn shown_names(names: &[String]) -> String {
    let mut s: Vec<String> = names.iter().take(20).map(|n| excerpt(n, 40)).collect();
    if names.len() > 20 {
        s.push(format!("… {} in all", names.len()));
    }
    s.join(", ")
}

/// 1-based line number of the header: the first line that is neither blank nor a
/// '#' metadata line.
fn header_line_number(bytes: &[u8]) -> u64 {
    let mut line = 1;
    for l in bytes.split(|b| *b == b'\n') {
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        if !l.iter().all(|b| b.is_ascii_whitespace()) && l[0] != b'#' {
            return line;
        }
        line += 1;
    }
    line
}

fn short(e: &InputError) -> String {
    match e {
        InputError::At { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

fn at(file: &Path, line: u64, col0: usize, name: &str, message: String) -> InputError {
    InputError::At {
        file: file.to_path_buf(),
        line,
        column: col0 + 1,
        message: format!("column '{name}': {message}"),
    }
}

/// Parse one numeric cell with the given decimal mark; finite values only.
fn parse_cell(cell: &[u8], decimal: Decimal, buf: &mut Vec<u8>) -> Result<f64, String> {
    let cell = cell.trim_ascii();
    let text = match decimal {
        Decimal::Point => cell,
        Decimal::Comma => {
            buf.clear();
            buf.extend(cell.iter().map(|&b| if b == b',' { b'.' } else { b }));
            buf.as_slice()
        }
    };
    let shown = || excerpt(&String::from_utf8_lossy(cell), 60);
    if text.is_empty() {
        return Err("empty cell: expected a number".into());
    }
    let s = std::str::from_utf8(text).map_err(|_| format!("'{}' is not text: expected a number", shown()))?;
    let v: f64 = s.parse().map_err(|_| {
        let hint = match decimal {
            Decimal::Point if s.contains(',') => " (a decimal comma? set [format].decimal = \",\")",
            _ => "",
        };
        format!("'{}' is not a number{hint}", shown())
    })?;
    if !v.is_finite() {
        return Err(format!("'{}' is not a finite number: expected a measured value", shown()));
    }
    Ok(v)
}

/// A header field as text: UTF-8, else Latin-1 (each byte its character;
/// Windows-1252 agrees on µ, °, ±, é), so that a logger writing 'disp_µm' in
/// Latin-1 matches a manifest's "disp_µm" instead of reading 'disp_\u{fffd}m'.
/// `init` names the columns it drafts by the same rule.
pub(crate) fn header_name(field: &[u8]) -> String {
    match std::str::from_utf8(field) {
        Ok(t) => t.to_string(),
        Err(_) => field.iter().map(|&b| char::from(b)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reader() -> LogReader {
        LogReader::new("t.csv")
    }

    #[test]
    fn reads_metadata_header_and_rows() {
        let d = reader().parse(b"# a\n# b\ntime_s,disp_mm,acc\n0.0,1.5,9\n0.005,1.25,9\n").unwrap();
        assert_eq!(d.time_s, vec![0.0, 0.005]);
        assert_eq!(d.disp_mm, vec![1.5, 1.25]);
    }

    #[test]
    fn detects_semicolon_and_decimal_comma_with_bom_and_crlf() {
        let d = reader()
            .parse("\u{feff}time_s;disp_mm\r\n0,000;1,5\r\n0,005;-2,25\r\n".as_bytes())
            .unwrap();
        assert_eq!(d.time_s, vec![0.0, 0.005]);
        assert_eq!(d.disp_mm, vec![1.5, -2.25]);
        assert!(d.notes.iter().any(|n| n.contains("detected")));
    }

    // Session 13: a logger writing its header in Latin-1 ('disp_\xb5m') could not
    // be matched by any manifest: the name read as 'disp_\u{fffd}m'.
    #[test]
    fn a_latin1_header_matches_its_name() {
        let d = LogReader::new("t.csv")
            .displacement("disp_µm", 1e-3)
            .parse(b"# Prova n\xb0 1\ntime_s,disp_\xb5m\n0,1500\n0.005,1250\n")
            .unwrap();
        assert_eq!(d.disp_mm, vec![1.5, 1.25]);
        let e = reader().parse(b"time_s,disp_\xb5m\n0,1\n").unwrap_err().to_string();
        assert!(e.contains("(columns: time_s, disp_µm)"), "{e}");
    }

    #[test]
    fn tab_delimited() {
        let d = reader().parse(b"disp_mm\ttime_s\n1\t0\n2\t1\n").unwrap();
        assert_eq!(d.disp_mm, vec![1.0, 2.0]);
    }

    #[test]
    fn scales_units_and_sign() {
        let d = LogReader::new("x")
            .time("t", 1e-3)
            .displacement("d", -1e3)
            .parse(b"t,d\n0,0.001\n5,0.002\n")
            .unwrap();
        assert_eq!(d.time_s, vec![0.0, 0.005]);
        assert_eq!(d.disp_mm, vec![-1.0, -2.0]);
    }

    #[test]
    fn non_numeric_cell_names_line_and_column() {
        let e = reader().parse(b"#m\ntime_s,disp_mm\n0,1\n0.1,abc\n").unwrap_err().to_string();
        assert!(e.contains("t.csv:4:2"), "{e}");
        assert!(e.contains("'abc' is not a number"), "{e}");
    }

    #[test]
    fn truncated_last_line_is_dropped_with_a_warning() {
        let d = reader().parse(b"time_s,disp_mm\n0,1\n0.1,2\n0.2").unwrap();
        assert_eq!(d.time_s.len(), 2);
        assert!(d.warnings[0].contains(":4: truncated last line"), "{:?}", d.warnings);
    }
}
