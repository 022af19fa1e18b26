//! A restitution law file, as a façade study names it (`law = FILE`): the
//! `summary.json` written by `rocklab reduce` (its campaign-level
//! `restitution_law`), or a JSON file holding the law object alone (SPEC,
//! "Per-impact coefficients and the restitution law").

use std::path::Path;

use crate::error::{FileError, FileKind};
use crate::ingest::text::read_text;
use crate::restitution_law::RestitutionLaw;

/// Read and validate the law of `path`; a defect names the file, and the line
/// and column where JSON places it.
pub fn read(path: &Path) -> Result<RestitutionLaw, FileError> {
    let text = read_text(path, FileKind::Law)?;
    let invalid = |e: serde_json::Error| FileError::Invalid {
        file: path.to_path_buf(),
        line: (e.line() > 0).then_some(e.line()),
        column: (e.line() > 0).then_some(e.column()),
        message: format!("restitution law: {e}"),
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(invalid)?;
    if value.get("restitution_law").is_none() && value.get("form").is_none() {
        return Err(FileError::invalid(
            path,
            "no restitution_law: expected a summary.json written by `rocklab reduce` with a campaign law, or a law object {\"form\", \"parameters\"}",
        ));
    }
    // The law is parsed from its own text, so that an error inside it is located
    // in the file (serde_json places the errors of a Value without positions).
    let start = law_offset(&text);
    let position = |at: usize| {
        let before = &text[..at];
        let line = before.matches('\n').count() + 1;
        (line, before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1)
    };
    // A reduction that could fit no law writes {"error": why} in its place: say
    // that, and why, rather than a missing `form`.
    if let Some(why) = value.get("restitution_law").and_then(|l| l.get("error")).and_then(|e| e.as_str()) {
        let (line, column) = position(start);
        return Err(FileError::Invalid {
            file: path.to_path_buf(),
            line: Some(line),
            column: Some(column),
            message: crate::error::excerpt_text(
                &format!(
                    "restitution_law: the reduction fitted no law to this campaign ({why}); a façade set cannot use it: give the set e_in and e_out, or calibration = FILE"
                ),
                400,
            ),
        });
    }
    let slice = &text[start..];
    let mut de = serde_json::Deserializer::from_str(slice);
    let parsed: RestitutionLaw = serde::Deserialize::deserialize(&mut de).map_err(|e| {
        let (line0, col0) = position(start);
        let (line0, col0) = (line0 - 1, col0 - 1);
        let (line, column) = if e.line() <= 1 {
            (line0 + 1, col0 + e.column())
        } else {
            (line0 + e.line(), e.column())
        };
        FileError::Invalid {
            file: path.to_path_buf(),
            line: Some(line),
            column: Some(column),
            message: format!("restitution law: {e}"),
        }
    })?;
    Ok(parsed)
}

/// Byte offset of the law object in the text: the value of the top-level
/// `"restitution_law"` key (found by scanning with a depth counter, strings
/// skipped), else 0 (the whole text is the law).
fn law_offset(text: &str) -> usize {
    let bytes = text.as_bytes();
    let (mut depth, mut i, mut in_str) = (0i32, 0usize, false);
    while i < bytes.len() {
        let c = bytes[i];
        if in_str {
            if c == b'\\' {
                i += 1;
            } else if c == b'"' {
                in_str = false;
            }
        } else if c == b'"' {
            if depth == 1 && text[i..].starts_with("\"restitution_law\"") {
                let rest = &text[i + "\"restitution_law\"".len()..];
                if let Some(k) = rest.find('{') {
                    return i + "\"restitution_law\"".len() + k;
                }
            }
            in_str = true;
        } else if c == b'{' || c == b'[' {
            depth += 1;
        } else if c == b'}' || c == b']' {
            depth -= 1;
        }
        i += 1;
    }
    0
}
