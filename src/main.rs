//! The `raylab` command line: run, summary, render, verify, trace, scenes. Parsing and printing only; the work is
//! in the library. Any `Error` is printed once and exits with its code (2 for bad input).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use raylab::error::{Error, Result};
use raylab::experiment::plan::config::DEFAULT_SOFT_SHADOW_SAMPLES;
use raylab::experiment::plan::overrides::Scale;
use raylab::experiment::plan::shard::Shard;
use raylab::experiment::record::files::SUMMARY_MD;
use raylab::experiment::record::results_dir::PendingResults;
use raylab::experiment::results::heatmap::{save_panels, Panel};
use raylab::experiment::results::summary::Summary;
use raylab::experiment::run::bench::{bench, BenchSettings};
use raylab::experiment::{run_experiment, Chatter, RunOverrides};
use raylab::geometry::ray_file::{hits_csv, occlusion_csv, read_rays};
use raylab::geometry::{RayBatch, RayKind};
use raylab::render::cost_map::{count_per_pixel, wavefront, Cost};
use raylab::render::distribution::{render_sampled, DrtSettings, FrameGeometry};
use raylab::render::image::Image;
use raylab::render::motion::MovingMesh;
use raylab::render::path::ShadeStreams;
use raylab::render::raycast::render_raycast;
use raylab::render::renderers::{RenderWorkload, RendererInfo, RENDERERS};
use raylab::render::wavefront::Tracing;
use raylab::render::whitted::{render_whitted, WhittedSettings};
use raylab::scene::library::{list_scenes, load_scene};
use raylab::scene::{Frame, Scene};
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::{tracer_for_frame, Params, Tracer, TracerInfo};
use raylab::verify::{self, format_table, Judgement, Tolerance};

