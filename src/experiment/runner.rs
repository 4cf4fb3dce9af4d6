//! Executes a plan: per scene and frame, build the structures the plan lists (timed), generate the
//! ray batches once (primary, then shadow, diffuse, reflection and refraction rays from the
//! reference tracer's primary hits), and measure every tracer instance on every ray kind at every
//! thread count. Every tracer gets the very same batch. Then each instance renders the frame with
//! every render workload (Whitted or distribution), timed like the batches, and once more
//! counting; a distribution frame's image is also compared with its cached high-sample reference
//! (`render::convergence`) by RMSE.

use std::collections::BTreeMap;
use std::hint::black_box;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::{ThreadPool, ThreadPoolBuilder};

use crate::accel::Accel;
use crate::error::{Error, Result};
use crate::geometry::{RayBatch, RayKind};
use crate::random::mix64;
use crate::render::assembly::BatchKind;
use crate::render::convergence::reference_image;
use crate::render::distribution::{render_distribution, DrtSettings, FrameGeometry};
use crate::render::image::Image;
use crate::render::motion::{tracer_for_motion, MovingMesh};
use crate::render::rays::{diffuse_rays, primary_rays, shadow_rays};
use crate::render::specular::specular_rays;
use crate::render::whitted::{render_whitted, BatchRecord, Tracing};
use crate::scene::{Frame, Scene};
use crate::tracers::batch::trace_hits;
use crate::tracers::{build_tracer, Params, Tracer, TracerInfo};

use super::config::{DistributionWorkload, Experiment, RenderWorkload, StructureKey};
use super::measure::{count_pass, time_passes, timing_of, Counted, Timing};
use super::plan::{secondary_ray_structure, Plan, SceneLoader, ScenePlan, SECONDARY_RAY_TRACER};

/// What a case measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traced {
    /// A batch of one ray kind, traced on its own.
    Batch(RayKind),
    /// One batch of a rendered frame of render workload `render` (an index into `Plan::renders`).
    Render {
        render: usize,
        batch: BatchKind,
        depth: u32,
    },
    /// A whole rendered frame: all its batches plus sampling, shading and packet assembly.
    Frame { render: usize },
}

impl Traced {
    /// runs.csv's `ray_kind`.
    pub fn kind_name(self) -> &'static str {
        match self {
            Traced::Batch(kind) => kind.name(),
            Traced::Render { batch, .. } => batch.name(),
            Traced::Frame { .. } => "frame",
        }
    }

    /// Bounce depth: camera rays 0, rays leaving their hits 1; none for a whole frame.
    pub fn depth(self) -> Option<u32> {
        match self {
            Traced::Batch(RayKind::Primary) => Some(0),
            Traced::Batch(_) => Some(1),
            Traced::Render { depth, .. } => Some(depth),
            Traced::Frame { .. } => None,
        }
    }

    pub fn render(self) -> Option<usize> {
        match self {
            Traced::Batch(_) => None,
            Traced::Render { render, .. } | Traced::Frame { render } => Some(render),
        }
    }
}

/// One tracer instance on one ray kind (or one batch of a rendered frame, or a whole frame) of one
/// frame of one scene: its counts and its timing at every thread count. One row of runs.csv per
/// timing.
#[derive(Clone, Debug)]
pub struct Case {
    /// Index into `Plan::scenes`.
    pub scene: usize,
    pub triangles: usize,
    pub frame: usize,
    /// Index into `Plan::instances`.
    pub instance: usize,
    pub traced: Traced,
    pub rays: usize,
    /// From the one counting pass (the same at every thread count).
    pub counted: Counted,
    /// False for tracers that count rays only: their box and triangle counts are not measured.
    pub counts_internals: bool,
    /// Seconds to build the instance's structure for this frame; 0 when reused.
    pub build_seconds: f64,
    /// Whether the structure was built this frame (false: reused from frame 0 of a static scene).
    pub built: bool,
    pub timings: Vec<Timing>,
    /// A distribution frame's RMSE against its reference image (frame rows only).
    pub rmse: Option<f64>,
}

/// A built structure with its build time.
struct Built {
    accel: Accel,
    seconds: f64,
}

/// The structures and tracers of the current frame (or of frame 0, for static scenes).
struct FrameTracers {
    structures: BTreeMap<StructureKey, Built>,
    /// One per plan instance.
    tracers: Vec<Box<dyn Tracer>>,
    /// The reference tracer that finds where secondary rays start, when any are needed.
    secondary: Option<Box<dyn Tracer>>,
}

