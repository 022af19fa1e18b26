//! The output edge: the `summary.json` contract, the tables (one model, four
//! formats), the plots and the HTML pages. Every renderer returns bytes into a
//! [`Files`]; [`write_files`] is the one function that writes them (atomically, as a set).
//! The inputs a page names in its provenance arrive as [`InputFile`]s, read and
//! hashed by the load step; nothing here reads a file.

pub mod calibration;
pub mod campaign;
pub mod docs;
pub mod facade;
pub mod finite;
pub mod html;
pub mod law;
pub mod parquet;
pub mod plots;
pub mod quality;
pub mod response;
pub mod summary;
pub mod table;
pub mod tables;

use std::path::{Path, PathBuf};

pub use campaign::{reduce_files, Extras};

/// What can go wrong while rendering or writing the outputs.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("plot: {0}")]
    Plot(String),
    #[error("CSV: {0}")]
    Csv(#[from] csv::Error),
    #[error("Parquet: {0}")]
    Parquet(String),
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("TOML: {0}")]
    Toml(#[from] toml::ser::Error),
    /// A calibration with nothing to write (every test left out).
    #[error("{0}; nothing was written")]
    Calibration(#[from] crate::calibrate::CalibrationFileError),
    #[error("writing {path}: {source}")]
    Write { path: PathBuf, source: std::io::Error },
    /// An output path that would leave the output folder, or two outputs under one name.
    #[error("output {path}: {why}; nothing was written")]
    Path { path: String, why: String },
    /// NaN or an infinity in an output (issue 22).
    #[error("{0}; nothing was written")]
    NonFinite(#[from] finite::NonFinite),
}

/// A name from an input (a test id, a record or a coefficient-set name) as one
/// file-name component, so that every output stays under `--out` (issue 22):
/// letters, digits, `-`, `_` and `.` are kept, anything else (separators, `..`
/// as a leading dot, NUL, spaces) becomes `_`, and the result is at most 100
/// characters and never empty.
pub fn file_stem(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' })
        .take(100)
        .collect();
    let dots = s.len() - s.trim_start_matches('.').len();
    s.replace_range(..dots, &"_".repeat(dots));
    if s.is_empty() {
        s.push('_');
    }
    s
}

/// A `Serialize` document as a JSON value, refused when it holds a NaN or an
/// infinity (serde_json would write `null`: [`finite::check_serialize`]).
pub(crate) fn json_value<T: serde::Serialize>(doc: &T) -> Result<serde_json::Value, ReportError> {
    finite::check_serialize(doc)?;
    Ok(serde_json::to_value(doc)?)
}

/// Files to write, by path relative to the output folder, in order, and the
/// inputs of the run, which no output may replace.
#[derive(Debug, Default)]
pub struct Files {
    files: Vec<(PathBuf, Vec<u8>)>,
    inputs: Vec<PathBuf>,
}

impl Files {
    pub fn add(&mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) {
        self.files.push((path.into(), bytes.into()));
    }
    pub fn append(&mut self, other: Files) {
        self.files.extend(other.files);
        self.inputs.extend(other.inputs);
    }
    /// The bytes of `path`, if a renderer produced it.
    pub fn get(&self, path: &str) -> Option<&[u8]> {
        self.files.iter().find(|(p, _)| p == Path::new(path)).map(|(_, b)| b.as_slice())
    }
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.files.iter().map(|(p, _)| p.as_path())
    }
    /// A file the run read (a manifest, a log, a record…): [`write_files`]
    /// refuses a set that would replace it. `--out` may be the inputs' own
    /// folder; a log that happens to be named `table1.csv` there stays the log.
    pub fn input(&mut self, path: impl Into<PathBuf>) {
        self.inputs.push(path.into());
    }
}

/// The one writer: every file under `dir` (folders created) as one set
/// ([`crate::atomic::write_set_under`]: each staged as a temporary sibling, then
/// all renamed into place).
/// Before the first byte is written, every file is checked ([`check_files`]): a
/// path that would leave `dir` (by its names or through a folder that is a
/// symbolic link), two files under one path, or a non-finite number in a text
/// output refuses the whole set, and so does an output that would replace one of
/// the run's inputs ([`Files::input`]); a failure while staging (a full disk)
/// removes what was staged: a failed run writes nothing.
pub fn write_files(dir: &Path, files: &Files) -> Result<(), ReportError> {
    check_files(files)?;
    for (rel, _) in &files.files {
        let shown = || crate::error::excerpt(&rel.to_string_lossy(), 60);
        crate::atomic::check_no_link(dir, rel).map_err(|why| ReportError::Path { path: shown(), why })?;
        if let Some(input) = files.inputs.iter().find(|i| same_file(&dir.join(rel), i)) {
            return Err(ReportError::Path {
                path: shown(),
                why: format!(
                    "{} is an input of this run: refusing to replace it (write the outputs to a folder apart from the inputs)",
                    crate::error::excerpt(&input.display().to_string(), 200)
                ),
            });
        }
    }
    crate::atomic::write_set_under(dir, &files.files).map_err(|(path, source)| ReportError::Write { path, source })
}

/// Whether `a` and `b` name one existing file (the same entry: device and inode
/// where the platform has them, else the same canonical path). A symbolic link
/// is the link itself, as the writer's rename replaces the link, not its target.
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::symlink_metadata(a), std::fs::symlink_metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((std::fs::canonicalize(a), std::fs::canonicalize(b)), (Ok(x), Ok(y)) if x == y)
    }
}

