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

impl InputError {
    /// The file at fault.
    pub fn file(&self) -> &std::path::Path {
        match self {
            InputError::Io { file, .. }
            | InputError::Missing { file }
            | InputError::Empty { file }
            | InputError::NoData { file, .. }
            | InputError::At { file, .. }
            | InputError::Line { file, .. }
            | InputError::File { file, .. } => file,
        }
    }
}

/// Which TOML input a [`FileError`] is about (named in its message).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    Manifest,
    Block,
    Study,
    Calibration,
}

impl std::fmt::Display for FileKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FileKind::Manifest => "manifest",
            FileKind::Block => "block file",
            FileKind::Study => "study",
            FileKind::Calibration => "calibration",
        })
    }
}

/// A defect in a TOML input (campaign manifest, block file, study, calibration):
/// every variant names the file; a parse error also its line and column.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("{}: {kind} not found", file.display())]
    NotFound { file: PathBuf, kind: FileKind },
    #[error("{}: cannot read {kind}: {source}", file.display())]
    Io {
        file: PathBuf,
        kind: FileKind,
        #[source]
        source: std::io::Error,
    },
    /// Not TOML, an unknown key, a missing key or a wrong type (the parser's
    /// message, which shows the line).
    #[error("{}: {message}", file.display())]
    Toml {
        file: PathBuf,
        /// 1-based line and column of the defect, when the parser located it.
        line: Option<usize>,
        column: Option<usize>,
        message: String,
    },
    /// A value out of its range or a combination that does not go together; the
    /// message names the table and key.
    #[error("{}: {message}", file.display())]
    Invalid { file: PathBuf, message: String },
    /// A file that this one refers to (a study's block, record or calibration).
    #[error(transparent)]
    Input(#[from] InputError),
}

impl FileError {
    /// An invalid value of `file`.
    pub fn invalid(file: &std::path::Path, message: impl std::fmt::Display) -> FileError {
        FileError::Invalid {
            file: file.to_path_buf(),
            message: message.to_string(),
        }
    }
}
