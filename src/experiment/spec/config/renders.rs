//! `render = {...}` or `[[render]]`: render workload grids (Whitted, distribution, path), one
//! workload per combination, each at most once.

use std::collections::BTreeMap;
use std::fmt;

use toml::Spanned;

use crate::error::{Error, Result};
use crate::render::distribution::{DrtSettings, Integrator};
use crate::render::whitted::WhittedSettings;
use crate::tracers::Params;

use super::source::{cartesian, too_many, Source, MAX_COMBINATIONS};

/// One combination of a `render` grid: rendering a frame with one renderer and its settings.
#[derive(Clone, Debug, PartialEq)]
pub enum RenderWorkload {
    Whitted(WhittedSettings),
    Distribution(DistributionWorkload),
}

/// A distribution ray tracing workload (Boulos et al. 2007 §4) or, with `settings.integrator`
/// `Path`, a path tracing one (Gribble & Ramani 2008 §4). Its `settings` carry no image size: the
/// runner renders at the experiment's resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistributionWorkload {
    pub settings: DrtSettings,
    /// Shutter interval in seconds of the scene's animation from the frame's time (motion blur);
    /// the tracers then run over the moving geometry (`render::motion`).
    pub shutter: Option<f32>,
    /// Whether frame rows carry the RMSE against the cached high-spp reference image (`rmse =
    /// false` in the `render` table skips the reference, for workloads measured for speed only).
    pub rmse: bool,
}

impl DistributionWorkload {
    /// The same workload at another sample count, or with other refinements (filter, retrace)
    /// of interleaved soft shadows: the points of one error-vs-time plot.
    pub fn same_but_spp(&self, other: &DistributionWorkload) -> bool {
        let with_spp = |w: &DistributionWorkload| DrtSettings {
            spp: 0,
            soft_shadows: w.settings.soft_shadows.map(|m| m.unrefined()),
            ..w.settings
        };
        with_spp(self) == with_spp(other)
            && self.shutter == other.shutter
            && self.rmse == other.rmse
    }
}

impl fmt::Display for RenderWorkload {
    /// Every setting, defaults included, except the per-kind depth limits, which appear only when
    /// set (unset they are `max_depth`): the `render` column of runs.csv.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let camera = |v: Option<f32>| v.map_or("camera".to_string(), |v| v.to_string());
        let limit =
            |key: &str, depth: Option<u32>| depth.map_or(String::new(), |d| format!(";{key}={d}"));
        match self {
            RenderWorkload::Whitted(s) => write!(
                f,
                "renderer=whitted;assembly={};materials={};max_depth={}{}{};packet={};pruning={};shadows={}",
                s.assembly,
                s.materials.map_or("scene", |p| p.name()),
                s.max_depth,
                limit("max_reflection_depth", s.max_reflection_depth),
                limit("max_refraction_depth", s.max_refraction_depth),
                s.packet,
                s.pruning.map_or("false".to_string(), |t| t.to_string()),
                s.shadows
            ),
            RenderWorkload::Distribution(w) => write!(
                f,
                "renderer={};aperture={};focus={};max_depth={}{};shutter={};spp={}{}",
                w.settings.integrator.name(),
                camera(w.settings.aperture),
                camera(w.settings.focus_distance),
                w.settings.max_depth,
                if w.rmse { "" } else { ";rmse=false" },
                w.shutter.map_or("none".to_string(), |s| s.to_string()),
                w.settings.spp,
                w.settings.soft_shadows.map_or(String::new(), |m| format!(
                    ";shadows=interleaved;sets={};filter={};retrace={}",
                    m.sets.name(),
                    m.filter,
                    m.retrace
                ))
            ),
        }
    }
}

/// One combination of a distribution or path `render` grid: the renderer's settings and the
/// workload's shutter interval (motion blur), or what is wrong with them.
fn distribution_workload(integrator: Integrator, params: &Params) -> Result<DistributionWorkload> {
    let mut settings = params.clone();
    let shutter = match settings.0.remove("shutter") {
        None => None,
        Some(value) => match value.parse::<f32>() {
            Ok(s) if s > 0.0 && s.is_finite() => Some(s),
            _ => {
                return Err(Error::usage(format!(
                    "render shutter = {value:?} is not valid (a shutter interval > 0 s)"
                )))
            }
        },
    };
    let rmse = match settings.0.remove("rmse").as_deref() {
        None | Some("true") => true,
        Some("false") => false,
        Some(value) => {
            return Err(Error::usage(format!(
                "render rmse = {value:?} is not valid (true or false)"
            )))
        }
    };
    Ok(DistributionWorkload {
        settings: DrtSettings::from_params(integrator, &settings, &["shutter", "rmse"])?,
        shutter,
        rmse,
    })
}

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
    let workload: fn(&Params) -> Result<RenderWorkload> = match axes.remove("renderer").as_deref() {
        Some([name]) if name == "whitted" => {
            |params| WhittedSettings::from_params(params).map(RenderWorkload::Whitted)
        }
        Some([name]) if name == "distribution" => |params| {
            distribution_workload(Integrator::Distribution, params)
                .map(RenderWorkload::Distribution)
        },
        Some([name]) if name == "path" => |params| {
            distribution_workload(Integrator::Path, params).map(RenderWorkload::Distribution)
        },
        _ => {
            return Err(src.usage_error(
                &table.span(),
                "render needs renderer = \"whitted\", \"distribution\" or \"path\"",
            ))
        }
    };
    cartesian(src, &table.span(), &axes)?
        .iter()
        .map(|params| workload(params).map_err(|e| src.usage_error(&table.span(), e)))
        .collect()
}
