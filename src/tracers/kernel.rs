//! The traits every tracer implements, at the bottom of `tracers/`: families import them from
//! here, and only `registry.rs` (on top) imports the families.

use std::cell::RefCell;
use std::ops::Range;

use crate::geometry::{Hit, Ray, RayBatch, Rays};
use crate::stats::{Counters, NoStats, Stats};

use super::chunked;
use super::staged::StagedRays;
use super::visibility::VisibilityQuery;

/// What an algorithm implements: closest hit and occlusion over a chunk of rays, generic over the
/// counters so counting compiles away in timing runs.
pub trait Kernel: Send + Sync {
    /// Whether the kernel counts its own box/triangle tests (Embree cannot; it only counts rays).
    const COUNTS_INTERNALS: bool = true;

    /// Whether `light_visibility_with` answers the query itself (generating its rays where it
    /// needs them, as multi-frusta tracing does) rather than by the query's shadow rays through
    /// `occluded_with` (the default answer), which a caller may then generate once for every
    /// tracer and hand over as a batch.
    const ANSWERS_VISIBILITY_NATIVELY: bool = false;

    /// `hits[i]` becomes the closest hit of ray `i` in `[tmin, tmax]`, or `Hit::MISS`.
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S);

    /// `occluded[i]` becomes whether anything lies on ray `i` within `[tmin, tmax]`.
    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S);

    /// `occluded` becomes the query's occlusion bits (`visibility::Visibility`'s layout). The
    /// default traces the query's shadow rays with `occluded_with`; a tracer answering natively
    /// must give the same bits.
    fn light_visibility_with<S: Stats>(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        stats: &mut S,
    ) {
        occluded_by_rays(self, query, occluded, stats)
    }

    /// `rays` converted, chunk by chunk (`chunks`, as `chunked` cuts them), into the tracer's own
    /// layout for closest hits (`staged`); `None` (every from-scratch tracer): it reads `Rays`
    /// as they are and there is nothing to convert.
    fn stage_closest(
        &self,
        _rays: Rays<'_>,
        _chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        None
    }

    /// As `stage_closest`, for occlusion.
    fn stage_occlusion(
        &self,
        _rays: Rays<'_>,
        _chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        None
    }
}

/// A tracer that answers one ray at a time (reference, obvhs, grid-dda): its `Kernel` is the loop
/// over the chunk.
pub trait SingleRayKernel: Send + Sync {
    /// Closest hit (`ANY = false`) or first hit found (`ANY = true`, for occlusion) of one ray.
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit;
}

impl<T: SingleRayKernel> Kernel for T {
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        for (i, hit) in hits.iter_mut().enumerate() {
            stats.charge_ray(i);
            *hit = trace_checked::<T, S, false>(self, &rays.ray(i), stats);
        }
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        for (i, o) in occluded.iter_mut().enumerate() {
            stats.charge_ray(i);
            *o = trace_checked::<T, S, true>(self, &rays.ray(i), stats).is_hit();
        }
    }
}

/// `kernel.trace`, with an ill-formed ray (`Ray::is_well_formed`) answered by a miss.
#[inline(always)]
fn trace_checked<K: SingleRayKernel, S: Stats, const ANY: bool>(
    kernel: &K,
    ray: &Ray,
    stats: &mut S,
) -> Hit {
    if ray.is_well_formed() {
        kernel.trace::<S, ANY>(ray, stats)
    } else {
        stats.ray();
        Hit::MISS
    }
}

