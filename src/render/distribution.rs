//! Distribution ray tracing (Cook et al. 1984; interactive form: Boulos et al. 2007 §4), breadth
//! first over any `Tracer`: n samples per pixel, each with its own image position, lens position
//! (thin-lens depth of field), time in the shutter interval (motion blur), point on each area
//! light (soft shadows) and glossy direction at each bounce. Samples come from the static
//! interleaved sample table (`interleaved`), so a frame renders identically every time.
//!
//! Breadth first: the camera rays of a wave of 32×32 tiles are one batch, their shadow rays the
//! next, their reflection rays the next, and so on to `max_depth` bounces. **A packet is one
//! pixel's samples** (Boulos §5.3, Table 3: "each setting uses a packet of rays equivalent to 1
//! pixel"): the camera batch starts an explicit packet at each pixel, pixels in the 32×32-tile
//! Morton order of `rays::CameraProjection::tile_rays`, and each secondary batch keeps the rays of
//! one pixel's samples together in one packet per kind.
//!
//! Shading, per sample path: emission + ambient + Lambert under each light sample, and one
//! reflection ray carrying the material's reflectance (`shading::specular_response`: mirror plus
//! glossy, Fresnel for dielectrics), its direction chosen between the mirror and glossy parts in
//! proportion to their reflectances (multisampling instead of branching, Boulos §4). Dielectric
//! transmission is not rendered here (a dielectric shows its diffuse and reflected light only).

use std::collections::BTreeMap;
use std::time::Instant;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::{Ray, RayBatch, RayKind, Triangle};
use crate::render::area_light::{sample_light, LightSampleSets};
use crate::render::assembly::BatchKind;
use crate::render::glossy::sample_phong_lobe;
use crate::render::image::Image;
use crate::render::interleaved::{SampleTable, DIMENSION_PAIRS};
use crate::render::interleaved_shadows::{render_interleaved_shadows, InterleavedShadows};
use crate::render::light_query::LightQueries;
use crate::render::motion::{tracer_for_motion, MovingMesh};
use crate::render::path::{
    render_path, ShadeStreams, PATH_DEFAULT_DEPTH, PATH_KINDS, PATH_MAX_DEPTH,
};
use crate::render::rays::{morton_decode, CameraProjection, SurfacePoint, TILE};
use crate::render::shading::{specular_response, AMBIENT, BACKGROUND};
use crate::render::specular::{reflect, reflection_ray};
use crate::render::wavefront::{trace, Answers, BatchRecord, Tracing, Work};
use crate::scene::{Camera, Frame, Scene};
use crate::stats::Counters;
use crate::tracers::{tracer_for_mesh, Params, Tracer, TracerInfo};

/// A wave holds at least this many camera rays (whole tiles), so each traced batch spreads over
/// many `tracers::chunked` chunks and every core has work even at 1 sample per pixel.
const WAVE_RAYS: usize = 1 << 16;

/// Dimension pairs of the sample table: image position, lens, time (first coordinate); then
/// three per bounce: light position, glossy direction, mirror-or-glossy choice (first coordinate).
const PAIR_PIXEL: usize = 0;
const PAIR_LENS: usize = 1;
const PAIR_TIME: usize = 2;
const PAIRS_BEFORE_BOUNCES: usize = 3;
const PAIRS_PER_BOUNCE: usize = 3;
/// The most reflection bounces the sample table has dimensions for.
pub const MAX_DEPTH: u32 = ((DIMENSION_PAIRS - PAIRS_BEFORE_BOUNCES) / PAIRS_PER_BOUNCE - 1) as u32;

/// Which estimator a sampled frame uses: Boulos et al.'s distribution ray tracing (this file) or
/// Monte Carlo path tracing (Gribble & Ramani 2008 §4, `render::path`). Both share these settings,
/// the frame record, the cached reference image and the error-vs-time measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    #[default]
    Distribution,
    Path,
}

