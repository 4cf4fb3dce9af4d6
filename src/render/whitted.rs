//! Whitted ray tracing (Whitted 1980), breadth first over any `Tracer`: the whole frame's camera
//! rays are one batch; their hits are shaded (Lambert + point lights with shadow rays, mirror
//! reflection, Fresnel-weighted refraction; `shading.rs`) and spawn the next generation's shadow,
//! reflection and refraction batches, packet-assembled per incoming packet (`assembly.rs`,
//! Boulos et al. 2007 §3.2), and so on until no rays are left. Each batch is traced through
//! `tracers::chunked`, so packet tracers see the assembled packets.
//!
//! Depth: camera rays have depth 0; every ray spawned at a hit of a depth-d ray has depth d + 1.
//! Reflection and refraction rays go up to `max_depth` (0 = ray casting), or each up to its own
//! limit when one is set (Overbeck et al. 2008 §6: the kitchen with "1-bounce reflections, 4-deep
//! refractions"); shadow rays may reach the deepest limit + 1 (the lights seen by the deepest
//! specular rays).
//!
//! Ray-tree attenuation (Boulos §5.1): a reflection or refraction ray is spawned only when the
//! product of the reflectances along its path (its weight) is at least the threshold. Shadow rays
//! are not pruned: they end the tree and their weight includes the light's units.
//!
//! The image does not depend on the thread count or on the assembly: every ray is shaded alone,
//! and radiance is summed per pixel in f64 in batch order, then rounded once.

use std::collections::BTreeMap;
use std::ops::Range;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::{Ray, RayBatch, RayKind};
use crate::render::assembly::{assemble, Assembly, BatchKind, Candidate, OutPackets};
use crate::render::image::Image;
use crate::render::rays::{primary_rays, shadow_ray};
use crate::render::shading::{light_as_point, point_irradiance, AMBIENT, BACKGROUND};
use crate::render::specular::{reflect, reflection_ray, refraction_ray, specular_at};
use crate::render::wavefront::{trace, Answers, BatchRecord, Tracing, Work};
use crate::scene::scene_file::Preset;
use crate::scene::{Frame, Material, Scene};
use crate::tracers::{Params, Tracer};

/// Default ray-tree attenuation threshold: 1/256, one step of an 8-bit pixel. A subtree whose
/// weight is below it changes the pixel by less than one display step as long as its radiance
/// stays under the white point, so pruning it is invisible in the PNG.
pub const DEFAULT_PRUNING_THRESHOLD: f32 = 1.0 / 256.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhittedSettings {
    /// Deepest reflection/refraction generation (0: camera rays and shadows only).
    pub max_depth: u32,
    /// Deepest generation of reflection rays (`None`: `max_depth`): a hit at depth d spawns a
    /// reflection ray only when d < this.
    pub max_reflection_depth: Option<u32>,
    /// Deepest generation of refraction rays (`None`: `max_depth`).
    pub max_refraction_depth: Option<u32>,
    /// Trace shadow rays; without them point lights light every surface they face, unoccluded.
    pub shadows: bool,
    /// Ray-tree attenuation threshold; `None` traces every specular ray up to `max_depth`.
    pub pruning: Option<f32>,
    pub assembly: Assembly,
    /// Side n of the incoming n×n packets whose secondary rays are assembled together: the
    /// packet size of the tracer being measured. Camera rays come in Morton-ordered tiles, so
    /// their packets are square screen blocks when n is a power of two ≤ 32.
    pub packet: usize,
    /// Material override applied to every material (`None`: the scene's materials as loaded).
    pub materials: Option<Preset>,
}

impl WhittedSettings {
    /// Deepest reflection generation in effect.
    pub fn reflection_depth(&self) -> u32 {
        self.max_reflection_depth.unwrap_or(self.max_depth)
    }

    /// Deepest refraction generation in effect.
    pub fn refraction_depth(&self) -> u32 {
        self.max_refraction_depth.unwrap_or(self.max_depth)
    }

