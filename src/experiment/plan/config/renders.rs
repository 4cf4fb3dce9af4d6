//! `render = {...}` or `[[render]]`: render workload grids (Whitted, distribution, path), one
//! workload per combination, each at most once.

use std::collections::BTreeMap;

use toml::Spanned;

use crate::error::Result;
use crate::render::renderers::RendererInfo;

use super::source::{cartesian, too_many, Source, MAX_COMBINATIONS};

pub use crate::render::renderers::{DistributionWorkload, RenderWorkload};

/// The `render` grids, one workload per combination, each at most once.
pub(super) fn expand_renders(
    src: &Source,
    render: &Spanned<toml::Value>,
) -> Result<Vec<RenderWorkload>> {
    let span = render.span();
    let not_a_table = || src.input_error(&span, "render must be a table or an array of tables");
    let tables: Vec<&toml::Table> = match render.get_ref() {
        toml::Value::Table(t) => vec![t],
        toml::Value::Array(list) => list
            .iter()
            .map(|v| v.as_table().ok_or_else(not_a_table))
            .collect::<Result<_>>()?,
        _ => return Err(not_a_table()),
    };
    let mut workloads: Vec<RenderWorkload> = Vec::new();
    for table in tables {
        let grid = table.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        let grid = expand_render_grid(src, &Spanned::new(span.clone(), grid))?;
        if workloads.len() + grid.len() > MAX_COMBINATIONS {
            return Err(too_many(src, &span));
        }
        for workload in grid {
            if workloads.contains(&workload) {
                return Err(
                    src.usage_error(&span, format!("render workload {workload} is listed twice"))
                );
            }
            workloads.push(workload);
        }
    }
    Ok(workloads)
}

/// One `render` table's grid, one workload per combination.
fn expand_render_grid(
    src: &Source,
    table: &Spanned<BTreeMap<String, toml::Value>>,
) -> Result<Vec<RenderWorkload>> {
    let mut axes = src.param_axes(table)?;
    let renderer = match axes.remove("renderer").as_deref() {
        Some([name]) => RendererInfo::find(name),
        // None or several: the same message as an unknown name.
        _ => RendererInfo::find(""),
    }
    .map_err(|e| src.usage_error(&table.span(), e))?;
    cartesian(src, &table.span(), &axes)?
        .iter()
        .map(|params| (renderer.parse)(params).map_err(|e| src.usage_error(&table.span(), e)))
        .collect()
}
