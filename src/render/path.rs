//! Monte Carlo path tracing, breadth first (Gribble & Ramani 2008 §4: "a Monte Carlo path tracer
//! … three different material models: a coupled model for glossy reflections, dielectrics, and
//! simple Lambertian surfaces … a thin-lens camera model"; §3.3: "ray streams are traced in a
//! breadth-first manner … each subsequent generation of rays is traced in a similar manner").
//!
//! Each bounce of a wave of 32×32 tiles is one batch (the camera rays, then the path rays of
//! bounce 1, 2, …), and each bounce's next-event estimation one light-visibility query per light,
//! so any `Tracer` traces the very same rays. Every random number is `sampling::uniform(seed,
//! pixel · spp + sample, dimension)`, the dimension fixed per bounce and use: the image depends
//! on the hits alone, not on the tracer, the thread count or the wave size.
//!
//! Shading runs as the filter stack of Fig. 4 over streams of `ShadeStreams::stream` consecutive
//! rays of a bounce: rays after the camera or a specular (delta) bounce that cross a quad light
//! take its emission ("light hits": lights are not geometry, they neither block nor end a path);
//! misses take the background; hits add their surface's emission; then each material shader runs
//! over its own sub-stream (next-event estimation, then the next ray). Each filter's sub-stream is
//! counted as SIMD work of width `ShadeStreams::width` (events `shade_*`, Tables 3 and 4's S and
//! shade columns). Shadow rays are a separate query per light, not a filter of the stream.
//! Materials map from `scene::Material` as follows:
//!
//! * `dielectric = Some((ior, transmittance))` → **dielectric**: Fresnel reflection (exact,
//!   `shading::fresnel_dielectric`) or Snell refraction, chosen with probability F, refraction
//!   weighted by the transmittance; the diffuse colour is ignored.
//! * `glossy = Some((exponent, rs))` → **coupled glossy**: the Ashikhmin–Shirley (2000) BRDF with
//!   isotropic exponent `exponent`, specular reflectance `rs` at normal incidence (Schlick
//!   Fresnel) and diffuse reflectance `diffuse`. Chosen because it is *coupled*: its diffuse
//!   term is scaled by what the glossy term does not reflect (`(1 − rs)` and the angular factors),
//!   so it is reciprocal and conserves energy, unlike a Phong sum; and it is sampled exactly by
//!   its half-vector density (`(n+1)/2π · cos^n θh`).
//! * otherwise → **Lambertian** with albedo `diffuse`.
//! * `mirror > 0` adds a perfect mirror lobe to the last two (the scenes' mirror coats).
//!
//! Light: quad and point lights by next-event estimation (one sample per light per non-delta
//! vertex, traced as a light-visibility query, `tracers::visibility`), the BRDF-sampled rays of
//! non-delta vertices not counting the lights again; `Material::emission` when a ray hits a
//! surface; the background for rays that leave. Quad-light `emission` is radiance and the BRDFs
//! are normalised (Lambertian ρ/π), so images are 1/π as bright in direct light as the ray-casting
//! convention of the other renderers. Russian roulette from bounce `RR_DEPTH` on (survival
//! probability the path weight's largest component, at most 1), and no bounce after `max_depth`.

use std::time::Instant;

use glam::Vec3;

use crate::error::Result;
use crate::geometry::{Ray, RayBatch, RayKind};
use crate::render::area_light::sample_light;
use crate::render::assembly::BatchKind;
use crate::render::distribution::{DrtFrame, DrtSettings, FrameGeometry, Records};
use crate::render::light_query::LightQueries;
use crate::render::rays::SurfacePoint;
use crate::render::sampling::{cosine_hemisphere, uniform};
use crate::render::shading::{fresnel_dielectric, BACKGROUND};
use crate::render::specular::{reflect, reflection_ray, refract, refraction_ray, relative_ior};
use crate::render::wavefront::{Answers, Tracing, Work};
use crate::scene::{Frame, Light, Material, Scene};
use crate::stats::{Counters, Event, Stats};
use crate::tracers::stream::StreamSize;
use crate::tracers::{Tracer, TracerConfig};

