//! The light-visibility query, beside closest hit and occlusion: shading points, a quad light and
//! a fixed set of light samples per point → which samples each point sees. It is the soft-shadow
//! workload of Benthin & Wald 2009 (§4: "for each shading point, S samples on the light source"),
//! stated so that every tracer answers it from the same rays.
//!
//! The rays are defined here, once: sample `(s, t)` of point `i` aims at
//! `corner + s·edge_u + t·edge_v` from the point's (offset) origin and stops just short of it
//! (`shadow_ray`). A sample behind the point's surface (`normal · (target − position) ≤ 0`) casts
//! no ray and counts as occluded: the surface itself blocks it. The default answer
//! (`occluded_by_rays`) makes those rays and calls the tracer's occlusion kernel; a tracer that
//! answers natively (multi-frusta, generating rays on demand) must give the same bits.

use std::ops::Range;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::ray_slots::RaySlots;
use crate::geometry::{Ray, RayBatch, RayKind};
use crate::scene::Light;

/// A parallelogram light `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1]. A point light is the
/// quad with zero edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadLight {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
}

impl QuadLight {
    /// The light's shape (a point light is a zero-size quad at its position).
    pub fn of(light: &Light) -> QuadLight {
        match *light {
            Light::Point { position, .. } => QuadLight {
                corner: position,
                edge_u: Vec3::ZERO,
                edge_v: Vec3::ZERO,
            },
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => QuadLight {
                corner,
                edge_u,
                edge_v,
            },
        }
    }

    /// The point of sample `(s, t)`: the same expression as `Light::sample_point`, so a renderer
    /// that shades with `Light` and shadows with this query aims at the very same point.
    #[inline]
    pub fn point(&self, s: f32, t: f32) -> Vec3 {
        self.corner + self.edge_u * s + self.edge_v * t
    }
}

/// A shadow ray from a surface point towards `target`: from `origin` (the point moved off its
/// surface) to just short of the target, so a light sample lying on geometry does not shadow
/// itself. `None` when the target is behind the surface (`normal` faces the viewer).
#[inline]
pub fn shadow_ray(position: Vec3, normal: Vec3, origin: Vec3, target: Vec3) -> Option<Ray> {
    // (`ray_count` repeats this test.)
    if (target - position).dot(normal) <= 0.0 {
        return None;
    }
    let to_light = target - origin;
    let distance = to_light.length();
    Some(Ray::new(
        origin,
        to_light / distance,
        0.0,
        distance * (1.0 - 1e-4),
    ))
}

/// One shading point: where it is, which way its surface faces, where its rays start, the time
/// of its rays (motion blur) and which sample set it uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    pub position: Vec3,
    pub normal: Vec3,
    pub origin: Vec3,
    pub time: f32,
    pub set: u32,
}

/// Shading points in order, with explicit packets: a packet tracer traces the rays of one packet
/// of points (e.g. one pixel's samples, or a 4×4 block of primary hits) as one packet.
#[derive(Clone, Debug, Default)]
pub struct ShadingPoints {
    pub points: Vec<ShadingPoint>,
    /// `packet_start[i]`: point `i` begins a packet (one flag per point; the first is always set).
    pub packet_start: Vec<bool>,
}

