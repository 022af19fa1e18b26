//! Parquet logs (`.parquet`): columns by name, numeric (float or integer), no nulls.
//! Read with polars' Parquet reader: polars is already the archive's table engine,
//! so this costs no further crate.

use polars::prelude::*;

use super::{err, not_found, Channels, Request};
use crate::error::InputError;

pub fn read(req: &Request) -> Result<Channels, InputError> {
    let file = req.file;
    let f = std::fs::File::open(file).map_err(|e| InputError::Io {
        file: file.to_path_buf(),
        source: e,
    })?;
    let df = ParquetReader::new(f)
        .finish()
        .map_err(|e| err(file, format!("not readable as a Parquet file: {e}")))?;
    let names: Vec<String> = df.get_column_names().iter().map(|n| n.to_string()).collect();
    let column = |name: &str| -> Result<Vec<f64>, InputError> {
        let c = df.column(name).map_err(|_| not_found(file, "column", name, "", &names))?;
        if !c.dtype().is_primitive_numeric() {
            return Err(err(file, format!("column '{name}' holds {}: expected numbers", c.dtype())));
        }
        let c = c
            .cast(&DataType::Float64)
            .map_err(|e| err(file, format!("column '{name}': not convertible to numbers: {e}")))?;
        let ca = c.f64().map_err(|e| err(file, format!("column '{name}': {e}")))?;
        ca.iter()
            .enumerate()
            .map(|(i, v)| v.ok_or_else(|| err(file, format!("row {}: '{name}' is null: expected a measured value", i + 1))))
            .collect()
    };
    Ok(Channels {
        time: column(req.time_column)?,
        disp: column(req.disp_column)?,
        time_in_s: false,
        first_row: 1,
        place: String::new(),
        notes: vec!["Parquet file".into()],
    })
}