/// The progress bar over the plan's measurements, drawn only on a terminal so logs and CI output
/// stay clean.
pub fn progress_bar(measurements: usize) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(
            Some(measurements as u64),
            ProgressDrawTarget::hidden(),
        );
    }
    let bar = ProgressBar::new(measurements as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}, ETA {eta}] {msg}")
            .expect("the template is a valid literal"),
    );
    // Redraw while one long measurement runs, so the elapsed time keeps moving.
    bar.enable_steady_tick(Duration::from_millis(250));
    bar
}

/// Runs every measurement of `plan`, loading each scene with `load` when its turn comes.
pub fn run_plan(
    exp: &Experiment,
    plan: &Plan,
    load: SceneLoader,
    progress: &ProgressBar,
) -> Result<Vec<Case>> {
    let pools = exp
        .threads
        .iter()
        .map(|&n| {
            ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::runtime(format!("cannot start a pool of {n} threads: {e}")))
        })
        .collect::<Result<Vec<ThreadPool>>>()?;
    // Counting and ray generation are not timed: give them the widest pool.
    let widest = pools
        .iter()
        .max_by_key(|p| p.current_num_threads())
        .expect("threads is never empty");

    let mut cases = Vec::new();
    for (scene_index, (spec, scene_plan)) in exp.scenes.iter().zip(&plan.scenes).enumerate() {
        let scene = load(spec)?;
        if scene.triangle_count() != scene_plan.triangles {
            return Err(Error::runtime(format!(
                "scene {} changed during the run: {} triangles when planned, {} now",
                spec.name,
                scene_plan.triangles,
                scene.triangle_count()
            )));
        }
        let mut current: Option<FrameTracers> = None;
        for f in 0..exp.frames {
            let frame = scene.frame(f, exp.frames);
            let built_now = scene_plan.builds_at(f);
            if built_now {
                // The previous frame's structures go to the next build: refitted in place where
                // configured (Embree `quality = "refit"`), freed before building otherwise.
                let previous = current.take().map(|t| t.structures).unwrap_or_default();
                current = Some(build_frame(exp, scene_plan, &frame, previous)?);
            }
            let frame_tracers = current.as_ref().expect("built above");
            let batches = generate_batches(exp, scene_plan, &scene, &frame, frame_tracers, widest);
            for (i, tracer) in frame_tracers.tracers.iter().enumerate() {
                let instance = &exp.instances[i];
                // The progress line of one measurement of this instance at `pool`'s size.
                let announce = |what: &dyn std::fmt::Display, pool: &ThreadPool| {
                    progress.set_message(format!(
                        "{} frame {}/{}: {instance} {what} ×{}",
                        spec.name,
                        f + 1,
                        exp.frames,
                        pool.current_num_threads()
                    ))
                };
                let build_seconds = match built_now {
                    true => frame_tracers.structures[&instance.structure()].seconds,
                    false => 0.0,
                };
                for batch in &batches {
                    let kind = batch.kind();
                    let timings: Vec<Timing> = pools
                        .iter()
                        .map(|pool| {
                            announce(&kind.name(), pool);
                            let timing =
                                time_passes(pool, tracer.as_ref(), batch, exp.warmup, exp.repeats);
                            progress.inc(1);
                            timing
                        })
                        .collect();
                    // After the timed passes, so it never acts as an extra warm-up for them.
                    let counted = count_pass(widest, tracer.as_ref(), batch);
                    cases.push(Case {
                        scene: scene_index,
                        triangles: frame.mesh.len(),
                        frame: f,
                        instance: i,
                        traced: Traced::Batch(kind),
                        rays: batch.len(),
                        counted,
                        counts_internals: tracer.counts_internals(),
                        build_seconds,
                        built: built_now,
                        timings,
                        rmse: None,
                    });
                }
                for (r, workload) in exp.renders.iter().enumerate() {
                    let case = |traced, rays, counted, timings, rmse| Case {
                        scene: scene_index,
                        triangles: frame.mesh.len(),
                        frame: f,
                        instance: i,
                        traced,
                        rays,
                        counted,
                        counts_internals: tracer.counts_internals(),
                        build_seconds,
                        built: built_now,
                        timings,
                        rmse,
                    };
                    // Motion blur traces over the moving geometry: its own structure (untimed).
                    let moving = match workload {
                        RenderWorkload::Distribution(DistributionWorkload {
                            shutter: Some(shutter),
                            ..
                        }) => Some(MovingMesh::of_scene(&scene, frame.time, *shutter)?),
                        _ => None,
                    };
                    let motion_tracer = moving
                        .as_ref()
                        .map(|m| tracer_for_motion(instance.info.name, &instance.params, m))
                        .transpose()?;
                    let job = RenderJob {
                        scene: &scene,
                        frame: &frame,
                        moving: moving.as_ref(),
                        tracer: motion_tracer.as_deref().unwrap_or(tracer.as_ref()),
                        exp,
                        workload,
                    };
                    let timed: Vec<RenderTimings> = pools
                        .iter()
                        .map(|pool| {
                            announce(&plan.renders[r], pool);
                            let timing = job.time(pool);
                            progress.inc(1);
                            timing
                        })
                        .collect::<Result<_>>()?;
                    let (counted, seconds) = job.count(widest)?;
                    let rmse = job.rmse(&counted.image)?;
                    let threads = widest.current_num_threads();
                    let mut total = Counted {
                        threads,
                        seconds,
                        ..Counted::default()
                    };
                    for (b, record) in counted.batches.iter().enumerate() {
                        total.counters.merge(&record.counters);
                        total.hits += record.hits;
                        let traced = Traced::Render {
                            render: r,
                            batch: record.kind,
                            depth: record.depth,
                        };
                        let timings = timed.iter().map(|t| t.batches[b]).collect();
                        let counted = Counted {
                            counters: record.counters.clone(),
                            hits: record.hits,
                            seconds: record.seconds,
                            threads,
                        };
                        cases.push(case(traced, record.rays, counted, timings, None));
                    }
                    let rays = counted.batches.iter().map(|b| b.rays).sum();
                    let timings = timed.iter().map(|t| t.frame).collect();
                    cases.push(case(
                        Traced::Frame { render: r },
                        rays,
                        total,
                        timings,
                        rmse,
                    ));
                }
            }
        }
    }
    Ok(cases)
}