/// The kinds of rays a path-traced frame traces: camera rays, shadow rays (next-event
/// estimation) and path rays (every bounce after the camera, whatever lobe sampled it).
pub const PATH_KINDS: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse];
/// The most bounces a path may take.
pub const PATH_MAX_DEPTH: u32 = 64;
/// Bounces when a workload does not say.
pub const PATH_DEFAULT_DEPTH: u32 = 5;
/// Russian roulette decides on paths from this bounce on.
pub const RR_DEPTH: u32 = 3;

/// Sample dimensions: image position (2), lens (2), time (1); then per bounce: light position
/// (2), lobe choice (1), direction (2), Russian roulette (1), sub-lobe choice (1).
const DIM_PIXEL: u32 = 0;
const DIM_LENS: u32 = 2;
const DIM_TIME: u32 = 4;
const DIMS_BEFORE_BOUNCES: u32 = 5;
const DIMS_PER_BOUNCE: u32 = 7;
const LIGHT: u32 = 0;
const LOBE: u32 = 2;
const DIRECTION: u32 = 3;
const ROULETTE: u32 = 5;
const SUB_LOBE: u32 = 6;

/// One sample's path: where its colour goes, how much of it arrives, and whether the last
/// bounce was specular (light hits count).
#[derive(Clone, Copy, Debug)]
struct PathState {
    pixel: u32,
    /// Index of the sample over the image: pixel · spp + sample (the random stream's index).
    index: u64,
    time: f32,
    weight: Vec3,
    specular: bool,
}

/// One bounce's batch under construction, with the path each ray serves; a packet per pixel.
struct Generation {
    batch: RayBatch,
    served: Vec<usize>,
    last_pixel: Option<u32>,
}

impl Generation {
    fn new(kind: RayKind) -> Self {
        Generation {
            batch: RayBatch::new(kind),
            served: Vec::new(),
            last_pixel: None,
        }
    }

    fn push(&mut self, ray: Ray, path: usize, state: &PathState) {
        let ray = ray.at_time(state.time);
        if self.last_pixel == Some(state.pixel) {
            self.batch.push(ray, state.pixel);
        } else {
            self.batch.push_packet_start(ray, state.pixel);
            self.last_pixel = Some(state.pixel);
        }
        self.served.push(path);
    }
}

/// The material shaders of §4, each a filter of the stack (Fig. 4: "the remaining rays are then
/// processed by the shader").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shader {
    Lambertian,
    CoupledGlossy,
    Dielectric,
}

impl Shader {
    pub const ALL: [Shader; 3] = [
        Shader::Lambertian,
        Shader::CoupledGlossy,
        Shader::Dielectric,
    ];
}

/// How the path renderer groups its shading (Gribble & Ramani 2008 §3.2, Fig. 4): streams of
/// `stream` consecutive rays of a bounce's batch go through the filter stack, each filter's
/// sub-stream processed `width` at a time. Only the shading counters depend on it, not the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadeStreams {
    pub stream: usize,
    pub width: usize,
}

impl Default for ShadeStreams {
    /// The stream tracer's defaults: 64×64 initial streams, N = 16.
    fn default() -> Self {
        ShadeStreams {
            stream: 4096,
            width: 16,
        }
    }
}

impl ShadeStreams {
    /// The streams and width of a tracer configured with `config` when it is the stream filtering
    /// tracer (a `frame` stream: its work chunk of `chunk_rays`), else the defaults.
    pub fn of_config(config: &TracerConfig, chunk_rays: usize) -> ShadeStreams {
        match config {
            TracerConfig::Stream(config) => ShadeStreams {
                stream: match config.stream {
                    StreamSize::Rays(n) => n,
                    StreamSize::Frame => chunk_rays,
                },
                width: config.width,
            },
            _ => ShadeStreams::default(),
        }
    }
}

/// The shading filters' counters: sub-streams, their rays and the SIMD lanes they issue.
struct ShadeCounts {
    width: usize,
    counters: Counters,
}

