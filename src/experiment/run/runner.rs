//! Executes a plan: per scene and frame, build the structures the plan lists (timed), generate the
//! workloads once (primary rays, then shadow, diffuse, reflection and refraction rays and the
//! soft-shadow light-visibility query from the reference tracer's primary hits), and measure
//! every tracer instance on every workload at every thread count (`TracerOnFrame::batch`). Every
//! tracer gets the very same rays. Then each instance renders the frame with every render
//! workload (Whitted or distribution), timed like the batches, and once more counting; a
//! distribution frame's image is also compared with its cached high-sample reference
//! (`render::convergence`) by RMSE (`TracerOnFrame::render`).

use std::collections::BTreeMap;
use std::hint::black_box;
use std::io::IsTerminal;
use std::path::Path;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::{ThreadPool, ThreadPoolBuilder};

use crate::accel::Accel;
use crate::error::{Error, Result};
use crate::experiment::record::heatmap_set::{for_figure, HeatmapPanel, HeatmapSet, ShadedFrame};
use crate::geometry::ray_file::read_rays;
use crate::geometry::{RayBatch, RayKind};
use crate::random::mix64;
use crate::render::area_light::SoftShadowWork;
use crate::render::convergence::reference_image;
use crate::render::cost_map::{count_per_pixel, soft_shadow_work, CostMap};
use crate::render::distribution::{render_sampled, DrtSettings, FrameGeometry};
use crate::render::image::Image;
use crate::render::motion::{tracer_for_motion, MovingMesh};
use crate::render::path::ShadeStreams;
use crate::render::raycast::render_raycast;
use crate::render::rays::{diffuse_rays, primary_rays, shadow_rays};
use crate::render::specular::specular_rays;
use crate::render::wavefront::{BatchRecord, Tracing, Work};
use crate::render::whitted::render_whitted;
use crate::scene::{Frame, Scene};
use crate::tracers::chunked::{query_rays, trace_hits};
use crate::tracers::{
    make_tracer, oracle_params, tracer_for_frame, Params, Tracer, VisibilityQuery, ORACLE,
};

use super::case::{Case, Traced};
use super::dump;
use super::sampled_check;
use crate::experiment::plan::config::{
    DistributionWorkload, Experiment, RenderWorkload, StructureKey,
};
use crate::experiment::plan::shard::Part;
use crate::experiment::plan::{
    secondary_ray_structure, secondary_ray_tracer, Plan, SceneLoader, ScenePlan,
};
use crate::experiment::run::passes::{count_pass, time_passes, timing_of, Counted, Timing};

/// The pool with the most threads.
fn widest(pools: &[ThreadPool]) -> &ThreadPool {
    pools
        .iter()
        .max_by_key(|p| p.current_num_threads())
        .expect("threads is never empty")
}

/// A built structure with its build time.
struct Built {
    accel: Accel,
    seconds: f64,
}

/// The structures and tracers of the current frame (or of frame 0, for static scenes).
struct FrameTracers {
    structures: BTreeMap<StructureKey, Built>,
    /// One per plan instance; `None` for those another shard measures.
    tracers: Vec<Option<Box<dyn Tracer>>>,
    /// The reference tracer that finds where secondary rays start, when any are needed.
    secondary: Option<Box<dyn Tracer>>,
    /// The verification oracle over the frame's geometry, for the sampled check.
    oracle: Box<dyn Tracer>,
}