    /// A usage error naming the offending value unless the packet side is ≥ 1 and the pruning
    /// threshold (when set) is a finite number > 0. The command line and experiment files both
    /// check through here.
    pub fn check(&self) -> Result<()> {
        if self.packet == 0 {
            return Err(Error::usage("packet side 0: must be at least 1"));
        }
        match self.pruning {
            Some(t) if !(t > 0.0 && t.is_finite()) => Err(Error::usage(format!(
                "pruning threshold {t}: must be a finite number > 0"
            ))),
            _ => Ok(()),
        }
    }
}

/// A `materials` setting: `scene` (the materials as loaded) or a preset name applied to every
/// material.
pub fn parse_materials(name: &str) -> Result<Option<Preset>> {
    match name {
        "scene" => Ok(None),
        _ => Preset::parse(name).map(Some).ok_or_else(|| {
            let presets: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
            Error::usage(format!(
                "unknown materials {name:?} (known: scene, {})",
                presets.join(", ")
            ))
        }),
    }
}

impl WhittedSettings {
    /// The keys of an experiment's whitted `render` table besides `renderer`.
    pub const KEYS: [&str; 8] = [
        "max_depth",
        "max_reflection_depth",
        "max_refraction_depth",
        "shadows",
        "pruning",
        "assembly",
        "packet",
        "materials",
    ];

    /// Settings from one combination of an experiment's `render` grid (defaults for the keys it
    /// does not give), checked.
    pub fn from_params(params: &Params) -> Result<Self> {
        let mut s = WhittedSettings::default();
        for (key, value) in &params.0 {
            let bad =
                |what: &str| Error::usage(format!("render {key} = {value:?} is not valid{what}"));
            match key.as_str() {
                "max_depth" => s.max_depth = value.parse().map_err(|_| bad(""))?,
                "max_reflection_depth" => {
                    s.max_reflection_depth = Some(value.parse().map_err(|_| bad(""))?)
                }
                "max_refraction_depth" => {
                    s.max_refraction_depth = Some(value.parse().map_err(|_| bad(""))?)
                }
                "shadows" => s.shadows = value.parse().map_err(|_| bad(""))?,
                "pruning" => {
                    s.pruning = match value.as_str() {
                        "true" => Some(DEFAULT_PRUNING_THRESHOLD),
                        "false" => None,
                        _ => Some(
                            value
                                .parse()
                                .map_err(|_| bad(" (true, false or a threshold > 0)"))?,
                        ),
                    }
                }
                "assembly" => {
                    s.assembly = Assembly::parse(value)
                        .ok_or_else(|| bad(&format!(" (known: {})", Assembly::names())))?
                }
                "packet" => s.packet = value.parse().map_err(|_| bad(" (a packet side ≥ 1)"))?,
                "materials" => {
                    s.materials =
                        parse_materials(value).map_err(|e| Error::usage(format!("render: {e}")))?
                }
                _ => {
                    return Err(Error::usage(format!(
                        "unknown render key {key:?} (known: renderer, {})",
                        Self::KEYS.join(", ")
                    )))
                }
            }
        }
        s.check()
            .map_err(|e| Error::usage(format!("render: {e}")))?;
        Ok(s)
    }
}

impl Default for WhittedSettings {
    fn default() -> Self {
        WhittedSettings {
            max_depth: 5,
            max_reflection_depth: None,
            max_refraction_depth: None,
            shadows: true,
            pruning: Some(DEFAULT_PRUNING_THRESHOLD),
            assembly: Assembly::RayTypes,
            packet: 8,
            materials: None,
        }
    }
}

pub struct WhittedFrame {
    pub image: Image,
    /// In tracing order: by depth, then `BatchKind` order.
    pub batches: Vec<BatchRecord>,
}

/// What a ray carries: a camera-descended path with its weight, or a shadow ray with the radiance
/// it adds to its pixel when nothing blocks it.
#[derive(Clone, Copy, Debug)]
enum Role {
    Path { weight: f32 },
    Shadow { radiance: Vec3 },
}

/// A batch of one generation and what each of its rays carries.
struct Generation {
    batch: RayBatch,
    roles: Vec<Role>,
}

/// A spawned ray: the ray, its pixel, what it carries.
type Child = (Ray, u32, Role);

