//! `tracers = [...]` and the shared `params` grid: each tracer × the cartesian product of its
//! parameter lists, checked against the registry, each instance at most once; `embree-best`
//! expands to every Embree configuration, `baseline-best` to those and every other production
//! baseline at its recommended settings.

use std::collections::BTreeMap;
use std::fmt;

use serde::Deserialize;
use toml::Spanned;

use crate::accel::AccelKind;
use crate::error::Result;
use crate::tracers::registry::{not_built, Axes, BaselineBest, TINYBVH_BUILT, TINYBVH_HINT};
use crate::tracers::{Params, TracerConfig, TracerInfo, TRACERS};

use super::source::{cartesian, line_of, too_many, Source, MAX_COMBINATIONS};
use super::{ExperimentFile, NameOr};

/// One tracer with one combination of parameters: one column of every comparison.
#[derive(Clone)]
pub struct TracerInstance {
    pub info: &'static TracerInfo,
    /// The tracer's and its structure's parameters (the structure reads its own subset).
    pub params: Params,
    /// The tracer's own parameters, parsed once (`TracerInfo::config`): what its tracers are made
    /// from.
    pub config: TracerConfig,
    /// The line of its entry in the experiment file, where an error in its values points.
    pub line: usize,
}

/// The structure a tracer instance traverses: instances with equal keys share one build.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StructureKey {
    pub kind: AccelKind,
    pub params: Params,
}

impl TracerInstance {
    pub fn structure(&self) -> StructureKey {
        let (kind, params) = self.info.structure(&self.config, &self.params);
        StructureKey { kind, params }
    }
}

impl fmt::Debug for TracerInstance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl fmt::Display for TracerInstance {
    /// `name` or `name[key=value;...]`: the label in the plan, the plots and the progress bar.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&label(self.info, &self.params))
    }
}

/// A tracer instance's label (its `Display`).
fn label(info: &TracerInfo, params: &Params) -> String {
    match params.0.is_empty() {
        true => info.name.to_string(),
        false => format!("{}[{params}]", info.name),
    }
}

