//! Line plots declared in the experiment file (`[[figures]]`), drawn from runs.csv into the
//! results directory: one line per series value (and per metric, when `y` lists several), points
//! at each distinct x value, each point a `Measure` (see `selection`).
//!
//! ```toml
//! [[figures]]
//! data = "runs"                      # runs.csv (default) or "histograms": histograms.csv, one
//!                                    # row per BVH depth (x = "depth", y = "aabb_tests" or
//!                                    # "triangle_tests"; ray batches only)
//! file = "fig6_lambda.png"
//! title = "Fig. 6: frame rate (normalised by the best) vs λ"
//! where = { tracer = "cgt", ray_kind = "primary", threads = 1 }
//! x = "param:lambda"                 # a numeric field
//! y = "seconds_min"                  # or a list of metrics, one line each
//! series = "scene"                   # optional: one line per distinct value
//! within_frame = "sum"               # as in tables (default sum, then mean over frames)
//! frames = "mean"
//! scale = 1.0
//! reciprocal = true                  # plot 1/value (frame rate from seconds)
//! normalise = true                   # divide each line by its largest value
//! x_label = "λ"                      # axis captions (default: the field names)
//! y_label = "normalised frame rate"
//! log_x = false                      # log10 axes
//! log_y = false
//! ```

use serde::Deserialize;

use crate::error::{Error, Result};

use crate::experiment::record::files::{HISTOGRAMS_CSV, RUNS_CSV};
use crate::experiment::record::histogram_row::HISTOGRAM_COLUMNS;
use crate::experiment::record::run_row::runs_columns;
use crate::experiment::record::selection::{check_field_of, Filter, Reduce};

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FigureSpec {
    #[serde(default)]
    pub data: DataFile,
    pub file: String,
    pub title: String,
    #[serde(default, rename = "where")]
    pub filter: Filter,
    pub x: String,
    pub y: Metrics,
    pub series: Option<String>,
    #[serde(default = "sum")]
    pub within_frame: Reduce,
    #[serde(default)]
    pub frames: Reduce,
    #[serde(default = "one")]
    pub scale: f64,
    #[serde(default)]
    pub reciprocal: bool,
    #[serde(default)]
    pub normalise: bool,
    pub x_label: Option<String>,
    pub y_label: Option<String>,
    #[serde(default)]
    pub log_x: bool,
    #[serde(default)]
    pub log_y: bool,
}

fn sum() -> Reduce {
    Reduce::Sum
}
fn one() -> f64 {
    1.0
}

/// The CSV file of the run a figure reads.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum DataFile {
    #[default]
    Runs,
    Histograms,
}

impl DataFile {
    pub fn file_name(self) -> &'static str {
        match self {
            DataFile::Runs => RUNS_CSV,
            DataFile::Histograms => HISTOGRAMS_CSV,
        }
    }

    fn columns(self) -> Vec<&'static str> {
        match self {
            DataFile::Runs => runs_columns(),
            DataFile::Histograms => HISTOGRAM_COLUMNS.to_vec(),
        }
    }
}

/// One metric or several.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Metrics {
    One(String),
    Many(Vec<String>),
}

impl Metrics {
    pub fn list(&self) -> Vec<&str> {
        match self {
            Metrics::One(m) => vec![m.as_str()],
            Metrics::Many(ms) => ms.iter().map(String::as_str).collect(),
        }
    }
}

/// One line: its legend label and its points, sorted by x.
pub type Line = (String, Vec<(f64, f64)>);

impl FigureSpec {
    pub fn check(&self) -> Result<()> {
        let what = format!("figure {:?}", self.file);
        let stem_ok =
            self.file.ends_with(".png") && !self.file.contains('/') && !self.file.starts_with('.');
        if !stem_ok {
            return Err(Error::usage(format!(
                "{what}: file must be a plain name ending in .png"
            )));
        }
        let (file, known) = (self.data.file_name(), self.data.columns());
        let check = |field: &str| check_field_of(field, &what, file, &known);
        self.filter.0.keys().try_for_each(|f| check(f))?;
        check(&self.x)?;
        if let Some(s) = &self.series {
            check(s)?;
        }
        let metrics = self.y.list();
        if metrics.is_empty() {
            return Err(Error::usage(format!("{what}: no y metric")));
        }
        metrics.iter().try_for_each(|m| check(m))
    }
}
