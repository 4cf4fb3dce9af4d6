//! Paper-vs-ours tables: each `[[tables]]` of an experiment (declared and checked in
//! `plan::table_spec`) computed over the run's rows (`TableModel`: the numbers with their spread,
//! which claims read) and written as markdown to `tables.md`.

use std::fmt::Write;

use crate::error::{Error, Result};
use crate::experiment::plan::table_spec::{RowsSpec, TableSpec};
use crate::experiment::record::cost_model::{self, Fit, Operation};
use crate::experiment::record::selection::{distinct, Filter, Measure, Reduce, Row};
use crate::experiment::record::spread::Spread;

/// A table computed from a run's rows: what tables.md shows and what claims read (`report::judge`),
/// numbers at full precision with their spread.
#[derive(Clone, Debug, PartialEq)]
pub struct TableModel {
    pub title: String,
    pub caption: String,
    pub row_header: String,
    pub columns: Vec<String>,
    /// (label, one cell per column).
    pub rows: Vec<(String, Vec<Cell>)>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A measured or derived number, shown with `decimals`.
    Number {
        value: Spread,
        decimals: usize,
    },
    /// The paper's number or a field's values, as written.
    Text(String),
    Missing,
}

impl Cell {
    /// As tables.md shows it.
    pub fn shown(&self) -> String {
        match self {
            Cell::Number { value, decimals } => format!("{:.*}", decimals, value.value),
            Cell::Text(text) => text.clone(),
            Cell::Missing => "–".to_string(),
        }
    }
}

impl TableModel {
    /// The cell of the row labelled `row` in the column headed `column`.
    pub fn cell(&self, row: &str, column: &str) -> Option<&Cell> {
        let c = self.columns.iter().position(|h| h == column)?;
        let (_, cells) = self.rows.iter().find(|(label, _)| label == row)?;
        cells.get(c)
    }

    /// The table as tables.md shows it.
    pub fn markdown(&self) -> String {
        let mut out = format!("## {}\n\n", self.title);
        if !self.caption.is_empty() {
            let _ = writeln!(out, "{}\n", self.caption.trim());
        }
        let _ = write!(out, "| {} |", self.row_header);
        for c in &self.columns {
            let _ = write!(out, " {c} |");
        }
        out.push_str("\n|---|");
        out.push_str(&"---:|".repeat(self.columns.len()));
        out.push('\n');
        for (label, cells) in &self.rows {
            let _ = write!(out, "| {label} |");
            for cell in cells {
                let _ = write!(out, " {} |", cell.shown());
            }
            out.push('\n');
        }
        out
    }
}

impl TableSpec {
    /// The table as markdown over runs.csv `rows`.
    pub fn render(&self, rows: &[Row]) -> String {
        self.model(rows).markdown()
    }

    /// The table computed over runs.csv `rows`.
    pub fn model(&self, rows: &[Row]) -> TableModel {
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
        let model_rows = table_rows
            .iter()
            .map(|(label, row_filter)| {
                let filter = self.filter.and(row_filter);
                let values = self.row_values(rows, &filter);
                let cells = self
                    .columns
                    .iter()
                    .zip(&values)
                    .map(|(c, value)| match (&c.paper, &c.text, value) {
                        (Some(paper), _, _) => paper
                            .get(label)
                            .map_or(Cell::Missing, |p| Cell::Text(paper_text(p))),
                        (None, Some(field), _) => {
                            let shown = distinct(rows, &filter.and(&c.filter), field);
                            let shown: Vec<String> =
                                shown.into_iter().filter(|v| !v.is_empty()).collect();
                            match shown.is_empty() {
                                true => Cell::Missing,
                                false => Cell::Text(shown.join(" / ")),
                            }
                        }
                        (None, None, Some(v)) => Cell::Number {
                            value: *v,
                            decimals: c.decimals.or(self.decimals).unwrap_or(2),
                        },
                        (None, None, None) => Cell::Missing,
                    })
                    .collect();
                (label.clone(), cells)
            })
            .collect();
        TableModel {
            title: self.title.clone(),
            caption: self.caption.clone(),
            row_header: self.row_header.clone(),
            columns: self.columns.iter().map(|c| c.label.clone()).collect(),
            rows: model_rows,
        }
    }

