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
//!   { label = "best", min = ["low", "refit"] },      # smallest of columns of the row
//!   { label = "fps", inverse = "total", scale = 1000 },  # scale / column (ms → frames/s)
//!   { label = "Embree best", text = "embree_best_config" },  # a field's values, as written
//! ]
//! ```
//!
//! A measured column's cell is `Measure::of` (see `selection`) over the rows matching the
//! table's, the row's and the column's `where` together. Missing values print as `–`.

use std::collections::BTreeMap;
use std::fmt::Write;

use serde::Deserialize;

use crate::error::{Error, Result};

use super::selection::{check_field, distinct, Filter, Measure, Reduce, Row};

pub const TABLES_MD: &str = "tables.md";

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
    pub min: Option<Vec<String>>,
    pub inverse: Option<String>,
    /// A runs.csv field shown as written (e.g. which Embree configuration was the best): the
    /// distinct values of the matching rows, joined by " / ".
    pub text: Option<String>,
}

impl ColumnSpec {
    /// Computed from other columns of the row rather than measured.
    fn derived(&self) -> bool {
        self.ratio.is_some() || self.sum.is_some() || self.min.is_some() || self.inverse.is_some()
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
                c.min.is_some(),
                c.inverse.is_some(),
                c.text.is_some(),
            ];
            if kinds.iter().filter(|&&k| k).count() > 1 {
                return Err(Error::usage(format!(
                    "{what}: give at most one of paper, ratio, sum, min, inverse, text"
                )));
            }
            if let Some(field) = &c.text {
                check_field(field, &what)?;
            }
            let refs = c
                .ratio
                .iter()
                .flatten()
                .chain(c.sum.iter().flatten())
                .chain(c.min.iter().flatten())
                .chain(&c.inverse);
            for r in refs {
                if !labels.contains(&r.as_str()) || *r == c.label {
                    return Err(Error::usage(format!(
                        "{what}: {r:?} is not another column of the table"
                    )));
                }
            }
            if kinds == [false; 6] {
                match c.metric.as_ref().or(self.metric.as_ref()) {
                    Some(m) => check_field(m, &what)?,
                    None => return Err(Error::usage(format!("{what}: no metric"))),
                }
            }
        }
        Ok(())
    }

    /// The table as markdown over runs.csv `rows`.
    pub fn render(&self, rows: &[Row]) -> String {
        let table_rows: Vec<(String, Filter)> = match &self.rows {
            RowsSpec::Field(field) => distinct(rows, &self.filter, field)
                .into_iter()
                .map(|value| {
                    let filter = Filter([(field.clone(), vec![value.clone()])].into());
                    (value, filter)
                })
                .collect(),
            RowsSpec::List(list) => list
                .iter()
                .map(|r| (r.label.clone(), r.filter.clone()))
                .collect(),
        };
        let mut out = format!("## {}\n\n", self.title);
        if !self.caption.is_empty() {
            let _ = writeln!(out, "{}\n", self.caption.trim());
        }
        let _ = write!(out, "| {} |", self.row_header);
        for c in &self.columns {
            let _ = write!(out, " {} |", c.label);
        }
        out.push_str("\n|---|");
        out.push_str(&"---:|".repeat(self.columns.len()));
        out.push('\n');
        for (label, row_filter) in &table_rows {
            let filter = self.filter.and(row_filter);
            let values = self.row_values(rows, &filter);
            let _ = write!(out, "| {label} |");
            for (c, value) in self.columns.iter().zip(&values) {
                let text = match (&c.paper, &c.text, value) {
                    (Some(paper), _, _) => paper.get(label).map_or("–".to_string(), paper_text),
                    (None, Some(field), _) => {
                        let shown = distinct(rows, &filter.and(&c.filter), field);
                        let shown: Vec<String> =
                            shown.into_iter().filter(|v| !v.is_empty()).collect();
                        match shown.is_empty() {
                            true => "–".to_string(),
                            false => shown.join(" / "),
                        }
                    }
                    (None, None, Some(v)) => {
                        format!("{v:.*}", c.decimals.or(self.decimals).unwrap_or(2))
                    }
                    (None, None, None) => "–".to_string(),
                };
                let _ = write!(out, " {text} |");
            }
            out.push('\n');
        }
        out
    }

    /// Every column's number for one row (paper columns: `None`), derived columns last.
    fn row_values(&self, rows: &[Row], row_filter: &Filter) -> Vec<Option<f64>> {
        let mut values: Vec<Option<f64>> = self
            .columns
            .iter()
            .map(|c| {
                if c.paper.is_some() || c.text.is_some() || c.derived() {
                    return None;
                }
                let measure = Measure {
                    metric: c.metric.clone().or(self.metric.clone())?,
                    within_frame: c.within_frame.or(self.within_frame).unwrap_or(Reduce::Sum),
                    frames: c.frames.or(self.frames).unwrap_or(Reduce::Mean),
                    scale: c.scale.or(self.scale).unwrap_or(1.0),
                };
                measure.of(rows, &row_filter.and(&c.filter))
            })
            .collect();
        let index = |label: &str| self.columns.iter().position(|c| c.label == label);
        // Derived columns may name derived columns: settle them in as many passes as there are.
        for _ in 0..self.columns.len() {
            for (i, c) in self.columns.iter().enumerate() {
                let get = |l: &String| index(l).and_then(|j| values[j]);
                let derived = if let Some([a, b]) = &c.ratio {
                    get(a).zip(get(b)).map(|(a, b)| a / b)
                } else if let Some(parts) = &c.sum {
                    parts.iter().map(get).sum()
                } else if let Some(parts) = &c.min {
                    parts.iter().filter_map(get).reduce(f64::min)
                } else if let Some(of) = &c.inverse {
                    get(of).map(|v| c.scale.unwrap_or(1.0) / v)
                } else {
                    continue;
                };
                values[i] = derived;
            }
        }
        values
    }
}

