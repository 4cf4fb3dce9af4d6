//! The `raylab` command line: run, render, verify, scenes. Parsing and printing only; the work is
//! in the library. Any `Error` is printed once and exits with its code (2 for bad input).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use raylab::error::{Error, Result};
use raylab::experiment::results_dir::PendingResults;
use raylab::experiment::{run_experiment, RunOverrides};
use raylab::render::distribution::{render_distribution, DrtRayKind, DrtSettings, FrameGeometry};
use raylab::render::image::Image;
use raylab::render::motion::{tracer_for_motion, MovingMesh};
use raylab::render::raycast::render_raycast;
use raylab::scene::library::{list_scenes, load_scene};
use raylab::scene::{Frame, Scene};
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
    /// Render a frame with ray casting, point-light shadows and Lambert shading to a PNG.
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
        /// `raycast` (v0) or `distribution` (DRT: depth of field, glossy, soft shadows, motion blur).
        #[arg(long, default_value = "raycast")]
        renderer: String,
        #[command(flatten)]
        drt: DrtArgs,
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

/// Distribution ray tracing options of `render --renderer distribution`.
#[derive(clap::Args)]
struct DrtArgs {
    /// Samples per pixel (a perfect square).
    #[arg(long, default_value_t = 16)]
    spp: u32,
    /// Lens radius (default: the camera's; 0 = pinhole).
    #[arg(long)]
    aperture: Option<f32>,
    /// Distance to the plane in focus (default: the camera's).
    #[arg(long)]
    focus: Option<f32>,
    /// Shutter interval in seconds of the scene's animation, from the frame's time (motion blur).
    #[arg(long)]
    shutter: Option<f32>,
    /// Reflection bounces.
    #[arg(long, default_value_t = 2)]
    max_depth: u32,
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
            drt,
        } => {
            check_frame(frame, frames)?;
            let scene = load_scene(&scene, size)?;
            let frame = scene.frame(frame, frames);
            let params = params_of(params);
            let image = match renderer.as_str() {
                "raycast" => {
                    let tracer = verify::tracer_for_frame(&tracer, &params, &frame)?;
                    render_raycast(&scene, &frame, tracer.as_ref(), width, height)
                }
                "distribution" => {
                    render_drt(&scene, &frame, &tracer, &params, width, height, &drt)?
                }
                other => {
                    return Err(Error::usage(format!(
                        "unknown renderer {other:?} (known: raycast, distribution)"
                    )))
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

/// A distribution-ray-traced frame; prints the rays, packets and tracing time of each kind.
fn render_drt(
    scene: &Scene,
    frame: &Frame,
    tracer: &str,
    params: &Params,
    width: u32,
    height: u32,
    args: &DrtArgs,
) -> Result<Image> {
    let settings = DrtSettings {
        width,
        height,
        spp: args.spp,
        aperture: args.aperture,
        focus_distance: args.focus,
        max_depth: args.max_depth,
        ..DrtSettings::default()
    };
    let moving = match args.shutter {
        Some(shutter) => Some(MovingMesh::of_scene(scene, frame.time, shutter)?),
        None => None,
    };
    let (tracer, geometry) = match &moving {
        Some(m) => (
            tracer_for_motion(tracer, params, m)?,
            FrameGeometry::Moving(m),
        ),
        None => (
            verify::tracer_for_frame(tracer, params, frame)?,
            FrameGeometry::Static(&frame.mesh),
        ),
    };
    let drt = render_distribution(scene, frame, geometry, tracer.as_ref(), &settings)?;
    for kind in DrtRayKind::ALL {
        let t = drt.totals(kind);
        println!(
            "{:<10} {:>11} rays {:>9} packets {:>9.3} s",
            kind.name(),
            t.rays,
            t.packets,
            t.seconds
        );
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