    /// Every column's number for one row (paper columns: `None`), derived columns last.
    fn row_values(&self, rows: &[Row], row_filter: &Filter) -> Vec<Option<Spread>> {
        let mut values: Vec<Option<Spread>> = self
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
                measure.spread_of(rows, &row_filter.and(&c.filter))
            })
            .collect();
        let index = |label: &str| self.columns.iter().position(|c| c.label == label);
        // Derived columns may name derived columns: settle them in as many passes as there are.
        for _ in 0..self.columns.len() {
            for (i, c) in self.columns.iter().enumerate() {
                let get = |l: &String| index(l).and_then(|j| values[j]);
                let derived = if let Some([a, b]) = &c.ratio {
                    get(a).zip(get(b)).map(|(a, b)| a.divided_by(b))
                } else if let Some(parts) = &c.sum {
                    parts
                        .iter()
                        .map(get)
                        .collect::<Option<Vec<Spread>>>()
                        .and_then(|p| p.into_iter().reduce(Spread::plus))
                } else if let Some([a, b]) = &c.difference {
                    get(a).zip(get(b)).map(|(a, b)| a.minus(b))
                } else if let Some(parts) = &c.min {
                    parts.iter().filter_map(get).reduce(Spread::min)
                } else if let Some(of) = &c.inverse {
                    get(of).map(|v| Spread::exact(c.scale.unwrap_or(1.0)).divided_by(v))
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

/// The tables of a run over its runs.csv `rows`: the experiment's, computed over the rows priced
/// by the cost model (so a column may read `box_test_seconds`), then the unit costs themselves
/// when some tracer configuration has a fit.
pub fn run_tables(tables: &[TableSpec], rows: &[Row]) -> Vec<TableModel> {
    let fits = cost_model::fits(rows);
    let priced = cost_model::priced(rows, &fits);
    let mut models: Vec<TableModel> = tables.iter().map(|t| t.model(&priced)).collect();
    models.extend(unit_costs(&fits));
    models
}

/// The title of the table of unit costs.
const UNIT_COSTS: &str = "Unit costs fitted over this run's rows";

/// The fits as a table: one row per tracer configuration and ray kinds, ns per operation.
fn unit_costs(fits: &[Fit]) -> Option<TableModel> {
    if fits.is_empty() {
        return None;
    }
    let ops: Vec<Operation> = cost_model::OPERATIONS
        .into_iter()
        .filter(|o| fits.iter().any(|f| f.costs.iter().any(|(c, _)| c == o)))
        .collect();
    let number = |value: f64, decimals: usize| Cell::Number {
        value: Spread::exact(value),
        decimals,
    };
    let rows = fits
        .iter()
        .map(|f| {
            let g = &f.group;
            let mut label = [&g.tracer, &g.parameters]
                .iter()
                .filter(|s| !s.is_empty())
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(" ");
            if g.threads != "1" {
                label.push_str(&format!(", {} threads", g.threads));
            }
            label.push_str(&format!(", {}", g.ray_kinds.join(" + ")));
            let mut cells = vec![number(f.rows as f64, 0)];
            cells.extend(ops.iter().map(|o| {
                f.costs
                    .iter()
                    .find(|(c, _)| c == o)
                    .map_or(Cell::Missing, |(_, cost)| number(cost * 1e9, 2))
            }));
            cells.push(number(f.error * 100.0, 1));
            (label, cells)
        })
        .collect();
    let mut columns = vec!["rows".to_string()];
    columns.extend(ops.iter().map(|o| format!("ns per {}", o.label)));
    columns.push("rms error %".to_string());
    Some(TableModel {
        title: UNIT_COSTS.to_string(),
        caption: "Each tracer configuration's fastest passes, per ray kind (kinds with too few \
            rows apart together), row by row, modelled as the sum of its counted operations times \
            their unit costs: non-negative least squares of the \
            relative error over the run's rows (a regression, not a calibrated kernel; \
            `record::cost_model`). A box test's cost includes its node's fetch and stack work; \
            \"rms error\" is how far the model is from the measured time of a row, in rms."
            .to_string(),
        row_header: "tracer, parameters".to_string(),
        columns,
        rows,
    })
}

/// Writes the run's tables (`run_tables`), one after the other, to `path`; nothing when there
/// are none.
pub fn write_tables(
    path: &std::path::Path,
    title: &str,
    tables: &[TableSpec],
    rows: &[Row],
) -> Result<()> {
    let models = run_tables(tables, rows);
    if models.is_empty() {
        return Ok(());
    }
    let mut out = format!("# {title}: paper vs ours\n\n");
    for table in models {
        out.push_str(&table.markdown());
        out.push('\n');
    }
    std::fs::write(path, out).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

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
