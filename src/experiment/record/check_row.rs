//! One verify.csv row: the sampled check of one tracer instance's answers on one workload against
//! the oracle (Embree in robust mode) on the same rays.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::Result;

use super::csv_file::write_csv;

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
        ]
    }

    pub fn parse(fields: &BTreeMap<String, String>) -> std::result::Result<CheckRow, String> {
        let text = |name: &str| {
            fields
                .get(name)
                .cloned()
                .ok_or_else(|| format!("no column {name:?}"))
        };
        let number = |name: &str| -> std::result::Result<u64, String> {
            let cell = text(name)?;
            cell.parse()
                .map_err(|_| format!("{name}: {cell:?} is not a number"))
        };
        Ok(CheckRow {
            scene: text("scene")?,
            triangles: number("triangles")? as usize,
            frame: number("frame")? as usize,
            tracer: text("tracer")?,
            parameters: text("parameters")?,
            ray_kind: text("ray_kind")?,
            checked_rays: number("checked_rays")? as usize,
            ties: number("ties")?,
            unexplained: number("unexplained")?,
        })
    }
}

/// verify.csv's rows.
pub fn write_checks(path: &Path, rows: &[CheckRow]) -> Result<()> {
    write_csv(path, VERIFY_COLUMNS, rows.iter().map(CheckRow::cells))
}
