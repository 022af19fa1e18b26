//! The reader of calibration.toml (written by `rocklab calibrate`): the type is
//! the calibration's own [`CalibrationFile`], shared with the writer.

use std::path::Path;

pub use crate::calibrate::CalibrationFile;
use crate::error::{FileError, FileKind};
use crate::ingest::text::{parse_toml, read_text};

/// Read a calibration.toml in full (the spread is None in files written before it
/// was added).
pub fn read(path: &Path) -> Result<CalibrationFile, FileError> {
    parse_toml(&read_text(path, FileKind::Calibration)?, path)
}

/// e_in and e_out of a calibration.toml (`[calibration] e_in, e_out`).
pub fn read_coefficients(path: &Path) -> Result<(f64, f64), FileError> {
    read(path).map(|f| (f.calibration.e_in, f.calibration.e_out))
}
