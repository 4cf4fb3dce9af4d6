//! Soft shadows the way Benthin & Wald 2009 render them (§4.5), as a mode of the distribution
//! renderer (`DrtSettings::soft_shadows`), over any tracer through the light-visibility query:
//!
//! 1. One camera ray per pixel, through its centre; a packet per 4×4 block of pixels.
//! 2. Visibility separated from shading: each primary hit asks which of its `spp` samples on the
//!    scene's quad light it sees (one light-visibility query, each shading point its own packet,
//!    pixel `(x, y)` using set `(x mod 4, y mod 4)` of the tile's interleaved sets:
//!    `LightSampleSets`); it is shaded with one sample at the light's centre ("A single sample
//!    to the center of the light is used for shading, while the fractional visibility is done by
//!    MFT"). Irradiance = centre sample's irradiance × visible fraction.
//! 3. Adaptive retrace (optional; §5.4 "adaptively refine only the penumbra pixels", Fig. 7):
//!    the pixels whose samples were partly occluded — some but not all — are asked again with
//!    `retrace` samples from one set, in a second query; their irradiance is the retraced one.
//! 4. The discontinuity filter (optional, `discontinuity_filter`) over the irradiance of the
//!    pixels not retraced (a retraced pixel keeps its own, better estimate); the colour is then
//!    emission + albedo × (ambient + irradiance).
//!
//! Direct light only: no reflection bounces, no lens or motion blur (the paper's workload is
//! primary and soft-shadow rays).

use std::time::Instant;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::{RayBatch, RayKind};
use crate::render::area_light::{sample_light, shading_point, LightSampleSets};
use crate::render::discontinuity_filter::{DiscontinuityFilter, PixelSurface};
use crate::render::distribution::{DrtFrame, DrtSettings, FrameGeometry, Records};
use crate::render::interleaved::K;
use crate::render::rays::SurfacePoint;
use crate::render::shading::{AMBIENT, BACKGROUND};
use crate::render::wavefront::{Answers, Tracing, Work};
use crate::scene::{Frame, Scene};
use crate::tracers::visibility::{
    LightSamples, QuadLight, ShadingPoint, ShadingPoints, Visibility,
};
use crate::tracers::{Tracer, VisibilityQuery};

/// The soft-shadow mode's own settings; its samples per pixel are `DrtSettings::spp`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InterleavedShadows {
    /// How the 4×4 tile's light sample sets are made.
    pub sets: LightSampleSets,
    /// Apply the 4×4 discontinuity filter.
    pub filter: bool,
    /// Light samples per retraced (partly occluded) pixel; 0: no retrace.
    pub retrace: u32,
}

impl InterleavedShadows {
    /// The render keys of this mode (besides `shadows = "interleaved"`).
    pub const KEYS: [&str; 3] = ["sets", "filter", "retrace"];

    /// Checks that the sample counts fit the sets (`spp` per pixel, `retrace` per retraced one).
    pub fn check(&self, spp: u32, seed: u64) -> Result<()> {
        self.sets.tile_sets(spp, seed)?;
        if self.retrace > 0 {
            self.sets.single_set(self.retrace, seed)?;
        }
        Ok(())
    }

    /// What the mode adds to the plain estimate, for labels: "", " filtered", " retrace 256", ...
    pub fn refinement(&self) -> String {
        let filter = if self.filter { " filtered" } else { "" };
        match self.retrace {
            0 => filter.to_string(),
            n => format!("{filter} retrace {n}"),
        }
    }

    /// The same mode without filter and retrace: what the reference image is rendered with.
    pub fn unrefined(self) -> Self {
        InterleavedShadows {
            filter: false,
            retrace: 0,
            ..self
        }
    }
}

/// What one pixel's primary hit needs for its colour.
struct Shaded {
    pixel: usize,
    /// Emission and ambient: what does not depend on the light's visibility.
    unshadowed: Vec3,
    albedo: Vec3,
    /// Irradiance from the light's centre, were it all visible.
    centre: Vec3,
}

