//! Error types of the input edge. Every ingest defect names the file, the line and
//! the column (1-based) and says what was expected.

use std::path::PathBuf;

/// A defect in a log file or a manifest, located to the line and column.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{}: cannot read: {source}", shown(file))]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: file not found (expected a log exported by the data-acquisition system)", shown(file))]
    Missing { file: PathBuf },
    #[error("{}: the file is empty (expected '#' metadata lines, a header row and numeric rows)", shown(file))]
    Empty { file: PathBuf },
    #[error("{}:{line}: header row without data (expected numeric rows after the header)", shown(file))]
    NoData { file: PathBuf, line: u64 },
    #[error("{}:{line}:{column}: {message}", shown(file))]
    At {
        file: PathBuf,
        line: u64,
        column: usize,
        message: String,
    },
    #[error("{}:{line}: {message}", shown(file))]
    Line { file: PathBuf, line: u64, message: String },
    #[error("{}: {message}", shown(file))]
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
    Law,
}

impl std::fmt::Display for FileKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FileKind::Manifest => "manifest",
            FileKind::Block => "block file",
            FileKind::Study => "study",
            FileKind::Calibration => "calibration",
            FileKind::Law => "restitution law",
        })
    }
}

/// A defect in a TOML input (campaign manifest, block file, study, calibration):
/// every variant names the file; a parse error also its line and column.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("{}: {kind} not found", shown(file))]
    NotFound { file: PathBuf, kind: FileKind },
    #[error("{}: cannot read {kind}: {source}", shown(file))]
    Io {
        file: PathBuf,
        kind: FileKind,
        #[source]
        source: std::io::Error,
    },
    /// Not TOML, an unknown key, a missing key or a wrong type (the parser's
    /// message, which shows the line).
    #[error("{}: {message}", shown(file))]
    Toml {
        file: PathBuf,
        /// 1-based line and column of the defect, when the parser located it.
        line: Option<usize>,
        column: Option<usize>,
        message: String,
    },
    /// A value out of its range or a combination that does not go together; the
    /// message names the table and key, and the line and column of the key are
    /// given when the text shows it in one place.
    #[error("{}: {message}", place(.file, *.line, *.column))]
    Invalid {
        file: PathBuf,
        line: Option<usize>,
        column: Option<usize>,
        message: String,
    },
    /// A file that this one refers to (a study's block, record or calibration).
    #[error(transparent)]
    Input(#[from] InputError),
}

/// "file:line:column", or "file" when the place is not known.
fn place(file: &std::path::Path, line: Option<usize>, column: Option<usize>) -> String {
    match (line, column) {
        (Some(l), Some(c)) => format!("{}:{l}:{c}", shown(file)),
        _ => shown(file),
    }
}

impl FileError {
    /// An invalid value of `file` (not yet located: see [`FileError::located`]);
    /// the message is cut to 400 characters (issue 22: a key or a value of any
    /// length may be quoted in it).
    pub fn invalid(file: &std::path::Path, message: impl std::fmt::Display) -> FileError {
        FileError::Invalid {
            file: file.to_path_buf(),
            line: None,
            column: None,
            message: excerpt_text(&message.to_string(), 400),
        }
    }

    /// An [`FileError::Invalid`] located in the TOML `text` it was found in: the
    /// key its message starts with (`[table].key = …`, `key = …`, or
    /// `[[table]] id = "x": …` / `[[table]] "x": …` for an entry), when that key
    /// stands on exactly one line of the text. Other errors are returned as they are.
    /// Only an error of `path` itself is located (not one of a file it names).
    pub fn located(self, path: &std::path::Path, text: &str) -> FileError {
        match self {
            FileError::Invalid {
                file,
                line: None,
                column: None,
                message,
            } if file == path => {
                let (line, column) = locate(text, &message).unzip();
                FileError::Invalid { file, line, column, message }
            }
            other => other,
        }
    }
}

/// Where the key an error message starts with stands in a TOML text (1-based line
/// and column), if on exactly one line.
fn locate(text: &str, message: &str) -> Option<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    // The line range of a table's body: after its header, up to the next header.
    let section = |table: &str| -> Option<(usize, usize)> {
        let start = lines.iter().position(|l| l.trim() == format!("[{table}]"))? + 1;
        let end = lines[start..]
            .iter()
            .position(|l| l.trim_start().starts_with('['))
            .map_or(lines.len(), |k| start + k);
        Some((start, end))
    };
    let (range, needle) = if let Some(rest) = message.strip_prefix("[[") {
        // An entry of an array of tables, named by its id or name value.
        let value = rest.split_once("]] ")?.1;
        let value = value.strip_prefix("id = ").unwrap_or(value);
        let quoted = value.split_once(": ").map_or(value, |(v, _)| v);
        ((0, lines.len()), quoted.to_string())
    } else if let Some(rest) = message.strip_prefix('[') {
        let (table, rest) = rest.split_once("].")?;
        let key: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        (section(table)?, key)
    } else {
        let key: String = message.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        ((0, lines.len()), key)
    };
    if needle.is_empty() {
        return None;
    }
    let is_key_line = |l: &str| {
        let l = l.trim_start();
        if needle.starts_with('"') {
            // `name = "x"` or `id = "x"` of an entry.
            l.split_once('=').is_some_and(|(_, v)| v.trim() == needle)
        } else {
            l.strip_prefix(needle.as_str()).is_some_and(|r| r.trim_start().starts_with('='))
        }
    };
    let hits: Vec<usize> = (range.0..range.1).filter(|&i| is_key_line(lines[i])).collect();
    match hits.as_slice() {
        [i] => {
            let l = lines[*i];
            let indent = l.chars().count() - l.trim_start().chars().count();
            Some((i + 1, indent + 1))
        }
        _ => None,
    }
}