impl fmt::Display for StructureKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.params.0.is_empty() {
            f.write_str(self.kind.name())
        } else {
            write!(f, "{}[{}]", self.kind.name(), self.params)
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TracerTable {
    name: String,
    #[serde(default)]
    params: Option<Spanned<BTreeMap<String, toml::Value>>>,
    /// A tracer this build may lack (Embree 4's, `accel::embree::EMBREE4_BUILT`): skipped with a
    /// note rather than refused when it is not built.
    #[serde(default)]
    if_built: bool,
}

impl From<String> for TracerTable {
    fn from(name: String) -> Self {
        TracerTable {
            name,
            params: None,
            if_built: false,
        }
    }
}

/// Each tracer × the cartesian product of its parameter lists: its own `params` table plus every
/// shared-grid key it reads (its own table wins where both give a key).
pub(super) fn expand_tracers(src: &Source, file: &ExperimentFile) -> Result<Vec<TracerInstance>> {
    let shared = match &file.params {
        Some(table) => src.param_axes(table)?,
        None => BTreeMap::new(),
    };
    let mut used_shared = vec![false; shared.len()];
    let mut instances: Vec<TracerInstance> = Vec::new();
    for TracerEntry {
        entry,
        info,
        sweep,
        fixed,
    } in tracer_entries(src, file)?
    {
        let table = &entry.get_ref().0;
        let accepts = info.accepts();
        let mut axes = match &table.params {
            Some(params) if !fixed => src.param_axes(params)?,
            _ => BTreeMap::new(),
        };
        for &(key, values) in sweep {
            axes.entry(key.to_string())
                .or_insert_with(|| values.iter().map(|v| v.to_string()).collect());
        }
        if let Some(unknown) = axes.keys().find(|k| !accepts.contains(&k.as_str())) {
            return Err(src.usage_error(
                &entry.span(),
                format!(
                    "unknown parameter {unknown:?} for tracer {} (known: {})",
                    info.name,
                    accepts.join(", ")
                ),
            ));
        }
        for (i, (key, values)) in shared.iter().enumerate() {
            if !fixed && accepts.contains(&key.as_str()) {
                used_shared[i] = true;
                axes.entry(key.clone()).or_insert_with(|| values.clone());
            }
        }
        let grid = cartesian(src, &entry.span(), &axes)?;
        if instances.len() + grid.len() > MAX_COMBINATIONS {
            return Err(too_many(src, &entry.span()));
        }
        for params in grid {
            // The values are checked now, not an hour into the run: the structure's, then the
            // tracer's, parsed into the configuration its tracers are made from.
            let config = info
                .accel
                .check_params(&params.subset(info.accel.params()))
                .and_then(|()| info.config(&params))
                .map_err(|e| {
                    src.usage_error(
                        &entry.span(),
                        format!("tracer {}: {e}", label(info, &params)),
                    )
                })?;
            let instance = TracerInstance {
                info,
                params,
                config,
                line: line_of(src.text, &entry.span()),
            };
            if instances
                .iter()
                .any(|i| i.info.name == info.name && i.params == instance.params)
            {
                return Err(src.usage_error(
                    &entry.span(),
                    format!("tracer instance {instance} is listed twice"),
                ));
            }
            instances.push(instance);
        }
    }
    if instances.is_empty() {
        return Err(src.input_error(&file.tracers.span(), "no tracers"));
    }
    if let Some((key, _)) = shared.keys().zip(&used_shared).find(|(_, used)| !**used) {
        let span = file.params.as_ref().map(|p| p.span()).unwrap_or(0..0);
        return Err(src.usage_error(
            &span,
            format!("shared parameter {key:?} is read by none of the tracers"),
        ));
    }
    Ok(instances)
}

/// The shorthand tracer entry for Embree at its best: every Embree entry point (1, 4, 8, 16,
/// stream) × intersect context × build quality (the registry's `BaselineBest::Sweep`), so that the
/// run measures the fastest Embree configuration on its rays. The entry's own `params` replace an
/// axis (e.g. `quality = ["low", "refit"]` for per-frame rebuilds); the entry points share one
/// scene per quality.
pub const EMBREE_BEST: &str = "embree-best";

/// The shorthand tracer entry for the production baselines at their best: `embree-best`, plus
/// the other libraries at their recommended settings (`BaselineBest::Fixed`: tinybvh's and
/// obvhs's), so that runs.csv's `baseline_best` is the fastest production library on the rays,
/// not only the fastest Embree. The entry's own `params` go to its Embree tracers, as
/// `embree-best`'s do.
pub const BASELINE_BEST: &str = "baseline-best";

/// A tracer entry of the file and one tracer it names, with the axes it sweeps by default;
/// `fixed`: those axes are all it runs with (neither the entry's nor the shared `params` apply).
struct TracerEntry<'f> {
    entry: &'f Spanned<NameOr<TracerTable>>,
    info: &'static TracerInfo,
    sweep: Axes,
    fixed: bool,
}

/// Each tracer entry with the tracer it names (`embree-best` names every Embree tracer,
/// `baseline-best` those and the other libraries' `BaselineBest::Fixed` ones).
fn tracer_entries<'f>(src: &Source, file: &'f ExperimentFile) -> Result<Vec<TracerEntry<'f>>> {
    let mut entries = Vec::new();
    for entry in file.tracers.get_ref() {
        let name = &entry.get_ref().0.name;
        let named = |info, sweep, fixed| TracerEntry {
            entry,
            info,
            sweep,
            fixed,
        };
        match name.as_str() {
            EMBREE_BEST | BASELINE_BEST => {
                for info in TRACERS {
                    match (info.best, name.as_str()) {
                        (BaselineBest::Sweep(axes), _) => entries.push(named(info, axes, false)),
                        (BaselineBest::Fixed(axes), BASELINE_BEST) => {
                            entries.push(named(info, axes, true))
                        }
                        _ => {}
                    }
                }
                if name == BASELINE_BEST && !TINYBVH_BUILT {
                    eprintln!(
                        "note: {}: {name} without tinybvh: {TINYBVH_HINT}",
                        src.path.display()
                    )
                }
            }
            _ => match TracerInfo::find(name) {
                Ok(info) => entries.push(named(info, &[], false)),
                Err(e) if entry.get_ref().0.if_built && not_built(name) => {
                    eprintln!(
                        "note: {}: skipping {name} (if_built): {e}",
                        src.path.display()
                    )
                }
                Err(e) => return Err(src.usage_error(&entry.span(), e)),
            },
        }
    }
    Ok(entries)
}