impl ShadingPoints {
    pub fn push(&mut self, point: ShadingPoint, packet_start: bool) {
        self.packet_start
            .push(packet_start || self.points.is_empty());
        self.points.push(point);
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The fixed light samples: `sets` sets of `per_point` samples `(s, t)` ∈ [0, 1)² each; a point
/// uses the set its `ShadingPoint::set` names (one set for all points, or interleaved sets, or
/// one set per point).
#[derive(Clone, Debug, PartialEq)]
pub struct LightSamples {
    per_point: usize,
    uv: Vec<[f32; 2]>,
}

impl LightSamples {
    /// The most samples per point: a point's bits fill at most this many 64-bit words.
    pub const MAX_PER_POINT: usize = 4096;

    /// `uv` holds the sets one after another, `per_point` samples each.
    pub fn new(per_point: usize, uv: Vec<[f32; 2]>) -> Result<LightSamples> {
        let in_unit = |x: f32| (0.0..=1.0).contains(&x);
        if per_point == 0 || per_point > Self::MAX_PER_POINT {
            return Err(Error::usage(format!(
                "light samples per point must be 1 to {}, got {per_point}",
                Self::MAX_PER_POINT
            )));
        }
        if uv.is_empty() || !uv.len().is_multiple_of(per_point) {
            return Err(Error::usage(format!(
                "{} light samples do not make whole sets of {per_point}",
                uv.len()
            )));
        }
        if let Some(bad) = uv.iter().find(|p| !in_unit(p[0]) || !in_unit(p[1])) {
            return Err(Error::usage(format!(
                "light sample {bad:?} lies outside [0, 1]²"
            )));
        }
        Ok(LightSamples { per_point, uv })
    }

    pub fn per_point(&self) -> usize {
        self.per_point
    }

    pub fn sets(&self) -> usize {
        self.uv.len() / self.per_point
    }

    /// The samples of set `set`.
    #[inline]
    pub fn set(&self, set: u32) -> &[[f32; 2]] {
        let begin = set as usize * self.per_point;
        &self.uv[begin..begin + self.per_point]
    }

    /// 64-bit words of occlusion bits per point.
    pub fn words_per_point(&self) -> usize {
        self.per_point.div_ceil(64)
    }

    /// Sets every sample bit of every point in `occluded` (`Visibility`'s layout), the bits past
    /// the sample count clear: where a light-visibility answer starts, clearing what sees the light.
    pub fn set_all_occluded(&self, occluded: &mut [u64]) {
        for point_words in occluded.chunks_exact_mut(self.words_per_point()) {
            for (w, word) in point_words.iter_mut().enumerate() {
                *word = u64::MAX >> (64 - (self.per_point - 64 * w).min(64));
            }
        }
    }
}

/// A light-visibility query over (a chunk of) shading points.
#[derive(Clone, Copy, Debug)]
pub struct VisibilityQuery<'a> {
    pub points: &'a [ShadingPoint],
    /// As `ShadingPoints::packet_start`, for these points.
    pub packet_start: &'a [bool],
    pub light: QuadLight,
    pub samples: &'a LightSamples,
}

impl<'a> VisibilityQuery<'a> {
    /// Every point of `points` against `light`, whose sets must all exist in `samples`.
    pub fn new(
        points: &'a ShadingPoints,
        light: QuadLight,
        samples: &'a LightSamples,
    ) -> Result<Self> {
        if let Some(p) = points
            .points
            .iter()
            .find(|p| p.set as usize >= samples.sets())
        {
            return Err(Error::usage(format!(
                "shading point uses light sample set {} of {}",
                p.set,
                samples.sets()
            )));
        }
        Ok(VisibilityQuery {
            points: &points.points,
            packet_start: &points.packet_start,
            light,
            samples,
        })
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Points `range` only (a chunk for one worker).
    pub fn slice(&self, range: Range<usize>) -> VisibilityQuery<'a> {
        VisibilityQuery {
            points: &self.points[range.clone()],
            packet_start: &self.packet_start[range],
            ..*self
        }
    }

    /// The shadow ray of sample `sample` of point `i`, or `None` when the sample is behind the
    /// point's surface.
    #[inline]
    pub fn ray(&self, i: usize, sample: usize) -> Option<Ray> {
        let p = &self.points[i];
        let [s, t] = self.samples.set(p.set)[sample];
        shadow_ray(p.position, p.normal, p.origin, self.light.point(s, t))
            .map(|r| r.at_time(p.time))
    }

    /// Every ray of the points in order, sample by sample, one explicit packet per packet of
    /// points: `f(point, sample, ray, starts_packet)`.
    #[inline(always)]
    fn each_ray(&self, mut f: impl FnMut(u32, u32, Ray, bool)) {
        let mut start_pending = false;
        for i in 0..self.len() {
            start_pending |= self.packet_start[i];
            for sample in 0..self.samples.per_point() {
                if let Some(ray) = self.ray(i, sample) {
                    f(
                        i as u32,
                        sample as u32,
                        ray,
                        std::mem::take(&mut start_pending),
                    );
                }
            }
        }
    }

    /// The rays of points in order, sample by sample, one explicit packet per packet of points;
    /// `traced[k]` is the (point, sample) of ray `k`. Both are cleared first.
    pub fn rays(&self, batch: &mut RayBatch, traced: &mut Vec<(u32, u32)>) {
        batch.clear(RayKind::SoftShadow);
        traced.clear();
        self.each_ray(|point, sample, ray, starts_packet| {
            match starts_packet {
                true => batch.push_packet_start(ray, point),
                false => batch.push(ray, point),
            }
            traced.push((point, sample));
        });
    }

