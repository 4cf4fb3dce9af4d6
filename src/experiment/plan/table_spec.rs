//! Paper-vs-ours tables: the `[[tables]]` of an experiment file, written as markdown to
//! `tables.md` in the results directory, our numbers from runs.csv beside the paper's.
//!
//! ```toml
//! [[tables]]
//! title = "Table 1: ray-triangle tests (millions), 4×4 packets"
//! caption = "optional text under the title"
//! row_header = "scene"                  # heading of the label column (default empty)
//! where = { ray_kind = "primary", threads = 1 }   # applies to every measured cell
//! metric = "triangle_tests"             # default metric of measured columns
//! scale = 1e-6                          # default 1; per column too
//! decimals = 2                          # default 2; per column too
//! within_frame = "sum"                  # rows of one frame: sum|mean|median|min|max|first
//! frames = "mean"                       # then over frames: the same choices
//! rows = "scene"                        # one row per distinct value of a field, or a list:
//! # rows = [{ label = "toys", where = { scene = "toys" } }, ...]
//! columns = [
//!   { label = "n/n", where = { "param:mailbox" = false, "param:cull" = false } },
//!   { label = "n/n paper", paper = { toys = 14.0, hand = "12.5" } },  # keyed by row label
//!   { label = "ratio", ratio = ["n/n", "y/y"] },     # quotient of two columns of the row
//!   { label = "total", sum = ["build", "trace"] },   # sum of columns of the row
//!   { label = "saved", difference = ["off", "on"] }, # one column of the row less another
//!   { label = "best", min = ["low", "refit"] },      # smallest of columns of the row
//!   { label = "fps", inverse = "total", scale = 1000 },  # scale / column (ms → frames/s)
//!   { label = "Embree best", text = "embree_best_config" },  # a field's values, as written
//! ]
//! ```
//!
//! A measured column's cell is `Measure::of` (see `selection`) over the rows matching the
//! table's, the row's and the column's `where` together. Missing values print as `–`.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::error::{Error, Result};

use crate::experiment::record::selection::{check_field, Filter, Reduce};

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    pub title: String,
    #[serde(default)]
    pub caption: String,
    #[serde(default)]
    pub row_header: String,
    #[serde(default, rename = "where")]
    pub filter: Filter,
    pub metric: Option<String>,
    pub scale: Option<f64>,
    pub decimals: Option<usize>,
    pub within_frame: Option<Reduce>,
    pub frames: Option<Reduce>,
    pub rows: RowsSpec,
    pub columns: Vec<ColumnSpec>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum RowsSpec {
    /// One row per distinct value of this field.
    Field(String),
    List(Vec<RowSpec>),
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RowSpec {
    pub label: String,
    #[serde(default, rename = "where")]
    pub filter: Filter,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ColumnSpec {
    pub label: String,
    #[serde(default, rename = "where")]
    pub filter: Filter,
    pub metric: Option<String>,
    pub scale: Option<f64>,
    pub decimals: Option<usize>,
    pub within_frame: Option<Reduce>,
    pub frames: Option<Reduce>,
    /// The paper's numbers by row label, shown as written.
    pub paper: Option<BTreeMap<String, toml::Value>>,
    pub ratio: Option<[String; 2]>,
    pub sum: Option<Vec<String>>,
    pub difference: Option<[String; 2]>,
    pub min: Option<Vec<String>>,
    pub inverse: Option<String>,
    /// A runs.csv field shown as written (e.g. which Embree configuration was the best): the
    /// distinct values of the matching rows, joined by " / ".
    pub text: Option<String>,
}

impl ColumnSpec {
    /// The columns of the row it is computed from (none for a measured column).
    pub fn inputs(&self) -> impl Iterator<Item = &String> {
        self.ratio
            .iter()
            .flatten()
            .chain(self.sum.iter().flatten())
            .chain(self.difference.iter().flatten())
            .chain(self.min.iter().flatten())
            .chain(&self.inverse)
    }

    /// Computed from other columns of the row rather than measured.
    pub fn derived(&self) -> bool {
        self.ratio.is_some()
            || self.sum.is_some()
            || self.difference.is_some()
            || self.min.is_some()
            || self.inverse.is_some()
    }
}

impl TableSpec {
    /// Usage errors for unknown fields, columns naming unknown columns, and ambiguous columns.
    pub fn check(&self) -> Result<()> {
        let what = format!("table {:?}", self.title);
        self.filter.check(&what)?;
        if let Some(m) = &self.metric {
            check_field(m, &what)?;
        }
        match &self.rows {
            RowsSpec::Field(f) => check_field(f, &format!("{what} rows"))?,
            RowsSpec::List(rows) => rows.iter().try_for_each(|r| r.filter.check(&what))?,
        }
        if self.columns.is_empty() {
            return Err(Error::usage(format!("{what}: no columns")));
        }
        let labels: Vec<&str> = self.columns.iter().map(|c| c.label.as_str()).collect();
        for c in &self.columns {
            let what = format!("{what} column {:?}", c.label);
            c.filter.check(&what)?;
            let kinds = [
                c.paper.is_some(),
                c.ratio.is_some(),
                c.sum.is_some(),
                c.difference.is_some(),
                c.min.is_some(),
                c.inverse.is_some(),
                c.text.is_some(),
            ];
            if kinds.iter().filter(|&&k| k).count() > 1 {
                return Err(Error::usage(format!(
                    "{what}: give at most one of paper, ratio, sum, difference, min, inverse, text"
                )));
            }
            if let Some(field) = &c.text {
                check_field(field, &what)?;
            }
            let refs = c.inputs();
            for r in refs {
                if !labels.contains(&r.as_str()) || *r == c.label {
                    return Err(Error::usage(format!(
                        "{what}: {r:?} is not another column of the table"
                    )));
                }
            }
            if kinds == [false; 7] {
                match c.metric.as_ref().or(self.metric.as_ref()) {
                    Some(m) => check_field(m, &what)?,
                    None => return Err(Error::usage(format!("{what}: no metric"))),
                }
            }
        }
        Ok(())
    }
}