impl Integrator {
    /// The `renderer` name of an experiment's `render` table and of `raylab render`.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Distribution => "distribution",
            Integrator::Path => "path",
        }
    }

    /// The kinds of rays its frames trace.
    pub fn kinds(self) -> [RayKind; 3] {
        match self {
            Integrator::Distribution => DRT_KINDS,
            Integrator::Path => PATH_KINDS,
        }
    }

    /// The most bounces this integrator renders.
    pub fn max_depth(self) -> u32 {
        match self {
            Integrator::Distribution => MAX_DEPTH,
            Integrator::Path => PATH_MAX_DEPTH,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrtSettings {
    pub integrator: Integrator,
    /// Path tracing: how shading is grouped into streams (counters only; set by the runner from
    /// the stream tracer's parameters).
    pub shade: ShadeStreams,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel: a perfect square (1, 4, 16, 64, ...).
    pub spp: u32,
    /// Lens radius; `None` keeps the camera's own (0 = pinhole).
    pub aperture: Option<f32>,
    /// Distance to the plane in focus; `None` keeps the camera's own.
    pub focus_distance: Option<f32>,
    /// Reflection bounces after the camera ray (0: direct light only).
    pub max_depth: u32,
    /// Seed of the static sample table.
    pub seed: u64,
    /// Soft shadows as Benthin & Wald 2009 §4.5 render them (`interleaved_shadows`): interleaved
    /// light sample sets, visibility apart from shading, filter and retrace; `spp` is then the
    /// light samples per pixel. `None`: one light sample per path sample.
    pub soft_shadows: Option<InterleavedShadows>,
    /// Trace one 32×32 tile in `tiles` (1: all), on diagonals across the image (`(tx + ty) %
    /// tiles == 0`): a stratified subset at the full resolution and sample count, for a paper's
    /// settings that would take hours over the whole frame (speed and counts only: no RMSE).
    pub tiles: u32,
    /// Path tracing: the camera rays of a wave pass by pass — every pixel's sample 0, then every
    /// pixel's sample 1, … — so that a stream of S camera rays holds S pixels once each, as
    /// Gribble & Ramani's input buffer (§4: "M primary rays … tiles of √M × √M pixels"); false:
    /// a pixel's samples one after another.
    pub passes: bool,
}

impl Default for DrtSettings {
    fn default() -> Self {
        DrtSettings {
            integrator: Integrator::Distribution,
            shade: ShadeStreams::default(),
            width: 256,
            height: 256,
            spp: 16,
            aperture: None,
            focus_distance: None,
            max_depth: 2,
            seed: 0x0D57_7ACE,
            soft_shadows: None,
            tiles: 1,
            passes: false,
        }
    }
}

impl DrtSettings {
    /// The image's camera projection, its 32×32 tiles traced (`tiles`) in row-major order, and
    /// how many tiles make one wave of about `WAVE_RAYS` camera rays (pass by pass: of about
    /// `WAVE_RAYS` pixels, each pass one stream's worth of distinct pixels or more).
    pub(crate) fn tile_waves(&self, camera: &Camera) -> (CameraProjection, Vec<(u32, u32)>, usize) {
        let projection = CameraProjection::new(&self.camera(camera), self.width, self.height);
        let (tiles_x, tiles_y) = projection.tiles();
        let samples = if self.passes { 1 } else { self.spp };
        let per_wave = WAVE_RAYS.div_ceil((TILE * TILE * samples) as usize).max(1);
        let every = self.tiles;
        let tiles = (0..tiles_y)
            .flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty)))
            .filter(|(tx, ty)| (tx + ty) % every == 0)
            .collect();
        (projection, tiles, per_wave)
    }

    /// The pixels `(x, y)` of a wave's tiles inside the image, each tile in Morton order.
    pub(crate) fn wave_pixels<'a>(
        &self,
        wave: &'a [(u32, u32)],
    ) -> impl Iterator<Item = (u32, u32)> + 'a {
        let (width, height) = (self.width, self.height);
        wave.iter().flat_map(move |&(tx, ty)| {
            (0..TILE * TILE).filter_map(move |code| {
                let (dx, dy) = morton_decode(code);
                let (x, y) = (tx * TILE + dx, ty * TILE + dy);
                (x < width && y < height).then_some((x, y))
            })
        })
    }

    /// The keys of an experiment's distribution `render` table besides `renderer`.
    pub const KEYS: [&str; 10] = [
        "spp",
        "tiles",
        "order",
        "aperture",
        "focus",
        "max_depth",
        "shadows",
        "sets",
        "filter",
        "retrace",
    ];

    /// Settings of `integrator` from one combination of an experiment's `render` grid (defaults
    /// for the keys it does not give), checked; `also` names the workload's own keys, for the
    /// message on an unknown one.
    pub fn from_params(integrator: Integrator, params: &Params, also: &[&str]) -> Result<Self> {
        let mut s = DrtSettings {
            integrator,
            max_depth: match integrator {
                Integrator::Distribution => DrtSettings::default().max_depth,
                Integrator::Path => PATH_DEFAULT_DEPTH,
            },
            ..DrtSettings::default()
        };
        let mut interleaved = InterleavedShadows {
            filter: true,
            ..InterleavedShadows::default()
        };
        // The keys of the interleaved mode given (they need `shadows = "interleaved"`).
        let mut mode_keys = Vec::new();
        for (key, value) in &params.0 {
            let bad = || Error::usage(format!("render {key} = {value:?} is not valid"));
            let number = || value.parse::<f32>().map_err(|_| bad());
            match key.as_str() {
                "spp" => s.spp = value.parse().map_err(|_| bad())?,
                "tiles" => s.tiles = value.parse().map_err(|_| bad())?,
                "order" => {
                    s.passes = match value.as_str() {
                        "pixels" => false,
                        "passes" => true,
                        _ => {
                            return Err(Error::usage(format!(
                                "render order = {value:?} is not valid (pixels or passes)"
                            )))
                        }
                    }
                }
                "aperture" => s.aperture = Some(number()?),
                "focus" => s.focus_distance = Some(number()?),
                "max_depth" => s.max_depth = value.parse().map_err(|_| bad())?,
                "shadows" => {
                    s.soft_shadows = match value.as_str() {
                        "sampled" => None,
                        "interleaved" => Some(interleaved),
                        _ => {
                            return Err(Error::usage(format!(
                                "render shadows = {value:?} is not valid (sampled or interleaved)"
                            )))
                        }
                    }
                }
                "sets" => {
                    interleaved.sets = LightSampleSets::parse(value)
                        .map_err(|e| Error::usage(format!("render sets: {e}")))?;
                    mode_keys.push(key.as_str());
                }
                "filter" => {
                    interleaved.filter = match value.as_str() {
                        "true" => true,
                        "false" => false,
                        _ => return Err(bad()),
                    };
                    mode_keys.push(key.as_str());
                }
                "retrace" => {
                    interleaved.retrace = value.parse().map_err(|_| bad())?;
                    mode_keys.push(key.as_str());
                }
                _ => {
                    let known: Vec<&str> = Self::KEYS.iter().chain(also).copied().collect();
                    return Err(Error::usage(format!(
                        "unknown {} render key {key:?} (known: renderer, {})",
                        integrator.name(),
                        known.join(", ")
                    )));
                }
            }
        }
        if s.soft_shadows.is_some() {
            // Keys sort before `shadows`: the mode's own settings are applied here.
            s.soft_shadows = Some(interleaved);
            if !params.0.contains_key("max_depth") {
                s.max_depth = 0;
            }
        } else if let Some(key) = mode_keys.first() {
            return Err(Error::usage(format!(
                "render {key} needs shadows = \"interleaved\""
            )));
        }
        s.check()?;
        if integrator == Integrator::Distribution {
            SampleTable::new(s.spp, s.seed)
                .map_err(|e| Error::usage(format!("render spp = {}: {e}", s.spp)))?;
        }
        if let Some(mode) = s.soft_shadows {
            mode.check(s.spp, s.seed).map_err(|e| {
                Error::usage(format!(
                    "render spp = {}, retrace = {}: {e}",
                    s.spp, mode.retrace
                ))
            })?;
        }
        Ok(s)
    }

    pub fn check(&self) -> Result<()> {
        let lens_ok = self.aperture.is_none_or(|a| a.is_finite() && a >= 0.0)
            && self.focus_distance.is_none_or(|f| f.is_finite() && f > 0.0);
        let max_depth = self.integrator.max_depth();
        if let Some(mode) = self.soft_shadows {
            let pinhole = self.aperture.is_none_or(|a| a == 0.0);
            if self.integrator != Integrator::Distribution || self.max_depth != 0 || !pinhole {
                return Err(Error::usage(format!(
                    "interleaved soft shadows (Benthin & Wald 2009) render direct light through a pinhole: renderer distribution, max_depth = 0, aperture 0 (got {} renderer, max_depth {}, aperture {:?}; {mode:?})",
                    self.integrator.name(),
                    self.max_depth,
                    self.aperture
                )));
            }
        }
        if self.passes && self.integrator != Integrator::Path {
            return Err(Error::usage(
                "render order = \"passes\" is a path tracing order (renderer path)",
            ));
        }
        if self.tiles != 1 && self.soft_shadows.is_some() {
            return Err(Error::usage(
                "render tiles: interleaved soft shadows filter across tiles; trace every tile",
            ));
        }
        if self.width == 0
            || self.height == 0
            || self.spp == 0
            || self.tiles == 0
            || self.shade.stream == 0
            || self.shade.width == 0
            || !lens_ok
            || self.max_depth > max_depth
        {
            return Err(Error::usage(format!(
                "{} settings out of range: width, height, spp, tiles ≥ 1, aperture ≥ 0, focus > 0, max_depth ≤ {max_depth} (got {self:?})",
                self.integrator.name()
            )));
        }
        Ok(())
    }

    /// The frame's camera with this run's lens.
    pub fn camera(&self, camera: &Camera) -> Camera {
        Camera {
            aperture: self.aperture.unwrap_or(camera.aperture),
            focus_distance: self.focus_distance.unwrap_or(camera.focus_distance),
            ..*camera
        }
    }
}

