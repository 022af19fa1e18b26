//! Parquet copies of the outputs' tables, for analysts' tools: each table in its
//! CSV layout (same columns, numbers at full precision as Float64, null where the
//! CSV cell is empty, text as String), and the per-impact rows of summary.json.

use polars::prelude::*;

use super::table::{CsvField, Table};
use super::ReportError;

fn err(e: PolarsError) -> ReportError {
    ReportError::Parquet(e.to_string())
}

/// The bytes of a Parquet file of `df`.
pub fn bytes(df: &mut DataFrame) -> Result<Vec<u8>, ReportError> {
    let mut out = Vec::new();
    ParquetWriter::new(&mut out).finish(df).map_err(err)?;
    Ok(out)
}

/// A table as a frame, in its CSV layout.
pub fn frame(t: &Table) -> Result<DataFrame, ReportError> {
    let columns = t
        .csv
        .iter()
        .map(|(name, f)| match *f {
            CsvField::Text(i) => {
                let v: Vec<String> = t
                    .rows
                    .iter()
                    .map(|r| r.cells[i].csv.clone().unwrap_or_else(|| r.cells[i].text.clone()))
                    .collect();
                Column::new(name.as_str().into(), v)
            }
            CsvField::Value(i) => Column::new(name.as_str().into(), t.rows.iter().map(|r| r.cells[i].value).collect::<Vec<_>>()),
            CsvField::U(i) => Column::new(name.as_str().into(), t.rows.iter().map(|r| r.cells[i].u).collect::<Vec<_>>()),
        })
        .collect();
    DataFrame::new(t.rows.len(), columns).map_err(err)
}

/// A table as Parquet bytes.
pub fn table(t: &Table) -> Result<Vec<u8>, ReportError> {
    bytes(&mut frame(t)?)
}
