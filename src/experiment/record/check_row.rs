//! One verify.csv row: the sampled check of one tracer instance's answers on one workload against
//! the oracle (Embree in robust mode) on the same rays.

use std::path::Path;

use crate::error::Result;

use super::csv_file::{write_csv, CellResult, Cells};

pub const VERIFY_COLUMNS: &[&str] = &[
    "scene",
    "triangles",
    "frame",
    "tracer",
    "parameters",
    "ray_kind",
    "checked_rays",
    "ties",
    "unexplained",
    "ours_right",
    "ours_wrong",
    "rounding",
    "undecided",
];

#[derive(Clone, Debug, PartialEq)]
pub struct CheckRow {
    pub scene: String,
    pub triangles: usize,
    pub frame: usize,
    pub tracer: String,
    pub parameters: String,
    pub ray_kind: String,
    pub checked_rays: usize,
    /// Disagreements explained by a tie (see `verify::compare`).
    pub ties: u64,
    pub unexplained: u64,
    /// The unexplained ones as the f64 truth judged them (`verify::Judgement`): ours right
    /// (Embree wrong), ours wrong, both within rounding, undecided.
    pub ours_right: u64,
    pub ours_wrong: u64,
    pub rounding: u64,
    pub undecided: u64,
}

impl CheckRow {
    pub fn cells(&self) -> Vec<String> {
        vec![
            self.scene.clone(),
            self.triangles.to_string(),
            self.frame.to_string(),
            self.tracer.clone(),
            self.parameters.clone(),
            self.ray_kind.clone(),
            self.checked_rays.to_string(),
            self.ties.to_string(),
            self.unexplained.to_string(),
            self.ours_right.to_string(),
            self.ours_wrong.to_string(),
            self.rounding.to_string(),
            self.undecided.to_string(),
        ]
    }

    /// A verify.csv row; files written before the f64 truth judged disagreements read with every
    /// unexplained one undecided.
    pub fn parse(cells: &Cells) -> CellResult<CheckRow> {
        let unexplained = cells.number("unexplained")?;
        let judged = |column: &str| match cells.0.contains_key(column) {
            true => cells.number(column).map(Some),
            false => Ok(None),
        };
        Ok(CheckRow {
            scene: cells.text("scene")?,
            triangles: cells.number("triangles")?,
            frame: cells.number("frame")?,
            tracer: cells.text("tracer")?,
            parameters: cells.text("parameters")?,
            ray_kind: cells.text("ray_kind")?,
            checked_rays: cells.number("checked_rays")?,
            ties: cells.number("ties")?,
            unexplained,
            ours_right: judged("ours_right")?.unwrap_or(0),
            ours_wrong: judged("ours_wrong")?.unwrap_or(0),
            rounding: judged("rounding")?.unwrap_or(0),
            undecided: judged("undecided")?.unwrap_or(unexplained),
        })
    }
}

/// verify.csv's rows.
pub fn write_checks(path: &Path, rows: &[CheckRow]) -> Result<()> {
    write_csv(path, VERIFY_COLUMNS, rows.iter().map(CheckRow::cells))
}