#[derive(Parser)]
#[command(
    name = "raylab",
    version,
    about = "Coherent ray tracing testbed: packet, grid, stream and frustum tracers against Embree and obvhs"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per process: boxing the larger variants' flags would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// Run an experiment TOML: scenes × tracers × parameters × frames → results/<experiment>/<run-id>/,
    /// ending with the run's summary (also saved there as summary.md).
    Run {
        experiment: PathBuf,
        /// Results root (default: the experiment's, else `results/`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override the experiment's thread counts.
        #[arg(long, num_args = 1..)]
        threads: Option<Vec<usize>>,
        /// Override the resolution (square).
        #[arg(long)]
        resolution: Option<u32>,
        /// Override the number of frames.
        #[arg(long)]
        frames: Option<usize>,
        /// Override the untimed warm-up passes.
        #[arg(long)]
        warmup: Option<usize>,
        /// Override the timed repeats.
        #[arg(long)]
        repeats: Option<usize>,
        /// Also write every generated ray batch to rays/<scene>[-s<size>]-f<frame>-<kind>.rays in
        /// the results directory (binary ray files, for `trace`, `verify --rays`, `rays = [{ file }]`).
        #[arg(long)]
        dump_rays: bool,
        /// Measure only part i of n (`i/n`, 0 ≤ i < n) of the sweep, split by (scene, tracer)
        /// and balanced by estimated cost; `raylab merge` joins the n results directories.
        #[arg(long, value_parser = parse_shard)]
        shard: Option<Shard>,
        /// Print nothing but the results directory (no plan, progress bar or summary).
        #[arg(long, conflicts_with = "json")]
        quiet: bool,
        /// Print only the summary, as JSON, on standard output (plan and progress on standard error).
        #[arg(long)]
        json: bool,
    },
    /// Join the results directories of a sharded sweep (`run --shard i/n`, every i once) into one
    /// results directory with the rows, plots and tables of an unsharded run.
    Merge {
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Results root (default: the experiment's, else `results/`).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run every experiment file of a paper (results/<paper>/claims.toml lists them) into
    /// results/<paper>/<experiment>/, then regenerate its REPORT.md and results/VERDICTS.md. Prints
    /// the plan with an estimated time per file first; keeps the runs at this scale that `report
    /// --check` calls current, so a killed reproduction resumes where it stopped.
    Reproduce {
        /// A paper's directory name under results/ (overbeck2008, boulos2007, wald2006,
        /// gribble2008, benthin2009, ...), one experiment file a paper's claims list (its name,
        /// e.g. wald06-resolution-1024: only that file is run, then the paper's report), or `all`.
        paper: String,
        /// `paper`: the experiment files' own settings; `quick`: 64² images, one frame, one pass,
        /// one thread (a smoke test in RESULTS/.quick/, never over the committed runs; its reports
        /// say so).
        #[arg(long, value_enum, default_value_t = Scale::Paper)]
        scale: Scale,
        /// Results root holding the papers' directories.
        #[arg(long, default_value = "results")]
        results: PathBuf,
        /// Where the experiment files are.
        #[arg(long, default_value = "experiments")]
        experiments: PathBuf,
        /// Print the plan and stop.
        #[arg(long)]
        dry_run: bool,
    },
    /// Report on results directories: a self-contained HTML page (several directories side by
    /// side), or with --markdown the reproduction report REPORT.md of a paper's directory (its
    /// verdicts computed from its claims.toml), or of results/ the index VERDICTS.md.
    Report {
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Write DIR/REPORT.md (markdown, one directory) instead of an HTML page.
        #[arg(long)]
        markdown: bool,
        /// Where to write (default: DIR/report.html, report.html for several, DIR/REPORT.md).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Write nothing: check every results directory under DIRS instead, and exit 1 when one
        /// was made from a dirty tree, has no record of the source it measured, measured code
        /// that has changed since (the shared core or one of its tracers' families), or whose
        /// experiment file changed since.
        #[arg(long, conflicts_with_all = ["markdown", "output"])]
        check: bool,
        /// With --check: name the stale runs but exit 0 (work in progress; the wave's last issue
        /// re-runs them).
        #[arg(long, requires = "check")]
        stale_ok: bool,
    },
    /// Print the summary of a results directory again (computed from its runs.csv, verify.csv and
    /// meta.json; the same table as its summary.md).
    Summary {
        /// A results directory, `results/<experiment>/<run-id>`.
        dir: PathBuf,
        /// As JSON.
        #[arg(long)]
        json: bool,
        /// The rows measured at this thread count (default: the run's largest).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Render a frame to a PNG: ray casting with point-light shadows and Lambert shading, or
    /// Whitted ray tracing (mirror reflection, Fresnel refraction, packet-assembled batches).
    Render {
        #[command(flatten)]
        on: TracerOnScene,
        #[arg(long, default_value_t = 1024)]
        width: u32,
        #[arg(long, default_value_t = 768)]
        height: u32,
        /// Frame index along the scene's animation / camera path, of `--frames`.
        #[arg(long, default_value_t = 0)]
        frame: usize,
        #[arg(long, default_value_t = 1)]
        frames: usize,
        #[arg(long, short, default_value = "render.png")]
        output: PathBuf,
        /// raycast, or a renderer of the registry (`render::renderers::RENDERERS`) with its
        /// settings from the flags below.
        #[arg(long, default_value = RAYCAST, value_parser = renderer_names())]
        renderer: String,
        /// Whitted: deepest reflection/refraction generation (default 5; 0 = ray casting with
        /// shadows). Distribution: reflection bounces (default 2). Path: bounces (default 5).
        #[arg(long)]
        max_depth: Option<u32>,
        #[command(flatten)]
        whitted: WhittedArgs,
        #[command(flatten)]
        drt: DrtArgs,
        #[command(flatten)]
        heatmap: HeatmapArgs,
    },
    /// Trace identical rays with a tracer and with Embree (robust) and compare them ray by ray.
    Verify {
        #[arg(long)]
        scene: String,
        #[arg(long)]
        size: Option<u32>,
        #[arg(long)]
        tracer: String,
        #[arg(long = "param", value_parser = parse_param)]
        params: Vec<(String, String)>,
        #[arg(long, default_value_t = 512)]
        resolution: u32,
        #[arg(long, default_value_t = 0)]
        frame: usize,
        #[arg(long, default_value_t = 1)]
        frames: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Compare on the rays of this ray file instead of generated camera and secondary rays:
        /// as closest-hit queries (row `primary`) and as occlusion queries (row `shadow`).
        #[arg(long, conflicts_with_all = ["resolution", "seed"])]
        rays: Option<PathBuf>,
        /// Disagreements no tie explains that the f64 truth calls ours wrong,
        /// allowed per ray kind (ours right, both within rounding and undecided never fail).
        #[arg(long, default_value_t = 0)]
        max_unexplained: u64,
        /// Largest allowed 99th-percentile relative distance error.
        #[arg(long, default_value_t = 1e-4)]
        max_distance_error: f64,
        /// Results root: summary.csv, disagreements.csv and failing.rays.csv (the rays of the
        /// failing disagreements, for `raylab trace --rays`) go to <out>/verify/<scene>-<tracer>
        /// (a -2, -3… suffix when that exists), written whole or not at all.
        #[arg(long, default_value = "results")]
        out: PathBuf,
    },
    /// Trace the rays of a ray file (binary or CSV, see README "Ray files") with one tracer and
    /// write one line per ray: `ray,hit,t,prim,u,v` (closest hit) or `ray,occluded`.
    Trace {
        #[command(flatten)]
        on: RayFileArgs,
        /// Frame index along the scene's animation / camera path, of `--frames`.
        #[arg(long, default_value_t = 0)]
        frame: usize,
        #[arg(long, default_value_t = 1)]
        frames: usize,
        /// Where to write the CSV (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Time one tracer on a ray file (`run --dump-rays` writes them): the runner's warm-up and
    /// timed passes, their fastest and median, and optionally one counting pass. The inner loop
    /// of kernel work (`tools/ab`, `tools/callgrind`; docs/REFERENCE.md, *Kernel work*).
    Bench {
        #[command(flatten)]
        on: RayFileArgs,
        /// Only the file's first N rays.
        #[arg(long)]
        sample: Option<usize>,
        #[arg(long, default_value_t = 1)]
        threads: usize,
        #[arg(long, default_value_t = 1)]
        warmup: usize,
        /// Timed passes (0: none, only load and build).
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Also run one counting pass: nodes, box and triangle tests per ray.
        #[arg(long)]
        counters: bool,
    },
    /// List built-in scenes and the scenes found on the search path, with triangle counts.
    Scenes,
}

/// A tracer on a scene: what `render`, `trace` and `bench` share.
#[derive(clap::Args)]
struct TracerOnScene {
    #[arg(long)]
    scene: String,
    /// The scene's size knob (built-in generators).
    #[arg(long)]
    size: Option<u32>,
    #[arg(long, default_value = "reference")]
    tracer: String,
    /// Tracer or structure parameter, `key=value` (repeatable).
    #[arg(long = "param", value_parser = parse_param)]
    params: Vec<(String, String)>,
}

/// A tracer on a scene and a ray file: what `trace` and `bench` share.
#[derive(clap::Args)]
struct RayFileArgs {
    #[command(flatten)]
    on: TracerOnScene,
    /// The ray file.
    #[arg(long)]
    rays: PathBuf,
    /// Ask whether anything lies within [tmin, tmax] (occlusion) instead of the closest hit.
    #[arg(long)]
    occluded: bool,
}

impl RayFileArgs {
    /// The ray file's rays (a shadow batch with `--occluded`), the scene, and the tracer with its
    /// parameters built over the scene's frame `frame` of `frames`.
    fn load(self, frame: usize, frames: usize) -> Result<(RayBatch, Box<dyn Tracer>, String)> {
        check_frame(frame, frames)?;
        let mut batch = read_rays(&self.rays)?;
        if self.occluded {
            batch.kind = Some(RayKind::Shadow);
        }
        let TracerOnScene {
            scene,
            size,
            tracer,
            params,
        } = self.on;
        let loaded = load_scene(&scene, size)?;
        let params = params_of(params);
        let built = tracer_for_frame(&tracer, &params, &loaded.frame(frame, frames))?;
        let label = match params.0.is_empty() {
            true => tracer,
            false => format!("{tracer} {params}"),
        };
        Ok((batch, built, label))
    }
}

/// `render --renderer`'s default, which is not a renderer of the registry: ray casting with
/// point-light shadows and Lambert shading, no settings.
const RAYCAST: &str = "raycast";

/// `raycast` and the registry's renderers, each with its line about it.
fn renderer_names() -> clap::builder::PossibleValuesParser {
    use clap::builder::PossibleValue;
    let raycast = PossibleValue::new(RAYCAST)
        .help("renderer v0: ray casting, point-light shadows, Lambert shading");
    let registered = RENDERERS
        .iter()
        .map(|r| PossibleValue::new(r.name).help(r.about));
    clap::builder::PossibleValuesParser::new(std::iter::once(raycast).chain(registered))
}

/// Whitted ray tracing options of `render --renderer whitted`.
#[derive(clap::Args)]
struct WhittedArgs {
    /// Whitted: no shadow rays (lights reach every surface they face).
    #[arg(long)]
    no_shadows: bool,
    /// Whitted: deepest reflection generation (default --max-depth).
    #[arg(long)]
    max_reflection_depth: Option<u32>,
    /// Whitted: deepest refraction generation (default --max-depth).
    #[arg(long)]
    max_refraction_depth: Option<u32>,
    /// Whitted: trace every specular ray up to --max-depth (no ray-tree attenuation).
    #[arg(long, conflicts_with = "pruning_threshold")]
    no_pruning: bool,
    /// Whitted: ray-tree attenuation threshold (default 1/256).
    #[arg(long)]
    pruning_threshold: Option<f32>,
    /// Whitted: packet assembly of secondary rays: none, runs, groups, ray_types (default),
    /// blind.
    #[arg(long)]
    assembly: Option<String>,
    /// Whitted: side n of the n×n packets whose secondary rays are assembled together (default
    /// 8).
    #[arg(long)]
    packet: Option<usize>,
    /// Whitted: a preset on every material: scene (as loaded, the default), diffuse, mirror,
    /// glossy, glass.
    #[arg(long)]
    materials: Option<String>,
}

/// `render --heatmap`: a per-pixel cost map instead of the shaded image.
#[derive(clap::Args, Debug)]
struct HeatmapArgs {
    /// Write a heat map of this cost per pixel instead of the image: box, triangle or nodes
    /// (tests or visits per ray, from a counting pass; not for the production baselines), or
    /// lanes (share of SIMD lanes active; SIMD tracers only).
    #[arg(long, value_parser = parse_cost)]
    heatmap: Option<Cost>,
    /// The rays the heat map counts: primary, shadow (one per hit and light), diffuse or
    /// soft-shadow (the light-visibility query of the primary hits on the scene's quad light:
    /// natively for mft, as its shadow rays for the others).
    #[arg(long, default_value = "primary", requires = "heatmap")]
    heatmap_rays: String,
    /// Light samples per shading point of --heatmap-rays soft-shadow (a perfect square).
    #[arg(long, default_value_t = DEFAULT_SOFT_SHADOW_SAMPLES, requires = "heatmap")]
    heatmap_samples: u32,
    /// Top of the colour scale in tests per ray (default: the map's largest; lanes: 1), so
    /// several tracers' maps share one scale.
    #[arg(long, requires = "heatmap")]
    heatmap_max: Option<f64>,
}

fn parse_cost(name: &str) -> std::result::Result<Cost, String> {
    name.parse::<Cost>().map_err(|e| e.to_string())
}

/// Distribution ray tracing options of `render --renderer distribution`.
#[derive(clap::Args)]
struct DrtArgs {
    /// Distribution: samples per pixel (a perfect square). Path: samples per pixel (any ≥ 1).
    /// Default 16.
    #[arg(long)]
    spp: Option<u32>,
    /// Distribution: lens radius (default: the camera's; 0 = pinhole).
    #[arg(long)]
    aperture: Option<f32>,
    /// Distribution: distance to the plane in focus (default: the camera's).
    #[arg(long)]
    focus: Option<f32>,
    /// Distribution: shutter interval in seconds of the scene's animation, from the frame's time
    /// (motion blur).
    #[arg(long)]
    shutter: Option<f32>,
    /// Distribution: soft shadows as Benthin & Wald 2009 §4.5 render them — one camera ray per
    /// pixel, --spp light samples per pixel from 4×4 interleaved sets, shading at the light's
    /// centre, the 4×4 discontinuity filter; direct light only (needs a quad light).
    #[arg(long)]
    interleaved_shadows: bool,
    /// Interleaved shadows: the sets, jittered (default), hammersley or lp (powers of 4).
    #[arg(long)]
    sets: Option<String>,
    /// Interleaved shadows: leave the discontinuity filter out.
    #[arg(long)]
    no_filter: bool,
    /// Interleaved shadows: light samples per partly occluded pixel, asked again (0: none, the
    /// default).
    #[arg(long)]
    retrace: Option<u32>,
}

/// The renderer settings given on the command line as the keys of an experiment's `render`
/// table, for the renderer's own parser (`RendererInfo::parse`), which reads the keys it knows
/// (`RendererInfo::keys`): a flag another renderer reads is left out.
fn render_params(max_depth: Option<u32>, whitted: &WhittedArgs, drt: &DrtArgs) -> Params {
    let given: [(&str, Option<String>); 15] = [
        ("max_depth", max_depth.map(|d| d.to_string())),
        (
            "max_reflection_depth",
            whitted.max_reflection_depth.map(|d| d.to_string()),
        ),
        (
            "max_refraction_depth",
            whitted.max_refraction_depth.map(|d| d.to_string()),
        ),
        (
            "shadows",
            match (whitted.no_shadows, drt.interleaved_shadows) {
                (true, _) => Some("false".into()),
                (_, true) => Some("interleaved".into()),
                _ => None,
            },
        ),
        (
            "pruning",
            match (whitted.no_pruning, whitted.pruning_threshold) {
                (true, _) => Some("false".into()),
                (_, threshold) => threshold.map(|t| t.to_string()),
            },
        ),
        ("assembly", whitted.assembly.clone()),
        ("packet", whitted.packet.map(|p| p.to_string())),
        ("materials", whitted.materials.clone()),
        ("spp", drt.spp.map(|s| s.to_string())),
        ("aperture", drt.aperture.map(|a| a.to_string())),
        ("focus", drt.focus.map(|f| f.to_string())),
        ("shutter", drt.shutter.map(|s| s.to_string())),
        ("sets", drt.sets.clone()),
        ("filter", drt.no_filter.then(|| "false".into())),
        ("retrace", drt.retrace.map(|r| r.to_string())),
    ];
    given
        .into_iter()
        .filter_map(|(key, value)| Some((key, value?)))
        .fold(Params::new(), |p, (key, value)| p.with(key, value))
}

fn parse_shard(s: &str) -> std::result::Result<Shard, String> {
    Shard::parse(s).map_err(|e| e.to_string())
}

fn parse_param(s: &str) -> std::result::Result<(String, String), String> {
    s.split_once('=')
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .ok_or_else(|| format!("expected key=value, got {s:?}"))
}

fn params_of(pairs: Vec<(String, String)>) -> Params {
    pairs
        .into_iter()
        .fold(Params::new(), |p, (k, v)| p.with(&k, v))
}

fn check_frame(frame: usize, frames: usize) -> Result<()> {
    at_least_one("--frames", frames)?;
    if frame >= frames {
        return Err(Error::usage(format!(
            "--frame {frame} is not one of --frames {frames}"
        )));
    }
    Ok(())
}

/// Refuses a count of zero given for `option` (an empty image or batch would "pass" vacuously or
/// fail only after the work, when the PNG is written).
fn at_least_one(option: &str, n: usize) -> Result<()> {
    match n {
        0 => Err(Error::usage(format!("{option} must be at least 1"))),
        _ => Ok(()),
    }
}

fn execute(command: Command) -> Result<bool> {
    match command {
        Command::Run {
            experiment,
            out,
            threads,
            resolution,
            frames,
            warmup,
            repeats,
            dump_rays,
            shard,
            quiet,
            json,
        } => {
            let chatter = match (quiet, json) {
                (true, _) => Chatter::Quiet,
                (false, true) => Chatter::Stderr,
                (false, false) => Chatter::Normal,
            };
            let overrides = RunOverrides {
                output: out,
                threads,
                resolution: resolution.map(|r| (r, r)),
                frames,
                warmup,
                repeats,
                dump_rays,
                shard,
                chatter,
                scale: None,
            };
            let dir = run_experiment(&experiment, &overrides)?;
            // A stability run has no summary.
            let has_summary = dir.join(SUMMARY_MD).is_file();
            match chatter {
                Chatter::Quiet => println!("{}", dir.display()),
                Chatter::Stderr if has_summary => print!("{}", Summary::read(&dir)?.json(&dir)),
                Chatter::Stderr => eprintln!("results: {}", dir.display()),
                Chatter::Normal => {
                    if has_summary {
                        println!("{}", Summary::read(&dir)?.markdown());
                    }
                    println!("results: {}", dir.display());
                }
            }
        }
        Command::Summary { dir, json, threads } => {
            let summary = Summary::read_at(&dir, threads)?;
            match json {
                true => print!("{}", summary.json(&dir)),
                false => print!("{}", summary.markdown()),
            }
        }
        Command::Merge { dirs, out } => {
            let load = |spec: &raylab::experiment::SceneSpec| load_scene(&spec.name, spec.size);
            let dir = raylab::experiment::merge::merge(&dirs, out.as_deref(), &load)?;
            println!("results: {}", dir.display());
        }
        Command::Reproduce {
            paper,
            scale,
            results,
            experiments,
            dry_run,
        } => {
            let written = raylab::experiment::reproduce::reproduce(
                &paper,
                &results,
                &experiments,
                scale,
                dry_run,
                Chatter::Normal,
            )?;
            for path in written {
                println!("report: {}", path.display());
            }
        }
        Command::Report {
            dirs,
            check: true,
            stale_ok,
            ..
        } => {
            let verdicts = raylab::experiment::results::staleness::check(&dirs)?;
            let stale: Vec<_> = verdicts.iter().filter(|v| !v.reasons.is_empty()).collect();
            for v in &stale {
                println!("stale: {}: {}", v.dir.display(), v.reasons.join("; "));
            }
            println!(
                "{} of {} results directories stale",
                stale.len(),
                verdicts.len()
            );
            return Ok(stale.is_empty() || stale_ok);
        }
        Command::Report {
            dirs,
            markdown,
            output,
            ..
        } => {
            let path =
                raylab::experiment::results::report::write(&dirs, markdown, output.as_deref())?;
            println!("report: {}", path.display());
        }
        Command::Render {
            on:
                TracerOnScene {
                    scene,
                    size,
                    tracer,
                    params,
                },
            width,
            height,
            frame,
            frames,
            output,
            renderer,
            max_depth,
            whitted,
            drt,
            heatmap,
        } => {
            check_frame(frame, frames)?;
            at_least_one("--width", width as usize)?;
            at_least_one("--height", height as usize)?;
            if !output
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png"))
            {
                return Err(Error::usage(format!(
                    "--output {}: the image is a PNG, so its name must end in .png",
                    output.display()
                )));
            }
            if let Some(max) = heatmap.heatmap_max.filter(|m| !(m.is_finite() && *m > 0.0)) {
                return Err(Error::usage(format!(
                    "--heatmap-max must be a number > 0, not {max}"
                )));
            }
            if heatmap.heatmap.is_some() && renderer != RAYCAST {
                return Err(Error::usage(format!(
                    "--heatmap counts a wavefront (--heatmap-rays), not a {renderer} render: \
                     leave out --renderer"
                )));
            }
            // The settings are checked before anything is loaded or allocated.
            let workload = match renderer.as_str() {
                RAYCAST => None,
                name => {
                    let info = RendererInfo::find(name)?;
                    let given = render_params(max_depth, &whitted, &drt).subset(info.keys);
                    Some((info.parse)(&given)?)
                }
            };
            let samples = match &workload {
                Some(RenderWorkload::Distribution(w)) => w.settings.spp as u64,
                _ => 1,
            };
            let rays = width as u64 * height as u64 * samples;
            raylab::memory::check(
                &format!("a {width}×{height} render ({rays} rays per batch)"),
                raylab::memory::for_rays(rays),
            )?;
            let scene = load_scene(&scene, size)?;
            let frame = scene.frame(frame, frames);
            let params = params_of(params);
            if let Some(cost) = heatmap.heatmap {
                let tracer_name = tracer;
                let tracer = raylab::tracers::tracer_for_frame(&tracer_name, &params, &frame)?;
                let size = (width, height);
                let rays = (heatmap.heatmap_rays.as_str(), heatmap.heatmap_samples);
                let wavefront = wavefront(&scene, &frame, tracer.as_ref(), rays, size)?;
                let (work, pixel_of) = wavefront.work_for(tracer.as_ref());
                let (_, maps) = count_per_pixel(tracer.as_ref(), work, &pixel_of, size)?;
                let map = maps.iter().find(|m| m.cost == cost).ok_or_else(|| {
                    Error::usage(format!(
                        "--heatmap lanes: {tracer_name} traces single rays, it has no ray lanes \
                         to share (the lanes map is for packet, stream, cgt and mft)"
                    ))
                })?;
                let scale = heatmap.heatmap_max.unwrap_or(cost.scale([map]));
                let caption = format!("{} on {} rays", tracer_name, heatmap.heatmap_rays);
                let panels = [(caption, Panel::Map(map))];
                save_panels(&output, &panels, cost.unit(), scale)?;
                println!(
                    "wrote {} ({} heat map of {} rays, {}, scale 0–{scale})",
                    output.display(),
                    cost.name(),
                    heatmap.heatmap_rays,
                    cost.caption(map.mean())
                );
                return Ok(true);
            }
            let image = match workload {
                None => {
                    let tracer = raylab::tracers::tracer_for_frame(&tracer, &params, &frame)?;
                    render_raycast(&scene, &frame, tracer.as_ref(), width, height)
                }
                Some(RenderWorkload::Whitted(settings)) => {
                    let tracer = raylab::tracers::tracer_for_frame(&tracer, &params, &frame)?;
                    render_whitted_cli(&scene, &frame, tracer.as_ref(), width, height, &settings)
                }
                Some(RenderWorkload::Distribution(w)) => {
                    let settings = DrtSettings {
                        width,
                        height,
                        ..w.settings
                    };
                    render_drt(&scene, &frame, (&tracer, &params), &settings, w.shutter)?
                }
            };
            image.save_png(&output)?;
            println!(
                "wrote {} ({}×{}, {} triangles)",
                output.display(),
                width,
                height,
                frame.mesh.len()
            );
        }
        Command::Verify {
            scene,
            size,
            tracer,
            params,
            resolution,
            frame,
            frames,
            seed,
            rays,
            max_unexplained,
            max_distance_error,
            out,
        } => {
            check_frame(frame, frames)?;
            at_least_one("--resolution", resolution as usize)?;
            if max_distance_error.is_nan() || max_distance_error < 0.0 {
                return Err(Error::usage(format!(
                    "--max-distance-error must be a number ≥ 0, not {max_distance_error}"
                )));
            }
            let file_rays = rays
                .map(|path| read_rays(&path).map(|batch| (path, batch)))
                .transpose()?;
            let (what, per_batch) = match &file_rays {
                Some((path, batch)) => (
                    format!("verification on {} ({} rays)", path.display(), batch.len()),
                    batch.len() as u64,
                ),
                None => {
                    let n = resolution as u64 * resolution as u64;
                    (
                        format!("verification at {resolution}² ({n} rays per batch)"),
                        n,
                    )
                }
            };
            raylab::memory::check(&what, raylab::memory::for_rays(per_batch))?;
            let loaded = load_scene(&scene, size)?;
            let frame = loaded.frame(frame, frames);
            let params = params_of(params);
            let (reports, on) = match &file_rays {
                Some((path, batch)) => (
                    verify::verify_rays(&frame, &tracer, &params, batch)?,
                    format!("the {} rays of {}", batch.len(), path.display()),
                ),
                None => (
                    verify::verify_frame(
                        &loaded, &frame, &tracer, &params, resolution, resolution, seed,
                    )?,
                    format!("{resolution}²"),
                ),
            };
            let tol = Tolerance {
                max_unexplained,
                max_distance_error_p99: max_distance_error,
            };
            println!(
                "{tracer} vs {} on {scene}, frame {}, {on}:",
                raylab::tracers::ORACLE,
                frame.index
            );
            print!("{}", format_table(&reports, &tol));
            // A scene given as a path must not turn into subdirectories.
            let name = format!("{scene}-{tracer}").replace(['/', '\\'], "_");
            let pending = PendingResults::create(&out, "verify", &name)?;
            verify::write_csv(pending.dir(), &scene, &tracer, &reports)?;
            let dir = pending.commit()?;
            println!("CSV: {}", dir.display());
            let pass = reports.iter().all(|r| r.passes(&tol));
            let count = |j: Judgement| -> u64 { reports.iter().map(|r| r.judged(j)).sum() };
            let (wrong, undecided) = (count(Judgement::OursWrong), count(Judgement::Undecided));
            if wrong + undecided > 0 {
                println!(
                    "the rays the f64 truth calls ours wrong ({wrong}) or cannot decide ({undecided}): {} (replay: raylab trace --rays)",
                    dir.join(verify::report::REPLAY_RAYS).display()
                );
            }
            println!(
                "{} (tolerance: ≤ {max_unexplained} disagreements per ray kind that the f64 truth calls ours wrong, p99 distance error ≤ {max_distance_error:e})",
                if pass { "PASS" } else { "FAIL" }
            );
            return Ok(pass);
        }
        Command::Trace {
            on,
            frame,
            frames,
            out,
        } => {
            let occluded = on.occluded;
            let (batch, tracer, _) = on.load(frame, frames)?;
            let csv = match occluded {
                true => occlusion_csv(&trace_occlusion(tracer.as_ref(), &batch)),
                false => hits_csv(&trace_hits(tracer.as_ref(), &batch)),
            };
            match out {
                Some(path) => {
                    std::fs::write(&path, csv).map_err(|e| Error::io(&path, e))?;
                    eprintln!("{} rays → {}", batch.len(), path.display());
                }
                None => print!("{csv}"),
            }
        }
        Command::Bench {
            on,
            sample,
            threads,
            warmup,
            repeats,
            counters,
        } => {
            let (batch, tracer, label) = on.load(0, 1)?;
            let batch = match sample {
                Some(0) => return Err(Error::usage("--sample must keep at least one ray")),
                Some(n) => batch.first(n),
                None => batch,
            };
            let settings = BenchSettings {
                threads,
                warmup,
                repeats,
                counters,
            };
            let measured = bench(tracer.as_ref(), &batch, settings)?;
            println!("{label}: {}", measured.line());
        }
        Command::Scenes => {
            println!("{:<22} {:>10}  source", "scene", "triangles");
            for listing in list_scenes() {
                let triangles = match load_scene(&listing.name, None) {
                    Ok(s) => s.triangle_count().to_string(),
                    Err(e) => format!("error: {e}"),
                };
                println!("{:<22} {:>10}  {}", listing.name, triangles, listing.source);
            }
        }
    }
    Ok(true)
}

fn render_whitted_cli(
    scene: &Scene,
    frame: &Frame,
    tracer: &dyn raylab::tracers::Tracer,
    width: u32,
    height: u32,
    settings: &WhittedSettings,
) -> Image {
    let out = render_whitted(
        scene,
        frame,
        tracer,
        width,
        height,
        settings,
        Tracing::Timed,
    );
    for b in &out.batches {
        println!(
            "  depth {} {:<10} {:>9} rays {:>9} hits {:>9.3} ms",
            b.depth,
            b.kind.name(),
            b.rays,
            b.hits,
            b.seconds * 1e3
        );
    }
    out.image
}

/// Renders a distribution or path-traced frame with tracer `(name, params)`, over the geometry moving during
/// `shutter` seconds from the frame's time when given (motion blur).
fn render_drt(
    scene: &Scene,
    frame: &Frame,
    (tracer, params): (&str, &Params),
    settings: &DrtSettings,
    shutter: Option<f32>,
) -> Result<Image> {
    let moving = match shutter {
        Some(shutter) => Some(MovingMesh::of_scene(scene, frame.time, shutter)?),
        None => None,
    };
    let geometry = FrameGeometry::of(frame, moving.as_ref());
    let built = geometry.tracer(tracer, params)?;
    // Path tracing shades in the stream tracer's streams (counters only).
    let config = TracerInfo::find(tracer)?.config(params)?;
    let settings = &DrtSettings {
        shade: ShadeStreams::of_config(&config, built.chunk_rays()),
        ..*settings
    };
    let tracer = built;
    let drt = render_sampled(
        scene,
        frame,
        geometry,
        tracer.as_ref(),
        settings,
        Tracing::Timed,
    )?;
    let kinds = match settings.soft_shadows {
        Some(_) => vec![RayKind::Primary, RayKind::SoftShadow],
        None => settings.integrator.kinds().to_vec(),
    };
    for kind in kinds {
        let t = drt.totals(kind);
        println!(
            "{:<10} {:>11} rays {:>9} packets {:>9.3} s",
            kind.name(),
            t.rays,
            t.packets,
            t.seconds
        );
    }
    if let Some(n) = drt.retraced_pixels {
        println!("retraced {n} pixels");
    }
    println!("frame: {:.3} s", drt.seconds);
    Ok(drt.image)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match execute(cli.command) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("raylab: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