impl ShadeCounts {
    fn new(width: usize) -> Self {
        ShadeCounts {
            width,
            counters: Counters::default(),
        }
    }

    /// Books one shading operation over the sub-stream `rays` and hands it back to run.
    fn filter<'a>(&mut self, rays: &'a [usize]) -> &'a [usize] {
        if !rays.is_empty() {
            let issued = rays.len().div_ceil(self.width) * self.width;
            self.counters.event(Event::ShadeFilters, 1);
            self.counters
                .event(Event::ShadeLanesActive, rays.len() as u64);
            self.counters.event(Event::ShadeLanesIssued, issued as u64);
        }
        rays
    }
}

/// How a surface scatters (the material mapping of the module comment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    Dielectric {
        ior: f32,
        transmittance: f32,
    },
    /// Lambertian (`glossy` = None) or coupled Ashikhmin–Shirley glossy, plus a mirror lobe.
    Opaque {
        diffuse: Vec3,
        /// (exponent, specular reflectance at normal incidence).
        glossy: Option<(f32, f32)>,
        mirror: f32,
    },
}

impl Bsdf {
    /// The shader that runs it.
    pub fn shader(&self) -> Shader {
        match self {
            Bsdf::Dielectric { .. } => Shader::Dielectric,
            Bsdf::Opaque { glossy: None, .. } => Shader::Lambertian,
            Bsdf::Opaque {
                glossy: Some(_), ..
            } => Shader::CoupledGlossy,
        }
    }

    pub fn of(m: &Material) -> Bsdf {
        match m.dielectric {
            Some((ior, transmittance)) => Bsdf::Dielectric { ior, transmittance },
            None => Bsdf::Opaque {
                diffuse: m.diffuse,
                glossy: m.glossy.map(|(e, r)| (e.max(0.0), r.clamp(0.0, 1.0))),
                mirror: m.mirror.max(0.0),
            },
        }
    }

    /// The non-delta BRDF value for light arriving along `wi` and leaving along `wo` (both unit,
    /// pointing away from the surface with unit normal `n`); zero below the surface.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let Bsdf::Opaque {
            diffuse, glossy, ..
        } = *self
        else {
            return Vec3::ZERO;
        };
        let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        match glossy {
            None => diffuse * std::f32::consts::FRAC_1_PI,
            Some((exponent, rs)) => ashikhmin_shirley(diffuse, exponent, rs, n, wo, wi),
        }
    }
}

/// The isotropic Ashikhmin–Shirley BRDF (Ashikhmin & Shirley 2000, eqs. 4–5).
fn ashikhmin_shirley(rd: Vec3, exponent: f32, rs: f32, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    use std::f32::consts::PI;
    let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
    let h = (wo + wi).normalize_or_zero();
    let k_h = wi.dot(h).max(1e-6);
    let n_h = n.dot(h).max(0.0);
    let fresnel = rs + (1.0 - rs) * (1.0 - k_h).powi(5);
    let specular =
        (exponent + 1.0) / (8.0 * PI) * n_h.powf(exponent) / (k_h * cos_o.max(cos_i)) * fresnel;
    let falloff = |c: f32| 1.0 - (1.0 - 0.5 * c).powi(5);
    let diffuse = rd * (28.0 / (23.0 * PI) * (1.0 - rs) * falloff(cos_o) * falloff(cos_i));
    diffuse + Vec3::splat(specular)
}

/// A sampled continuation of a path: direction, weight (BSDF · cos / pdf), whether it is a delta
/// lobe, and whether it leaves through the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    pub dir: Vec3,
    pub weight: Vec3,
    pub specular: bool,
    pub transmitted: bool,
}

/// The luminance-like mean of a colour, for choosing lobes.
fn mean(c: Vec3) -> f32 {
    c.element_sum() / 3.0
}