/// The progress bar over the plan's measurements: the current scene, frame, tracer and workload,
/// and an ETA. Drawn only when `shown` and standard error is a terminal, so logs, CI output and
/// `--quiet` runs stay clean.
pub fn progress_bar(measurements: usize, shown: bool) -> ProgressBar {
    if !shown || !std::io::stderr().is_terminal() {
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

/// Runs the measurements of `plan` that belong to `part`, loading each scene with `load` when its
/// turn comes (scenes with nothing to measure are not loaded). With `dump_rays`, every generated
/// ray batch is also written there, with the frame's triangles and soft-shadow points (`dump`).
pub fn run_plan(
    exp: &Experiment,
    plan: &Plan,
    part: &Part,
    load: SceneLoader,
    progress: &ProgressBar,
    dump_rays: Option<&Path>,
) -> Result<(Vec<Case>, HeatmapSet)> {
    let file_batches = plan
        .ray_files
        .iter()
        .map(|f| {
            let batch = read_rays(&f.path)?;
            match batch.len() == f.rays {
                true => Ok(batch),
                false => Err(Error::runtime(format!(
                    "ray file {} changed during the run: {} rays when planned, {} now",
                    f.path.display(),
                    f.rays,
                    batch.len()
                ))),
            }
        })
        .collect::<Result<Vec<RayBatch>>>()?;
    if let Some(dir) = dump_rays {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
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
    let widest = widest(&pools);

    let mut cases = Vec::new();
    let mut heatmaps = HeatmapSet::default();
    for (scene_index, (spec, scene_plan)) in exp.scenes.iter().zip(&plan.scenes).enumerate() {
        if !part.measures_scene(scene_index) {
            continue;
        }
        let measured = |instance: usize| part.measures(scene_index, instance);
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
                current = Some(build_frame(exp, scene_plan, &frame, previous, &measured)?);
            }
            let frame_tracers = current.as_ref().expect("built above");
            let workloads =
                generate_workloads(exp, scene_plan, &scene, &frame, frame_tracers, &pools)?;
            if let Some(dir) = dump_rays {
                dump::write_triangles(
                    &dir.join(dump::triangles_name(spec, f)),
                    &frame.mesh.triangles,
                )?;
                for workload in &workloads {
                    match workload {
                        Workload::Rays(batch) => {
                            let path = dir.join(dump::rays_name(spec, f, batch.kind()));
                            dump::write_batch(&path, batch)?;
                        }
                        Workload::SoftShadow { work, rays, .. } => {
                            let path = dir.join(dump::points_name(spec, f));
                            let per_point = work.samples.per_point();
                            dump::write_points(&path, &work.points, work.light, per_point)?;
                            let path = dir.join(dump::rays_name(spec, f, rays.kind()));
                            dump::write_batch(&path, rays)?;
                        }
                    }
                }
            }
            let maps_now = f == 0 && !exp.heatmaps.is_empty();
            if maps_now {
                let oracle = frame_tracers.oracle.as_ref();
                let image = widest
                    .install(|| render_raycast(&scene, &frame, oracle, exp.width, exp.height));
                heatmaps.shaded.push(ShadedFrame {
                    scene: scene_index,
                    // As the plots name it (`plots::scene_stem`): one name may come in sizes.
                    name: match spec.size {
                        Some(size) => format!("{}-{size}", spec.name),
                        None => spec.name.clone(),
                    },
                    image,
                });
            }
            for (i, tracer) in frame_tracers.tracers.iter().enumerate() {
                let Some(tracer) = tracer else {
                    continue;
                };
                if maps_now {
                    for workload in &workloads {
                        heatmaps.panels.push(HeatmapPanel {
                            scene: scene_index,
                            kind: workload.kind(),
                            instance: i,
                            tracer: plan.instances[i].label.clone(),
                            maps: workload
                                .cost_maps(tracer.as_ref(), exp, widest)?
                                .map(|maps| for_figure(maps, &exp.heatmaps)),
                        });
                    }
                }
                let measure = TracerOnFrame {
                    exp,
                    pools: &pools,
                    widest,
                    progress,
                    scene: &scene,
                    scene_name: &spec.name,
                    scene_index,
                    frame: &frame,
                    instance: i,
                    tracer: tracer.as_ref(),
                    oracle: frame_tracers.oracle.as_ref(),
                    build_seconds: match built_now {
                        true => frame_tracers.structures[&exp.instances[i].structure()].seconds,
                        false => 0.0,
                    },
                    built: built_now,
                    sah_cost: frame_tracers.structures[&exp.instances[i].structure()]
                        .accel
                        .sah_cost(),
                };
                for workload in &workloads {
                    cases.push(measure.batch(workload));
                }
                for (file, batch) in file_batches.iter().enumerate() {
                    cases.push(measure.file(file, batch));
                }
                for &r in &scene_plan.renders {
                    cases.extend(measure.render(r, &plan.renders[r], &exp.renders[r])?);
                }
            }
        }
    }
    Ok((cases, heatmaps))
}

/// Measuring one tracer instance on one frame: the batches traced on their own, then the render
/// workloads.
struct TracerOnFrame<'a> {
    exp: &'a Experiment,
    pools: &'a [ThreadPool],
    /// Counting and ray generation are not timed: they run in the widest pool.
    widest: &'a ThreadPool,
    progress: &'a ProgressBar,
    scene: &'a Scene,
    scene_name: &'a str,
    scene_index: usize,
    frame: &'a Frame<'a>,
    instance: usize,
    tracer: &'a dyn Tracer,
    /// What the sampled check compares the tracer with.
    oracle: &'a dyn Tracer,
    build_seconds: f64,
    built: bool,
    sah_cost: Option<f64>,
}

