//! The `raylab` command line: run, render, verify, scenes. Parsing and printing only; the work is
//! in the library. Any `Error` is printed once and exits with its code (2 for bad input).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use raylab::error::{Error, Result};
use raylab::experiment::results_dir::PendingResults;
use raylab::experiment::{run_experiment, RunOverrides};
use raylab::render::assembly::Assembly;
use raylab::render::raycast::render_raycast;
use raylab::render::whitted::{
    render_whitted, Tracing, WhittedSettings, DEFAULT_PRUNING_THRESHOLD,
};
use raylab::scene::library::{list_scenes, load_scene};
use raylab::scene::scene_file::Preset;
use raylab::tracers::Params;
use raylab::verify::{self, format_table, Tolerance};

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

#[derive(Subcommand)]
enum Command {
    /// Run an experiment TOML: scenes × tracers × parameters × frames → results/<experiment>/<run-id>/.
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
    },
    /// Render a frame to a PNG: ray casting with point-light shadows and Lambert shading, or
    /// Whitted ray tracing (mirror reflection, Fresnel refraction, packet-assembled batches).
    Render {
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
        #[arg(long, value_enum, default_value_t = Renderer::Raycast)]
        renderer: Renderer,
        /// Whitted: deepest reflection/refraction generation (0 = ray casting with shadows).
        #[arg(long, default_value_t = 5)]
        max_depth: u32,
        /// Whitted: no shadow rays (lights reach every surface they face).
        #[arg(long)]
        no_shadows: bool,
        /// Whitted: trace every specular ray up to --max-depth (no ray-tree attenuation).
        #[arg(long, conflicts_with = "pruning_threshold")]
        no_pruning: bool,
        /// Whitted: ray-tree attenuation threshold (default 1/256).
        #[arg(long)]
        pruning_threshold: Option<f32>,
        /// Whitted: packet assembly of secondary rays: none, runs, groups, ray_types, blind.
        #[arg(long, default_value = "ray_types", value_parser = parse_assembly)]
        assembly: Assembly,
        /// Whitted: side n of the n×n packets whose secondary rays are assembled together.
        #[arg(long, default_value_t = 8)]
        packet: usize,
        /// Whitted: a preset on every material: scene (as loaded), diffuse, mirror, glossy, glass.
        #[arg(long, default_value = "scene")]
        materials: String,
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
        /// Unexplained disagreements allowed per ray kind.
        #[arg(long, default_value_t = 0)]
        max_unexplained: u64,
        /// Largest allowed 99th-percentile relative distance error.
        #[arg(long, default_value_t = 1e-4)]
        max_distance_error: f64,
        /// Results root: summary.csv and disagreements.csv go to <out>/verify/<scene>-<tracer>
        /// (a -2, -3… suffix when that exists), written whole or not at all.
        #[arg(long, default_value = "results")]
        out: PathBuf,
    },
    /// List built-in scenes and the scenes found on the search path, with triangle counts.
    Scenes,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Renderer {
    Raycast,
    Whitted,
}

fn parse_assembly(s: &str) -> std::result::Result<Assembly, String> {
    Assembly::parse(s)
        .ok_or_else(|| format!("unknown assembly {s:?} (known: {})", Assembly::names()))
}

fn parse_materials(s: &str) -> std::result::Result<Option<Preset>, String> {
    match s {
        "scene" => Ok(None),
        _ => Preset::parse(s).map(Some).ok_or_else(|| {
            format!("unknown materials {s:?} (scene, diffuse, mirror, glossy, glass)")
        }),
    }
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
    if frames == 0 || frame >= frames {
        return Err(Error::usage(format!(
            "--frame {frame} is not one of --frames {frames}"
        )));
    }
    Ok(())
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
        } => {
            let overrides = RunOverrides {
                output: out,
                threads,
                resolution: resolution.map(|r| (r, r)),
                frames,
                warmup,
                repeats,
            };
            let dir = run_experiment(&experiment, &overrides)?;
            println!("results: {}", dir.display());
        }
        Command::Render {
            scene,
            size,
            tracer,
            params,
            width,
            height,
            frame,
            frames,
            output,
            renderer,
            max_depth,
            no_shadows,
            no_pruning,
            pruning_threshold,
            assembly,
            packet,
            materials,
        } => {
            check_frame(frame, frames)?;
            if packet == 0 {
                return Err(Error::usage("--packet must be at least 1"));
            }
            if pruning_threshold.is_some_and(|t| !(t > 0.0 && t.is_finite())) {
                return Err(Error::usage("--pruning-threshold must be > 0"));
            }
            let scene = load_scene(&scene, size)?;
            let frame = scene.frame(frame, frames);
            let tracer = verify::tracer_for_frame(&tracer, &params_of(params), &frame)?;
            let image = match renderer {
                Renderer::Raycast => render_raycast(&scene, &frame, tracer.as_ref(), width, height),
                Renderer::Whitted => {
                    let settings = WhittedSettings {
                        max_depth,
                        shadows: !no_shadows,
                        pruning: match no_pruning {
                            true => None,
                            false => Some(pruning_threshold.unwrap_or(DEFAULT_PRUNING_THRESHOLD)),
                        },
                        assembly,
                        packet,
                        materials: parse_materials(&materials).map_err(Error::usage)?,
                    };
                    let out = render_whitted(
                        &scene,
                        &frame,
                        tracer.as_ref(),
                        width,
                        height,
                        &settings,
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
            max_unexplained,
            max_distance_error,
            out,
        } => {
            check_frame(frame, frames)?;
            let loaded = load_scene(&scene, size)?;
            let frame = loaded.frame(frame, frames);
            let reports = verify::verify_frame(
                &loaded,
                &frame,
                &tracer,
                &params_of(params),
                resolution,
                resolution,
                seed,
            )?;
            let tol = Tolerance {
                max_unexplained,
                max_distance_error_p99: max_distance_error,
            };
            println!(
                "{tracer} vs {} on {scene}, frame {}, {resolution}²:",
                verify::ORACLE,
                frame.index
            );
            print!("{}", format_table(&reports, &tol));
            // A scene given as a path must not turn into subdirectories.
            let name = format!("{scene}-{tracer}").replace(['/', '\\'], "_");
            let pending = PendingResults::create(&out, "verify", &name)?;
            verify::write_csv(pending.dir(), &scene, &tracer, &reports)?;
            println!("CSV: {}", pending.commit()?.display());
            let pass = reports.iter().all(|r| r.passes(&tol));
            println!(
                "{} (tolerance: ≤ {max_unexplained} unexplained disagreements per ray kind, p99 distance error ≤ {max_distance_error:e})",
                if pass { "PASS" } else { "FAIL" }
            );
            return Ok(pass);
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
