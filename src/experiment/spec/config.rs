//! The experiment file: which scenes, which tracers over which parameter grid, which rays, how
//! many frames, threads and repeats. Parsing checks every name (tracer, ray kind, parameter) and
//! expands the grid into the exact list of tracer instances, so nothing unknown reaches the run.
//!
//! ```toml
//! name = "quick"
//! description = "built-in scenes, all ray kinds"
//! scenes = ["room", { name = "balls", size = 3 }]
//! tracers = ["reference", { name = "embree3-16", params = { quality = ["low", "high"] } },
//!            { name = "embree4-16", if_built = true }]   # skipped (with a note) by a build
//!                                      # without Embree 4; without `if_built` such a build refuses
//! params = { leaf_size = [2, 4] }      # shared grid: applies to every tracer that reads the key
//! rays = ["primary", "shadow", "diffuse", "reflection", "refraction"]   # ray batches (optional
//!                                      # with `render`): each kind traced on its own; reflection and
//!                                      # refraction leave the primary hits (bounce 1)
//!                                      # `{ file = "my.rays" }` entries (path relative to this file;
//!                                      # binary or CSV, see `geometry::ray_file`) mix with the kinds:
//!                                      # the file's rays, closest hit, measured on every scene and
//!                                      # frame; runs.csv's ray_kind says `file:my.rays`
//! # A rendering workload (optional): every tracer instance renders each frame with the Whitted
//! # renderer, once per combination of the lists below (a single value is a one-value list).
//! # Or `[[render]]` tables, each its own grid (e.g. one per workload of Overbeck 2008, Fig. 5).
//! # The distribution renderer takes the same form (Boulos 2007 §4):
//! #   render = { renderer = "distribution", spp = [1, 4, 16, 64],   # perfect squares
//! #              aperture = [0, 15], focus = 1650,   # lens radius, focal distance (default: camera's)
//! #              shutter = 0.25,                     # motion blur over this many seconds (optional)
//! #              max_depth = 1 }                     # glossy/mirror bounces (default 2)
//! # Soft shadows as Benthin & Wald 2009 §4.5 render them (`render::interleaved_shadows`): one
//! # camera ray per pixel, `spp` light samples per pixel from 4×4 interleaved sets, shading at the
//! # light's centre, direct light only (max_depth 0, no aperture, no shutter):
//! #   render = { renderer = "distribution", shadows = "interleaved",   # default "sampled"
//! #              sets = "hammersley",   # jittered (default) | hammersley | lp (powers of 4)
//! #              filter = [true, false],   # 4×4 discontinuity filter (default true)
//! #              retrace = 256,         # light samples per partly occluded pixel (default 0: off)
//! #              spp = [4, 16, 64] }
//! # The frame row's `retraced_share` is the share of pixels retraced.
//! # Its frame rows also carry `rmse` against the 1024-spp reference image (cached under
//! # <output>/cache/drt-reference), and workloads differing only in spp give error_vs_time.png.
//! render = { renderer = "whitted",
//!            max_depth = [1, 2],       # deepest reflection/refraction generation (default 5)
//!            max_reflection_depth = 1, # deepest reflection generation (default max_depth)
//!            max_refraction_depth = 4, # deepest refraction generation (default max_depth)
//!            shadows = true,           # shadow rays (default true)
//!            pruning = [true, false],  # ray-tree attenuation: true (threshold 1/256), false, or a
//!                                      # threshold such as 0.01 (default true)
//!            assembly = ["runs", "ray_types"],  # none | runs | groups | ray_types | blind
//!                                      # (default ray_types; Boulos et al. 2007 §3.2)
//!            packet = [4, 8],          # side n of the incoming n×n packets (default 8): match the
//!                                      # tracer's packet size
//!            materials = ["scene", "glass"] }   # scene (as loaded) | diffuse | mirror | glossy |
//!                                      # glass: that preset on every material (default scene)
//! resolution = { width = 1024, height = 1024 }
//! frames = 2
//! threads = [1, 2]
//! warmup = 1
//! repeats = 3
//! seed = 1
//! soft_shadow = { samples = 16,        # light samples per shading point of rays = ["soft_shadow"]
//!                sets = "lp" }         # (a perfect square; default 16): each primary hit asks
//!                                      # which of its samples on the scene's first quad light it sees;
//!                                      # sets: jittered (default) | hammersley | lp (powers of 4)
//! output = "results"                   # relative to the working directory
//!
//! [[tables]]                           # optional: paper-vs-ours tables → tables.md
//! title = "..."                        # schema: src/experiment/tables.rs
//! rows = "scene"
//! columns = [{ label = "ours", metric = "mrays_per_s" }, { label = "paper", paper = { room = 1.5 } }]
//!
//! [[figures]]                          # optional: line plots → <file>.png
//! file = "sweep.png"                   # schema: src/experiment/figures.rs
//! title = "..."
//! x = "param:lambda"
//! y = "seconds_min"
//! ```
//!
//! runs.csv gets one row per (tracer instance, ray kind, thread count) for ray batches, and for
//! each render combination one row per traced batch — `ray_kind` (shadow, reflection, refraction,
//! or blind for blind assembly's mixed batches) and bounce `depth` (camera rays 0) — plus one
//! `ray_kind = frame` row for the whole frame (all rays; time includes shading and assembly). The
//! `render` column holds the combination (`assembly=..;materials=..;max_depth=..;...`); tables and
//! figures read one of its settings as `render:<key>`.
//!
//! Tables and figures select runs.csv rows by field (a column or `param:<key>`) and reduce them
//! over the frames of a run (see `selection`): they are computed from the run's own runs.csv, so
//! the same declarations serve every paper's experiment file.

use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use toml::Spanned;

use crate::accel::AccelKind;
use crate::error::{Error, Result};
use crate::geometry::RayKind;
use crate::render::area_light::LightSampleSets;
use crate::render::distribution::{DrtSettings, Integrator};
use crate::render::interleaved::SampleTable;
use crate::render::whitted::WhittedSettings;
use crate::tracers::registry::not_built;
use crate::tracers::visibility::LightSamples;
use crate::tracers::{Params, TracerInfo, TRACERS};
use crate::verify::stability::{CaseKind, Sweep};

use super::figure_spec::FigureSpec;
use super::table_spec::TableSpec;

