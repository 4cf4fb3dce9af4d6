//! The next-event light queries of the sampled renderers (distribution ray tracing's soft
//! shadows, Boulos et al. 2007 §4; path tracing's next-event estimation, Gribble & Ramani 2008
//! §4): per light, one shading point per path vertex with its own light sample, one packet per
//! pixel, asked of the tracer as one light-visibility query; each visible sample adds its
//! colour to its path.

use glam::Vec3;

use crate::error::Result;
use crate::geometry::RayKind;
use crate::render::distribution::Records;
use crate::render::rays::SurfacePoint;
use crate::render::wavefront::{Tracing, Work};
use crate::scene::Scene;
use crate::tracers::visibility::{LightSamples, QuadLight, ShadingPoint, ShadingPoints};
use crate::tracers::{Tracer, VisibilityQuery};

/// One light's query under construction.
#[derive(Default)]
struct LightQuery {
    points: ShadingPoints,
    samples: Vec<[f32; 2]>,
    /// Per point: its path and the colour it adds when the light sample is visible.
    served: Vec<(usize, Vec3)>,
    last_pixel: Option<u32>,
}

/// The queries of one bounce, one per light of the scene.
pub(crate) struct LightQueries(Vec<LightQuery>);

impl LightQueries {
    pub fn new(scene: &Scene) -> Self {
        LightQueries(scene.lights.iter().map(|_| LightQuery::default()).collect())
    }

    /// Asks whether `surface` sees `sample` on light `light`; when it does, path `path` (of
    /// pixel `pixel`, cast at `time`) gains `carries`.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        light: usize,
        surface: &SurfacePoint,
        sample: [f32; 2],
        path: usize,
        pixel: u32,
        time: f32,
        carries: Vec3,
    ) {
        let query = &mut self.0[light];
        let point = ShadingPoint {
            position: surface.p,
            normal: surface.n,
            origin: surface.ray_origin(),
            time,
            set: query.samples.len() as u32,
        };
        let new_pixel = query.last_pixel != Some(pixel);
        query.last_pixel = Some(pixel);
        query.points.push(point, new_pixel);
        query.samples.push(sample);
        query.served.push((path, carries));
    }

    /// Traces every light's query as shadow rays of bounce `depth + 1` and adds the colour of
    /// each visible sample to its path's entry of `colour`.
    pub fn trace(
        self,
        scene: &Scene,
        tracer: &dyn Tracer,
        records: &mut Records,
        depth: u32,
        tracing: Tracing,
        colour: &mut [Vec3],
    ) -> Result<()> {
        for (light, query) in scene.lights.iter().zip(self.0) {
            if query.points.is_empty() {
                continue;
            }
            let samples = LightSamples::new(1, query.samples)?;
            let work = VisibilityQuery::new(&query.points, QuadLight::of(light), &samples)?;
            let packets = query.points.packet_start.iter().filter(|s| **s).count();
            let answers = records.trace(
                tracer,
                Work::LightVisibility(work),
                RayKind::Shadow,
                packets,
                depth + 1,
                tracing,
            );
            for (i, &(path, carries)) in query.served.iter().enumerate() {
                // One sample per point: sample i is point i's.
                if !answers.blocked(i) {
                    colour[path] += carries;
                }
            }
        }
        Ok(())
    }
}