/// Samples the BSDF for a ray along unit `dir` meeting a surface with unit normal `n` facing the
/// ray and geometric (winding) normal `geometric`, from samples `lobe`, `sub` and `(u1, u2)` in
/// [0, 1). `None` when the path ends (no reflectance, or a direction below the surface).
pub fn sample_bsdf(
    bsdf: &Bsdf,
    dir: Vec3,
    n: Vec3,
    geometric: Vec3,
    lobe: f32,
    sub: f32,
    (u1, u2): (f32, f32),
) -> Option<Scatter> {
    let wo = -dir;
    match *bsdf {
        Bsdf::Dielectric { ior, transmittance } => {
            let eta = relative_ior(geometric, dir, ior);
            let reflected = Scatter {
                dir: reflect(dir, n),
                weight: Vec3::ONE,
                specular: true,
                transmitted: false,
            };
            match refract(dir, n, eta) {
                None => Some(reflected),
                Some(t) if lobe >= fresnel_dielectric(wo.dot(n), eta) => Some(Scatter {
                    dir: t,
                    weight: Vec3::splat(transmittance),
                    specular: true,
                    transmitted: true,
                }),
                Some(_) => Some(reflected),
            }
        }
        Bsdf::Opaque {
            diffuse,
            glossy,
            mirror,
        } => {
            let rest = mean(diffuse) + glossy.map_or(0.0, |(_, rs)| rs);
            if mirror + rest <= 0.0 {
                return None;
            }
            let p_mirror = mirror / (mirror + rest);
            if lobe < p_mirror {
                return Some(Scatter {
                    dir: reflect(dir, n),
                    weight: Vec3::splat(mirror / p_mirror),
                    specular: true,
                    transmitted: false,
                });
            }
            let p_rest = 1.0 - p_mirror;
            let (wi, pdf) = match glossy {
                None => {
                    let wi = cosine_hemisphere(n, u1, u2);
                    (wi, n.dot(wi) * std::f32::consts::FRAC_1_PI)
                }
                Some((exponent, rs)) => {
                    // One-sample mixture of the half-vector lobe and the cosine lobe.
                    let kd = mean(diffuse) * (1.0 - rs);
                    let p_glossy = if rs + kd > 0.0 { rs / (rs + kd) } else { 1.0 };
                    let wi = if sub < p_glossy {
                        let h = half_vector(n, exponent, u1, u2);
                        reflect(dir, h)
                    } else {
                        cosine_hemisphere(n, u1, u2)
                    };
                    let pdf = p_glossy * half_vector_pdf(n, exponent, wo, wi)
                        + (1.0 - p_glossy) * n.dot(wi).max(0.0) * std::f32::consts::FRAC_1_PI;
                    (wi, pdf)
                }
            };
            let cos_i = n.dot(wi);
            if cos_i <= 0.0 || pdf <= 0.0 || !wi.is_finite() {
                return None;
            }
            let weight = bsdf.eval(n, wo, wi) * (cos_i / (pdf * p_rest));
            Some(Scatter {
                dir: wi,
                weight,
                specular: false,
                transmitted: false,
            })
        }
    }
}

/// A half vector about `n` with density `(e+1)/2π · cos^e θh` (Ashikhmin & Shirley 2000 §5.3);
/// `1 − u1` keeps the origin of sample space at the normal (as `glossy::sample_phong_lobe`).
fn half_vector(n: Vec3, exponent: f32, u1: f32, u2: f32) -> Vec3 {
    let cos_h = (1.0 - u1).powf(1.0 / (exponent + 1.0));
    let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (t, b) = n.any_orthonormal_pair();
    (t * (sin_h * phi.cos()) + b * (sin_h * phi.sin()) + n * cos_h).normalize()
}

/// The solid-angle density of `wi` when sampled by reflecting about a `half_vector`.
fn half_vector_pdf(n: Vec3, exponent: f32, wo: Vec3, wi: Vec3) -> f32 {
    let h = (wo + wi).normalize_or_zero();
    let (n_h, o_h) = (n.dot(h), wo.dot(h));
    if n_h <= 0.0 || o_h <= 0.0 {
        return 0.0;
    }
    (exponent + 1.0) / (2.0 * std::f32::consts::PI) * n_h.powf(exponent) / (4.0 * o_h)
}