/// What shading one incoming packet produced.
#[derive(Default)]
struct PacketOutput {
    radiance: Vec<(u32, Vec3)>,
    /// The outgoing packets' rays, one packet after another (one vector, not one per packet).
    rays: Vec<Child>,
    /// Per outgoing packet: the batch it joins and the end of its rays.
    packets: Vec<(BatchKind, usize)>,
}

/// One worker's buffers, reused from incoming packet to incoming packet.
#[derive(Default)]
struct Scratch {
    candidates: Vec<Candidate>,
    children: Vec<Child>,
    assembled: OutPackets,
}

/// Scene data every shading call reads.
struct Shader<'a> {
    frame: &'a Frame<'a>,
    materials: Vec<Material>,
    /// Lights as points: (position, intensity).
    lights: Vec<(Vec3, Vec3)>,
    settings: &'a WhittedSettings,
}

impl Shader<'_> {
    /// Shades rays `range` of `gen` (one incoming packet) at depth `depth`.
    fn packet(
        &self,
        gen: &Generation,
        answers: &Answers,
        range: Range<usize>,
        depth: u32,
        scratch: &mut Scratch,
    ) -> PacketOutput {
        let mut out = PacketOutput::default();
        let Scratch {
            candidates,
            children,
            assembled,
        } = scratch;
        candidates.clear();
        children.clear();
        let mesh = &*self.frame.mesh;
        let s = self.settings;
        let keep = |w: f32| w > 0.0 && s.pruning.is_none_or(|t| w >= t);
        for i in range.clone() {
            let pixel = gen.batch.pixel[i];
            let weight = match gen.roles[i] {
                Role::Shadow { radiance } => {
                    if !answers.blocked(i) {
                        out.radiance.push((pixel, radiance));
                    }
                    continue;
                }
                Role::Path { weight } => weight,
            };
            let Answers::Hits(hits) = answers else {
                unreachable!("path rays are traced for closest hits")
            };
            let hit = &hits[i];
            if !hit.is_hit() {
                out.radiance.push((pixel, BACKGROUND * weight));
                continue;
            }
            let ray = gen.batch.ray(i);
            let material_id = mesh.material_ids[hit.prim as usize];
            let m = &self.materials[material_id as usize];
            let (surface, response) = specular_at(mesh, &self.materials, &ray, hit);
            let mut local = m.emission + m.diffuse * AMBIENT;
            let mut spawn = |kind: RayKind, light: u32, child: Ray, role: Role| {
                candidates.push(Candidate {
                    parent: i - range.start,
                    material: material_id,
                    kind,
                    light,
                });
                children.push((child, pixel, role));
            };
            if m.diffuse != Vec3::ZERO {
                for (light, &(position, intensity)) in (0u32..).zip(&self.lights) {
                    let lit =
                        m.diffuse * point_irradiance(surface.p, surface.n, position, intensity);
                    if !s.shadows {
                        local += lit;
                    } else if let Some(shadow) = shadow_ray(&surface, position) {
                        let radiance = lit * weight;
                        spawn(RayKind::Shadow, light, shadow, Role::Shadow { radiance });
                    }
                }
            }
            out.radiance.push((pixel, local * weight));
            if depth < s.reflection_depth() {
                let w = weight * response.reflection;
                if keep(w) {
                    let child = reflection_ray(&surface, reflect(ray.dir, surface.n));
                    spawn(RayKind::Reflection, 0, child, Role::Path { weight: w });
                }
            }
            if let Some((dir, t)) = response.refraction.filter(|_| depth < s.refraction_depth()) {
                let w = weight * t;
                if keep(w) {
                    let child = refraction_ray(&surface, dir);
                    spawn(RayKind::Refraction, 0, child, Role::Path { weight: w });
                }
            }
        }
        assemble(s.assembly, candidates, assembled);
        out.rays.reserve_exact(children.len());
        for (batch, members) in assembled.iter() {
            out.rays.extend(members.iter().map(|&c| children[c]));
            out.packets.push((batch, out.rays.len()));
        }
        out
    }
}