/// The kinds of rays a distribution frame traces; timings and counts are kept per kind.
/// Reflection rays are mirror and glossy reflection rays alike.
pub const DRT_KINDS: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Reflection];

/// Rays, explicit packets and tracing wall time of one kind over a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KindTotals {
    pub rays: u64,
    pub packets: u64,
    /// Wall time inside the tracer's batch calls.
    pub seconds: f64,
}

pub struct DrtFrame {
    pub image: Image,
    /// One record per (ray kind, bounce depth), summed over the frame's waves, in (depth, kind)
    /// order: camera rays have depth 0, the shadow and reflection rays leaving the hits of
    /// depth-d rays depth d + 1 (as in `whitted`).
    pub batches: Vec<BatchRecord>,
    /// Explicit packets (pixels' sample groups) traced, indexed by `RayKind as usize`.
    pub packets: [u64; RayKind::ALL.len()],
    /// Wall time of the whole frame: sampling, shading and tracing.
    pub seconds: f64,
    /// Interleaved soft shadows with retrace: how many pixels were retraced.
    pub retraced_pixels: Option<u64>,
}

impl DrtFrame {
    pub fn totals(&self, kind: RayKind) -> KindTotals {
        let of_kind = self
            .batches
            .iter()
            .filter(|b| b.kind == BatchKind::Rays(kind));
        KindTotals {
            rays: of_kind.clone().map(|b| b.rays as u64).sum(),
            packets: self.packets[kind as usize],
            seconds: of_kind.map(|b| b.seconds).sum(),
        }
    }