/// The emission a ray collects from the quad lights it crosses before `t_max` (both faces emit,
/// as in `area_light`); lights are not geometry, so they do not stop the ray.
fn light_hits(lights: &[Light], ray: &Ray, t_max: f32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for light in lights {
        let Light::Quad {
            corner,
            edge_u,
            edge_v,
            emission,
        } = *light
        else {
            continue;
        };
        let normal = edge_u.cross(edge_v);
        let (denom, area2) = (normal.dot(ray.dir), normal.length_squared());
        if denom == 0.0 || area2 == 0.0 {
            continue;
        }
        let t = normal.dot(corner - ray.origin) / denom;
        if !(t > ray.tmin && t < t_max) {
            continue;
        }
        let p = ray.at(t) - corner;
        let s = p.cross(edge_v).dot(normal) / area2;
        let v = edge_u.cross(p).dot(normal) / area2;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&v) {
            sum += emission;
        }
    }
    sum
}

/// The path rays of bounce `depth` (≥ 1; the camera rays are bounce 0) of `frame` path traced
/// with `tracer` at `settings` (`max_depth` raised to `depth`), every wave's, each carrying the
/// pixel its path started at (`render --heatmap-rays bounce-N`). Also the frame, whose batch
/// records count the same rays.
pub fn path_bounce_rays(
    scene: &Scene,
    frame: &Frame,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    depth: u32,
    tracing: Tracing,
) -> Result<(RayBatch, DrtFrame)> {
    let settings = DrtSettings {
        max_depth: settings.max_depth.max(depth),
        ..*settings
    };
    let mut kept = Some((depth, RayBatch::default()));
    let geometry = FrameGeometry::Static(&frame.mesh);
    let traced = render_path(
        scene, frame, geometry, tracer, &settings, tracing, &mut kept,
    )?;
    let (_, rays) = kept.expect("left in place by render_path");
    Ok((rays, traced))
}

