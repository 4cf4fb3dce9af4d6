//! Picking runs.csv (or histograms.csv) rows and boiling them down to one number: the shared core of the data-driven
//! `[[tables]]` (tables.md) and `[[figures]]` (line plots) of an experiment file.
//!
//! - A **field** is a runs.csv column (`scene`, `triangles`, `seconds_min`, ...) or `param:<key>`,
//!   the value of one tracer or structure parameter in the row's `parameters` cell (empty when the
//!   row's instance does not set it), or `render:<key>`, one setting of the row's `render` cell
//!   (`render:spp`, `render:aperture`; empty for ray-batch rows).
//! - A **filter** (`where = { field = value, ... }`) keeps rows whose field equals the value, or one
//!   of the values when a list is given; values compare as text the way runs.csv writes them
//!   (`threads = 1`, `"param:packet" = 8`, `"param:mailbox" = false`).
//! - A **reduction** turns the kept rows into one value: rows of the same (scene, triangles,
//!   frame) are first combined with `within_frame` (`sum` by default: primary + shadow seconds of
//!   one frame), then the per-frame values with `frames` (`mean` by default), then multiplied by
//!   `scale`. Empty cells (counts a tracer cannot measure) are skipped; no value at all is `None`.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::tracers::registry::canonical_name;

use crate::experiment::record::cost_model;
use crate::experiment::record::files::{read_text, RUNS_CSV};
use crate::experiment::record::run_row::runs_columns;
use crate::experiment::record::spread::Spread;

/// One runs.csv row: column → cell.
pub type Row = BTreeMap<String, String>;

/// How several values become one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Reduce {
    #[default]
    Mean,
    Median,
    Min,
    Max,
    Sum,
    /// The first in runs.csv order (e.g. one build time shared by a frame's ray kinds).
    First,
}

impl Reduce {
    pub fn apply(self, values: &[f64]) -> Option<f64> {
        let first = *values.first()?;
        Some(match self {
            Reduce::Mean => values.iter().sum::<f64>() / values.len() as f64,
            Reduce::Median => {
                let mut sorted = values.to_vec();
                sorted.sort_by(f64::total_cmp);
                median_of_sorted(&sorted)
            }
            Reduce::Min => values.iter().copied().fold(f64::INFINITY, f64::min),
            Reduce::Max => values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Reduce::Sum => values.iter().sum(),
            Reduce::First => first,
        })
    }
}

/// `where = { field = value | [values], ... }`: every field must match.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Filter(pub BTreeMap<String, Vec<String>>);

impl<'de> Deserialize<'de> for Filter {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let table = BTreeMap::<String, toml::Value>::deserialize(d)?;
        let mut filter = BTreeMap::new();
        for (field, value) in table {
            let values = match value {
                toml::Value::Array(list) => list.iter().map(scalar_text).collect(),
                single => vec![scalar_text(&single)],
            };
            let mut values = values
                .into_iter()
                .collect::<Option<Vec<String>>>()
                .ok_or_else(|| {
                    serde::de::Error::custom(format!(
                        "where.{field}: expected a string, number or boolean (or a list of them)"
                    ))
                })?;
            // Rows carry a tracer's new name: an old one (`embree16`) selects them too.
            if field == "tracer" {
                for v in &mut values {
                    *v = canonical_name(v).to_string();
                }
            }
            filter.insert(field, values);
        }
        Ok(Filter(filter))
    }
}

/// A scalar as runs.csv would write it (`1`, `1.5`, `true`, `low`); `None` for tables and lists.
pub fn scalar_text(value: &toml::Value) -> Option<String> {
    match value {
        toml::Value::String(s) => Some(s.clone()),
        toml::Value::Integer(i) => Some(i.to_string()),
        toml::Value::Float(x) => Some(x.to_string()),
        toml::Value::Boolean(b) => Some(b.to_string()),
        _ => None,
    }
}

impl Filter {
    pub fn matches(&self, row: &Row) -> bool {
        self.0
            .iter()
            .all(|(field, values)| values.iter().any(|v| *v == field_value(row, field)))
    }

