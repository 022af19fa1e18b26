//! The reader of ground-motion record files; the formats are parsed from text by
//! [`crate::ground_motion::parse`].

use std::path::Path;

use crate::error::InputError;
use crate::ground_motion::{parse, ReadOptions, Record};
use crate::ingest::text::read_bytes;

/// Read a record file (any format [`crate::ground_motion`] parses; invalid UTF-8
/// is replaced, the formats are ASCII).
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Record, InputError> {
    let bytes = read_bytes(path)?;
    parse(path, &String::from_utf8_lossy(&bytes), opts)
}