/// Renders `frame` of `scene` by path tracing with `tracer`, which must have been built over
/// `geometry`. `settings.max_depth` bounces at most after the camera ray. With `keep` =
/// `Some((depth, rays))`, the path rays of bounce `depth` are appended to `rays`.
pub fn render_path(
    scene: &Scene,
    frame: &Frame,
    geometry: FrameGeometry<'_>,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    tracing: Tracing,
    keep: &mut Option<(u32, RayBatch)>,
) -> Result<DrtFrame> {
    settings.check()?;
    let start = Instant::now();
    let seed = settings.seed;
    let spp = settings.spp as u64;
    let (projection, tiles, tiles_per_wave) = settings.tile_waves(&frame.camera);
    let bsdfs: Vec<Bsdf> = scene.materials.iter().map(Bsdf::of).collect();
    let has_quad_light = scene.quad_light().is_some();

    let mut sum = vec![Vec3::ZERO; (settings.width * settings.height) as usize];
    let mut records = Records::default();
    for wave in tiles.chunks(tiles_per_wave) {
        let mut paths = Vec::new();
        let mut current = Generation::new(RayKind::Primary);
        let pixels: Vec<(u32, u32)> = settings.wave_pixels(wave).collect();
        // (pixel, sample) in the wave's order: a pixel's samples together, or pass by pass.
        let camera_samples: Vec<((u32, u32), u64)> = match settings.passes {
            false => pixels
                .iter()
                .flat_map(|&p| (0..spp).map(move |s| (p, s)))
                .collect(),
            true => (0..spp)
                .flat_map(|s| pixels.iter().map(move |&p| (p, s)))
                .collect(),
        };
        for ((x, y), sample) in camera_samples {
            let pixel = y * settings.width + x;
            let index = pixel as u64 * spp + sample;
            let u = |dim: u32| uniform(seed, index, dim);
            let state = PathState {
                pixel,
                index,
                time: if geometry.is_moving() {
                    u(DIM_TIME)
                } else {
                    0.0
                },
                weight: Vec3::ONE,
                specular: true,
            };
            let ray = projection.ray(
                x as f32 + u(DIM_PIXEL),
                y as f32 + u(DIM_PIXEL + 1),
                (u(DIM_LENS), u(DIM_LENS + 1)),
            );
            paths.push(state);
            current.push(ray, paths.len() - 1, &state);
        }
        let mut colour = vec![Vec3::ZERO; paths.len()];
        for depth in 0..=settings.max_depth {
            if current.batch.is_empty() {
                break;
            }
            let kind = current.batch.kind();
            if let Some((_, kept)) = keep.as_mut().filter(|(d, _)| *d == depth) {
                append(kept, &current.batch);
            }
            let packets = current.batch.packet_start.iter().filter(|s| **s).count();
            let work = Work::of_batch(&current.batch);
            let Answers::Hits(hits) = records.trace(tracer, work, kind, packets, depth, tracing)
            else {
                unreachable!("camera and path rays are traced for closest hits")
            };
            let base = DIMS_BEFORE_BOUNCES + DIMS_PER_BOUNCE * depth;
            let ray_of = |i: usize| current.batch.ray(i);
            // Per ray of the batch, what the filter stages leave for the ones after: the surface
            // it hit (with the triangle's normal and the material), its next ray; and the
            // next-event samples as (ray, light, sample, colour if visible).
            let mut surfaces: Vec<Option<(SurfacePoint, Vec3, u32)>> = vec![None; hits.len()];
            let mut scattered: Vec<Option<Ray>> = vec![None; hits.len()];
            let mut nee: Vec<(usize, usize, [f32; 2], Vec3)> = Vec::new();
            let mut shade = ShadeCounts::new(settings.shade.width);
            let all: Vec<usize> = (0..hits.len()).collect();
            for stream in all.chunks(settings.shade.stream) {
                // Fig. 4's filter stack, in order: light hits (rays after the camera or a
                // specular bounce that cross a quad light) …
                if has_quad_light {
                    let lit: Vec<usize> = stream
                        .iter()
                        .copied()
                        .filter(|&i| paths[current.served[i]].specular)
                        .collect();
                    for &i in shade.filter(&lit) {
                        let (p, ray) = (current.served[i], ray_of(i));
                        let t_max = if hits[i].is_hit() {
                            hits[i].t
                        } else {
                            ray.tmax
                        };
                        colour[p] += paths[p].weight * light_hits(&scene.lights, &ray, t_max);
                    }
                }
                // … misses …
                let (missed, hit): (Vec<usize>, Vec<usize>) =
                    stream.iter().partition(|&&i| !hits[i].is_hit());
                for &i in shade.filter(&missed) {
                    let p = current.served[i];
                    colour[p] += paths[p].weight * BACKGROUND;
                }
                // … the surfaces hit and their emission …
                for &i in shade.filter(&hit) {
                    let (p, ray) = (current.served[i], ray_of(i));
                    let (triangle, material) = geometry.triangle(hits[i].prim, ray.time);
                    let surface = SurfacePoint::on_triangle(&triangle, &ray, &hits[i]);
                    colour[p] += paths[p].weight * scene.materials[material as usize].emission;
                    surfaces[i] = Some((surface, triangle.normal(), material));
                }
                // … then the material's own split: each shader's rays shaded together.
                for shader in Shader::ALL {
                    let of_shader: Vec<usize> = hit
                        .iter()
                        .copied()
                        .filter(|&i| {
                            surfaces[i]
                                .is_some_and(|(_, _, m)| bsdfs[m as usize].shader() == shader)
                        })
                        .collect();
                    // Next-event estimation for the non-delta lobes: one point on each light.
                    if shader != Shader::Dielectric {
                        for &i in shade.filter(&of_shader) {
                            let Some((surface, _, material)) = surfaces[i] else {
                                continue;
                            };
                            let (p, ray) = (current.served[i], ray_of(i));
                            let index = paths[p].index;
                            let u = |k: u32| uniform(seed, index, base + k);
                            let (s, t) = (u(LIGHT), u(LIGHT + 1));
                            for (l, light) in scene.lights.iter().enumerate() {
                                let Some(ls) = sample_light(light, surface.p, surface.n, s, t)
                                else {
                                    continue;
                                };
                                let wi = (ls.point - surface.p).normalize_or_zero();
                                let f = bsdfs[material as usize].eval(surface.n, -ray.dir, wi);
                                let carries = paths[p].weight * f * ls.incident;
                                if carries.max_element() > 0.0 {
                                    nee.push((i, l, [s, t], carries));
                                }
                            }
                        }
                    }
                    if depth == settings.max_depth {
                        continue;
                    }
                    for &i in shade.filter(&of_shader) {
                        let Some((surface, geometric, material)) = surfaces[i] else {
                            continue;
                        };
                        let (p, ray) = (current.served[i], ray_of(i));
                        let state = paths[p];
                        let u = |k: u32| uniform(seed, state.index, base + k);
                        let Some(scatter) = sample_bsdf(
                            &bsdfs[material as usize],
                            ray.dir,
                            surface.n,
                            geometric,
                            u(LOBE),
                            u(SUB_LOBE),
                            (u(DIRECTION), u(DIRECTION + 1)),
                        ) else {
                            continue;
                        };
                        let mut weight = state.weight * scatter.weight;
                        if depth + 1 >= RR_DEPTH {
                            let survive = weight.max_element().min(1.0);
                            if u(ROULETTE) >= survive {
                                continue;
                            }
                            weight /= survive;
                        }
                        if !weight.is_finite() || weight.max_element() <= 0.0 {
                            continue;
                        }
                        paths[p] = PathState {
                            weight,
                            specular: scatter.specular,
                            ..state
                        };
                        scattered[i] = Some(match scatter.transmitted {
                            true => refraction_ray(&surface, scatter.dir),
                            false => reflection_ray(&surface, scatter.dir),
                        });
                    }
                }
            }
            if tracing == Tracing::Counted {
                records.count(depth, BatchKind::Rays(kind), &shade.counters);
            }
            // The next batch and the shadow queries in the batch's order (pixels together).
            let mut next = Generation::new(RayKind::Diffuse);
            for (i, ray) in scattered.iter().enumerate() {
                if let Some(ray) = ray {
                    let p = current.served[i];
                    next.push(*ray, p, &paths[p]);
                }
            }
            nee.sort_by_key(|&(i, l, _, _)| (i, l));
            let mut shadows = LightQueries::new(scene);
            for (i, l, sample, carries) in nee {
                if let Some((surface, _, _)) = &surfaces[i] {
                    let p = current.served[i];
                    let (pixel, time) = (paths[p].pixel, paths[p].time);
                    shadows.push(l, surface, sample, p, pixel, time, carries);
                }
            }
            shadows.trace(scene, tracer, &mut records, depth, tracing, &mut colour)?;
            current = next;
        }
        for (state, c) in paths.iter().zip(&colour) {
            sum[state.pixel as usize] += *c;
        }
    }
    Ok(records.finish(settings.width, settings.height, &sum, settings.spp, start))
}