    /// Wall time inside the tracer over all kinds.
    pub fn trace_seconds(&self) -> f64 {
        self.batches.iter().map(|b| b.seconds).sum()
    }

    /// Rays traced over all kinds.
    pub fn rays(&self) -> u64 {
        self.batches.iter().map(|b| b.rays as u64).sum()
    }
}

/// The frame's batch records under construction, keyed by (depth, kind).
#[derive(Default)]
pub(crate) struct Records {
    batches: BTreeMap<(u32, BatchKind), BatchRecord>,
    packets: [u64; RayKind::ALL.len()],
}

impl Records {
    /// Traces `work`, a wavefront of `kind` at bounce `depth` in `packets` explicit packets, and
    /// books it.
    pub(crate) fn trace(
        &mut self,
        tracer: &dyn Tracer,
        work: Work<'_>,
        kind: RayKind,
        packets: usize,
        depth: u32,
        tracing: Tracing,
    ) -> Answers {
        let batch_kind = BatchKind::Rays(kind);
        let (answers, traced) = trace(tracer, work, batch_kind, depth, tracing);
        self.batches
            .entry((depth, batch_kind))
            .and_modify(|record| record.add(&traced))
            .or_insert(traced);
        self.packets[kind as usize] += packets as u64;
        answers
    }