/// Renders `frame` with soft shadows as `mode` says (module docs) with `tracer`, built over
/// `geometry`; `settings.spp` light samples per pixel.
pub fn render_interleaved_shadows(
    scene: &Scene,
    frame: &Frame,
    geometry: FrameGeometry<'_>,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    mode: InterleavedShadows,
    tracing: Tracing,
) -> Result<DrtFrame> {
    settings.check()?;
    let start = Instant::now();
    if geometry.is_moving() {
        return Err(Error::usage(
            "interleaved soft shadows render one instant: no shutter (motion blur)",
        ));
    }
    let Some(light) = scene.quad_light() else {
        return Err(Error::usage(format!(
            "interleaved soft shadows need a quad light; scene {} has none",
            scene.name
        )));
    };
    let samples = mode.sets.tile_sets(settings.spp, settings.seed)?;
    let (width, height) = (settings.width, settings.height);
    let mut records = Records::default();

    // 1. Camera rays, a packet per 4×4 block of pixels (the tiles' Morton order keeps blocks
    // together).
    let (projection, tiles, _) = settings.tile_waves(&frame.camera);
    let mut camera = RayBatch::new(RayKind::Primary);
    let mut block = None;
    for (x, y) in settings.wave_pixels(&tiles) {
        let pixel = y * width + x;
        let starts = block.replace((x / K, y / K)) != Some((x / K, y / K));
        // A pinhole's rays carry their grid, so multi-frusta tracing can make them on demand.
        match projection.pinhole_grid() {
            Some(grid) => camera.push_camera_ray(grid, pixel, starts),
            None => {
                let ray = projection.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5));
                match starts {
                    true => camera.push_packet_start(ray, pixel),
                    false => camera.push(ray, pixel),
                }
            }
        }
    }
    let packets = camera.packet_start.iter().filter(|s| **s).count();
    let Answers::Hits(hits) = records.trace(
        tracer,
        Work::Closest(&camera),
        RayKind::Primary,
        packets,
        0,
        tracing,
    ) else {
        unreachable!("camera rays are traced for closest hits")
    };

    // 2. Shading at the light's centre, and the shading points of the visibility query.
    let mut colour = vec![BACKGROUND; (width * height) as usize];
    let mut surfaces = vec![None; colour.len()];
    let mut shaded = Vec::new();
    let mut points = ShadingPoints::default();
    for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
        let ray = camera.ray(i);
        let (triangle, material) = geometry.triangle(hit.prim, 0.0);
        let surface = SurfacePoint::on_triangle(&triangle, &ray, hit);
        let m = &scene.materials[material as usize];
        let pixel = camera.pixel[i];
        let centre =
            sample_light(light, surface.p, surface.n, 0.5, 0.5).map_or(Vec3::ZERO, |s| s.incident);
        shaded.push(Shaded {
            pixel: pixel as usize,
            unshadowed: m.emission + m.diffuse * AMBIENT,
            albedo: m.diffuse,
            centre,
        });
        surfaces[pixel as usize] = Some(PixelSurface {
            position: surface.p,
            depth: hit.t,
            normal: surface.n,
        });
        points.push(shading_point(&surface, pixel % width, pixel / width), true);
    }
    let light = QuadLight::of(light);
    let visibility = records.visibility(tracer, &points, light, &samples, 1, tracing)?;
    let mut visible = vec![0.0; colour.len()];
    for (i, s) in shaded.iter().enumerate() {
        visible[s.pixel] = visibility.visible_fraction(i);
    }

    // 3. Adaptive retrace of the partly occluded pixels.
    let mut retraced = vec![false; colour.len()];
    let mut retraced_pixels = None;
    if mode.retrace > 0 {
        let retrace_samples = mode.sets.single_set(mode.retrace, settings.seed)?;
        let mut again = ShadingPoints::default();
        let mut which = Vec::new();
        for (i, point) in points.points.iter().enumerate() {
            if partly_occluded(&visibility, i) {
                again.push(ShadingPoint { set: 0, ..*point }, true);
                which.push(i);
            }
        }
        if !again.is_empty() {
            let v = records.visibility(tracer, &again, light, &retrace_samples, 2, tracing)?;
            for (j, &i) in which.iter().enumerate() {
                let pixel = shaded[i].pixel;
                visible[pixel] = v.visible_fraction(j);
                retraced[pixel] = true;
            }
        }
        retraced_pixels = Some(which.len() as u64);
    }

    // 4. The discontinuity filter, then the colour.
    if mode.filter {
        let filtered = DiscontinuityFilter::default().apply(width, &visible, &surfaces);
        for ((value, filtered), retraced) in visible.iter_mut().zip(filtered).zip(&retraced) {
            if !retraced {
                *value = filtered;
            }
        }
    }
    for s in &shaded {
        colour[s.pixel] = s.unshadowed + s.albedo * s.centre * visible[s.pixel];
    }
    let mut frame = records.finish(width, height, &colour, 1, start);
    frame.retraced_pixels = retraced_pixels;
    Ok(frame)
}