/// A parsed, checked experiment with its tracer grid expanded.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// The file it was read from (for messages and meta.json).
    pub path: PathBuf,
    pub name: String,
    pub description: String,
    pub scenes: Vec<SceneSpec>,
    /// The line of the `scenes` entry, where an unknown scene name points.
    pub scenes_line: usize,
    /// Every (tracer, parameter combination) to measure, in file order, grid in key order.
    pub instances: Vec<TracerInstance>,
    pub ray_kinds: Vec<RayKind>,
    /// `rays = [{ file = "…" }]` entries, in file order.
    pub ray_files: Vec<RayFileSpec>,
    /// Render workloads (Whitted or distribution), one per combination of a `render` grid.
    pub renders: Vec<RenderWorkload>,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub threads: Vec<usize>,
    pub warmup: usize,
    pub repeats: usize,
    pub seed: u64,
    /// Light samples per shading point of the `soft_shadow` workload (a perfect square).
    pub soft_shadow_samples: u32,
    /// How the `soft_shadow` workload's interleaved light sample sets are made.
    pub soft_shadow_sets: LightSampleSets,
    /// Results go to `<output>/<name>/<run-id>/`.
    pub output: PathBuf,
    /// Paper-vs-ours tables written to tables.md.
    pub tables: Vec<TableSpec>,
    /// Line plots drawn from runs.csv.
    pub figures: Vec<FigureSpec>,
    /// The numerical stability suite, run instead of scenes × ray kinds.
    pub stability: Option<StabilitySettings>,
}

/// A `rays = [{ file = "…" }]` entry: the path as written, and resolved against the experiment
/// file's directory.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RayFileSpec {
    /// As written in the experiment (the `file:<name>` of runs.csv's ray_kind).
    pub name: String,
    pub path: PathBuf,
}

/// A scene by name, with the size for generated scenes (`None`: the generator's default).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<u32>,
}

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

/// One tracer with one combination of parameters: one column of every comparison.
#[derive(Clone)]
pub struct TracerInstance {
    pub info: &'static TracerInfo,
    /// The tracer's and its structure's parameters (the structure reads its own subset).
    pub params: Params,
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
        StructureKey {
            kind: self.info.accel,
            params: self.params.subset(self.info.accel.params()),
        }
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
        if self.params.0.is_empty() {
            f.write_str(self.info.name)
        } else {
            write!(f, "{}[{}]", self.info.name, self.params)
        }
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

/// The file as written, before names are checked and the grid expanded.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExperimentFile {
    name: Spanned<String>,
    #[serde(default)]
    description: String,
    #[serde(default = "no_scenes")]
    scenes: Spanned<Vec<NameOr<SceneSpec>>>,
    tracers: Spanned<Vec<Spanned<NameOr<TracerTable>>>>,
    /// The shared grid.
    #[serde(default)]
    params: Option<Spanned<BTreeMap<String, toml::Value>>>,
    #[serde(default)]
    rays: Option<Spanned<Vec<Spanned<NameOr<RayEntry>>>>>,
    /// The render workload grid: a table, or an array of tables (each its own grid).
    #[serde(default)]
    render: Option<Spanned<toml::Value>>,
    #[serde(default)]
    resolution: Option<Spanned<Resolution>>,
    /// The numerical stability suite instead of scenes and ray kinds (`experiment::stability`).
    #[serde(default)]
    stability: Option<Spanned<StabilitySpec>>,
    #[serde(default = "one")]
    frames: Spanned<usize>,
    #[serde(default = "one_thread")]
    threads: Spanned<Vec<usize>>,
    #[serde(default = "one")]
    warmup: Spanned<usize>,
    #[serde(default = "three")]
    repeats: Spanned<usize>,
    #[serde(default)]
    seed: u64,
    #[serde(default)]
    soft_shadow: Option<Spanned<SoftShadowSpec>>,
    #[serde(default = "default_output")]
    output: PathBuf,
    #[serde(default)]
    tables: Vec<Spanned<TableSpec>>,
    #[serde(default)]
    figures: Vec<Spanned<FigureSpec>>,
}

/// A `rays` entry: a ray kind by name, or `{ file = "…" }`.
enum RayEntry {
    Kind(String),
    File(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RayFileTable {
    file: String,
}

impl From<String> for RayEntry {
    fn from(name: String) -> Self {
        RayEntry::Kind(name)
    }
}

impl<'de> Deserialize<'de> for RayEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        RayFileTable::deserialize(d).map(|t| RayEntry::File(t.file))
    }
}

/// `soft_shadow = { samples = 16 }`: the `soft_shadow` workload's light samples per point.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SoftShadowSpec {
    samples: u32,
    sets: Option<String>,
}

/// `[stability]`: what the numerical stability suite sweeps; every key has a default.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StabilitySpec {
    cases: Option<Vec<String>>,
    offsets: Option<Vec<f64>>,
    scales: Option<Vec<f64>>,
    ratios: Option<Vec<f64>>,
    bounces: Option<u32>,
    timeout_seconds: Option<f64>,
}

/// The stability suite's sweep and the time limit of one tracer on one case.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilitySettings {
    pub sweep: Sweep,
    pub timeout: Duration,
}

