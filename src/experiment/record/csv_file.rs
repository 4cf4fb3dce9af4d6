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

/// One CSV line read back, by column: what a typed row's `parse` reads its fields from.
pub struct Cells<'a>(pub &'a BTreeMap<String, String>);

/// A cell that does not read as its field: the message names the column.
pub type CellResult<T> = std::result::Result<T, String>;

impl Cells<'_> {
    /// The cell of `column` as written.
    pub fn text(&self, column: &str) -> CellResult<String> {
        self.0
            .get(column)
            .cloned()
            .ok_or_else(|| format!("no column {column:?}"))
    }

    /// The cell of `column` as a number.
    pub fn number<T: std::str::FromStr>(&self, column: &str) -> CellResult<T> {
        let cell = self.text(column)?;
        cell.parse()
            .map_err(|_| format!("{column}: {cell:?} is not a number"))
    }

    /// The cell of `column`, `None` when empty.
    pub fn optional_text(&self, column: &str) -> CellResult<Option<String>> {
        Ok(Some(self.text(column)?).filter(|c| !c.is_empty()))
    }

    /// The cell of `column` as a number, `None` when empty.
    pub fn optional<T: std::str::FromStr>(&self, column: &str) -> CellResult<Option<T>> {
        match self.optional_text(column)? {
            None => Ok(None),
            Some(_) => self.number(column).map(Some),
        }
    }
}

/// Reads typed rows back from a CSV file; a row that does not parse names its line.
pub fn read_typed<T>(path: &Path, parse: fn(&Cells) -> CellResult<T>) -> Result<Vec<T>> {
    super::selection::read_rows(path)?
        .iter()
        .enumerate()
        // Line 1 is the header.
        .map(|(i, fields)| parse(&Cells(fields)).map_err(|e| Error::at_line(path, i + 2, e)))
        .collect()
}
