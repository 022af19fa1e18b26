//! The output edge: the `summary.json` contract, the tables (one model, four
//! formats), the plots and the HTML pages. Every renderer returns bytes into a
//! [`Files`]; [`write_files`] is the one function that writes them (atomically).
//! The inputs a page names in its provenance arrive as [`InputFile`]s, read and
//! hashed by the load step; nothing here reads a file.

pub mod calibration;
pub mod campaign;
pub mod docs;
pub mod facade;
pub mod html;
pub mod parquet;
pub mod plots;
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
    #[error("writing {path}: {source}")]
    Write { path: PathBuf, source: std::io::Error },
}

/// Files to write, by path relative to the output folder, in order.
#[derive(Debug, Default)]
pub struct Files(Vec<(PathBuf, Vec<u8>)>);

impl Files {
    pub fn add(&mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) {
        self.0.push((path.into(), bytes.into()));
    }
    pub fn append(&mut self, other: Files) {
        self.0.extend(other.0);
    }
    /// The bytes of `path`, if a renderer produced it.
    pub fn get(&self, path: &str) -> Option<&[u8]> {
        self.0.iter().find(|(p, _)| p == Path::new(path)).map(|(_, b)| b.as_slice())
    }
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.0.iter().map(|(p, _)| p.as_path())
    }
}

/// The one writer: every file under `dir` (folders created), each atomically
/// ([`crate::atomic::write_atomic`]: a temporary sibling, then a rename).
pub fn write_files(dir: &Path, files: &Files) -> Result<(), ReportError> {
    for (rel, bytes) in &files.0 {
        let path = dir.join(rel);
        crate::atomic::write_atomic(&path, bytes).map_err(|source| ReportError::Write { path, source })?;
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
    /// The provenance row: role, path, size, SHA-256.
    pub fn row(&self) -> Vec<String> {
        let (size, sha) = match &self.facts {
            Ok((n, sha)) => (format!("{n} bytes"), sha.clone()),
            Err(e) => ("—".into(), e.clone()),
        };
        vec![self.role.clone(), self.path.display().to_string(), size, sha]
    }
}