/// Every path relative, made of plain components (no `..`, root, prefix, NUL,
/// component over 255 bytes), each path once; every text output finite.
pub fn check_files(files: &Files) -> Result<(), ReportError> {
    let mut seen = std::collections::HashSet::new();
    for (rel, bytes) in &files.files {
        let shown = || crate::error::excerpt(&rel.to_string_lossy(), 60);
        crate::atomic::check_relative(rel).map_err(|why| ReportError::Path { path: shown(), why })?;
        if !seen.insert(rel.as_path()) {
            return Err(ReportError::Path {
                path: shown(),
                why: "two outputs under one name (two inputs whose names differ only in characters a file name cannot hold?)".into(),
            });
        }
        finite::check_bytes(&rel.to_string_lossy(), bytes)?;
    }
    Ok(())
}

/// The bytes of a finished CSV writer.
pub(crate) fn csv_bytes(w: csv::Writer<Vec<u8>>) -> Result<Vec<u8>, ReportError> {
    w.into_inner().map_err(|e| ReportError::Csv(e.into_error().into()))
}

/// An input file as the load step found it, for a page's provenance: its role
/// ("manifest", a test id, "study"…), its path, and its size and SHA-256 (hex)
/// or why it could not be read.
#[derive(Debug, Clone, PartialEq)]
pub struct InputFile {
    pub role: String,
    pub path: PathBuf,
    pub facts: Result<(usize, String), String>,
}

impl InputFile {
    /// Describe `path` from what reading it gave.
    pub fn new(role: &str, path: &Path, read: std::io::Result<Vec<u8>>) -> InputFile {
        use sha2::{Digest, Sha256};
        let facts = read
            .map(|b| (b.len(), Sha256::digest(&b).iter().map(|x| format!("{x:02x}")).collect()))
            .map_err(|e| format!("unreadable: {e}"));
        InputFile {
            role: role.into(),
            path: path.to_path_buf(),
            facts,
        }
    }
    /// Describe a file from a reader of its bytes, hashed as they stream (issue
    /// 22: a 242 MB log is not held whole to be hashed).
    pub fn from_reader(role: &str, path: &Path, read: std::io::Result<impl std::io::Read>) -> InputFile {
        use sha2::{Digest, Sha256};
        let facts = read.and_then(|mut r| {
            let (mut h, mut n, mut buf) = (Sha256::new(), 0usize, vec![0u8; 1 << 16]);
            loop {
                match r.read(&mut buf) {
                    Ok(0) => break,
                    Ok(k) => {
                        h.update(&buf[..k]);
                        n += k;
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(e),
                }
            }
            Ok((n, h.finalize().iter().map(|x| format!("{x:02x}")).collect()))
        });
        InputFile {
            role: role.into(),
            path: path.to_path_buf(),
            facts: facts.map_err(|e| format!("unreadable: {e}")),
        }
    }
    /// The provenance row: role, path, size, SHA-256.
    pub fn row(&self) -> Vec<String> {
        let (size, sha) = match &self.facts {
            Ok((n, sha)) => (format!("{n} bytes"), sha.clone()),
            Err(e) => ("—".into(), e.clone()),
        };
        vec![self.role.clone(), self.path.display().to_string(), size, sha]
    }
}