    /// Traces `generation`'s batch at bounce `depth` and books it.
    fn trace_generation(
        &mut self,
        tracer: &dyn Tracer,
        generation: &Generation,
        depth: u32,
        tracing: Tracing,
    ) -> Answers {
        let batch = &generation.batch;
        let packets = batch.packet_start.iter().filter(|s| **s).count();
        let work = Work::of_batch(batch);
        self.trace(tracer, work, generation.kind, packets, depth, tracing)
    }

    /// Adds `counters` (the shading filters') to the record of `kind` at `depth`.
    pub(crate) fn count(&mut self, depth: u32, kind: BatchKind, counters: &Counters) {
        if let Some(record) = self.batches.get_mut(&(depth, kind)) {
            record.counters.merge(counters);
        }
    }

    /// The finished frame: `sum` (per pixel, over `spp` samples) averaged into its image.
    pub(crate) fn finish(
        self,
        width: u32,
        height: u32,
        sum: &[Vec3],
        spp: u32,
        start: Instant,
    ) -> DrtFrame {
        let mut image = Image::new(width, height);
        let scale = 1.0 / spp as f32;
        for (p, s) in image.pixels.iter_mut().zip(sum) {
            *p = *s * scale;
        }
        DrtFrame {
            image,
            batches: self.batches.into_values().collect(),
            packets: self.packets,
            seconds: start.elapsed().as_secs_f64(),
            retraced_pixels: None,
        }
    }
}

