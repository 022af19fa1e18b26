//! Error types of the input edge. Every ingest defect names the file, the line and
//! the column (1-based) and says what was expected.

use std::path::PathBuf;

/// A defect in a log file or a manifest, located to the line and column.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: file not found (expected a log exported by the data-acquisition system)")]
    Missing { file: PathBuf },
    #[error("{file}: the file is empty (expected '#' metadata lines, a header row and numeric rows)")]
    Empty { file: PathBuf },
    #[error("{file}:{line}: header row without data (expected numeric rows after the header)")]
    NoData { file: PathBuf, line: u64 },
    #[error("{file}:{line}:{column}: {message}")]
    At {
        file: PathBuf,
        line: u64,
        column: usize,
        message: String,
    },
    #[error("{file}:{line}: {message}")]
    Line { file: PathBuf, line: u64, message: String },
    #[error("{file}: {message}")]
    File { file: PathBuf, message: String },
}
