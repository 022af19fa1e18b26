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

/// The text of a TOML input. Text that is not UTF-8 (a manifest saved as
/// Latin-1 or Windows-1252 by an editor, with an `é` or a `°` in a comment) is
/// refused at the line and column of its first such byte, saying so.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String, FileError> {
    let bytes = std::fs::read(path).map_err(|e| {
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
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        // The valid prefix is text: locate the byte in it.
        let (line, column) = line_column(std::str::from_utf8(&bytes[..at]).unwrap_or_default(), at);
        FileError::Invalid {
            file: path.to_path_buf(),
            line: Some(line),
            column: Some(column),
            message: format!(
                "byte 0x{:02X} is not UTF-8 text: save the {kind} as UTF-8 (an editor's Latin-1 or Windows-1252 é, ° or ± is not)",
                bytes[at]
            ),
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

    // Session 13: a manifest with a Latin-1 'é' in a comment was refused as
    // "stream did not contain valid UTF-8", without a line.
    #[test]
    fn text_that_is_not_utf8_is_located() {
        // (a temporary file written through its handle: src/ holds one writer)
        let file = |bytes: &[u8]| {
            let mut f = tempfile::Builder::new().suffix(".toml").tempfile().unwrap();
            std::io::Write::write_all(&mut f, bytes).unwrap();
            f
        };
        let latin1 = file(b"# ok\n# Prova di laboratorio n\xb0 1, parete \xe9\n[campaign]\n");
        let e = read_text(latin1.path(), FileKind::Manifest).unwrap_err().to_string();
        assert!(
            e.ends_with(".toml:2:25: byte 0xB0 is not UTF-8 text: save the manifest as UTF-8 (an editor's Latin-1 or Windows-1252 é, ° or ± is not)"),
            "{e}"
        );
        let utf8 = file("# n° 1 é ±\n[campaign]\n".as_bytes());
        assert_eq!(read_text(utf8.path(), FileKind::Manifest).unwrap(), "# n° 1 é ±\n[campaign]\n");
    }

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