/// The geometry a frame is rendered against: the frame's mesh, moving to another mesh over the
/// shutter interval when there is motion blur.
#[derive(Clone, Copy, Debug)]
pub enum FrameGeometry<'a> {
    Static(&'a crate::scene::Mesh),
    Moving(&'a MovingMesh),
}

impl<'a> FrameGeometry<'a> {
    /// The frame's own mesh, or `moving` when the frame is rendered with motion blur.
    pub fn of(frame: &'a Frame, moving: Option<&'a MovingMesh>) -> Self {
        match moving {
            Some(moving) => FrameGeometry::Moving(moving),
            None => FrameGeometry::Static(&frame.mesh),
        }
    }

    /// Builds tracer `name` with `params` over this geometry (its own structure, built here;
    /// over both ends of the shutter when moving).
    pub fn tracer(&self, name: &str, params: &Params) -> Result<Box<dyn Tracer>> {
        match self {
            FrameGeometry::Static(mesh) => tracer_for_mesh(name, params, mesh),
            FrameGeometry::Moving(moving) => {
                let info = TracerInfo::find(name)?;
                tracer_for_motion(info, &info.config(params)?, params, moving)
            }
        }
    }

    /// The triangle `prim` as a ray at `time` sees it, and its material.
    pub(crate) fn triangle(&self, prim: u32, time: f32) -> (Triangle, u32) {
        match self {
            FrameGeometry::Static(mesh) => (
                mesh.triangles[prim as usize],
                mesh.material_ids[prim as usize],
            ),
            FrameGeometry::Moving(moving) => (
                moving.triangle(prim, time),
                moving.material_ids()[prim as usize],
            ),
        }
    }

    pub(crate) fn is_moving(&self) -> bool {
        matches!(self, FrameGeometry::Moving(_))
    }
}

/// One sample's path through the scene: where it adds its colour and how much of it arrives.
#[derive(Clone, Copy, Debug)]
struct Path {
    pixel: u32,
    x: u32,
    y: u32,
    sample: u32,
    time: f32,
    weight: Vec3,
}

/// A batch of one kind under construction, with the path each ray serves and what it carries.
struct Generation {
    kind: RayKind,
    batch: RayBatch,
    /// Per ray: its path and, for shadow rays, the colour it adds when unoccluded.
    served: Vec<(usize, Vec3)>,
    last_pixel: Option<u32>,
}

impl Generation {
    fn new(kind: RayKind) -> Self {
        Generation {
            kind,
            batch: RayBatch::new(kind),
            served: Vec::new(),
            last_pixel: None,
        }
    }

    /// Adds a ray of `path` at the path's time, starting a packet when the pixel changes.
    fn push(&mut self, ray: Ray, path: usize, paths: &[Path], carries: Vec3) {
        let p = &paths[path];
        let ray = ray.at_time(p.time);
        if self.last_pixel == Some(p.pixel) {
            self.batch.push(ray, p.pixel);
        } else {
            self.batch.push_packet_start(ray, p.pixel);
            self.last_pixel = Some(p.pixel);
        }
        self.served.push((path, carries));
    }
}

/// Renders `frame` of `scene` with the settings' integrator (distribution or path tracing) and
/// `tracer`, which must have been built over `geometry`.
pub fn render_sampled(
    scene: &Scene,
    frame: &Frame,
    geometry: FrameGeometry<'_>,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    tracing: Tracing,
) -> Result<DrtFrame> {
    if let Some(mode) = settings.soft_shadows {
        return render_interleaved_shadows(scene, frame, geometry, tracer, settings, mode, tracing);
    }
    match settings.integrator {
        Integrator::Distribution => {
            render_distribution(scene, frame, geometry, tracer, settings, tracing)
        }
        Integrator::Path => {
            render_path(scene, frame, geometry, tracer, settings, tracing, &mut None)
        }
    }
}

/// Renders `frame` of `scene` by distribution ray tracing with `tracer`, which must have been
/// built over `geometry` (a moving mesh needs a tracer that honours ray times).
pub fn render_distribution(
    scene: &Scene,
    frame: &Frame,
    geometry: FrameGeometry<'_>,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    tracing: Tracing,
) -> Result<DrtFrame> {
    settings.check()?;
    let start = Instant::now();
    let table = SampleTable::new(settings.spp, settings.seed)?;
    let (projection, tiles, tiles_per_wave) = settings.tile_waves(&frame.camera);

    let mut sum = vec![Vec3::ZERO; (settings.width * settings.height) as usize];
    let mut records = Records::default();
    for wave in tiles.chunks(tiles_per_wave) {
        let mut paths = Vec::new();
        let mut camera = Generation::new(RayKind::Primary);
        for (x, y) in settings.wave_pixels(wave) {
            for sample in 0..settings.spp {
                let time = if geometry.is_moving() {
                    table.get(x, y, sample, PAIR_TIME).0
                } else {
                    0.0
                };
                paths.push(Path {
                    pixel: y * settings.width + x,
                    x,
                    y,
                    sample,
                    time,
                    weight: Vec3::ONE,
                });
                let ray = camera_ray(&projection, &table, x, y, sample);
                camera.push(ray, paths.len() - 1, &paths, Vec3::ONE);
            }
        }
        let mut colour = vec![Vec3::ZERO; paths.len()];
        let mut current = camera;
        for depth in 0..=settings.max_depth {
            if current.batch.is_empty() {
                break;
            }
            let Answers::Hits(hits) = records.trace_generation(tracer, &current, depth, tracing)
            else {
                unreachable!("camera and reflection rays are traced for closest hits")
            };
            let mut shadows = LightQueries::new(scene);
            let mut reflections = Generation::new(RayKind::Reflection);
            let pairs = PAIRS_BEFORE_BOUNCES + PAIRS_PER_BOUNCE * depth as usize;
            for (i, hit) in hits.iter().enumerate() {
                let path_index = current.served[i].0;
                let path = paths[path_index];
                if !hit.is_hit() {
                    colour[path_index] += path.weight * BACKGROUND;
                    continue;
                }
                let ray = current.batch.ray(i);
                let (triangle, material) = geometry.triangle(hit.prim, ray.time);
                let surface = SurfacePoint::on_triangle(&triangle, &ray, hit);
                let m = &scene.materials[material as usize];
                colour[path_index] += path.weight * (m.emission + m.diffuse * AMBIENT);
                let sample = |pair: usize| table.get(path.x, path.y, path.sample, pair);

                // Soft shadows: per light, this sample's point on it, asked of the tracer as a
                // light-visibility query (one sample per shading point).
                if m.diffuse != Vec3::ZERO {
                    let (s, t) = sample(pairs);
                    for (l, light) in scene.lights.iter().enumerate() {
                        if let Some(ls) = sample_light(light, surface.p, surface.n, s, t) {
                            let carries = path.weight * m.diffuse * ls.incident;
                            let (pixel, time) = (path.pixel, path.time);
                            shadows.push(l, &surface, [s, t], path_index, pixel, time, carries);
                        }
                    }
                }

                // One reflection ray carrying the whole reflectance (Fresnel for dielectrics),
                // its direction mirror or glossy in proportion to the two reflectances.
                let total = specular_response(m, ray.dir, surface.n, triangle.normal()).reflection;
                if depth < settings.max_depth && total > 0.0 {
                    let reflected = reflect(ray.dir, surface.n);
                    let dir = match m.glossy {
                        Some((exponent, r)) if sample(pairs + 2).0 * (m.mirror + r) < r => {
                            let (u1, u2) = sample(pairs + 1);
                            sample_phong_lobe(reflected, surface.n, exponent, u1, u2)
                        }
                        _ => reflected,
                    };
                    let next = reflection_ray(&surface, dir);
                    paths[path_index].weight = path.weight * total;
                    reflections.push(next, path_index, &paths, Vec3::ZERO);
                }
            }
            shadows.trace(scene, tracer, &mut records, depth, tracing, &mut colour)?;
            current = reflections;
        }
        for (path, c) in paths.iter().zip(&colour) {
            sum[path.pixel as usize] += *c;
        }
    }
    Ok(records.finish(settings.width, settings.height, &sum, settings.spp, start))
}

/// The camera ray of sample `sample` of pixel `(x, y)`: its image position jittered in the pixel
/// and its lens position, both from the sample table.
pub fn camera_ray(
    projection: &CameraProjection,
    table: &SampleTable,
    x: u32,
    y: u32,
    sample: u32,
) -> Ray {
    let (jx, jy) = table.get(x, y, sample, PAIR_PIXEL);
    let lens = table.get(x, y, sample, PAIR_LENS);
    projection.ray(x as f32 + jx, y as f32 + jy, lens)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::room::EXTENT;
    use crate::scene::{library::load_scene, Light};
    use crate::tracers::tracer_for_frame;
    use crate::tracers::Params;

    fn lens_camera(aperture: f32) -> Camera {
        Camera {
            position: Vec3::new(0.5, 1.0, 6.0),
            target: Vec3::new(0.0, 0.8, 0.0),
            aperture,
            focus_distance: 5.0,
            ..Camera::default()
        }
    }

    #[test]
    fn aperture_zero_gives_the_pinhole_rays() {
        let table = SampleTable::new(16, 1).unwrap();
        let settings = DrtSettings {
            aperture: Some(0.0),
            ..DrtSettings::default()
        };
        let lens = CameraProjection::new(&settings.camera(&lens_camera(0.3)), 64, 48);
        let pinhole = CameraProjection::new(&lens_camera(0.0), 64, 48);
        for (x, y) in [(0, 0), (17, 5), (63, 47)] {
            for s in 0..16 {
                let (jx, jy) = table.get(x, y, s, PAIR_PIXEL);
                let ray = camera_ray(&lens, &table, x, y, s);
                let expected = pinhole.ray(x as f32 + jx, y as f32 + jy, (0.5, 0.5));
                assert_eq!(ray, expected);
                assert_eq!(ray.origin, Vec3::new(0.5, 1.0, 6.0));
            }
        }
    }

    #[test]
    fn lens_samples_of_a_pixel_meet_on_the_focal_plane() {
        let camera = lens_camera(0.4);
        let projection = CameraProjection::new(&camera, 64, 48);
        let table = SampleTable::new(64, 2).unwrap();
        let (_, _, forward) = camera.basis();
        for (x, y) in [(3u32, 40u32), (32, 24)] {
            let rays: Vec<Ray> = (0..64)
                .map(|s| {
                    let lens = table.get(x, y, s, PAIR_LENS);
                    projection.ray(x as f32 + 0.5, y as f32 + 0.5, lens)
                })
                .collect();
            let spread = rays
                .iter()
                .map(|r| r.origin.distance(camera.position))
                .fold(0.0, f32::max);
            assert!(spread > 0.3, "lens samples cover the aperture: {spread}");
            // Where each ray crosses the plane at focus distance along the view direction.
            let on_plane = |r: &Ray| {
                let t = (5.0 - (r.origin - camera.position).dot(forward)) / r.dir.dot(forward);
                r.at(t)
            };
            let first = on_plane(&rays[0]);
            for r in &rays {
                assert!(
                    on_plane(r).distance(first) < 1e-4,
                    "{:?} vs {first:?}",
                    on_plane(r)
                );
            }
        }
    }

    /// The built-in room with its point light replaced by a 1×1 quad light 1 mm under the
    /// ceiling (not lower: the ceiling right above a lower quad would be lit from 1/d² close,
    /// fireflies that need thousands of samples), and a glossy floor.
    fn quad_lit_room() -> Scene {
        let mut scene = load_scene("room", None).unwrap();
        let Light::Point {
            position,
            intensity,
        } = scene.lights[0]
        else {
            panic!("the room has a point light");
        };
        let under_ceiling = Vec3::new(position.x, EXTENT.y - 1e-3, position.z);
        scene.lights = vec![Light::Quad {
            corner: under_ceiling - Vec3::new(0.5, 0.0, 0.5),
            edge_u: Vec3::X,
            edge_v: Vec3::Z,
            emission: intensity,
        }];
        for m in &mut scene.materials {
            if m.name == "floor" {
                m.glossy = Some((30.0, 0.4));
            }
        }
        scene
    }

    fn render(scene: &Scene, spp: u32, aperture: f32) -> DrtFrame {
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
        let settings = DrtSettings {
            width: 64,
            height: 64,
            spp,
            aperture: Some(aperture),
            focus_distance: Some(6.0),
            ..DrtSettings::default()
        };
        render_distribution(
            scene,
            &frame,
            FrameGeometry::Static(&frame.mesh),
            tracer.as_ref(),
            &settings,
            Tracing::Counted,
        )
        .unwrap()
    }

    #[test]
    fn more_samples_converge_to_the_reference_image() {
        let scene = quad_lit_room();
        let reference = render(&scene, 256, 0.1).image;
        let rmse: Vec<f64> = [1, 4, 16]
            .iter()
            .map(|&spp| render(&scene, spp, 0.1).image.rmse(&reference))
            .collect();
        assert!(rmse[1] < rmse[0] && rmse[2] < rmse[1], "{rmse:?}");
        assert!(rmse[2] < 0.6 * rmse[0], "{rmse:?}");
    }

    #[test]
    fn a_frame_renders_identically_and_packets_are_pixels() {
        let scene = quad_lit_room();
        let a = render(&scene, 4, 0.1);
        let b = render(&scene, 4, 0.1);
        assert_eq!(a.image, b.image);
        let primary = a.totals(RayKind::Primary);
        assert_eq!(primary.rays, 64 * 64 * 4);
        assert_eq!(primary.packets, 64 * 64);
        // Per bounce (camera hit and two reflections): at most one shadow packet per pixel, one
        // shadow ray per sample (one light).
        let shadow = a.totals(RayKind::Shadow);
        assert!(shadow.packets <= 3 * 64 * 64 && shadow.rays <= 3 * 64 * 64 * 4);
        assert!(shadow.rays > shadow.packets, "pixels share shadow packets");
        let reflection = a.totals(RayKind::Reflection);
        assert!(reflection.rays > 0 && reflection.packets <= 2 * 64 * 64);
        assert!(reflection.rays <= 2 * 64 * 64 * 4);
        // One record per (depth, kind): shadows leave every hit; only the floor reflects, and
        // what it reflects (walls, boxes) does not, so no reflection ray reaches depth 2.
        let records: Vec<(u32, &str)> =
            a.batches.iter().map(|b| (b.depth, b.kind.name())).collect();
        assert_eq!(
            records,
            [
                (0, "primary"),
                (1, "shadow"),
                (1, "reflection"),
                (2, "shadow"),
            ]
        );
        // Counted: every ray of every record.
        assert!(a.batches.iter().all(|b| b.counters.rays == b.rays as u64));
        // The same frame at 1 spp differs from 4 spp (it is not the same estimate).
        assert_ne!(render(&scene, 1, 0.1).image, a.image);
    }
}