/// At most `max` characters of `value` for a message, with "…" and the full
/// length when it was cut (issue 22: a bad cell of 8 MB or a whole nested TOML
/// line is not quoted whole); control characters are shown escaped.
pub fn excerpt(value: &str, max: usize) -> String {
    let n = value.chars().count();
    // Only control characters are escaped: `escape_debug` on every character
    // also turned the quotes of a TOML line into \" (`cutoff_hz = \"x\"`).
    let shown: String = value
        .chars()
        .take(max)
        .flat_map(|c| if c.is_control() { c.escape_debug().collect::<Vec<_>>() } else { vec![c] })
        .collect();
    if n > max {
        format!("{shown}… ({n} characters)")
    } else {
        shown
    }
}

/// A path as a message shows it: whole up to 300 characters, else its first and
/// last 120 with the length (issue 22: a mutated name of 4,000 characters made a
/// message of 4,000; the start and the file name are what a reader needs).
pub fn shown(path: &std::path::Path) -> String {
    let text = path.display().to_string();
    let n = text.chars().count();
    if n <= 300 {
        return text;
    }
    let head: String = text.chars().take(120).collect();
    let tail: String = text.chars().skip(n - 120).collect();
    format!("{head}…{tail} (a path of {n} characters)")
}

/// At most `max` characters of a message (newlines kept), with "…" when cut.
pub fn excerpt_text(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((i, _)) => format!("{}… ({} characters)", &text[..i], text.chars().count()),
        None => text.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_path_is_shown_by_its_ends() {
        let long = format!("/tmp/study/{}/block.toml", "7".repeat(3917));
        let m = FileError::NotFound {
            file: long.clone().into(),
            kind: FileKind::Block,
        }
        .to_string();
        assert!(m.chars().count() < 320, "{} characters", m.chars().count());
        assert!(
            m.starts_with("/tmp/study/777") && m.contains("7/block.toml (a path of 3939 characters): block file not found"),
            "{m}"
        );
        let short = InputError::Missing { file: "a/b.csv".into() }.to_string();
        assert!(short.starts_with("a/b.csv: file not found"), "{short}");
    }

    #[test]
    fn an_excerpt_escapes_control_characters_only() {
        assert_eq!(excerpt("cutoff_hz = \"x\"", 60), "cutoff_hz = \"x\"");
        assert_eq!(excerpt("a\0b\nc", 60), "a\\0b\\nc");
        assert_eq!(excerpt("é'7", 60), "é'7");
        assert_eq!(excerpt(&"7".repeat(100), 3), "777… (100 characters)");
    }

    const TEXT: &str = "[campaign]\nname = \"c\"\n[wall]\nheight_m = 2.7\n  thickness_m = -0.36\n[[test]]\nid = \"a\"\n[[test]]\nid = \"b\"\n";

    fn at(message: &str) -> (Option<usize>, Option<usize>) {
        let m = std::path::Path::new("m.toml");
        match FileError::invalid(m, message).located(m, TEXT) {
            FileError::Invalid { line, column, .. } => (line, column),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_validation_error_names_the_line_and_column_of_its_key() {
        assert_eq!(at("[wall].thickness_m = -0.36: expected a positive number"), (Some(5), Some(3)));
        assert_eq!(at("[[test]] id = \"b\": duplicate test id"), (Some(9), Some(1)));
        assert_eq!(at("height_m = 0: expected a positive number"), (Some(4), Some(1)));
        // Not in the text, or in more than one place: no place rather than a wrong one.
        assert_eq!(at("[wall].alpha_rad = 2: expected 0 < α < π/2"), (None, None));
        assert_eq!(at("no [[test]] entries"), (None, None));
        let m = std::path::Path::new("m.toml");
        let e = FileError::invalid(m, "[wall].thickness_m = -0.36: expected a positive number").located(m, TEXT);
        assert_eq!(e.to_string(), "m.toml:5:3: [wall].thickness_m = -0.36: expected a positive number");
        // An error of another file (a study's block file) is left alone.
        let other = FileError::invalid(std::path::Path::new("block.toml"), "[wall].thickness_m = 1").located(m, TEXT);
        assert_eq!(other.to_string(), "block.toml: [wall].thickness_m = 1");
    }
}