fn paper_text(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Writes every table, one after the other, to `path`.
pub fn write_tables(
    path: &std::path::Path,
    title: &str,
    tables: &[TableSpec],
    rows: &[Row],
) -> Result<()> {
    let mut out = format!("# {title}: paper vs ours\n\n");
    for table in tables {
        out.push_str(&table.render(rows));
        out.push('\n');
    }
    std::fs::write(path, out).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> TableSpec {
        #[derive(Deserialize)]
        struct File {
            tables: Vec<TableSpec>,
        }
        toml::from_str::<File>(text).unwrap().tables.remove(0)
    }

    #[test]
    fn unknown_fields_and_bad_columns_are_usage_errors() {
        let bad = table(
            "[[tables]]\ntitle = \"t\"\nrows = \"scene\"\nmetric = \"seconds\"\ncolumns = [{ label = \"a\" }]\n",
        );
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("unknown field \"seconds\""));
        let bad = table(
            "[[tables]]\ntitle = \"t\"\nrows = \"scene\"\ncolumns = [{ label = \"a\", ratio = [\"a\", \"b\"] }]\n",
        );
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("not another column"));
        let bad =
            table("[[tables]]\ntitle = \"t\"\nrows = \"scene\"\ncolumns = [{ label = \"a\" }]\n");
        assert!(bad.check().unwrap_err().to_string().contains("no metric"));
    }

    #[test]
    fn text_columns_show_the_field_as_written_beside_the_numbers() {
        let spec = table(
            "[[tables]]\ntitle = \"t\"\nrows = \"scene\"\nmetric = \"seconds_min\"\nscale = 1000\ncolumns = [\n\
             { label = \"ours\", where = { tracer = \"packet\" } },\n\
             { label = \"best\", metric = \"embree_best_seconds\", where = { tracer = \"packet\" } },\n\
             { label = \"config\", text = \"embree_best_config\", where = { tracer = \"packet\" } },\n\
             { label = \"x\", ratio = [\"best\", \"ours\"] },\n]\n",
        );
        spec.check().unwrap();
        let row = |scene: &str, seconds: &str, best: &str, config: &str| -> Row {
            [
                ("scene", scene),
                ("tracer", "packet"),
                ("frame", "0"),
                ("seconds_min", seconds),
                ("embree_best_seconds", best),
                ("embree_best_config", config),
            ]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
        };
        let rows = [
            row(
                "room",
                "0.010",
                "0.020",
                "embree16 context=coherent quality=high",
            ),
            row("hall", "0.040", "", ""),
        ];
        let text = spec.render(&rows);
        assert!(
            text.contains(
                "| room | 10.00 | 20.00 | embree16 context=coherent quality=high | 2.00 |"
            ),
            "{text}"
        );
        // A run without an Embree row for the group: dashes, not an empty config.
        assert!(text.contains("| hall | 40.00 | – | – | – |"), "{text}");
        let both = table(
            "[[tables]]\ntitle = \"t\"\nrows = \"scene\"\ncolumns = [{ label = \"a\", text = \"tracer\", ratio = [\"a\", \"a\"] }]\n",
        );
        assert!(both
            .check()
            .unwrap_err()
            .to_string()
            .contains("at most one"));
    }
}