impl TracerOnFrame<'_> {
    /// The progress line of one measurement at `pool`'s size.
    fn announce(&self, what: &dyn std::fmt::Display, pool: &ThreadPool) {
        self.progress.set_message(format!(
            "{} frame {}/{}: {} {what} ×{}",
            self.scene_name,
            self.frame.index + 1,
            self.exp.frames,
            self.exp.instances[self.instance],
            pool.current_num_threads()
        ))
    }

    /// `f` at every thread count, one progress step each.
    fn at_every_pool<T>(
        &self,
        what: &dyn std::fmt::Display,
        f: impl Fn(&ThreadPool) -> T,
    ) -> Vec<T> {
        self.pools
            .iter()
            .map(|pool| {
                self.announce(what, pool);
                let out = f(pool);
                self.progress.inc(1);
                out
            })
            .collect()
    }

    fn case(&self, traced: Traced, rays: usize, counted: Counted, timings: Vec<Timing>) -> Case {
        Case {
            scene: self.scene_index,
            triangles: self.frame.mesh.len(),
            frame: self.frame.index,
            instance: self.instance,
            traced,
            rays,
            counted,
            counts_internals: self.tracer.counts_internals(),
            build_seconds: self.build_seconds,
            built: self.built,
            sah_cost: self.sah_cost,
            timings,
            generation: Vec::new(),
            rmse: None,
            retraced_share: None,
            checked: None,
        }
    }

    /// One workload traced on its own. The soft-shadow query goes to a tracer that answers it
    /// natively as a query, to the others as its shadow rays, generated once for all of them
    /// (their generation time is the row's `generation_seconds`, not in its own).
    fn batch(&self, workload: &Workload) -> Case {
        let kind = workload.kind();
        let case = match workload {
            Workload::SoftShadow {
                rays, generation, ..
            } if !self.tracer.answers_visibility_natively() => Case {
                generation: generation.clone(),
                ..self.traced(Traced::Batch(kind), kind.name(), Work::Occlusion(rays))
            },
            _ => self.traced(Traced::Batch(kind), kind.name(), workload.work()),
        };
        let (mesh, tracer, oracle) = (&self.frame.mesh, self.tracer, self.oracle);
        let checked = self.widest.install(|| match workload {
            Workload::Rays(batch) => sampled_check::check(mesh, tracer, oracle, batch),
            Workload::SoftShadow { work, .. } => {
                sampled_check::check_visibility(mesh, tracer, oracle, &work.query())
            }
        });
        Case {
            checked: Some(checked),
            ..case
        }
    }

    /// The rays of `Experiment::ray_files[file]`.
    fn file(&self, file: usize, batch: &RayBatch) -> Case {
        let what = format!("file:{}", self.exp.ray_files[file].name);
        let case = self.traced(Traced::File(file), &what, Work::of_batch(batch));
        self.checked(case, batch)
    }

    /// `case` with the sampled check of its `batch` against the oracle (untimed, widest pool).
    fn checked(&self, case: Case, batch: &RayBatch) -> Case {
        let checked = self
            .widest
            .install(|| sampled_check::check(&self.frame.mesh, self.tracer, self.oracle, batch));
        Case {
            checked: Some(checked),
            ..case
        }
    }

    /// `work` traced on its own (`what` in the progress line): timed at every thread count, then
    /// counted once.
    fn traced(&self, traced: Traced, what: &str, work: Work<'_>) -> Case {
        let (exp, tracer) = (self.exp, self.tracer);
        let timings = self.at_every_pool(&what, |pool| {
            time_passes(pool, tracer, work, exp.warmup, exp.repeats)
        });
        // After the timed passes, so it never acts as an extra warm-up for them.
        let counted = count_pass(self.widest, tracer, work);
        self.case(traced, work.rays(), counted, timings)
    }

    /// Render workload `r` (`label` in the plan): every frame timed at every thread count, one
    /// counted render, and a case per traced batch plus one for the whole frame.
    fn render(&self, r: usize, label: &str, workload: &RenderWorkload) -> Result<Vec<Case>> {
        let instance = &self.exp.instances[self.instance];
        // Motion blur traces over the moving geometry: its own structure (untimed).
        let moving = match workload {
            RenderWorkload::Distribution(DistributionWorkload {
                shutter: Some(shutter),
                ..
            }) => Some(MovingMesh::of_scene(self.scene, self.frame.time, *shutter)?),
            _ => None,
        };
        let motion_tracer = moving
            .as_ref()
            .map(|m| tracer_for_motion(instance.info, &instance.config, &instance.params, m))
            .transpose()?;
        let job = RenderJob {
            scene: self.scene,
            frame: self.frame,
            moving: moving.as_ref(),
            tracer: motion_tracer.as_deref().unwrap_or(self.tracer),
            exp: self.exp,
            workload,
            shade: ShadeStreams::of_config(&instance.config, self.tracer.chunk_rays()),
        };
        let timed = self
            .at_every_pool(&label, |pool| job.time(pool))
            .into_iter()
            .collect::<Result<Vec<_>>>()?;
        let (counted, seconds) = job.count(self.widest)?;
        let rmse = job.rmse(&counted.image)?;
        let threads = self.widest.current_num_threads();
        let mut total = Counted {
            threads,
            seconds,
            ..Counted::default()
        };
        let mut cases = Vec::with_capacity(counted.batches.len() + 1);
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
            cases.push(self.case(traced, record.rays, counted, timings));
        }
        let rays = counted.batches.iter().map(|b| b.rays).sum();
        let timings = timed.iter().map(|t| t.frame).collect();
        let pixels = (self.exp.width * self.exp.height) as f64;
        cases.push(Case {
            rmse,
            retraced_share: counted.retraced_pixels.map(|n| n as f64 / pixels),
            ..self.case(Traced::Frame { render: r }, rays, total, timings)
        });
        Ok(cases)
    }
}