/// `batch`'s rays, pixels and packets after `kept`'s, of its kind.
fn append(kept: &mut RayBatch, batch: &RayBatch) {
    if kept.is_empty() {
        kept.clear(batch.kind());
    }
    for i in 0..batch.len() {
        match batch.packet_start[i] {
            true => kept.push_packet_start(batch.ray(i), batch.pixel[i]),
            false => kept.push(batch.ray(i), batch.pixel[i]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampling::uniform;

    /// Monte Carlo albedo of a BSDF for a view direction: E[weight] over its own samples.
    fn albedo(bsdf: &Bsdf, wo: Vec3, n: Vec3, samples: u64) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for i in 0..samples {
            let u = |d| uniform(11, i, d);
            if let Some(s) = sample_bsdf(bsdf, -wo, n, n, u(0), u(1), (u(2), u(3))) {
                sum += s.weight;
            }
        }
        sum / samples as f32
    }

    #[test]
    fn lambertian_albedo_is_its_colour() {
        let bsdf = Bsdf::of(&Material::diffuse("d", Vec3::new(0.2, 0.5, 0.9)));
        let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
        let a = albedo(&bsdf, wo, Vec3::Z, 20_000);
        assert!(
            (a - Vec3::new(0.2, 0.5, 0.9)).abs().max_element() < 1e-3,
            "{a}"
        );
    }

    /// The coupled model neither creates energy nor loses much of it: its albedo lies between
    /// the larger of its parts and 1, and sampling agrees with integrating its value.
    #[test]
    fn ashikhmin_shirley_sampling_matches_its_value_and_conserves_energy() {
        let n = Vec3::Z;
        for (exponent, rs, rd) in [(10.0, 0.3, 0.6), (200.0, 0.05, 0.9), (1000.0, 0.9, 0.1)] {
            let bsdf = Bsdf::Opaque {
                diffuse: Vec3::splat(rd),
                glossy: Some((exponent, rs)),
                mirror: 0.0,
            };
            for theta in [0.1f32, 0.8, 1.3] {
                let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                let sampled = albedo(&bsdf, wo, n, 200_000).x;
                // The same integral by uniform hemisphere sampling of eval · cos.
                let count = 400_000u64;
                let integral: f32 = (0..count)
                    .map(|i| {
                        let z = uniform(5, i, 0);
                        let phi = 2.0 * std::f32::consts::PI * uniform(5, i, 1);
                        let r = (1.0 - z * z).sqrt();
                        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                        bsdf.eval(n, wo, wi).x * z * 2.0 * std::f32::consts::PI
                    })
                    .sum::<f32>()
                    / count as f32;
                let tolerance = 0.03 + 0.05 * integral;
                assert!(
                    (sampled - integral).abs() < tolerance,
                    "e={exponent} θ={theta}: sampled {sampled} vs integral {integral}"
                );
                assert!(sampled < 1.02, "e={exponent} θ={theta}: albedo {sampled}");
            }
        }
    }

    #[test]
    fn dielectric_paths_keep_their_weight_and_choose_by_fresnel() {
        let bsdf = Bsdf::Dielectric {
            ior: 1.5,
            transmittance: 1.0,
        };
        let (mut reflected, count) = (0u32, 100_000u64);
        for i in 0..count {
            let s = sample_bsdf(
                &bsdf,
                -Vec3::Z,
                Vec3::Z,
                Vec3::Z,
                uniform(3, i, 0),
                0.0,
                (0.0, 0.0),
            )
            .unwrap();
            assert_eq!(s.weight, Vec3::ONE);
            reflected += u32::from(!s.transmitted);
        }
        let fraction = reflected as f64 / count as f64;
        assert!((fraction - 0.04).abs() < 0.003, "{fraction}");
    }

    #[test]
    fn light_hits_find_the_quad_from_either_side_and_only_before_t_max() {
        let light = Light::Quad {
            corner: Vec3::new(-1.0, 2.0, -1.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
            emission: Vec3::splat(3.0),
        };
        let up = Ray::new(Vec3::ZERO, Vec3::Y, 0.0, f32::INFINITY);
        assert_eq!(light_hits(&[light], &up, f32::INFINITY), Vec3::splat(3.0));
        assert_eq!(light_hits(&[light], &up, 1.5), Vec3::ZERO);
        let down = Ray::new(Vec3::new(0.5, 4.0, 0.5), -Vec3::Y, 0.0, f32::INFINITY);
        assert_eq!(light_hits(&[light], &down, f32::INFINITY), Vec3::splat(3.0));
        let aside = Ray::new(Vec3::new(3.0, 0.0, 0.0), Vec3::Y, 0.0, f32::INFINITY);
        assert_eq!(light_hits(&[light], &aside, f32::INFINITY), Vec3::ZERO);
    }
}
