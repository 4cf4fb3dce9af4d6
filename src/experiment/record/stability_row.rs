//! One stability.csv row: a tracer on one case of the numerical stability suite and one query
//! (closest hit or occlusion), as written. The suite measures `verify::stability::Outcome`s;
//! `run::stability_suite` writes them as these rows, and readers read them back through `parse`.

use std::path::Path;

use crate::error::Result;

use super::csv_file::{write_csv, CellResult, Cells};

pub const STABILITY_COLUMNS: &[&str] = &[
    "case",
    "variant",
    "magnitude",
    "tracer",
    "query",
    "status",
    "note",
    "rays",
    "must_hit",
    "leaks",
    "missed",
    "false_hits",
    "rounding",
    "unexplained",
    "unexplained_tracer_right",
    "unexplained_oracle_right",
    "unexplained_rounding",
    "unexplained_both_wrong",
    "seconds",
    "relative_time",
    "slowdown",
];

#[derive(Clone, Debug, PartialEq)]
pub struct StabilityRow {
    /// The case kind (`verify::stability::CaseKind`'s name), its variant and its magnitude.
    pub case: String,
    pub variant: String,
    pub magnitude: f64,
    /// The contender's label: its tracer and parameters.
    pub tracer: String,
    /// `closest` or `occluded`.
    pub query: String,
    /// `answered`, `refused`, `crashed` or `hung`, with the message of a refusal or crash.
    pub status: String,
    pub note: String,
    /// Rays, must-hit rays, and the counts of `Outcome` in its order: leaks, missed, false hits,
    /// rounding, unexplained and its four parts.
    pub counts: [usize; 11],
    pub seconds: f64,
    pub relative_time: Option<f64>,
    pub slowdown: Option<f64>,
}

impl StabilityRow {
    pub fn cells(&self) -> Vec<String> {
        let mut row = vec![
            self.case.clone(),
            self.variant.clone(),
            format!("{:e}", self.magnitude),
            self.tracer.clone(),
            self.query.clone(),
            self.status.clone(),
            self.note.clone(),
        ];
        row.extend(self.counts.iter().map(usize::to_string));
        row.push(format!("{:.6}", self.seconds));
        row.push(
            self.relative_time
                .map_or(String::new(), |r| format!("{r:.3}")),
        );
        row.push(self.slowdown.map_or(String::new(), |s| format!("{s:.3}")));
        row
    }

    pub fn parse(cells: &Cells) -> CellResult<StabilityRow> {
        let mut counts = [0; 11];
        for (count, column) in counts.iter_mut().zip(&STABILITY_COLUMNS[7..18]) {
            *count = cells.number(column)?;
        }
        Ok(StabilityRow {
            case: cells.text("case")?,
            variant: cells.text("variant")?,
            magnitude: cells.number("magnitude")?,
            tracer: cells.text("tracer")?,
            query: cells.text("query")?,
            status: cells.text("status")?,
            note: cells.text("note")?,
            counts,
            seconds: cells.number("seconds")?,
            relative_time: cells.optional("relative_time")?,
            slowdown: cells.optional("slowdown")?,
        })
    }
}

/// stability.csv's rows.
pub fn write_stability(path: &Path, rows: &[StabilityRow]) -> Result<()> {
    write_csv(
        path,
        STABILITY_COLUMNS,
        rows.iter().map(StabilityRow::cells),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::record::csv_file::read_typed;

    #[test]
    fn rows_read_back_as_written() {
        let row = StabilityRow {
            case: "offset".into(),
            variant: "sphere, far".into(),
            magnitude: 1e5,
            tracer: "packet packet=8".into(),
            query: "closest".into(),
            status: "refused".into(),
            note: "a tree deeper than its stack".into(),
            counts: [4096, 1000, 1, 2, 3, 4, 5, 1, 2, 1, 1],
            seconds: 0.25,
            relative_time: Some(1.5),
            slowdown: None,
        };
        let path =
            std::env::temp_dir().join(format!("raylab-stability-{}.csv", std::process::id()));
        write_stability(&path, std::slice::from_ref(&row)).unwrap();
        let back = read_typed(&path, StabilityRow::parse).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back, vec![row]);
        assert_eq!(STABILITY_COLUMNS[7], "rays");
        assert_eq!(STABILITY_COLUMNS[17], "unexplained_both_wrong");
    }
}
