//! CSV files of rows: written whole from cells, read back as typed rows whose parse errors name
//! the file and line.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Result};

fn csv_error(path: &Path, e: csv::Error) -> Error {
    Error::input(path, None, e.to_string())
}

/// Writes `header` and `rows` (each a list of cells) as a CSV file.
pub fn write_csv<I: IntoIterator<Item = Vec<String>>>(
    path: &Path,
    header: &[&str],
    rows: I,
) -> Result<()> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    w.write_record(header).map_err(|e| csv_error(path, e))?;
    for row in rows {
        w.write_record(&row).map_err(|e| csv_error(path, e))?;
    }
    w.flush().map_err(|e| Error::io(path, e))
}

/// Reads typed rows back from a CSV file; a row that does not parse names its line.
pub fn read_typed<T>(
    path: &Path,
    parse: fn(&BTreeMap<String, String>) -> std::result::Result<T, String>,
) -> Result<Vec<T>> {
    super::selection::read_rows(path)?
        .iter()
        .enumerate()
        // Line 1 is the header.
        .map(|(i, fields)| parse(fields).map_err(|e| Error::at_line(path, i + 2, e)))
        .collect()
}