/// The timings of one render workload at one thread count: each batch's trace, and the frame.
struct RenderTimings {
    batches: Vec<Timing>,
    frame: Timing,
}

/// What a render returns to the runner: the image, one record per traced batch, and the pixels
/// retraced (interleaved soft shadows with retrace).
struct Rendered {
    image: Image,
    batches: Vec<BatchRecord>,
    retraced_pixels: Option<u64>,
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
    /// How a path workload groups its shading: the stream tracer's own streams and width.
    shade: ShadeStreams,
}

impl RenderJob<'_> {
    /// A distribution or path workload's settings at the experiment's resolution.
    fn drt_settings(&self, w: &DistributionWorkload) -> DrtSettings {
        DrtSettings {
            width: self.exp.width,
            height: self.exp.height,
            shade: self.shade,
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
                    retraced_pixels: None,
                })
            }
            RenderWorkload::Distribution(w) => {
                let out = render_sampled(
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
                    retraced_pixels: out.retraced_pixels,
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

    /// A distribution or path frame's RMSE against the reference image of the same settings, cached
    /// under the results root (rendered with the reference tracer on first use); `None` for
    /// other renderers.
    fn rmse(&self, image: &Image) -> Result<Option<f64>> {
        let RenderWorkload::Distribution(w) = self.workload else {
            return Ok(None);
        };
        if !w.rmse {
            return Ok(None);
        }
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

/// Builds the plan's structures over `frame`'s geometry that the `measured` instances traverse or
/// that generate secondary rays, timing each, and the measured instances' tracers over them.
/// `previous` holds the last frame's structures (their tracers already dropped, so each is
/// unshared): a refittable one is updated in place and the update timed as this frame's build.
fn build_frame(
    exp: &Experiment,
    scene_plan: &ScenePlan,
    frame: &Frame,
    mut previous: BTreeMap<StructureKey, Built>,
    measured: &dyn Fn(usize) -> bool,
) -> Result<FrameTracers> {
    // Free what will be built anew before building anything.
    previous.retain(|key, _| key.kind.refits(&key.params));
    let mut structures = BTreeMap::new();
    let needed = scene_plan
        .structures
        .iter()
        .filter(|s| s.generates_secondary_rays || s.used_by.iter().any(|&i| measured(i)));
    for s in needed {
        let old = previous.remove(&s.key).map(|b| b.accel);
        let start = Instant::now();
        let accel = s.key.kind.rebuild(old, &frame.mesh, &s.key.params)?;
        let seconds = start.elapsed().as_secs_f64();
        structures.insert(s.key.clone(), Built { accel, seconds });
    }
    let tracers = exp
        .instances
        .iter()
        .enumerate()
        .map(|(i, instance)| {
            measured(i)
                .then(|| {
                    make_tracer(
                        instance.info,
                        &instance.config,
                        &structures[&instance.structure()].accel,
                    )
                })
                .transpose()
        })
        .collect::<Result<Vec<_>>>()?;
    let secondary = match scene_plan.needs_secondary_rays() {
        true => {
            let info = secondary_ray_tracer()?;
            Some(make_tracer(
                info,
                &info.config(&Params::new())?,
                &structures[&secondary_ray_structure(info)].accel,
            )?)
        }
        false => None,
    };
    // Its own structure (robust, high quality), built untimed like the secondary-ray tracer's.
    let oracle = tracer_for_frame(ORACLE, &oracle_params(), frame)?;
    Ok(FrameTracers {
        structures,
        tracers,
        secondary,
        oracle,
    })
}

/// What the runner measures on its own: a batch of rays, or the soft-shadow light-visibility
/// query over the primary hits.
enum Workload {
    Rays(RayBatch),
    SoftShadow {
        work: SoftShadowWork,
        /// The query's shadow rays (`chunked::query_rays`), for the tracers that take rays.
        rays: RayBatch,
        /// Their generation, timed like a tracer's passes at every thread count.
        generation: Vec<Timing>,
    },
}

impl Workload {
    fn kind(&self) -> RayKind {
        match self {
            Workload::Rays(batch) => batch.kind(),
            Workload::SoftShadow { .. } => RayKind::SoftShadow,
        }
    }

    /// `tracer`'s cost maps of this workload (`None` for a tracer that reports no counts),
    /// counted in `pool` as `batch` traces it: the soft-shadow query natively or as its rays.
    fn cost_maps(
        &self,
        tracer: &dyn Tracer,
        exp: &Experiment,
        pool: &ThreadPool,
    ) -> Result<Option<Vec<CostMap>>> {
        if !tracer.counts_internals() {
            return Ok(None);
        }
        let size = (exp.width, exp.height);
        let (work, pixel_of) = match self {
            Workload::Rays(batch) => (Work::of_batch(batch), batch.pixel.clone()),
            Workload::SoftShadow { work, rays, .. } => soft_shadow_work(tracer, work, rays),
        };
        let (_, maps) = pool.install(|| count_per_pixel(tracer, work, &pixel_of, size))?;
        Ok(Some(maps))
    }

    fn work(&self) -> Work<'_> {
        match self {
            Workload::Rays(batch) => Work::of_batch(batch),
            Workload::SoftShadow { work, .. } => Work::LightVisibility(work.query()),
        }
    }
}

/// The shadow rays of `query`, generated `warmup` + `repeats` times in every pool, the
/// generations timed as a tracer's passes are.
fn time_shadow_rays(
    exp: &Experiment,
    pools: &[ThreadPool],
    query: VisibilityQuery<'_>,
) -> (RayBatch, Vec<Timing>) {
    let mut rays = RayBatch::new(RayKind::SoftShadow);
    let timings = pools
        .iter()
        .map(|pool| {
            pool.install(|| {
                // Each generation refills the previous one's memory, as a renderer's ray buffers
                // are refilled frame after frame.
                for _ in 0..exp.warmup {
                    query_rays(query, &mut rays);
                }
                let seconds = (0..exp.repeats)
                    .map(|_| {
                        let start = Instant::now();
                        query_rays(query, &mut rays);
                        start.elapsed().as_secs_f64()
                    })
                    .collect();
                timing_of(pool.current_num_threads(), seconds)
            })
        })
        .collect();
    (rays, timings)
}

/// The workloads of the scene's ray kinds for one frame, in the plan's order. Secondary rays are
/// seeded per frame and kind, so every run of the experiment traces the same rays.
fn generate_workloads(
    exp: &Experiment,
    scene_plan: &ScenePlan,
    scene: &Scene,
    frame: &Frame,
    tracers: &FrameTracers,
    pools: &[ThreadPool],
) -> Result<Vec<Workload>> {
    let pool = widest(pools);
    let primary = primary_rays(&frame.camera, exp.width, exp.height);
    let hits = tracers
        .secondary
        .as_ref()
        .map(|t| pool.install(|| trace_hits(t.as_ref(), &primary)));
    let seed = |kind: RayKind| mix64(exp.seed ^ mix64(frame.index as u64) ^ mix64(kind as u64 + 1));
    let mut workloads = Vec::with_capacity(scene_plan.ray_kinds.len());
    for &kind in &scene_plan.ray_kinds {
        let hits = || {
            hits.as_deref()
                .expect("the plan builds the secondary-ray tracer for secondary kinds")
        };
        let batch = match kind {
            // Placed below, once the secondary rays no longer need it.
            RayKind::Primary => continue,
            RayKind::Shadow => shadow_rays(scene, &frame.mesh, &primary, hits(), seed(kind)),
            RayKind::Diffuse => diffuse_rays(&frame.mesh, &primary, hits(), seed(kind)),
            RayKind::Reflection | RayKind::Refraction => {
                specular_rays(kind, &frame.mesh, &scene.materials, &primary, hits())
            }
            RayKind::SoftShadow => {
                let work = SoftShadowWork::of_hits(
                    scene,
                    &frame.mesh,
                    (&primary, hits()),
                    exp.width,
                    (exp.soft_shadow_samples, exp.soft_shadow_sets),
                    seed(kind),
                )?
                .expect("the plan gives soft shadows only to scenes with a quad light");
                let (rays, generation) = time_shadow_rays(exp, pools, work.query());
                workloads.push(Workload::SoftShadow {
                    work,
                    rays,
                    generation,
                });
                continue;
            }
        };
        workloads.push(Workload::Rays(batch));
    }
    if let Some(at) = scene_plan
        .ray_kinds
        .iter()
        .position(|&k| k == RayKind::Primary)
    {
        workloads.insert(at, Workload::Rays(primary));
    }
    Ok(workloads)
}
