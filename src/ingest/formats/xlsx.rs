//! Excel workbooks (`.xlsx`) through `calamine`: the first sheet, or the one the
//! manifest names (`sheet = "…"`); one header row (the first non-empty row), then one
//! numeric row per sample. Rows and columns in messages are Excel's (1-based, as the
//! user sees them: row 2, column B → "row 2, column 2").

use calamine::{open_workbook, Data, Reader, Xlsx};

use super::{err, not_found, Channels, Request};
use crate::error::InputError;

pub fn read(req: &Request) -> Result<Channels, InputError> {
    let file = req.file;
    let mut wb: Xlsx<_> = open_workbook(file).map_err(|e| err(file, format!("not readable as an Excel workbook (.xlsx): {e}")))?;
    let names = wb.sheet_names();
    let sheet = match &req.source.sheet {
        Some(s) if names.contains(s) => s.clone(),
        Some(s) => {
            return Err(err(
                file,
                format!(
                    "sheet '{s}' not found (sheets: {}). Set 'sheet' in this [[test]] or [channels]",
                    names.join(", ")
                ),
            ))
        }
        None => names.first().cloned().ok_or_else(|| err(file, "the workbook has no sheet".into()))?,
    };
    let range = wb
        .worksheet_range(&sheet)
        .map_err(|e| err(file, format!("sheet '{sheet}': not readable: {e}")))?;
    let place = format!("sheet '{sheet}'");
    let Some((row0, col0)) = range.start() else {
        return Err(err(file, format!("{place}: the sheet is empty (expected a header row and numeric rows)")));
    };
    let mut rows = range.rows();
    let header: Vec<String> = rows.next().unwrap_or_default().iter().map(|c| c.to_string().trim().to_string()).collect();
    let find = |name: &str, what: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| not_found(file, what, name, &place, &header))
    };
    let (it, id) = (find(req.time_column, "time column")?, find(req.disp_column, "displacement column")?);
    let first_row = row0 as usize + 2; // 1-based row of the first sample
    let (mut time, mut disp) = (Vec::new(), Vec::new());
    for (k, row) in rows.enumerate() {
        let at = |i: usize| (first_row + k, col0 as usize + i + 1);
        time.push(cell(row.get(it), at(it), req.time_column).map_err(|m| err(file, format!("{place}, {m}")))?);
        disp.push(cell(row.get(id), at(id), req.disp_column).map_err(|m| err(file, format!("{place}, {m}")))?);
    }
    Ok(Channels {
        time,
        disp,
        time_in_s: false,
        first_row,
        place,
        notes: vec![format!("Excel workbook, sheet '{sheet}'")],
    })
}

/// A numeric cell; its (row, column) and channel name for the message.
fn cell(c: Option<&Data>, (row, col): (usize, usize), name: &str) -> Result<f64, String> {
    let at = format!("row {row}, column {col} ('{name}')");
    match c {
        Some(Data::Float(v)) => Ok(*v),
        Some(Data::Int(v)) => Ok(*v as f64),
        Some(Data::String(s)) => s.trim().parse().map_err(|_| format!("{at}: '{s}' is not a number")),
        None | Some(Data::Empty) => Err(format!("{at}: empty cell: expected a number")),
        Some(other) => Err(format!("{at}: '{other}' is not a number")),
    }
}