    /// Both filters at once (`other`'s value list wins for a field both name).
    pub fn and(&self, other: &Filter) -> Filter {
        let mut both = self.0.clone();
        both.extend(other.0.clone());
        Filter(both)
    }

    pub fn check(&self, what: &str) -> Result<()> {
        self.0
            .keys()
            .try_for_each(|f| check_field(f, &format!("{what} where")))
    }
}

/// The value of `field` in `row` (see the module comment); empty when absent.
pub fn field_value(row: &Row, field: &str) -> String {
    // `key=value;...` cells: tracer parameters and render workload settings.
    let setting = |column: &str, key: &str| {
        row.get(column)
            .and_then(|cell| {
                cell.split(';')
                    .filter_map(|kv| kv.split_once('='))
                    .find(|(k, _)| *k == key)
                    .map(|(_, v)| v.to_string())
            })
            .unwrap_or_default()
    };
    if let Some(key) = field.strip_prefix("param:") {
        return setting("parameters", key);
    }
    if let Some(key) = field.strip_prefix("render:") {
        return setting("render", key);
    }
    row.get(field).cloned().unwrap_or_default()
}

/// A usage error unless `field` is a runs.csv column, a column the cost model adds
/// (`cost_model::columns`), `param:<key>` or `render:<key>`.
pub fn check_field(field: &str, what: &str) -> Result<()> {
    let priced = cost_model::columns();
    let mut known = runs_columns();
    known.extend(priced.iter().map(String::as_str));
    check_field_of(field, what, RUNS_CSV, &known)
}

/// A usage error unless `field` is one of the `known` columns of `file`, `param:<key>` or
/// `render:<key>`.
pub fn check_field_of(field: &str, what: &str, file: &str, known: &[&str]) -> Result<()> {
    let keyed = ["param:", "render:"]
        .iter()
        .any(|p| field.strip_prefix(p).is_some_and(|key| !key.is_empty()));
    match keyed || known.contains(&field) {
        true => Ok(()),
        false => Err(Error::usage(format!(
            "{what}: unknown field {field:?} (a {file} column — {} — param:<key> or render:<key>)",
            known.join(", ")
        ))),
    }
}

/// How a set of rows becomes one number.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    pub metric: String,
    pub within_frame: Reduce,
    pub frames: Reduce,
    pub scale: f64,
}

impl Measure {
    /// The reduction of `metric` over the rows `filter` keeps; `None` when no kept row has a value.
    pub fn of(&self, rows: &[Row], filter: &Filter) -> Option<f64> {
        self.spread_of(rows, filter).map(|s| s.value)
    }

    /// `of`, with the range the number spans over the run's timed passes (`Spread`): the same
    /// reductions applied to each end.
    pub fn spread_of(&self, rows: &[Row], filter: &Filter) -> Option<Spread> {
        // Frames in first-seen order, so `first` means first in runs.csv.
        let mut frames: Vec<((String, String, String), Vec<Spread>)> = Vec::new();
        for row in rows.iter().filter(|r| filter.matches(r)) {
            let Some(value) = Spread::in_row(row, &self.metric) else {
                continue;
            };
            let key = (
                field_value(row, "scene"),
                field_value(row, "triangles"),
                field_value(row, "frame"),
            );
            match frames.iter_mut().find(|(k, _)| *k == key) {
                Some((_, values)) => values.push(value),
                None => frames.push((key, vec![value])),
            }
        }
        let reduce = |how: Reduce, values: &[Spread]| -> Option<Spread> {
            let end =
                |pick: fn(&Spread) -> f64| how.apply(&values.iter().map(pick).collect::<Vec<_>>());
            Some(Spread {
                value: end(|s| s.value)?,
                low: end(|s| s.low)?,
                high: end(|s| s.high)?,
            })
        };
        let per_frame: Vec<Spread> = frames
            .iter()
            .filter_map(|(_, values)| reduce(self.within_frame, values))
            .collect();
        reduce(self.frames, &per_frame).map(|v| v.scaled(self.scale))
    }
}

