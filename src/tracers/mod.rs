//! Every tracer — from-scratch or baseline — behind one trait, so the runner, the verifier and
//! the benchmarks treat them alike. Adding a tracer is adding a file and one line in `registry.rs`.

pub mod chunked;
pub mod coherent_grid;
pub mod embree;
pub mod grid_dda;
pub mod multi_frusta;
pub mod obvhs;
pub mod packet;
pub mod reference;
pub mod registry;
pub mod staged;
pub mod stream;
#[cfg(tinybvh)]
pub mod tinybvh;
pub mod visibility;
pub mod wide_single;

use std::ops::Range;

use crate::geometry::{Hit, Ray, Rays};
use crate::stats::{Counters, NoStats, Stats};

pub use crate::params::Params;
pub use registry::{
    build_tracer, make_tracer, oracle_params, tracer_for_frame, tracer_for_mesh, Role,
    TracerConfig, TracerInfo, ORACLE, TRACERS,
};
pub use staged::StagedRays;
pub use visibility::VisibilityQuery;

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
        visibility::occluded_by_rays(self, query, occluded, stats)
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
