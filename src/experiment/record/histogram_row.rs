//! One histograms.csv row: the box and triangle tests at one BVH depth of a counted ray batch
//! (the tracers that count them; depths past the deepest count are omitted).

use std::path::Path;

use crate::error::Result;

use super::csv_file::{write_csv, CellResult, Cells};
use super::selection::Row;

pub const HISTOGRAM_COLUMNS: &[&str] = &[
    "experiment",
    "scene",
    "frame",
    "tracer",
    "parameters",
    "ray_kind",
    "depth",
    "aabb_tests",
    "triangle_tests",
];

/// One histograms.csv row: the box and triangle tests at one BVH depth of a counted ray batch.
#[derive(Clone, Debug, PartialEq)]
pub struct HistogramRow {
    pub experiment: String,
    pub scene: String,
    pub frame: usize,
    pub tracer: String,
    pub parameters: String,
    pub ray_kind: String,
    pub depth: usize,
    pub aabb_tests: u64,
    pub triangle_tests: u64,
}

impl HistogramRow {
    pub fn cells(&self) -> Vec<String> {
        vec![
            self.experiment.clone(),
            self.scene.clone(),
            self.frame.to_string(),
            self.tracer.clone(),
            self.parameters.clone(),
            self.ray_kind.clone(),
            self.depth.to_string(),
            self.aabb_tests.to_string(),
            self.triangle_tests.to_string(),
        ]
    }

    /// The row as a field map, as `selection` reads rows for figures.
    pub fn fields(&self) -> Row {
        HISTOGRAM_COLUMNS
            .iter()
            .map(|c| c.to_string())
            .zip(self.cells())
            .collect()
    }

    pub fn parse(cells: &Cells) -> CellResult<HistogramRow> {
        Ok(HistogramRow {
            experiment: cells.text("experiment")?,
            scene: cells.text("scene")?,
            frame: cells.number("frame")?,
            tracer: cells.text("tracer")?,
            parameters: cells.text("parameters")?,
            ray_kind: cells.text("ray_kind")?,
            depth: cells.number("depth")?,
            aabb_tests: cells.number("aabb_tests")?,
            triangle_tests: cells.number("triangle_tests")?,
        })
    }
}

/// histograms.csv's rows.
pub fn write_histograms(path: &Path, rows: &[HistogramRow]) -> Result<()> {
    write_csv(
        path,
        HISTOGRAM_COLUMNS,
        rows.iter().map(HistogramRow::cells),
    )
}
