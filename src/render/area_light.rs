//! Direct light from one light sample: a point light as it is, a quad light (area light, soft
//! shadows: Boulos et al. 2007 §4, "shadow rays to different positions on area light sources")
//! through one uniformly chosen point of its area per sample. A stratified 2D sample
//! (`interleaved::SampleTable`) maps to a stratified set of points on the quad, since the map
//! `(s, t) ↦ corner + s·edge_u + t·edge_v` is affine. The soft-shadow workload's sets of light
//! samples per 4×4 tile of pixels are jittered or QMC (`LightSampleSets`).

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::{Hit, RayBatch};
use crate::render::interleaved::{SampleTable, K};
use crate::render::qmc::Net;
use crate::render::rays::SurfacePoint;
use crate::render::shading::point_irradiance;
use crate::scene::{Light, Mesh, Scene};
use crate::tracers::visibility::{
    LightSamples, QuadLight, ShadingPoint, ShadingPoints, VisibilityQuery,
};

/// Where to aim the shadow ray, and the irradiance-like factor it delivers if unoccluded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub point: Vec3,
    /// Incoming light times the surface cosine, in the convention of the ray-casting renderer
    /// v0 (`raycast.rs`): times the diffuse albedo it is the reflected colour.
    pub incident: Vec3,
}

/// The sample of `light` from surface point `p` with unit normal `n` (facing the viewer), for the
/// sample `(s, t)` ∈ [0,1)²; `None` when the light is behind the surface or faces away.
pub fn sample_light(light: &Light, p: Vec3, n: Vec3, s: f32, t: f32) -> Option<LightSample> {
    let point = light.sample_point(s, t);
    let to_light = point - p;
    let d2 = to_light.length_squared();
    let cos_surface = n.dot(to_light) / d2.sqrt();
    if cos_surface <= 0.0 || d2 <= 0.0 {
        return None;
    }
    let incident = match *light {
        Light::Point { intensity, .. } => point_irradiance(p, n, point, intensity),
        Light::Quad {
            edge_u,
            edge_v,
            emission,
            ..
        } => {
            // Uniform area sampling: pdf 1/A, so radiance · A · cos_light · cos_surface / d² (the
            // quad seen face-on is v0's point of intensity radiance · A). Both faces emit: scene
            // files do not say which way a quad faces.
            let normal = edge_u.cross(edge_v);
            let area = normal.length();
            let cos_light = normal.dot(to_light).abs() / (area * d2.sqrt());
            emission * (area * cos_light * cos_surface / d2)
        }
    };
    Some(LightSample { point, incident })
}

/// How the light samples of a `K×K` tile of pixels are made (Benthin & Wald 2009 §4.5: "each
/// pixel is assigned to a different interleaved sampling set, using a 4×4 pixel grid pattern ...
/// all 2D sets yield 256 2D random numbers").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampleSets {
    /// Interleaved jittered sets of the static sample table (Keller & Heidrich 2001): each set
    /// a jittered grid, the tile together a finer one. Any perfect square per set. The default
    /// (the soft-shadow workload's sets before the QMC ones existed).
    #[default]
    Jittered,
    /// The tile's sets are the disjoint parts of one Hammersley net (`qmc`). Powers of 4.
    Hammersley,
    /// As `Hammersley` with the Larcher–Pillichshammer net (`qmc`). Powers of 4.
    LarcherPillichshammer,
}

impl LightSampleSets {
    pub const NAMES: [&str; 3] = ["jittered", "hammersley", "lp"];

    pub fn name(self) -> &'static str {
        match self {
            LightSampleSets::Jittered => "jittered",
            LightSampleSets::Hammersley => "hammersley",
            LightSampleSets::LarcherPillichshammer => "lp",
        }
    }

    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "jittered" => Ok(LightSampleSets::Jittered),
            "hammersley" => Ok(LightSampleSets::Hammersley),
            "lp" => Ok(LightSampleSets::LarcherPillichshammer),
            _ => Err(Error::usage(format!(
                "unknown light sample sets {name:?} (known: {})",
                Self::NAMES.join(", ")
            ))),
        }
    }

    /// The `K²` sets of `per_set` samples of one tile, set `p` for the pixels of pattern `p`
    /// (`SampleTable::pattern_of`); `seed` seeds the jittered table (the QMC nets are fixed).
    pub fn tile_sets(self, per_set: u32, seed: u64) -> Result<LightSamples> {
        self.sets(per_set, K * K, seed)
    }

    /// One set of `per_set` samples for every point (the adaptive retrace's samples).
    pub fn single_set(self, per_set: u32, seed: u64) -> Result<LightSamples> {
        self.sets(per_set, 1, seed)
    }

    fn sets(self, per_set: u32, sets: u32, seed: u64) -> Result<LightSamples> {
        let uv = match self {
            LightSampleSets::Jittered => {
                let table = SampleTable::new(per_set, seed)?;
                (0..sets)
                    .flat_map(|pattern| {
                        let (x, y) = (pattern % K, pattern / K);
                        let table = &table;
                        (0..per_set).map(move |s| <[f32; 2]>::from(table.get(x, y, s, 0)))
                    })
                    .collect()
            }
            LightSampleSets::Hammersley => Net::Hammersley.interleaved_sets(per_set, sets)?,
            LightSampleSets::LarcherPillichshammer => {
                Net::LarcherPillichshammer.interleaved_sets(per_set, sets)?
            }
        };
        LightSamples::new(per_set as usize, uv)
    }
}