impl StabilitySpec {
    fn settings(&self, seed: u64) -> std::result::Result<StabilitySettings, String> {
        let d = Sweep::default();
        let kinds = match &self.cases {
            None => d.kinds,
            Some(names) => names
                .iter()
                .map(|n| {
                    CaseKind::parse(n).ok_or_else(|| {
                        let known: Vec<&str> = CaseKind::ALL.iter().map(|k| k.name()).collect();
                        format!("unknown case {n:?} (known: {})", known.join(", "))
                    })
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        let finite = |what: &str, v: &Option<Vec<f64>>, default: Vec<f64>, min: f64| {
            let v = v.clone().unwrap_or(default);
            match v
                .iter()
                .find(|x| !(x.is_finite() && **x >= min && **x <= 1e30))
            {
                Some(x) => Err(format!("{what}: {x} is not a number in [{min}, 1e30]")),
                None if v.is_empty() => Err(format!("{what}: empty list")),
                None => Ok(v),
            }
        };
        let bounces = self.bounces.unwrap_or(d.bounces);
        if !(1..=64).contains(&bounces) {
            return Err(format!("bounces = {bounces}: 1 to 64"));
        }
        let timeout = self.timeout_seconds.unwrap_or(60.0);
        if !(timeout > 0.0 && timeout <= 86_400.0) {
            return Err(format!(
                "timeout_seconds = {timeout}: more than 0, at most a day"
            ));
        }
        Ok(StabilitySettings {
            sweep: Sweep {
                kinds,
                offsets: finite("offsets", &self.offsets, d.offsets, 0.0)?,
                scales: finite("scales", &self.scales, d.scales, 1e-30)?,
                ratios: finite("ratios", &self.ratios, d.ratios, 1.0)?,
                bounces,
                seed,
            },
            timeout: Duration::from_secs_f64(timeout),
        })
    }
}

/// Light samples per point when the file does not say (Benthin & Wald 2009 §6 measure 4 to 64).
pub const DEFAULT_SOFT_SHADOW_SAMPLES: u32 = 16;

fn no_scenes() -> Spanned<Vec<NameOr<SceneSpec>>> {
    Spanned::new(0..0, Vec::new())
}
fn one() -> Spanned<usize> {
    Spanned::new(0..0, 1)
}
fn three() -> Spanned<usize> {
    Spanned::new(0..0, 3)
}
fn one_thread() -> Spanned<Vec<usize>> {
    Spanned::new(0..0, vec![1])
}
fn default_output() -> PathBuf {
    PathBuf::from("results")
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Resolution {
    width: u32,
    height: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TracerTable {
    name: String,
    #[serde(default)]
    params: Option<Spanned<BTreeMap<String, toml::Value>>>,
    /// A tracer this build may lack (Embree 4's, `accel::embree::EMBREE4_BUILT`): skipped with a
    /// note rather than refused when it is not built.
    #[serde(default)]
    if_built: bool,
}

impl From<String> for SceneSpec {
    fn from(name: String) -> Self {
        SceneSpec { name, size: None }
    }
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

/// A list entry written either as a bare name or as a table with more fields. Hand-written rather
/// than `#[serde(untagged)]` so a mistake inside the table reports the real error (an unknown
/// field, a wrong type) instead of "did not match any variant".
struct NameOr<T>(T);

impl<'de, T: Deserialize<'de> + From<String>> Deserialize<'de> for NameOr<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct NameOrVisitor<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de> + From<String>> Visitor<'de> for NameOrVisitor<T> {
            type Value = NameOr<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a name or a table with a `name` key")
            }
            fn visit_str<E: de::Error>(self, name: &str) -> std::result::Result<Self::Value, E> {
                Ok(NameOr(T::from(name.to_string())))
            }
            fn visit_map<M: MapAccess<'de>>(
                self,
                map: M,
            ) -> std::result::Result<Self::Value, M::Error> {
                T::deserialize(de::value::MapAccessDeserializer::new(map)).map(NameOr)
            }
        }
        d.deserialize_any(NameOrVisitor(PhantomData))
    }
}

/// Where a span starts, as a 1-based line of `text`.
fn line_of(text: &str, span: &Range<usize>) -> usize {
    text[..span.start.min(text.len())].matches('\n').count() + 1
}

/// Everything needed to point at a place in the experiment file.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn input_error(&self, span: &Range<usize>, message: impl Into<String>) -> Error {
        Error::at_line(self.path, line_of(self.text, span), message)
    }

    /// A bad name: a usage error (exit code 2) that still says where in which file.
    fn usage_error(&self, span: &Range<usize>, message: impl fmt::Display) -> Error {
        Error::usage(format!(
            "{}:{}: {message}",
            self.path.display(),
            line_of(self.text, span)
        ))
    }

    /// A parameter table as name → list of values (a single value is a one-value list).
    fn param_axes(
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

impl Experiment {
    /// Reads and checks an experiment file.
    /// The largest ray batch of the run: a frame's camera rays, times the light samples of
    /// the soft-shadow workload or a distribution render's samples per pixel.
    pub fn largest_batch(&self) -> u64 {
        let pixels = self.width as u64 * self.height as u64;
        let soft = if self.ray_kinds.contains(&RayKind::SoftShadow) {
            self.soft_shadow_samples as u64
        } else {
            1
        };
        let spp = self
            .renders
            .iter()
            .map(|r| match r {
                RenderWorkload::Distribution(d) => d.settings.spp as u64,
                RenderWorkload::Whitted(_) => 1,
            })
            .max()
            .unwrap_or(1);
        pixels.saturating_mul(soft.max(spp))
    }

    pub fn load(path: &Path) -> Result<Experiment> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Experiment::parse(path, &text)
    }

    /// Parses `text` (the contents of `path`): syntax and type errors name the line; unknown
    /// tracers, ray kinds and parameters are usage errors naming the file and line.
    pub fn parse(path: &Path, text: &str) -> Result<Experiment> {
        let src = Source { path, text };
        let file: ExperimentFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(1, |s| line_of(text, &s));
            Error::at_line(path, line, e.message().trim_end())
        })?;

        let positive = |field: &str, value: &Spanned<usize>| -> Result<usize> {
            match *value.get_ref() {
                0 => Err(src.input_error(&value.span(), format!("{field} must be at least 1"))),
                n => Ok(n),
            }
        };
        let frames = positive("frames", &file.frames)?;
        let repeats = positive("repeats", &file.repeats)?;
        let stability = match &file.stability {
            Some(spec) => {
                // The suite generates its own meshes and rays.
                let given = [
                    ("scenes", !file.scenes.get_ref().is_empty()),
                    ("rays", file.rays.is_some()),
                    ("render", file.render.is_some()),
                    ("resolution", file.resolution.is_some()),
                ];
                if let Some((key, _)) = given.iter().find(|(_, given)| *given) {
                    return Err(src.usage_error(
                        &spec.span(),
                        format!("a [stability] experiment generates its own cases: remove `{key}`"),
                    ));
                }
                Some(
                    spec.get_ref()
                        .settings(file.seed)
                        .map_err(|e| src.usage_error(&spec.span(), format!("stability: {e}")))?,
                )
            }
            None => None,
        };
        let (width, height) = match (&file.resolution, &stability) {
            (Some(r), _) if r.get_ref().width == 0 || r.get_ref().height == 0 => {
                return Err(src.input_error(&r.span(), "resolution must be at least 1×1"));
            }
            (Some(r), _) => (r.get_ref().width, r.get_ref().height),
            (None, Some(_)) => (0, 0),
            (None, None) => return Err(src.input_error(&(0..0), "missing field `resolution`")),
        };
        let threads = file.threads.get_ref().clone();
        check_threads(&threads).map_err(|e| src.input_error(&file.threads.span(), e))?;
        // The name becomes a directory: one plain path component.
        let name = file.name.get_ref();
        let name_ok = !name.is_empty()
            && !name.starts_with('.')
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
        if !name_ok {
            return Err(src.input_error(
                &file.name.span(),
                format!(
                    "experiment name {name:?} must be letters, digits, '-', '_' or '.' (not first)"
                ),
            ));
        }
        let scenes: Vec<SceneSpec> = file.scenes.get_ref().iter().map(|s| s.0.clone()).collect();
        if scenes.is_empty() && stability.is_none() {
            return Err(src.input_error(&file.scenes.span(), "no scenes"));
        }
        if let Some(twice) = scenes
            .iter()
            .enumerate()
            .find(|(i, s)| scenes[..*i].contains(s))
        {
            let size = twice
                .1
                .size
                .map_or(String::new(), |s| format!(" at size {s}"));
            return Err(src.input_error(
                &file.scenes.span(),
                format!("scene {}{size} is listed twice", twice.1.name),
            ));
        }