/// Renders `frame` of `scene` with `tracer` in the current rayon pool.
pub fn render_whitted(
    scene: &Scene,
    frame: &Frame,
    tracer: &dyn Tracer,
    width: u32,
    height: u32,
    settings: &WhittedSettings,
    tracing: Tracing,
) -> WhittedFrame {
    assert!(settings.packet > 0, "packets of at least one ray");
    let mut materials = scene.materials.clone();
    if let Some(preset) = settings.materials {
        preset.apply_to_all(&mut materials);
    }
    let shader = Shader {
        frame,
        materials,
        lights: scene.lights.iter().map(light_as_point).collect(),
        settings,
    };
    let primary = primary_rays(&frame.camera, width, height);
    let roles = vec![Role::Path { weight: 1.0 }; primary.len()];
    let mut generation = BTreeMap::from([(
        BatchKind::Rays(RayKind::Primary),
        Generation {
            batch: primary,
            roles,
        },
    )]);
    let mut radiance = vec![DVec3::ZERO; (width * height) as usize];
    let mut records = Vec::new();
    let packet_rays = settings.packet * settings.packet;
    for depth in 0.. {
        if generation.is_empty() {
            break;
        }
        let mut next: BTreeMap<BatchKind, Generation> = BTreeMap::new();
        for (kind, gen) in generation {
            let (answers, record) = trace(tracer, Work::of_batch(&gen.batch), kind, depth, tracing);
            records.push(record);
            let ranges: Vec<Range<usize>> = gen.batch.view().packets(packet_rays).collect();
            let outputs: Vec<PacketOutput> = ranges
                .into_par_iter()
                .map_init(Scratch::default, |scratch, range| {
                    shader.packet(&gen, &answers, range, depth, scratch)
                })
                .collect();
            for output in outputs {
                for (pixel, c) in output.radiance {
                    radiance[pixel as usize] += c.as_dvec3();
                }
                let mut start = 0;
                for (kind, end) in output.packets {
                    let target = next.entry(kind).or_insert_with(|| Generation {
                        batch: RayBatch::new(match kind {
                            BatchKind::Rays(k) => k,
                            // A mixed batch is traced with closest-hit calls, like reflection rays.
                            BatchKind::Blind => RayKind::Reflection,
                        }),
                        roles: Vec::new(),
                    });
                    for (j, &(ray, pixel, role)) in output.rays[start..end].iter().enumerate() {
                        match j {
                            0 => target.batch.push_packet_start(ray, pixel),
                            _ => target.batch.push(ray, pixel),
                        }
                        target.roles.push(role);
                    }
                    start = end;
                }
            }
        }
        generation = next;
    }
    let mut image = Image::new(width, height);
    for (p, r) in image.pixels.iter_mut().zip(&radiance) {
        *p = r.as_vec3();
    }
    WhittedFrame {
        image,
        batches: records,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use crate::scene::{Camera, Mesh};
    use crate::tracers::tracer_for_frame;
    use crate::tracers::Params;

    /// Two facing mirrors (reflectance 0.5, diffuse 0.2, no lights) at z = −1 and z = +1, 200
    /// units wide, with the camera between them looking down −z: every camera ray bounces
    /// between them for ever, its weight halving at each bounce.
    fn mirror_corridor() -> Scene {
        let quad = |z: f32, facing: f32| {
            let s = 100.0;
            let (a, b, c, d) = (
                Vec3::new(-s, -s, z),
                Vec3::new(s, -s, z),
                Vec3::new(s, s, z),
                Vec3::new(-s, s, z),
            );
            // Counter-clockwise seen from the side the mirror faces.
            if facing > 0.0 {
                [Triangle { v: [a, b, c] }, Triangle { v: [a, c, d] }]
            } else {
                [Triangle { v: [a, c, b] }, Triangle { v: [a, d, c] }]
            }
        };
        let mut mesh = Mesh::default();
        for tri in quad(-1.0, 1.0).into_iter().chain(quad(1.0, -1.0)) {
            mesh.push(tri, 0);
        }
        Scene {
            name: "corridor".into(),
            source: "test".into(),
            mesh,
            materials: vec![Material {
                mirror: 0.5,
                ..Material::diffuse("mirror", Vec3::splat(0.2))
            }],
            lights: vec![],
            camera: Camera {
                position: Vec3::ZERO,
                target: -Vec3::Z,
                fov_y_deg: 10.0,
                ..Camera::default()
            },
            camera_path: None,
            animation: None,
        }
    }

    fn render(
        scene: &Scene,
        tracer: &str,
        settings: &WhittedSettings,
        w: u32,
        h: u32,
    ) -> WhittedFrame {
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame(tracer, &Params::new(), &frame).unwrap();
        render_whitted(
            scene,
            &frame,
            tracer.as_ref(),
            w,
            h,
            settings,
            Tracing::Counted,
        )
    }

    fn rays_by_depth(frame: &WhittedFrame) -> Vec<(u32, &'static str, usize)> {
        frame
            .batches
            .iter()
            .map(|b| (b.depth, b.kind.name(), b.rays))
            .collect()
    }

    #[test]
    fn pruning_drops_exactly_the_rays_below_the_threshold() {
        let scene = mirror_corridor();
        let pruned = WhittedSettings {
            max_depth: 10,
            pruning: Some(0.125),
            ..WhittedSettings::default()
        };
        // Weights 0.5, 0.25, 0.125 reach the threshold (≥); 0.0625 does not: three bounces.
        let frame = render(&scene, "reference", &pruned, 8, 8);
        let expected: Vec<_> = (0..=3)
            .map(|d| (d, if d == 0 { "primary" } else { "reflection" }, 64))
            .collect();
        assert_eq!(rays_by_depth(&frame), expected);
        assert!(frame.batches.iter().all(|b| b.hits == 64));
        // Each pixel: diffuse 0.2 × ambient 0.08 × (1 + 0.5 + 0.25 + 0.125).
        let want = 0.2 * AMBIENT * 1.875;
        assert!(frame.image.pixels.iter().all(|p| (p.x - want).abs() < 1e-7));

        // Without pruning, every bounce up to max_depth.
        let full = WhittedSettings {
            pruning: None,
            ..pruned
        };
        let frame = render(&scene, "reference", &full, 8, 8);
        assert_eq!(frame.batches.len(), 11);
        assert_eq!(frame.batches.last().unwrap().depth, 10);
        let want = 0.2 * AMBIENT * (2.0 - 0.5f32.powi(10));
        assert!(frame.image.pixels.iter().all(|p| (p.x - want).abs() < 1e-7));
        // max_depth 0: ray casting.
        let cast = WhittedSettings {
            max_depth: 0,
            ..full
        };
        assert_eq!(
            rays_by_depth(&render(&scene, "reference", &cast, 8, 8)),
            vec![(0, "primary", 64)]
        );
    }

    /// Five parallel glass panes (one quad each) at z = −1 … −5 facing the camera at the origin,
    /// which looks down −z with a narrow field of view, no lights: every camera ray crosses the
    /// panes nearly head-on, each hit splitting it into a reflection ray (back out towards +z,
    /// where nothing is: a miss) and a refraction ray (on to the next pane: a hit).
    fn glass_panes() -> Scene {
        let mut mesh = Mesh::default();
        for k in 1..=5 {
            let (z, s) = (-(k as f32), 100.0);
            let (a, b, c, d) = (
                Vec3::new(-s, -s, z),
                Vec3::new(s, -s, z),
                Vec3::new(s, s, z),
                Vec3::new(-s, s, z),
            );
            mesh.push(Triangle { v: [a, b, c] }, 0);
            mesh.push(Triangle { v: [a, c, d] }, 0);
        }
        let mut materials = vec![Material::diffuse("pane", Vec3::ONE)];
        Preset::Glass.apply_to_all(&mut materials);
        Scene {
            name: "panes".into(),
            source: "test".into(),
            mesh,
            materials,
            lights: vec![],
            camera: Camera {
                position: Vec3::ZERO,
                target: -Vec3::Z,
                fov_y_deg: 10.0,
                ..Camera::default()
            },
            camera_path: None,
            animation: None,
        }
    }

    #[test]
    fn reflection_and_refraction_depths_are_limited_separately() {
        let scene = glass_panes();
        let hits_by_depth = |f: &WhittedFrame| -> Vec<(u32, &'static str, usize, usize)> {
            f.batches
                .iter()
                .map(|b| (b.depth, b.kind.name(), b.rays, b.hits))
                .collect()
        };
        // One limit for both (max_depth 2): depth-0 hits (pane 1) spawn 64 reflection rays (all
        // miss) and 64 refraction rays (hit pane 2), which spawn 64 of each again at depth 2:
        // refraction rays on to pane 3, reflection rays back to pane 1 (hits).
        let both = WhittedSettings {
            max_depth: 2,
            pruning: None,
            ..WhittedSettings::default()
        };
        assert_eq!(
            hits_by_depth(&render(&scene, "reference", &both, 8, 8)),
            vec![
                (0, "primary", 64, 64),
                (1, "reflection", 64, 0),
                (1, "refraction", 64, 64),
                (2, "reflection", 64, 64),
                (2, "refraction", 64, 64),
            ]
        );
        // "1-bounce reflections, 4-deep refractions" (Overbeck §6) with max_depth 2 as the
        // default of neither: only camera-ray hits reflect; refraction rays go to depth 4 (pane 5).
        let split = WhittedSettings {
            max_reflection_depth: Some(1),
            max_refraction_depth: Some(4),
            ..both
        };
        assert_eq!(
            hits_by_depth(&render(&scene, "reference", &split, 8, 8)),
            vec![
                (0, "primary", 64, 64),
                (1, "reflection", 64, 0),
                (1, "refraction", 64, 64),
                (2, "refraction", 64, 64),
                (3, "refraction", 64, 64),
                (4, "refraction", 64, 64),
            ]
        );
        // No refraction at all: the reflection rays of the camera-ray hits only.
        let mirror_only = WhittedSettings {
            max_refraction_depth: Some(0),
            ..split
        };
        assert_eq!(
            hits_by_depth(&render(&scene, "reference", &mirror_only, 8, 8)),
            vec![(0, "primary", 64, 64), (1, "reflection", 64, 0)]
        );
    }

    /// The room with its floor a mirror and its red and blue boxes glass.
    fn room_with_glass() -> Scene {
        crate::scene::library::load_scene("room-glass-boxes", None).unwrap()
    }

    #[test]
    fn images_do_not_depend_on_assembly_threads_or_counting() {
        let scene = room_with_glass();
        let base = WhittedSettings {
            max_depth: 4,
            packet: 4,
            ..WhittedSettings::default()
        };
        let reference = render(&scene, "reference", &base, 64, 48);
        // The room has reflection and refraction rays at several depths, and shadows.
        let kinds: Vec<&str> = reference.batches.iter().map(|b| b.kind.name()).collect();
        for kind in ["shadow", "reflection", "refraction"] {
            assert!(kinds.contains(&kind), "{kinds:?}");
        }
        let total = |f: &WhittedFrame, d: u32| -> usize {
            f.batches
                .iter()
                .filter(|b| b.depth == d)
                .map(|b| b.rays)
                .sum()
        };
        for assembly in Assembly::ALL {
            let settings = WhittedSettings { assembly, ..base };
            let frame = render(&scene, "reference", &settings, 64, 48);
            assert!(
                frame.image == reference.image,
                "{assembly} changed the image"
            );
            for d in 0..=base.max_depth + 1 {
                assert_eq!(
                    total(&frame, d),
                    total(&reference, d),
                    "{assembly} depth {d}"
                );
            }
            if assembly == Assembly::Blind {
                assert!(frame
                    .batches
                    .iter()
                    .all(|b| b.depth == 0 || b.kind == BatchKind::Blind));
            }
        }
        // Timed on one thread: the same image and batches.
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let timed = pool.install(|| {
            render_whitted(
                &scene,
                &frame,
                tracer.as_ref(),
                64,
                48,
                &base,
                Tracing::Timed,
            )
        });
        assert!(timed.image == reference.image);
        assert_eq!(rays_by_depth(&timed), rays_by_depth(&reference));
        // Counting counts every ray of every batch.
        assert!(reference
            .batches
            .iter()
            .all(|b| b.counters.rays == b.rays as u64));
    }
}