    /// The rays `rays` makes, into `slots` (which hold `ray_count` of them), their points
    /// numbered from `first`; the first ray starts a packet (as the first pushed one does).
    pub fn write_rays(&self, slots: &mut RaySlots<'_>, first: u32) {
        let mut k = 0;
        self.each_ray(|point, _, ray, starts_packet| {
            slots.set(k, &ray, first + point, starts_packet || k == 0);
            k += 1;
        });
    }

    /// How many of point `i`'s samples cast a ray (are in front of its surface: `shadow_ray`'s
    /// test).
    #[inline]
    fn point_rays(&self, i: usize) -> usize {
        let p = &self.points[i];
        let target = |&[s, t]: &[f32; 2]| self.light.point(s, t);
        let samples = self.samples.set(p.set).iter();
        samples
            .filter(|uv| (target(uv) - p.position).dot(p.normal) > 0.0)
            .count()
    }

    /// How many samples cast a ray.
    pub fn ray_count(&self) -> usize {
        (0..self.len()).map(|i| self.point_rays(i)).sum()
    }

    /// Whether a ray of the query has a time other than 0 (motion blur).
    pub fn timed(&self) -> bool {
        (0..self.len()).any(|i| self.points[i].time != 0.0 && self.point_rays(i) > 0)
    }
}

/// Occlusion bits of points: point `i`'s sample `s` is bit `s % 64` of word
/// `i · words_per_point + s / 64`; a set bit means the sample is occluded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Visibility {
    pub per_point: usize,
    pub words: Vec<u64>,
}

impl Visibility {
    /// All bits clear for `points` points of `samples`.
    pub fn new(points: usize, samples: &LightSamples) -> Visibility {
        Visibility {
            per_point: samples.per_point(),
            words: vec![0; points * samples.words_per_point()],
        }
    }

    fn words_per_point(&self) -> usize {
        self.per_point.div_ceil(64)
    }

    pub fn points(&self) -> usize {
        self.words.len() / self.words_per_point().max(1)
    }

    pub fn occluded(&self, i: usize, sample: usize) -> bool {
        self.words[i * self.words_per_point() + sample / 64] >> (sample % 64) & 1 == 1
    }

    /// Occluded samples of point `i`.
    pub fn occluded_count(&self, i: usize) -> usize {
        let w = self.words_per_point();
        self.words[i * w..(i + 1) * w]
            .iter()
            .map(|x| x.count_ones() as usize)
            .sum()
    }

    /// The fraction of point `i`'s samples that see the light.
    pub fn visible_fraction(&self, i: usize) -> f32 {
        1.0 - self.occluded_count(i) as f32 / self.per_point as f32
    }

    /// Occluded samples over all points.
    pub fn total_occluded(&self) -> usize {
        self.words.iter().map(|x| x.count_ones() as usize).sum()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 2 × 2 light at height 4 over x, z ∈ [0, 2].
    pub(crate) fn light() -> QuadLight {
        QuadLight {
            corner: Vec3::new(0.0, 4.0, 0.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
        }
    }

    pub(crate) fn point(x: f32, normal: Vec3, set: u32) -> ShadingPoint {
        let position = Vec3::new(x, 0.0, 1.0);
        ShadingPoint {
            position,
            normal,
            origin: position,
            time: 0.0,
            set,
        }
    }

    /// `per_point` samples evenly across the light's width at its middle (t = 0.5).
    pub(crate) fn samples(per_point: usize) -> LightSamples {
        let uv = (0..per_point)
            .map(|i| [(i as f32 + 0.5) / per_point as f32, 0.5])
            .collect();
        LightSamples::new(per_point, uv).unwrap()
    }

    #[test]
    fn bad_sample_sets_are_refused() {
        assert!(LightSamples::new(0, vec![]).is_err());
        assert!(LightSamples::new(2, vec![[0.5, 0.5]; 3]).is_err());
        assert!(LightSamples::new(1, vec![[f32::NAN, 0.5]]).is_err());
        assert!(LightSamples::new(1, vec![[1.5, 0.5]]).is_err());
        let samples = LightSamples::new(1, vec![[0.5, 0.5]]).unwrap();
        let mut points = ShadingPoints::default();
        points.push(point(0.0, Vec3::Y, 1), true);
        let light = light();
        assert!(VisibilityQuery::new(&points, light, &samples).is_err());
    }

    #[test]
    fn a_point_light_is_a_zero_size_quad_at_its_position() {
        let position = Vec3::new(1.0, -2.0, 3.5);
        let light = QuadLight::of(&Light::Point {
            position,
            intensity: Vec3::ONE,
        });
        assert_eq!(light.point(0.3, 0.9), position);
    }
}