/// Whether some but not all of point `i`'s samples are occluded: the penumbra.
pub fn partly_occluded(visibility: &Visibility, i: usize) -> bool {
    let occluded = visibility.occluded_count(i);
    occluded > 0 && occluded < visibility.per_point
}

impl Records {
    /// Asks `tracer` which of its `samples` on `light` each of `points` sees (each point its own
    /// packet), as soft-shadow rays of bounce `depth`, and books it.
    pub(crate) fn visibility(
        &mut self,
        tracer: &dyn Tracer,
        points: &ShadingPoints,
        light: QuadLight,
        samples: &LightSamples,
        depth: u32,
        tracing: Tracing,
    ) -> Result<Visibility> {
        if points.is_empty() {
            return Ok(Visibility::new(0, samples));
        }
        let query = VisibilityQuery::new(points, light, samples)?;
        let work = Work::LightVisibility(query);
        match self.trace(
            tracer,
            work,
            RayKind::SoftShadow,
            points.len(),
            depth,
            tracing,
        ) {
            Answers::Visibility(v) => Ok(v),
            _ => unreachable!("a light-visibility query is answered with visibility bits"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::assembly::BatchKind;
    use crate::render::rays::CameraProjection;
    use crate::scene::library::load_scene;
    use crate::tracers::chunked::trace_hits;
    use crate::tracers::{tracer_for_frame, Params};

    const SIDE: u32 = 64;

    fn settings(spp: u32, mode: InterleavedShadows) -> DrtSettings {
        sized(SIDE, spp, mode)
    }

    fn sized(side: u32, spp: u32, mode: InterleavedShadows) -> DrtSettings {
        DrtSettings {
            width: side,
            height: side,
            spp,
            max_depth: 0,
            soft_shadows: Some(mode),
            ..DrtSettings::default()
        }
    }

    fn render(scene: &Scene, settings: &DrtSettings) -> DrtFrame {
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
        let geometry = FrameGeometry::Static(&frame.mesh);
        let mode = settings.soft_shadows.unwrap();
        render_interleaved_shadows(
            scene,
            &frame,
            geometry,
            tracer.as_ref(),
            settings,
            mode,
            Tracing::Counted,
        )
        .unwrap()
    }

    fn mode(sets: LightSampleSets, filter: bool, retrace: u32) -> InterleavedShadows {
        InterleavedShadows {
            sets,
            filter,
            retrace,
        }
    }

    /// At 256×256 (measured: 16 samples 0.0076, filtered 0.0034, 64 samples 0.0035 with jittered
    /// sets; 0.0059 and 0.0038 with LP sets, whose 16 samples are better to begin with). At 64×64 the filter's 4-pixel blur of the contact shadows costs more than its
    /// averaging saves (0.0120 against 0.0075): the window is large against the shadows there.
    #[test]
    fn the_filter_brings_16_samples_close_to_the_256_sample_image() {
        let scene = load_scene("room-area-light", None).unwrap();
        for sets in [
            LightSampleSets::Jittered,
            LightSampleSets::Hammersley,
            LightSampleSets::LarcherPillichshammer,
        ] {
            let reference = render(&scene, &sized(256, 256, mode(sets, false, 0))).image;
            let rmse = |filter| {
                let image = render(&scene, &sized(256, 16, mode(sets, filter, 0))).image;
                image.rmse(&reference)
            };
            let (plain, filtered) = (rmse(false), rmse(true));
            assert!(plain > 0.0, "{sets:?}");
            assert!(filtered < 0.7 * plain, "{sets:?}: {filtered} vs {plain}");
        }
    }

    #[test]
    fn retrace_adds_samples_exactly_to_the_partly_occluded_pixels() {
        let scene = load_scene("room-area-light", None).unwrap();
        let sets = LightSampleSets::Hammersley;
        let plain = render(&scene, &settings(16, mode(sets, false, 0)));
        let retraced = render(&scene, &settings(16, mode(sets, false, 64)));
        assert_eq!(plain.retraced_pixels, None);

        // The first pass by hand: the pixels' centre rays, their hits, their visibility.
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
        let projection = CameraProjection::new(&frame.camera, SIDE, SIDE);
        let mut camera = RayBatch::new(RayKind::Primary);
        for y in 0..SIDE {
            for x in 0..SIDE {
                let ray = projection.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5));
                camera.push(ray, y * SIDE + x);
            }
        }
        let hits = trace_hits(tracer.as_ref(), &camera);
        let mut points = ShadingPoints::default();
        for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
            let surface = SurfacePoint::of_hit(&frame.mesh, &camera.ray(i), hit);
            let pixel = camera.pixel[i];
            points.push(shading_point(&surface, pixel % SIDE, pixel / SIDE), true);
        }
        let light = QuadLight::of(scene.quad_light().unwrap());
        let samples = sets.tile_sets(16, 0).unwrap();
        let query = VisibilityQuery::new(&points, light, &samples).unwrap();
        let mut first = Visibility::new(points.len(), &samples);
        tracer.light_visibility(query, &mut first.words);
        let mut marked = ShadingPoints::default();
        for i in (0..points.len()).filter(|&i| partly_occluded(&first, i)) {
            marked.push(
                ShadingPoint {
                    set: 0,
                    ..points.points[i]
                },
                true,
            );
        }
        let count = marked.len();
        assert!(
            count > 0 && count < points.len() / 2,
            "{count} of {}",
            points.len()
        );
        assert_eq!(retraced.retraced_pixels, Some(count as u64));
        // The second pass: 64 samples for each marked pixel, no ray for any other.
        let retrace_samples = sets.single_set(64, 0).unwrap();
        let again = VisibilityQuery::new(&marked, light, &retrace_samples).unwrap();
        let second: Vec<_> = retraced
            .batches
            .iter()
            .filter(|b| b.kind == BatchKind::Rays(RayKind::SoftShadow))
            .map(|b| (b.depth, b.rays))
            .collect();
        assert_eq!(second, [(1, query.ray_count()), (2, again.ray_count())]);
        assert_eq!(
            retraced.packets[RayKind::SoftShadow as usize],
            (points.len() + count) as u64
        );
        // Unfiltered, only the retraced pixels change.
        let changed = (0..plain.image.pixels.len())
            .filter(|&p| plain.image.pixels[p] != retraced.image.pixels[p])
            .count();
        assert!(
            changed > 0 && changed <= count,
            "{changed} changed, {count} marked"
        );
    }

    #[test]
    fn bad_settings_are_refused() {
        let scene = load_scene("room", None).unwrap();
        let frame = scene.frame(0, 1);
        let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
        let s = settings(16, InterleavedShadows::default());
        let err = render_interleaved_shadows(
            &scene,
            &frame,
            FrameGeometry::Static(&frame.mesh),
            tracer.as_ref(),
            &s,
            InterleavedShadows::default(),
            Tracing::Timed,
        )
        .err()
        .unwrap();
        assert!(err.to_string().contains("quad light"), "{err}");
        let deep = DrtSettings { max_depth: 1, ..s };
        assert!(deep
            .check()
            .unwrap_err()
            .to_string()
            .contains("max_depth = 0"));
    }
}