/// The timings of one render workload at one thread count: each batch's trace, and the frame.
struct RenderTimings {
    batches: Vec<Timing>,
    frame: Timing,
}

/// What a render returns to the runner: the image and one record per traced batch.
struct Rendered {
    image: Image,
    batches: Vec<BatchRecord>,
}

/// One tracer rendering one frame with one workload's settings.
struct RenderJob<'a> {
    scene: &'a Scene,
    frame: &'a Frame<'a>,
    /// The frame's geometry over the shutter interval, for motion-blurred workloads; `tracer`
    /// is then built over it.
    moving: Option<&'a MovingMesh>,
    tracer: &'a dyn Tracer,
    exp: &'a Experiment,
    workload: &'a RenderWorkload,
}

impl RenderJob<'_> {
    /// A distribution workload's settings at the experiment's resolution.
    fn drt_settings(&self, w: &DistributionWorkload) -> DrtSettings {
        DrtSettings {
            width: self.exp.width,
            height: self.exp.height,
            ..w.settings
        }
    }

    fn render(&self, tracing: Tracing) -> Result<Rendered> {
        let (width, height) = (self.exp.width, self.exp.height);
        match self.workload {
            RenderWorkload::Whitted(settings) => {
                let out = render_whitted(
                    self.scene,
                    self.frame,
                    self.tracer,
                    width,
                    height,
                    settings,
                    tracing,
                );
                Ok(Rendered {
                    image: out.image,
                    batches: out.batches,
                })
            }
            RenderWorkload::Distribution(w) => {
                let out = render_distribution(
                    self.scene,
                    self.frame,
                    FrameGeometry::of(self.frame, self.moving),
                    self.tracer,
                    &self.drt_settings(w),
                    tracing,
                )?;
                Ok(Rendered {
                    image: out.image,
                    batches: out.batches,
                })
            }
        }
    }

    /// `warmup` untimed renders, then `repeats` timed ones, in `pool`. The renders are
    /// deterministic, so every render traces the same batches in the same order.
    fn time(&self, pool: &ThreadPool) -> Result<RenderTimings> {
        pool.install(|| {
            for _ in 0..self.exp.warmup {
                black_box(self.render(Tracing::Timed)?);
            }
            let mut frame = Vec::with_capacity(self.exp.repeats);
            let mut batches: Vec<Vec<f64>> = Vec::new();
            for _ in 0..self.exp.repeats {
                let start = Instant::now();
                let out = self.render(Tracing::Timed)?;
                frame.push(start.elapsed().as_secs_f64());
                batches.resize(out.batches.len(), Vec::new());
                for (seconds, record) in batches.iter_mut().zip(&out.batches) {
                    seconds.push(record.seconds);
                }
                black_box(out);
            }
            let threads = pool.current_num_threads();
            Ok(RenderTimings {
                batches: batches.into_iter().map(|s| timing_of(threads, s)).collect(),
                frame: timing_of(threads, frame),
            })
        })
    }

    /// One render with the counting calls, in `pool`, and its wall time.
    fn count(&self, pool: &ThreadPool) -> Result<(Rendered, f64)> {
        let start = Instant::now();
        let out = pool.install(|| self.render(Tracing::Counted))?;
        Ok((out, start.elapsed().as_secs_f64()))
    }

    /// A distribution frame's RMSE against the reference image of the same settings, cached
    /// under the results root (rendered with the reference tracer on first use); `None` for
    /// other renderers.
    fn rmse(&self, image: &Image) -> Result<Option<f64>> {
        let RenderWorkload::Distribution(w) = self.workload else {
            return Ok(None);
        };
        let (reference, _) = reference_image(
            self.scene,
            self.frame,
            self.moving,
            &self.drt_settings(w),
            &self.exp.output,
        )?;
        Ok(Some(image.rmse(&reference)))
    }
}

