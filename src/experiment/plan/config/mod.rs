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
use std::path::{Path, PathBuf};

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use toml::Spanned;

use crate::error::{Error, Result};
use crate::geometry::RayKind;
use crate::render::area_light::LightSampleSets;

use super::figure_spec::FigureSpec;
use super::table_spec::TableSpec;

mod rays;
mod renders;
mod scenes;
mod soft_shadow;
mod source;
mod stability;
#[cfg(test)]
mod tests;
mod tracers;

use crate::render::cost_map::Cost;
pub use rays::RayFileSpec;
pub use renders::{DistributionWorkload, RenderWorkload};
pub use scenes::SceneSpec;
pub use soft_shadow::DEFAULT_SOFT_SHADOW_SAMPLES;
pub use stability::StabilitySettings;
pub use tracers::{StructureKey, TracerInstance, BASELINE_BEST, EMBREE_BEST};

use rays::RayEntry;
use soft_shadow::SoftShadowSpec;

use crate::experiment::record::settings::PaperSettings;
use source::{line_of, Source};
use stability::StabilitySpec;
use tracers::TracerTable;

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
    /// `heatmaps = ["box", "triangle"]`: the per-pixel cost maps the run draws (first frame,
    /// every scene × ray kind, every tracer side by side; `results::heatmap`).
    pub heatmaps: Vec<Cost>,
    /// Results go to `<output>/<name>/<run-id>/`.
    pub output: PathBuf,
    /// Paper-vs-ours tables written to tables.md.
    pub tables: Vec<TableSpec>,
    /// Line plots drawn from runs.csv.
    pub figures: Vec<FigureSpec>,
    /// The numerical stability suite, run instead of scenes × ray kinds.
    pub stability: Option<StabilitySettings>,
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
    /// The paper's own settings (`record::settings`): checked here, read from the recorded text
    /// when a run is labelled and when a report or `report --check` compares a run with them.
    #[serde(default, rename = "paper_settings")]
    _paper_settings: Option<PaperSettings>,
    #[serde(default)]
    heatmaps: Vec<Spanned<String>>,
    #[serde(default = "default_output")]
    output: PathBuf,
    #[serde(default)]
    tables: Vec<Spanned<TableSpec>>,
    #[serde(default)]
    figures: Vec<Spanned<FigureSpec>>,
}

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

impl Experiment {
    /// The largest ray batch of the run: a frame's camera rays, times the light samples of
    /// the soft-shadow workload or a distribution render's samples per pixel (over its tiles).
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
                // A tile subset traces about one pixel in `tiles`.
                RenderWorkload::Distribution(d) => {
                    (d.settings.spp as u64).div_ceil(d.settings.tiles as u64)
                }
                RenderWorkload::Whitted(_) => 1,
            })
            .max()
            .unwrap_or(1);
        pixels.saturating_mul(soft.max(spp))
    }

    /// Reads and checks an experiment file.
    pub fn load(path: &Path) -> Result<Experiment> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Experiment::parse(path, &text)
    }

    /// Parses `text` (the contents of `path`): syntax and type errors name the line; unknown
    /// tracers, ray kinds and parameters are usage errors naming the file and line. One section
    /// of the file at a time, each in its own module.
    pub fn parse(path: &Path, text: &str) -> Result<Experiment> {
        let src = Source { path, text };
        let file: ExperimentFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(1, |s| line_of(text, &s));
            Error::at_line(path, line, e.message().trim_end())
        })?;
        let frames = at_least_one(&src, "frames", &file.frames)?;
        let repeats = at_least_one(&src, "repeats", &file.repeats)?;
        let stability = stability::stability(&src, &file)?;
        let suite = stability.is_some();
        let (width, height) = resolution(&src, &file, suite)?;
        let threads = file.threads.get_ref().clone();
        check_threads(&threads).map_err(|e| src.input_error(&file.threads.span(), e))?;
        check_name(&src, &file.name)?;
        let scenes = scenes::scenes(&src, &file, suite)?;
        let (ray_kinds, ray_files) = rays::rays(&src, &file)?;
        let renders = match &file.render {
            Some(render) => renders::expand_renders(&src, render)?,
            None => Vec::new(),
        };
        if ray_kinds.is_empty() && ray_files.is_empty() && renders.is_empty() && !suite {
            let span = file.rays.as_ref().map_or(0..0, |r| r.span());
            return Err(src.input_error(&span, "no ray kinds and no render workload"));
        }
        let (soft_shadow_samples, soft_shadow_sets) = soft_shadow::soft_shadow(&src, &file)?;
        let instances = tracers::expand_tracers(&src, &file)?;
        check_tables_and_figures(&src, &file)?;
        let heatmaps = file
            .heatmaps
            .iter()
            .map(|name| {
                name.get_ref()
                    .parse::<Cost>()
                    .map_err(|e| src.usage_error(&name.span(), format!("heatmaps: {e}")))
            })
            .collect::<Result<Vec<Cost>>>()?;
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
            heatmaps,
            output: file.output,
            tables: file.tables.into_iter().map(Spanned::into_inner).collect(),
            figures: file.figures.into_iter().map(Spanned::into_inner).collect(),
        })
    }
}

/// The name becomes a directory: one plain path component.
fn check_name(src: &Source, name: &Spanned<String>) -> Result<()> {
    let text = name.get_ref();
    let plain = !text.is_empty()
        && !text.starts_with('.')
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    match plain {
        true => Ok(()),
        false => Err(src.input_error(
            &name.span(),
            format!(
                "experiment name {text:?} must be letters, digits, '-', '_' or '.' (not first)"
            ),
        )),
    }
}

fn at_least_one(src: &Source, field: &str, value: &Spanned<usize>) -> Result<usize> {
    match *value.get_ref() {
        0 => Err(src.input_error(&value.span(), format!("{field} must be at least 1"))),
        n => Ok(n),
    }
}

/// The image size; a stability suite, which makes its own rays, needs none.
fn resolution(src: &Source, file: &ExperimentFile, suite: bool) -> Result<(u32, u32)> {
    match (&file.resolution, suite) {
        (Some(r), _) if r.get_ref().width == 0 || r.get_ref().height == 0 => {
            Err(src.input_error(&r.span(), "resolution must be at least 1×1"))
        }
        (Some(r), _) => Ok((r.get_ref().width, r.get_ref().height)),
        (None, true) => Ok((0, 0)),
        (None, false) => Err(src.input_error(&(0..0), "missing field `resolution`")),
    }
}

/// `[[tables]]` and `[[figures]]`: their fields and columns exist.
fn check_tables_and_figures(src: &Source, file: &ExperimentFile) -> Result<()> {
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
    Ok(())
}

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