/// The object-safe face of a `Kernel`: the runner holds `Box<dyn Tracer>`.
pub trait Tracer: Send + Sync {
    fn counts_internals(&self) -> bool;
    /// `Kernel::ANSWERS_VISIBILITY_NATIVELY`.
    fn answers_visibility_natively(&self) -> bool;
    /// Rays per work chunk of a batch pass (`TracerInfo::chunk_rays`).
    fn chunk_rays(&self) -> usize;
    fn intersect(&self, rays: Rays<'_>, hits: &mut [Hit]);
    fn occluded(&self, rays: Rays<'_>, occluded: &mut [bool]);
    fn intersect_counted(&self, rays: Rays<'_>, hits: &mut [Hit], counters: &mut Counters);
    fn occluded_counted(&self, rays: Rays<'_>, occluded: &mut [bool], counters: &mut Counters);
    fn light_visibility(&self, query: VisibilityQuery<'_>, occluded: &mut [u64]);
    fn light_visibility_counted(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        counters: &mut Counters,
    );
    /// `Kernel::stage_closest`.
    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>>;
    /// `Kernel::stage_occlusion`.
    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>>;
}

impl<K: Kernel> Tracer for K {
    fn counts_internals(&self) -> bool {
        K::COUNTS_INTERNALS
    }
    fn answers_visibility_natively(&self) -> bool {
        K::ANSWERS_VISIBILITY_NATIVELY
    }
    fn chunk_rays(&self) -> usize {
        chunked::CHUNK_RAYS
    }
    fn intersect(&self, rays: Rays<'_>, hits: &mut [Hit]) {
        self.intersect_with(rays, hits, &mut NoStats)
    }
    fn occluded(&self, rays: Rays<'_>, occluded: &mut [bool]) {
        self.occluded_with(rays, occluded, &mut NoStats)
    }
    fn intersect_counted(&self, rays: Rays<'_>, hits: &mut [Hit], counters: &mut Counters) {
        self.intersect_with(rays, hits, counters)
    }
    fn occluded_counted(&self, rays: Rays<'_>, occluded: &mut [bool], counters: &mut Counters) {
        self.occluded_with(rays, occluded, counters)
    }
    fn light_visibility(&self, query: VisibilityQuery<'_>, occluded: &mut [u64]) {
        self.light_visibility_with(query, occluded, &mut NoStats)
    }
    fn light_visibility_counted(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        counters: &mut Counters,
    ) {
        self.light_visibility_with(query, occluded, counters)
    }
    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        Kernel::stage_closest(self, rays, chunks)
    }
    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        Kernel::stage_occlusion(self, rays, chunks)
    }
}

/// The default answer: the query's shadow rays through `kernel`'s occlusion test. `occluded`
/// holds `words_per_point` words per point of `query` and is overwritten.
pub fn occluded_by_rays<K: Kernel + ?Sized, S: Stats>(
    kernel: &K,
    query: VisibilityQuery<'_>,
    occluded: &mut [u64],
    stats: &mut S,
) {
    let words = query.samples.words_per_point();
    // The rays that get through clear their bit. Samples behind their surface cast no ray and stay
    // occluded.
    query.samples.set_all_occluded(occluded);
    SCRATCH.with_borrow_mut(
        |Scratch {
             batch,
             traced,
             flags,
         }| {
            query.rays(batch, traced);
            flags.clear();
            flags.resize(batch.len(), false);
            // Per-ray counters charge each shadow ray's counts to its shading point.
            let points: Vec<Range<u32>> = match S::ENABLED {
                true => batch.pixel.iter().map(|&p| p..p + 1).collect(),
                false => Vec::new(),
            };
            stats.relabelled(&points, |stats| {
                kernel.occluded_with(batch.view(), flags, stats)
            });
            for (&(i, sample), _) in traced.iter().zip(&*flags).filter(|(_, &o)| !o) {
                occluded[i as usize * words + sample as usize / 64] &= !(1 << (sample % 64));
            }
        },
    )
}

/// One worker's buffers for `occluded_by_rays`, reused from chunk to chunk (fresh ones per chunk
/// cost page faults comparable to generating the rays).
#[derive(Default)]
struct Scratch {
    batch: RayBatch,
    traced: Vec<(u32, u32)>,
    flags: Vec<bool>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::default();
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::RayKind;
    use crate::stats::Counters;
    use crate::tracers::visibility::tests::{light, point, samples};
    use crate::tracers::visibility::{LightSamples, ShadingPoints, Visibility};

    /// A kernel over one blocker, the square y = 2, x ∈ [0, 1], z ∈ [−1, 3], answered in closed
    /// form: the default visibility answer is tested apart from any tracer family.
    struct Blocker;

    impl Blocker {
        fn hit(ray: &Ray) -> Hit {
            let t = (2.0 - ray.origin.y) / ray.dir.y;
            let p = ray.origin + t * ray.dir;
            let inside = (0.0..=1.0).contains(&p.x) && (-1.0..=3.0).contains(&p.z);
            match inside && t >= ray.tmin && t <= ray.tmax {
                true => Hit {
                    t,
                    prim: 0,
                    u: p.x,
                    v: (p.z + 1.0) / 4.0,
                },
                false => Hit::MISS,
            }
        }
    }

    impl Kernel for Blocker {
        fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
            for (i, hit) in hits.iter_mut().enumerate() {
                stats.charge_ray(i);
                stats.ray();
                *hit = Blocker::hit(&rays.ray(i));
            }
        }

        fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
            for (i, o) in occluded.iter_mut().enumerate() {
                stats.charge_ray(i);
                stats.ray();
                *o = Blocker::hit(&rays.ray(i)).is_hit();
            }
        }
    }

    fn answer(query: VisibilityQuery<'_>) -> (Visibility, Counters) {
        let mut v = Visibility::new(query.len(), query.samples);
        let mut counters = Counters::default();
        Blocker.light_visibility_with(query, &mut v.words, &mut counters);
        (v, counters)
    }

    #[test]
    fn bits_follow_the_blocker_and_the_horizon() {
        let light = light();
        let samples = samples(10);
        let mut points = ShadingPoints::default();
        points.push(point(0.4, Vec3::Y, 0), false);
        // Facing away from the light: every sample is behind the surface.
        points.push(point(0.4, -Vec3::Y, 0), true);
        let query = VisibilityQuery::new(&points, light, &samples).unwrap();
        assert_eq!(query.ray_count(), 10);
        let (v, counters) = answer(query);
        // Light x = 0.1, 0.3, …, 1.9: the ray from x = 0.4 crosses y = 2 at (0.4 + x) / 2,
        // inside the blocker (< 1) for light x < 1.6: samples 0..=7.
        let first: Vec<bool> = (0..10).map(|s| v.occluded(0, s)).collect();
        let expected: Vec<bool> = (0..10).map(|s| s <= 7).collect();
        assert_eq!(first, expected);
        assert!((v.visible_fraction(0) - 0.2).abs() < 1e-6);
        assert!((0..10).all(|s| v.occluded(1, s)), "behind the surface");
        assert_eq!(v.visible_fraction(1), 0.0);
        assert_eq!(v.total_occluded(), 18);
        // Only the 10 rays in front of their surface were traced.
        assert_eq!(counters.rays, 10);
    }

    #[test]
    fn bits_span_several_words_and_stop_at_the_sample_count() {
        let light = light();
        let samples = samples(100);
        let mut points = ShadingPoints::default();
        points.push(point(0.4, -Vec3::Y, 0), true);
        let query = VisibilityQuery::new(&points, light, &samples).unwrap();
        let (v, _) = answer(query);
        assert_eq!(v.words, vec![u64::MAX, (1 << 36) - 1]);
        assert_eq!(v.occluded_count(0), 100);
    }

    #[test]
    fn the_default_answer_is_the_rays_one_by_one() {
        // Points across x ∈ [−1, 3], two sample sets: each bit equals the occlusion of its own ray.
        let light = light();
        let uv = (0..32)
            .map(|i| [(i % 8) as f32 / 7.0, (i / 8) as f32 / 3.0])
            .collect();
        let samples = LightSamples::new(16, uv).unwrap();
        let mut points = ShadingPoints::default();
        for i in 0..40 {
            points.push(point(-1.0 + 0.1 * i as f32, Vec3::Y, i % 2), i % 4 == 0);
        }
        let query = VisibilityQuery::new(&points, light, &samples).unwrap();
        let (v, _) = answer(query);
        let mut occluded = 0;
        for i in 0..points.len() {
            for s in 0..16 {
                let ray = query.ray(i, s).unwrap();
                let mut one = [false];
                let rays = RayBatch {
                    kind: Some(RayKind::SoftShadow),
                    ox: vec![ray.origin.x],
                    oy: vec![ray.origin.y],
                    oz: vec![ray.origin.z],
                    dx: vec![ray.dir.x],
                    dy: vec![ray.dir.y],
                    dz: vec![ray.dir.z],
                    tmin: vec![ray.tmin],
                    tmax: vec![ray.tmax],
                    pixel: vec![0],
                    ..RayBatch::default()
                };
                Blocker.occluded_with(rays.view(), &mut one, &mut crate::stats::NoStats);
                assert_eq!(v.occluded(i, s), one[0], "point {i} sample {s}");
                occluded += one[0] as usize;
            }
        }
        assert!(
            occluded > 0 && occluded < 40 * 16,
            "a case with both answers"
        );
        // The query's rays keep its packets: one explicit packet per 4 points.
        let mut batch = RayBatch::default();
        let mut traced = Vec::new();
        query.rays(&mut batch, &mut traced);
        assert_eq!(batch.packet_start.iter().filter(|s| **s).count(), 10);
        assert_eq!(traced.len(), 40 * 16);
    }
}