/// Builds the plan's structures over `frame`'s geometry, timing each, and the tracers over them.
/// `previous` holds the last frame's structures (their tracers already dropped, so each is
/// unshared): a refittable one is updated in place and the update timed as this frame's build.
fn build_frame(
    exp: &Experiment,
    scene_plan: &ScenePlan,
    frame: &Frame,
    mut previous: BTreeMap<StructureKey, Built>,
) -> Result<FrameTracers> {
    // Free what will be built anew before building anything.
    previous.retain(|key, _| key.kind.refits(&key.params));
    let mut structures = BTreeMap::new();
    for s in &scene_plan.structures {
        let old = previous.remove(&s.key).map(|b| b.accel);
        let start = Instant::now();
        let accel = s.key.kind.rebuild(old, &frame.mesh, &s.key.params)?;
        let seconds = start.elapsed().as_secs_f64();
        structures.insert(s.key.clone(), Built { accel, seconds });
    }
    let tracers = exp
        .instances
        .iter()
        .map(|instance| {
            build_tracer(
                instance.info,
                &instance.params,
                &structures[&instance.structure()].accel,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let secondary = match scene_plan.needs_secondary_rays() {
        true => {
            let info = TracerInfo::find(SECONDARY_RAY_TRACER)?;
            Some(build_tracer(
                info,
                &Params::new(),
                &structures[&secondary_ray_structure()].accel,
            )?)
        }
        false => None,
    };
    Ok(FrameTracers {
        structures,
        tracers,
        secondary,
    })
}

/// The batches of the scene's ray kinds for one frame, in the plan's order. Secondary rays are
/// seeded per frame and kind, so every run of the experiment traces the same rays.
fn generate_batches(
    exp: &Experiment,
    scene_plan: &ScenePlan,
    scene: &Scene,
    frame: &Frame,
    tracers: &FrameTracers,
    pool: &ThreadPool,
) -> Vec<RayBatch> {
    let primary = primary_rays(&frame.camera, exp.width, exp.height);
    let hits = tracers
        .secondary
        .as_ref()
        .map(|t| pool.install(|| trace_hits(t.as_ref(), &primary)));
    let seed = |kind: RayKind| mix64(exp.seed ^ mix64(frame.index as u64) ^ mix64(kind as u64 + 1));
    let mut batches: Vec<RayBatch> = Vec::with_capacity(scene_plan.ray_kinds.len());
    for &kind in &scene_plan.ray_kinds {
        let hits = || {
            hits.as_deref()
                .expect("the plan builds the secondary-ray tracer for secondary kinds")
        };
        match kind {
            // Placed below, once the secondary rays no longer need it.
            RayKind::Primary => {}
            RayKind::Shadow => batches.push(shadow_rays(
                scene,
                &frame.mesh,
                &primary,
                hits(),
                seed(kind),
            )),
            RayKind::Diffuse => {
                batches.push(diffuse_rays(&frame.mesh, &primary, hits(), seed(kind)))
            }
            RayKind::Reflection | RayKind::Refraction => batches.push(specular_rays(
                kind,
                &frame.mesh,
                &scene.materials,
                &primary,
                hits(),
            )),
        }
    }
    if let Some(at) = scene_plan
        .ray_kinds
        .iter()
        .position(|&k| k == RayKind::Primary)
    {
        batches.insert(at, primary);
    }
    batches
}
