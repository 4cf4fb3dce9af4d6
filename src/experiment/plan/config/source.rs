//! Pointing at a place in the experiment file, and parameter grids: a table's values as axes,
//! expanded to every combination, bounded.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::Path;

use toml::Spanned;

use crate::error::{Error, Result};
use crate::tracers::Params;

/// Where a span starts, as a 1-based line of `text`.
pub(super) fn line_of(text: &str, span: &Range<usize>) -> usize {
    text[..span.start.min(text.len())].matches('\n').count() + 1
}

/// Everything needed to point at a place in the experiment file.
pub(super) struct Source<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl Source<'_> {
    pub fn input_error(&self, span: &Range<usize>, message: impl Into<String>) -> Error {
        Error::at_line(self.path, line_of(self.text, span), message)
    }

    /// A bad name: a usage error (exit code 2) that still says where in which file.
    pub fn usage_error(&self, span: &Range<usize>, message: impl fmt::Display) -> Error {
        Error::usage(format!(
            "{}:{}: {message}",
            self.path.display(),
            line_of(self.text, span)
        ))
    }

    /// A parameter table as name → list of values (a single value is a one-value list).
    pub fn param_axes(
        &self,
        table: &Spanned<BTreeMap<String, toml::Value>>,
    ) -> Result<BTreeMap<String, Vec<String>>> {
        let span = table.span();
        let scalar = |key: &str, v: &toml::Value| -> Result<String> {
            match v {
                toml::Value::String(s) => Ok(s.clone()),
                toml::Value::Integer(i) => Ok(i.to_string()),
                toml::Value::Float(x) => Ok(x.to_string()),
                toml::Value::Boolean(b) => Ok(b.to_string()),
                other => Err(self.input_error(
                    &span,
                    format!(
                        "parameter {key}: expected a number, string or boolean, found {}",
                        other.type_str()
                    ),
                )),
            }
        };
        table
            .get_ref()
            .iter()
            .map(|(key, value)| {
                let values = match value {
                    toml::Value::Array(list) if list.is_empty() => {
                        return Err(self
                            .input_error(&span, format!("parameter {key}: empty list of values")))
                    }
                    toml::Value::Array(list) => {
                        list.iter().map(|v| scalar(key, v)).collect::<Result<_>>()?
                    }
                    single => vec![scalar(key, single)?],
                };
                Ok((key.clone(), values))
            })
            .collect()
    }
}

/// More tracer instances or render workloads than this is a typo, not an experiment (the
/// committed ones have at most 36): a few short lists multiply to millions, each checked against
/// the others for repeats.
pub(super) const MAX_COMBINATIONS: usize = 1000;

pub(super) fn too_many(src: &Source, span: &Range<usize>) -> Error {
    src.input_error(
        span,
        format!("the parameter lists make more than {MAX_COMBINATIONS} combinations"),
    )
}

/// All combinations of one value per key, the first key varying slowest; refused (at `span`)
/// when there are more than `MAX_COMBINATIONS`.
pub(super) fn cartesian(
    src: &Source,
    span: &Range<usize>,
    axes: &BTreeMap<String, Vec<String>>,
) -> Result<Vec<Params>> {
    let count = axes.values().fold(1usize, |n, v| n.saturating_mul(v.len()));
    if count > MAX_COMBINATIONS {
        return Err(too_many(src, span));
    }
    Ok(axes
        .iter()
        .fold(vec![Params::new()], |partial, (key, values)| {
            partial
                .iter()
                .flat_map(|p| values.iter().map(move |v| p.clone().with(key, v)))
                .collect()
        }))
}