        let mut ray_kinds = Vec::new();
        let mut ray_files: Vec<RayFileSpec> = Vec::new();
        let no_rays = Vec::new();
        let rays = file.rays.as_ref().map_or(&no_rays, |r| r.get_ref());
        for entry in rays {
            let name = match &entry.get_ref().0 {
                RayEntry::Kind(name) => name,
                RayEntry::File(name) => {
                    if name.is_empty() {
                        return Err(src.input_error(&entry.span(), "ray file: empty path"));
                    }
                    if !ray_files.iter().any(|f| &f.name == name) {
                        let dir = path.parent().unwrap_or(Path::new(""));
                        ray_files.push(RayFileSpec {
                            name: name.clone(),
                            path: dir.join(name),
                        });
                    }
                    continue;
                }
            };
            let kind = RayKind::parse(name).ok_or_else(|| {
                let known: Vec<&str> = RayKind::ALL.iter().map(|k| k.name()).collect();
                src.usage_error(
                    &entry.span(),
                    format!(
                        "unknown ray kind {name:?} (known: {}, or {{ file = \"…\" }})",
                        known.join(", ")
                    ),
                )
            })?;
            if !ray_kinds.contains(&kind) {
                ray_kinds.push(kind);
            }
        }
        let renders = match &file.render {
            Some(render) => expand_renders(&src, render)?,
            None => Vec::new(),
        };
        if ray_kinds.is_empty() && ray_files.is_empty() && renders.is_empty() && stability.is_none()
        {
            let span = file.rays.as_ref().map_or(0..0, |r| r.span());
            return Err(src.input_error(&span, "no ray kinds and no render workload"));
        }

        let (soft_shadow_samples, soft_shadow_sets) = match &file.soft_shadow {
            None => (DEFAULT_SOFT_SHADOW_SAMPLES, LightSampleSets::default()),
            Some(spec) => {
                let SoftShadowSpec { samples, sets } = spec.get_ref();
                let bad = |e: String| src.usage_error(&spec.span(), format!("soft_shadow: {e}"));
                if *samples as usize > LightSamples::MAX_PER_POINT {
                    return Err(bad(format!(
                        "samples = {samples} is more than {} per point",
                        LightSamples::MAX_PER_POINT
                    )));
                }
                let sets = match sets {
                    None => LightSampleSets::default(),
                    Some(name) => LightSampleSets::parse(name).map_err(|e| bad(e.to_string()))?,
                };
                SampleTable::new(*samples, 0).map_err(|e| bad(e.to_string()))?;
                sets.tile_sets(*samples, 0)
                    .map_err(|e| bad(e.to_string()))?;
                (*samples, sets)
            }
        };
        let instances = expand_tracers(&src, &file)?;
        for table in &file.tables {
            table
                .get_ref()
                .check()
                .map_err(|e| src.usage_error(&table.span(), e))?;
        }
        for figure in &file.figures {
            figure
                .get_ref()
                .check()
                .map_err(|e| src.usage_error(&figure.span(), e))?;
        }
        Ok(Experiment {
            path: path.to_path_buf(),
            name: file.name.into_inner(),
            description: file.description,
            scenes,
            scenes_line: line_of(src.text, &file.scenes.span()),
            instances,
            ray_kinds,
            ray_files,
            renders,
            width,
            height,
            stability,
            frames,
            threads,
            warmup: *file.warmup.get_ref(),
            repeats,
            seed: file.seed,
            soft_shadow_samples,
            soft_shadow_sets,
            output: file.output,
            tables: file.tables.into_iter().map(Spanned::into_inner).collect(),
            figures: file.figures.into_iter().map(Spanned::into_inner).collect(),
        })
    }
}

/// Each tracer × the cartesian product of its parameter lists: its own `params` table plus every
/// shared-grid key it reads (its own table wins where both give a key).
fn expand_tracers(src: &Source, file: &ExperimentFile) -> Result<Vec<TracerInstance>> {
    let shared = match &file.params {
        Some(table) => src.param_axes(table)?,
        None => BTreeMap::new(),
    };
    let mut used_shared = vec![false; shared.len()];
    let mut instances: Vec<TracerInstance> = Vec::new();
    for (entry, info, sweep) in tracer_entries(src, file)? {
        let table = &entry.get_ref().0;
        let accepts = info.accepts();
        let mut axes = match &table.params {
            Some(params) => src.param_axes(params)?,
            None => BTreeMap::new(),
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
            if accepts.contains(&key.as_str()) {
                used_shared[i] = true;
                axes.entry(key.clone()).or_insert_with(|| values.clone());
            }
        }
        let grid = cartesian(src, &entry.span(), &axes)?;
        if instances.len() + grid.len() > MAX_COMBINATIONS {
            return Err(too_many(src, &entry.span()));
        }
        for params in grid {
            let instance = TracerInstance {
                info,
                params,
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
/// stream) × intersect context × build quality, so that the run measures the fastest Embree
/// configuration on its rays. The entry's own `params` replace an axis (e.g. `quality =
/// ["low", "refit"]` for per-frame rebuilds); the entry points share one scene per quality.
pub const EMBREE_BEST: &str = "embree-best";

/// Parameter axes given in code: (key, values).
type Axes = &'static [(&'static str, &'static [&'static str])];

/// The axes `embree-best` sweeps unless its entry gives them.
const EMBREE_BEST_AXES: Axes = &[
    ("context", &["coherent", "incoherent"]),
    ("quality", &["medium", "high"]),
];

/// A tracer entry of the file, one tracer it names, and the axes it sweeps by default.
type TracerEntry<'f> = (&'f Spanned<NameOr<TracerTable>>, &'static TracerInfo, Axes);

/// Each tracer entry with the tracer it names (`embree-best` names every Embree tracer).
fn tracer_entries<'f>(src: &Source, file: &'f ExperimentFile) -> Result<Vec<TracerEntry<'f>>> {
    let mut entries = Vec::new();
    for entry in file.tracers.get_ref() {
        let name = &entry.get_ref().0.name;
        if name == EMBREE_BEST {
            let embree = TRACERS.iter().filter(|t| t.accel.is_embree());
            entries.extend(embree.map(|info| (entry, info, EMBREE_BEST_AXES)));
        } else {
            match TracerInfo::find(name) {
                Ok(info) => entries.push((entry, info, &[][..])),
                Err(e) if entry.get_ref().0.if_built && not_built(name) => {
                    eprintln!(
                        "note: {}: skipping {name} (if_built): {e}",
                        src.path.display()
                    )
                }
                Err(e) => return Err(src.usage_error(&entry.span(), e)),
            }
        }
    }
    Ok(entries)
}

