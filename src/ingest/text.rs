//! Reading an input file's text and parsing TOML into a typed raw form, with errors
//! that name the file (and the line and column of a parse error).

use std::path::Path;

use crate::error::{FileError, FileKind, InputError};

/// The bytes of a data file (log, record): a missing file is [`InputError::Missing`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, InputError> {
    std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            InputError::Missing { file: path.to_path_buf() }
        } else {
            InputError::Io {
                file: path.to_path_buf(),
                source: e,
            }
        }
    })
}

/// The text of a TOML input.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String, FileError> {
    std::fs::read_to_string(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            FileError::NotFound {
                file: path.to_path_buf(),
                kind,
            }
        } else {
            FileError::Io {
                file: path.to_path_buf(),
                kind,
                source: e,
            }
        }
    })
}

/// Parse TOML text into `T`; `path` names it in errors.
pub fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, path: &Path) -> Result<T, FileError> {
    toml::from_str(text).map_err(|e| {
        let (line, column) = e.span().map(|s| line_column(text, s.start)).unzip();
        FileError::Toml {
            file: path.to_path_buf(),
            line,
            column,
            message: e
                .to_string()
                .trim_end()
                .lines()
                .map(|l| crate::error::excerpt(l, 120))
                .collect::<Vec<_>>()
                .join("\n"),
        }
    })
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parse_error_is_located() {
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct T {
            a: f64,
        }
        match parse_toml::<T>("a = 1.0\nb = 2\n", Path::new("x.toml")) {
            Err(FileError::Toml { line, column, message, .. }) => {
                assert_eq!((line, column), (Some(2), Some(1)), "{message}");
                assert!(message.contains('b'));
            }
            other => panic!("{other:?}"),
        }
    }
}