/// Distinct values of `field` among the rows `filter` keeps, in runs.csv order.
pub fn distinct(rows: &[Row], filter: &Filter, field: &str) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for row in rows.iter().filter(|r| filter.matches(r)) {
        let value = field_value(row, field);
        if !seen.contains(&value) {
            seen.push(value);
        }
    }
    seen
}

/// Reads a results CSV (runs.csv, verify.csv, …) back as rows, plain or compressed
/// (`files::read_text`).
pub fn read_rows(path: &std::path::Path) -> Result<Vec<Row>> {
    let fail = |e: csv::Error| Error::input(path, None, e.to_string());
    let text = read_text(path)?
        .ok_or_else(|| Error::io(path, std::io::Error::from(std::io::ErrorKind::NotFound)))?;
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(fail)?
        .iter()
        .map(String::from)
        .collect();
    reader
        .records()
        .map(|record| {
            let record = record.map_err(fail)?;
            Ok(header
                .iter()
                .cloned()
                .zip(record.iter().map(String::from))
                .collect())
        })
        .collect()
}

/// The median of an ascending slice (the mean of the middle two for an even length).
pub fn median_of_sorted(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0
    }
}

/// A row of `(column, cell)` pairs, for tests.
#[cfg(test)]
pub fn row(cells: &[(&str, &str)]) -> Row {
    cells
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filter(text: &str) -> Filter {
        #[derive(Deserialize)]
        struct W {
            r#where: Filter,
        }
        toml::from_str::<W>(text).unwrap().r#where
    }

    #[test]
    fn filters_match_columns_params_and_lists() {
        let r = row(&[
            ("scene", "toys"),
            ("threads", "1"),
            ("parameters", "lambda=5;packet=8"),
            ("render", "renderer=distribution;aperture=7.5;spp=16"),
        ]);
        assert!(filter("where = { scene = \"toys\", threads = 1 }").matches(&r));
        assert!(filter("where = { \"param:packet\" = [4, 8] }").matches(&r));
        assert!(!filter("where = { \"param:packet\" = 4 }").matches(&r));
        // An unset parameter is the empty string.
        assert!(filter("where = { \"param:mailbox\" = \"\" }").matches(&r));
        assert_eq!(field_value(&r, "param:lambda"), "5");
        assert_eq!(field_value(&r, "render:aperture"), "7.5");
        assert_eq!(field_value(&r, "render:shutter"), "");
        assert!(filter("where = { \"render:spp\" = 16 }").matches(&r));
        assert!(check_field("render:spp", "t").is_ok());
        assert!(check_field("render:", "t").is_err());
        assert!(check_field("param:x", "t").is_ok());
        assert!(check_field("seconds_min", "t").is_ok());
        assert!(check_field("secs", "t").is_err());
    }

    #[test]
    fn measures_combine_within_then_across_frames() {
        // Two frames, two ray kinds each: per-frame sums 3 and 7, mean 5; max over frames 7;
        // first within frame: 1 and 3, mean 2. Scale 10. An empty cell is skipped.
        let rows: Vec<Row> = [("0", "1"), ("0", "2"), ("1", "3"), ("1", "4"), ("1", "")]
            .iter()
            .map(|(frame, v)| row(&[("scene", "s"), ("frame", frame), ("seconds_min", v)]))
            .collect();
        let m = |within_frame, frames| Measure {
            metric: "seconds_min".into(),
            within_frame,
            frames,
            scale: 10.0,
        };
        let all = Filter::default();
        assert_eq!(m(Reduce::Sum, Reduce::Mean).of(&rows, &all), Some(50.0));
        assert_eq!(m(Reduce::Sum, Reduce::Max).of(&rows, &all), Some(70.0));
        assert_eq!(m(Reduce::First, Reduce::Mean).of(&rows, &all), Some(20.0));
        assert_eq!(m(Reduce::Max, Reduce::Median).of(&rows, &all), Some(30.0));
        assert_eq!(
            m(Reduce::Sum, Reduce::Mean).of(&rows, &filter("where = { scene = \"x\" }")),
            None
        );
        assert_eq!(distinct(&rows, &all, "frame"), ["0", "1"]);
    }
}