/// The `render` grids, one workload per combination, each at most once.
fn expand_renders(src: &Source, render: &Spanned<toml::Value>) -> Result<Vec<RenderWorkload>> {
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

/// More tracer instances or render workloads than this is a typo, not an experiment (the
/// committed ones have at most 36): a few short lists multiply to millions, each checked against
/// the others for repeats.
const MAX_COMBINATIONS: usize = 1000;

/// The most threads a measurement may ask for: each is an OS thread of a rayon pool, and far
/// more than any machine's cores only measures the scheduler (a pool of 100,000 never finished
/// starting).
pub const MAX_THREADS: usize = 1024;

/// A list of thread counts to measure at: non-empty, each in 1..=`MAX_THREADS`, none twice (a
/// count listed twice would measure and write the same rows twice).
pub fn check_threads(threads: &[usize]) -> std::result::Result<(), String> {
    if threads.is_empty() || threads.contains(&0) {
        return Err("threads must be a non-empty list of counts ≥ 1".into());
    }
    if let Some(n) = threads.iter().find(|&&n| n > MAX_THREADS) {
        return Err(format!("{n} threads are more than {MAX_THREADS}"));
    }
    if let Some((_, n)) = threads
        .iter()
        .enumerate()
        .find(|(i, n)| threads[..*i].contains(n))
    {
        return Err(format!("thread count {n} is listed twice"));
    }
    Ok(())
}

fn too_many(src: &Source, span: &Range<usize>) -> Error {
    src.input_error(
        span,
        format!("the parameter lists make more than {MAX_COMBINATIONS} combinations"),
    )
}

/// All combinations of one value per key, the first key varying slowest; refused (at `span`)
/// when there are more than `MAX_COMBINATIONS`.
fn cartesian(
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

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::accel::embree::EMBREE4_BUILT;
    use crate::render::assembly::Assembly;
    use crate::scene::scene_file::Preset;

    fn parse(text: &str) -> Result<Experiment> {
        Experiment::parse(Path::new("exp.toml"), text)
    }

    const BASE: &str = "name = \"t\"\nscenes = [\"room\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 4 }\n";

    #[test]
    fn parameter_grids_are_bounded() {
        // Three lists of 39 values asked for 59,319 instances, checked pairwise for repeats:
        // a minute of parsing for 600 bytes.
        let values = (1..40)
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ");
        let text = format!(
            "{BASE}tracers = [{{ name = \"reference\", params = {{ leaf_size = [{values}], \
             max_depth = [{values}], bins = [{values}] }} }}]\n"
        );
        let err = parse(&text).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().starts_with("exp.toml:5:"), "{err}");
        assert!(
            err.to_string().contains("more than 1000 combinations"),
            "{err}"
        );
        let renders = "[[render]]\nrenderer = \"whitted\"\nmax_reflection_depth = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, \
                       11]\nmax_depth = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\nmax_refraction_depth = [1, 2, 3, 4, 5, 6, \
                       7, 8, 9, 10]\n";
        let err = parse(&format!("{BASE}tracers = [\"reference\"]\n{renders}")).unwrap_err();
        assert!(
            err.to_string().contains("more than 1000 combinations"),
            "{err}"
        );
    }

    #[test]
    fn embree_best_sweeps_every_entry_point_context_and_quality() {
        let exp = parse(&format!(
            "{BASE}tracers = [\"reference\", \"embree-best\"]\n"
        ))
        .unwrap();
        let embree: Vec<String> = exp.instances[1..].iter().map(|i| i.to_string()).collect();
        // Embree 3's 5 entry points and Embree 4's 4 (when built) × 2 contexts × 2 qualities,
        // keys sorted, values as listed.
        let entry_points = if EMBREE4_BUILT { 9 } else { 5 };
        assert_eq!(embree.len(), entry_points * 4);
        assert_eq!(embree[0], "embree3-1[context=coherent;quality=medium]");
        assert_eq!(
            embree[19],
            "embree3-stream[context=incoherent;quality=high]"
        );
        if EMBREE4_BUILT {
            assert_eq!(embree[20], "embree4-1[context=coherent;quality=medium]");
            assert_eq!(embree[35], "embree4-16[context=incoherent;quality=high]");
        }
        let names: BTreeSet<&str> = exp.instances[1..].iter().map(|i| i.info.name).collect();
        assert_eq!(names.len(), entry_points);
        // Its own params replace an axis: per-frame rebuilds sweep low and refit.
        let exp = parse(&format!(
            "{BASE}tracers = [{{ name = \"embree-best\", params = {{ quality = [\"low\", \"refit\"], context = [\"auto\"] }} }}]\n"
        ))
        .unwrap();
        assert_eq!(exp.instances.len(), entry_points * 2);
        assert!(exp
            .instances
            .iter()
            .all(|i| i.params.0["context"] == "auto"));
        // A sweep entry also listed on its own is a duplicate instance.
        let twice = parse(&format!(
            "{BASE}tracers = [\"embree-best\", {{ name = \"embree16\", params = {{ context = [\"coherent\"], quality = [\"high\"] }} }}]\n"
        ));
        assert!(twice.unwrap_err().to_string().contains("listed twice"));
    }

    #[test]
    fn embree_4_tracers_are_refused_or_skipped_when_not_built() {
        let named = parse(&format!(
            "{BASE}tracers = [\"reference\", \"embree4-16\"]\n"
        ));
        let optional = parse(&format!(
            "{BASE}tracers = [\"reference\", {{ name = \"embree4-16\", if_built = true }}]\n"
        ))
        .unwrap();
        if EMBREE4_BUILT {
            assert_eq!(named.unwrap().instances[1].info.name, "embree4-16");
            assert_eq!(optional.instances[1].info.name, "embree4-16");
        } else {
            let err = named.unwrap_err();
            assert!(
                matches!(err, Error::Usage(_) | Error::Input { .. }),
                "{err}"
            );
            assert!(err.to_string().contains("Embree 4 was not built"), "{err}");
            assert_eq!(optional.instances.len(), 1);
        }
        // `if_built` never hides a misspelt name.
        let misspelt = parse(&format!(
            "{BASE}tracers = [{{ name = \"embree5-16\", if_built = true }}]\n"
        ));
        assert!(misspelt.unwrap_err().to_string().contains("unknown tracer"));
    }

    #[test]
    fn grid_expands_to_every_combination() {
        // reference reads the BVH's leaf_size, max_depth and bins. Its own table gives leaf_size
        // (2 values) and max_depth (1); the shared grid gives bins (2) and a leaf_size that the
        // own table overrides: 2 × 1 × 2 = 4 instances, then the bare entry takes the shared
        // leaf_size (3) × bins (2) = 6 more.
        let text = format!(
            "{BASE}tracers = [{{ name = \"reference\", params = {{ leaf_size = [1, 2], max_depth = 20 }} }}, \
             {{ name = \"reference\" }}]\nparams = {{ bins = [8, 16], leaf_size = [4, 6, 8] }}\n"
        );
        let exp = parse(&text).unwrap();
        let labels: Vec<String> = exp.instances.iter().map(|i| i.to_string()).collect();
        assert_eq!(
            labels,
            [
                "reference[bins=8;leaf_size=1;max_depth=20]",
                "reference[bins=8;leaf_size=2;max_depth=20]",
                "reference[bins=16;leaf_size=1;max_depth=20]",
                "reference[bins=16;leaf_size=2;max_depth=20]",
                "reference[bins=8;leaf_size=4]",
                "reference[bins=8;leaf_size=6]",
                "reference[bins=8;leaf_size=8]",
                "reference[bins=16;leaf_size=4]",
                "reference[bins=16;leaf_size=6]",
                "reference[bins=16;leaf_size=8]",
            ]
        );
        // Instances differing only in tracer-side parameters would share the structure; these
        // all differ in BVH parameters.
        assert_eq!(exp.instances[0].structure().params, exp.instances[0].params);
    }

    #[test]
    fn thread_counts_twice_or_absurd_are_refused_at_their_line() {
        for (threads, message) in [
            ("[1, 1]", "exp.toml:6: thread count 1 is listed twice"),
            ("[2, 1, 2]", "exp.toml:6: thread count 2 is listed twice"),
            ("[100000]", "exp.toml:6: 100000 threads are more than 1024"),
            (
                "[0]",
                "exp.toml:6: threads must be a non-empty list of counts ≥ 1",
            ),
        ] {
            let text = format!("{BASE}tracers = [\"reference\"]\nthreads = {threads}\n");
            let err = parse(&text).unwrap_err();
            assert_eq!(err.exit_code(), 2);
            assert_eq!(err.to_string(), message);
        }
        assert_eq!(check_threads(&[1, 2, MAX_THREADS]), Ok(()));
    }

    #[test]
    fn defaults_and_explicit_fields() {
        let exp = parse(&format!("{BASE}tracers = [\"reference\"]\n")).unwrap();
        assert_eq!(
            (
                exp.width,
                exp.height,
                exp.frames,
                exp.warmup,
                exp.repeats,
                exp.seed
            ),
            (8, 4, 1, 1, 3, 0)
        );
        assert_eq!(exp.threads, vec![1]);
        assert_eq!(exp.output, PathBuf::from("results"));
        assert_eq!(
            exp.scenes,
            vec![SceneSpec {
                name: "room".into(),
                size: None
            }]
        );

        let text = "name = \"t\"\ntracers = [\"reference\"]\nrays = [\"shadow\", \"primary\", \"shadow\"]\n\
                    scenes = [\"room\", { name = \"balls\", size = 3 }]\nresolution = { width = 2, height = 2 }\n\
                    frames = 5\nthreads = [1, 2, 4]\nwarmup = 0\nrepeats = 7\nseed = 42\noutput = \"out\"\n";
        let exp = parse(text).unwrap();
        assert_eq!(exp.ray_kinds, vec![RayKind::Shadow, RayKind::Primary]);
        assert_eq!(
            exp.scenes[1],
            SceneSpec {
                name: "balls".into(),
                size: Some(3)
            }
        );
        assert_eq!(
            (exp.frames, exp.warmup, exp.repeats, exp.seed),
            (5, 0, 7, 42)
        );
        assert_eq!(exp.threads, vec![1, 2, 4]);
        assert_eq!(exp.output, PathBuf::from("out"));
    }

    fn line_of_error(e: Error) -> (Option<usize>, String) {
        match e {
            Error::Input { line, message, .. } => (line, message),
            other => panic!("expected an input error, got {other:?}"),
        }
    }

    #[test]
    fn invalid_toml_names_the_line() {
        let (line, _) = line_of_error(
            parse(&format!(
                "{BASE}tracers = [\"reference\" \"obvhs\"]\nframes = 2\n"
            ))
            .unwrap_err(),
        );
        assert_eq!(line, Some(5));
        // A wrong type on line 6.
        let (line, msg) = line_of_error(
            parse(&format!(
                "{BASE}tracers = [\"reference\"]\nframes = \"two\"\n"
            ))
            .unwrap_err(),
        );
        assert_eq!(line, Some(6), "{msg}");
        // An unknown key inside a scene table, line 1.
        let (line, msg) = line_of_error(
            parse("scenes = [{ name = \"room\", sise = 2 }]\nname = \"t\"\ntracers = [\"reference\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 4 }\n")
                .unwrap_err(),
        );
        assert_eq!(line, Some(1));
        assert!(msg.contains("sise"), "{msg}");
        // A semantic error with its line: zero repeats on line 6.
        let (line, _) = line_of_error(
            parse(&format!("{BASE}tracers = [\"reference\"]\nrepeats = 0\n")).unwrap_err(),
        );
        assert_eq!(line, Some(6));
    }

    fn usage_message(e: Error) -> String {
        match e {
            Error::Usage(m) => m,
            other => panic!("expected a usage error, got {other:?}"),
        }
    }

    #[test]
    fn unknown_names_are_usage_errors_naming_file_and_line() {
        let msg = usage_message(
            parse(&format!("{BASE}tracers = [\"reference\", \"nope\"]\n")).unwrap_err(),
        );
        assert!(
            msg.starts_with("exp.toml:5: unknown tracer \"nope\""),
            "{msg}"
        );

        let msg = usage_message(
            parse("name = \"t\"\nscenes = [\"room\"]\nrays = [\"primary\",\n \"glossy\"]\nresolution = { width = 8, height = 4 }\ntracers = [\"reference\"]\n")
                .unwrap_err(),
        );
        assert!(
            msg.starts_with("exp.toml:4: unknown ray kind \"glossy\""),
            "{msg}"
        );

        let msg = usage_message(
            parse(&format!(
                "{BASE}tracers = [{{ name = \"reference\", params = {{ leafsize = 2 }} }}]\n"
            ))
            .unwrap_err(),
        );
        assert!(
            msg.starts_with("exp.toml:5: unknown parameter \"leafsize\" for tracer reference"),
            "{msg}"
        );

        let msg = usage_message(
            parse(&format!(
                "{BASE}tracers = [\"reference\"]\nparams = {{ width = [1] }}\n"
            ))
            .unwrap_err(),
        );
        assert!(
            msg.starts_with("exp.toml:6: shared parameter \"width\" is read by none"),
            "{msg}"
        );

        let msg = usage_message(
            parse(&format!("{BASE}tracers = [\"reference\", \"reference\"]\n")).unwrap_err(),
        );
        assert!(msg.contains("listed twice"), "{msg}");
    }

    #[test]
    fn ray_files_mix_with_kinds_relative_to_the_experiment() {
        let text = "name = \"t\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\n\
                    rays = [\"primary\", { file = \"sub/a.rays\" }, \"shadow\", { file = \"sub/a.rays\" }]\n\
                    resolution = { width = 8, height = 4 }\n";
        let exp = Experiment::parse(Path::new("dir/exp.toml"), text).unwrap();
        assert_eq!(exp.ray_kinds, vec![RayKind::Primary, RayKind::Shadow]);
        assert_eq!(
            exp.ray_files,
            vec![RayFileSpec {
                name: "sub/a.rays".into(),
                path: PathBuf::from("dir/sub/a.rays"),
            }]
        );
        // Files alone are enough rays.
        let only = text
            .replace("\"primary\", ", "")
            .replace("\"shadow\", ", "");
        assert!(Experiment::parse(Path::new("exp.toml"), &only)
            .unwrap()
            .ray_kinds
            .is_empty());
        for (bad, needle) in [
            ("{ file = \"\" }", "empty path"),
            ("{ path = \"a.rays\" }", "unknown field"),
            ("\"a.rays\"", "unknown ray kind"),
        ] {
            let e = parse(&format!(
                "{}tracers = [\"reference\"]\n",
                BASE.replace("[\"primary\"]", &format!("[{bad}]"))
            ))
            .unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(needle), "{bad}: {e}");
            assert!(e.to_string().contains("exp.toml:3"), "{bad}: {e}");
        }
    }

    #[test]
    fn the_render_grid_expands_to_every_combination() {
        let text = "name = \"t\"\nscenes = [\"room\"]\nresolution = { width = 8, height = 4 }\n\
                    tracers = [\"reference\"]\nrender = { renderer = \"whitted\", max_depth = [1, 2], \
                    assembly = [\"runs\", \"blind\"], pruning = [false, 0.01], materials = \"glass\" }\n";
        let exp = parse(text).unwrap();
        assert!(exp.ray_kinds.is_empty());
        let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
        // Keys vary slowest in name order: assembly, materials, max_depth, pruning.
        let label = |a: &str, d: u32, p: &str| {
            format!("renderer=whitted;assembly={a};materials=glass;max_depth={d};packet=8;pruning={p};shadows=true")
        };
        assert_eq!(
            labels,
            [
                label("runs", 1, "false"),
                label("runs", 1, "0.01"),
                label("runs", 2, "false"),
                label("runs", 2, "0.01"),
                label("blind", 1, "false"),
                label("blind", 1, "0.01"),
                label("blind", 2, "false"),
                label("blind", 2, "0.01"),
            ]
        );
        assert_eq!(whitted(&exp, 1).pruning, Some(0.01));
        assert_eq!(whitted(&exp, 4).assembly, Assembly::Blind);
        assert_eq!(whitted(&exp, 0).materials, Some(Preset::Glass));

        for (bad, word) in [
            ("render = { renderer = \"bidirectional\" }", "renderer"),
            (
                "render = { renderer = \"whitted\", assembly = \"octants\" }",
                "octants",
            ),
            ("render = { renderer = \"whitted\", depth = 2 }", "depth"),
            (
                "render = { renderer = \"whitted\", pruning = -1 }",
                "pruning",
            ),
        ] {
            let text = format!("{BASE}tracers = [\"reference\"]\n{bad}\n");
            let msg = usage_message(parse(&text).unwrap_err());
            assert!(
                msg.starts_with("exp.toml:6:") && msg.contains(word),
                "{msg}"
            );
        }
        // An array of tables: each its own grid, duplicates rejected.
        let text = format!(
            "{BASE}tracers = [\"reference\"]\n[[render]]\nrenderer = \"whitted\"\nmax_depth = 0\nshadows = false\n\
             [[render]]\nrenderer = \"whitted\"\nmax_depth = 2\nmaterials = [\"mirror\", \"glass\"]\n"
        );
        let exp = parse(&text).unwrap();
        let settings: Vec<(u32, bool, Option<Preset>)> = (0..exp.renders.len())
            .map(|r| {
                let s = whitted(&exp, r);
                (s.max_depth, s.shadows, s.materials)
            })
            .collect();
        assert_eq!(
            settings,
            [
                (0, false, None),
                (2, true, Some(Preset::Mirror)),
                (2, true, Some(Preset::Glass))
            ]
        );
        let twice = format!(
            "{BASE}tracers = [\"reference\"]\nrender = [{{ renderer = \"whitted\" }}, {{ renderer = \"whitted\", max_depth = 5 }}]\n"
        );
        let msg = usage_message(parse(&twice).unwrap_err());
        assert!(msg.contains("listed twice"), "{msg}");

        // Separate reflection / refraction limits (Overbeck 2008 §6's kitchen): parsed, and named
        // in the render column only when set.
        let split = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"whitted\", max_depth = 4, \
             max_reflection_depth = 1 }}\n"
        );
        let exp = parse(&split).unwrap();
        let s = whitted(&exp, 0);
        assert_eq!((s.reflection_depth(), s.refraction_depth()), (1, 4));
        assert_eq!(
            exp.renders[0].to_string(),
            "renderer=whitted;assembly=ray_types;materials=scene;max_depth=4;max_reflection_depth=1;\
             packet=8;pruning=0.00390625;shadows=true"
        );

        let none = "name = \"t\"\nscenes = [\"room\"]\nresolution = { width = 8, height = 4 }\ntracers = [\"reference\"]\n";
        let (_, msg) = line_of_error(parse(none).unwrap_err());
        assert!(msg.contains("no ray kinds and no render workload"), "{msg}");
    }

    fn whitted(exp: &Experiment, r: usize) -> WhittedSettings {
        match exp.renders[r] {
            RenderWorkload::Whitted(s) => s,
            RenderWorkload::Distribution(_) => panic!("render {r} is not Whitted"),
        }
    }

    #[test]
    fn a_distribution_grid_expands_like_whitted_and_checks_its_settings() {
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", spp = [1, 4], aperture = [0, 0.05], max_depth = 1 }}\n"
        );
        let exp = parse(&text).unwrap();
        let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
        let label = |a: &str, spp: u32| {
            format!("renderer=distribution;aperture={a};focus=camera;max_depth=1;shutter=none;spp={spp}")
        };
        assert_eq!(
            labels,
            [
                label("0", 1),
                label("0", 4),
                label("0.05", 1),
                label("0.05", 4)
            ]
        );
        let RenderWorkload::Distribution(w) = exp.renders[3] else {
            panic!("a distribution workload")
        };
        assert_eq!((w.settings.spp, w.settings.aperture), (4, Some(0.05)));
        let RenderWorkload::Distribution(v) = exp.renders[2] else {
            panic!("a distribution workload")
        };
        assert!(w.same_but_spp(&v));
        for (bad, word) in [
            ("spp = 3", "spp"),
            ("aperture = -1", "aperture"),
            ("shutter = 0", "shutter"),
            ("max_depth = 99", "max_depth"),
            ("assembly = \"runs\"", "assembly"),
        ] {
            let text = format!(
                "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", {bad} }}\n"
            );
            let msg = usage_message(parse(&text).unwrap_err());
            assert!(
                msg.starts_with("exp.toml:6:") && msg.contains(word),
                "{msg}"
            );
        }
    }

    #[test]
    fn a_path_grid_is_a_sampled_workload_with_its_own_limits() {
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", spp = [1, 3], aperture = 0.1 }}\n"
        );
        let exp = parse(&text).unwrap();
        let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
        assert_eq!(
            labels,
            [
                "renderer=path;aperture=0.1;focus=camera;max_depth=5;shutter=none;spp=1",
                "renderer=path;aperture=0.1;focus=camera;max_depth=5;shutter=none;spp=3"
            ]
        );
        let RenderWorkload::Distribution(w) = exp.renders[1] else {
            panic!("a sampled workload")
        };
        assert_eq!((w.settings.integrator, w.rmse), (Integrator::Path, true));
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", rmse = false }}\n"
        );
        let exp = parse(&text).unwrap();
        assert_eq!(
            exp.renders[0].to_string(),
            "renderer=path;aperture=camera;focus=camera;max_depth=5;rmse=false;shutter=none;spp=16"
        );
        for (bad, word) in [
            ("spp = 0", "spp"),
            ("max_depth = 65", "max_depth"),
            ("rmse = 1", "rmse"),
            ("packet = 4", "packet"),
        ] {
            let text = format!(
                "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", {bad} }}\n"
            );
            let msg = usage_message(parse(&text).unwrap_err());
            assert!(
                msg.starts_with("exp.toml:6:") && msg.contains(word),
                "{msg}"
            );
        }
    }

    #[test]
    fn interleaved_soft_shadows_are_a_distribution_mode_with_checked_keys() {
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", shadows = \"interleaved\", \
             sets = \"lp\", filter = [true, false], retrace = 64, spp = 16 }}\nsoft_shadow = {{ samples = 4, sets = \"hammersley\" }}\n"
        );
        let exp = parse(&text).unwrap();
        assert_eq!(exp.soft_shadow_sets, LightSampleSets::Hammersley);
        let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
        let label = |filter| {
            format!("renderer=distribution;aperture=camera;focus=camera;max_depth=0;shutter=none;spp=16;shadows=interleaved;sets=lp;filter={filter};retrace=64")
        };
        assert_eq!(labels, [label(true), label(false)]);
        let (RenderWorkload::Distribution(a), RenderWorkload::Distribution(b)) =
            (&exp.renders[0], &exp.renders[1])
        else {
            panic!("distribution workloads")
        };
        // Filtered and unfiltered are one error-vs-time plot.
        assert!(a.same_but_spp(b));
        assert_eq!(
            a.settings.soft_shadows.unwrap().refinement(),
            " filtered retrace 64"
        );
        assert_eq!(b.settings.soft_shadows.unwrap().refinement(), " retrace 64");
        for (bad, word) in [
            ("sets = \"lp\"", "needs shadows = \"interleaved\""),
            ("shadows = \"soft\"", "sampled or interleaved"),
            ("shadows = \"interleaved\", sets = \"sobol\"", "sobol"),
            (
                "shadows = \"interleaved\", sets = \"lp\", spp = 9",
                "powers of 4",
            ),
            (
                "shadows = \"interleaved\", retrace = 8, sets = \"lp\"",
                "powers of 4",
            ),
            ("shadows = \"interleaved\", filter = 1", "filter"),
            ("shadows = \"interleaved\", max_depth = 1", "max_depth = 0"),
            ("shadows = \"interleaved\", aperture = 2", "aperture 0"),
        ] {
            let text = format!(
                "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", {bad} }}\n"
            );
            let msg = usage_message(parse(&text).unwrap_err());
            assert!(
                msg.starts_with("exp.toml:6:") && msg.contains(word),
                "{bad}: {msg}"
            );
        }
        let text = format!("{BASE}tracers = [\"reference\"]\nsoft_shadow = {{ samples = 16, sets = \"halton\" }}\n");
        let msg = usage_message(parse(&text).unwrap_err());
        assert!(
            msg.contains("soft_shadow") && msg.contains("halton"),
            "{msg}"
        );
    }
}