/// The soft-shadow workload of Benthin & Wald 2009 (§4) over a frame's primary hits: one shading
/// point per hit, each its own packet (its samples share an origin), with interleaved light
/// sample sets (§4.5; Keller & Heidrich 2001): pixel `(x, y)` of a `width`-wide image uses set
/// `(x mod K, y mod K)` of the tile's `sets`.
pub fn soft_shadow_points(
    mesh: &Mesh,
    primary: &RayBatch,
    hits: &[Hit],
    width: u32,
    samples: u32,
    sets: LightSampleSets,
    seed: u64,
) -> Result<(ShadingPoints, LightSamples)> {
    let samples = sets.tile_sets(samples, seed)?;
    let mut points = ShadingPoints::default();
    for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
        let surface = SurfacePoint::of_hit(mesh, &primary.ray(i), hit);
        let pixel = primary.pixel[i];
        points.push(shading_point(&surface, pixel % width, pixel / width), true);
    }
    Ok((points, samples))
}

/// The soft-shadow workload of a frame's primary hits against its scene's first quad light, with
/// the pixel of each shading point: what experiments measure and `render --heatmap soft-shadow`
/// counts.
pub struct SoftShadowWork {
    pub points: ShadingPoints,
    pub light: QuadLight,
    pub samples: LightSamples,
    /// The pixel of each shading point.
    pub pixels: Vec<u32>,
}

impl SoftShadowWork {
    /// `soft_shadow_points` of `primary`'s `hits` (a `width`-wide image), `samples` per point of
    /// `sets`; `None` when `scene` has no quad light.
    pub fn of_hits(
        scene: &Scene,
        mesh: &Mesh,
        (primary, hits): (&RayBatch, &[Hit]),
        width: u32,
        (samples, sets): (u32, LightSampleSets),
        seed: u64,
    ) -> Result<Option<SoftShadowWork>> {
        let Some(light) = scene.quad_light() else {
            return Ok(None);
        };
        let (points, samples) =
            soft_shadow_points(mesh, primary, hits, width, samples, sets, seed)?;
        // `soft_shadow_points` makes one point per hit, in ray order.
        let pixels = (0..primary.len())
            .filter(|&i| hits[i].is_hit())
            .map(|i| primary.pixel[i])
            .collect();
        Ok(Some(SoftShadowWork {
            points,
            light: QuadLight::of(light),
            samples,
            pixels,
        }))
    }

    /// The light-visibility query.
    pub fn query(&self) -> VisibilityQuery<'_> {
        VisibilityQuery {
            points: &self.points.points,
            packet_start: &self.points.packet_start,
            light: self.light,
            samples: &self.samples,
        }
    }
}

/// The shading point of pixel `(x, y)` at `surface`, with the pixel's interleaved set.
pub fn shading_point(surface: &SurfacePoint, x: u32, y: u32) -> ShadingPoint {
    ShadingPoint {
        position: surface.p,
        normal: surface.n,
        origin: surface.ray_origin(),
        time: 0.0,
        set: SampleTable::pattern_of(x, y) as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Light {
        Light::Quad {
            corner: Vec3::new(-1.0, 4.0, -0.5),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.0),
            emission: Vec3::splat(10.0),
        }
    }

    #[test]
    fn quad_samples_lie_on_the_quad_and_are_stratified() {
        let table = SampleTable::new(16, 4).unwrap();
        let light = quad();
        for (x, y) in [(0, 0), (3, 1), (6, 7)] {
            let mut cells = [0u32; 16];
            for s in 0..16 {
                let (u, v) = table.get(x, y, s, 3);
                let sample = sample_light(&light, Vec3::ZERO, Vec3::Y, u, v).unwrap();
                let q = sample.point;
                assert_eq!(q.y, 4.0, "in the plane of the quad");
                assert!(
                    (-1.0..1.0).contains(&q.x) && (-0.5..0.5).contains(&q.z),
                    "{q:?}"
                );
                // 4×4 cells of the quad: x in steps of 0.5, z in steps of 0.25.
                let (cx, cz) = (((q.x + 1.0) / 0.5) as usize, ((q.z + 0.5) / 0.25) as usize);
                cells[cz * 4 + cx] += 1;
            }
            assert_eq!(cells, [1; 16], "pixel ({x},{y})");
        }
    }

    #[test]
    fn quad_sample_carries_radiance_times_solid_angle() {
        // Straight below the centre of a 2×1 quad at height 4: L · A · 1 · 1 / 16.
        let s = sample_light(&quad(), Vec3::ZERO, Vec3::Y, 0.5, 0.5).unwrap();
        assert_eq!(s.point, Vec3::new(0.0, 4.0, 0.0));
        let expected = 10.0 * 2.0 / 16.0;
        assert!((s.incident.x - expected).abs() < 1e-6);
        assert!(sample_light(&quad(), Vec3::ZERO, -Vec3::Y, 0.5, 0.5).is_none());
    }
}
