//! The tinybvh baseline (J. Bikker's `tiny_bvh.h` 1.6.8, through raylab's shim; cfg `tinybvh`):
//! tinybvh's own kernels over its own structures (`accel::tinybvh`), nothing of ours in the loop.
//!
//! - `tinybvh-2`, `tinybvh-4`, `tinybvh-8`: single rays, `Intersect` / `IsOccluded` of `BVH`,
//!   `BVH4_CPU` (SSE) and `BVH8_CPU` (AVX2 + FMA, after Fuetterling et al. 2017);
//! - `tinybvh-256` (`tile`): `BVH::Intersect256Rays` on 16×16 blocks of camera rays.
//!
//! What tinybvh's rays lack, and how we ask it the same question anyway:
//! - **tmin.** tinybvh's ray starts at its origin (hits need t > 0). A ray with tmin > 0 is handed
//!   over from `origin + tmin·dir` with far end `tmax − tmin`, and the hit distance is shifted
//!   back; tmin = 0, every camera ray, goes over unchanged.
//! - **tmax = ∞.** tinybvh's far end is finite (`ffi::BVH_FAR` = 1e30): hits beyond it are lost.
//! - **Scale.** tinybvh traces a copy of the scene scaled by a power of two (`accel::tinybvh`,
//!   *Scale*): origins and far ends are scaled in, hit distances out, exactly.
//! - **Ill-formed rays** (`Ray::is_well_formed`) are not handed over: they miss, as for every
//!   tracer (tinybvh would exit on a NaN).
//!
//! tinybvh's triangle test is Möller–Trumbore, not watertight: the stability suite says what that
//! costs. Counters: rays only (`COUNTS_INTERNALS = false`), as for Embree: tinybvh's kernels
//! count nothing. As for Embree, a timed pass traces rays staged beforehand in tinybvh's layout
//! (`tiny_rays`; for `tinybvh-256`, its packets), so the clock covers only tinybvh's calls.

pub mod tile;
mod tiny_rays;

#[cfg(test)]
mod guard_tests;

use std::ops::Range;
use std::sync::Arc;

use crate::accel::TinyBvh;
use crate::geometry::{Hit, Rays};
use crate::stats::Stats;
use crate::tracers::kernel::Kernel;
use crate::tracers::staged::{staged_by, StagedRays};

pub use tile::TileTracer;
use tiny_rays::TinyRays;

/// tinybvh's kernels count nothing: rays are all we count.
#[inline(always)]
fn count_rays<S: Stats>(n: usize, stats: &mut S) {
    if S::ENABLED {
        for _ in 0..n {
            stats.ray();
        }
    }
}

/// Single rays through one tinybvh layout: `Intersect` and `IsOccluded`, one call per ray.
pub struct SingleTracer {
    bvh: Arc<TinyBvh>,
}

impl SingleTracer {
    pub fn new(bvh: Arc<TinyBvh>) -> Self {
        SingleTracer { bvh }
    }
}

/// `rays` staged chunk by chunk for single-ray occlusion through `bvh` (every layout's and
/// `tinybvh-256`'s occlusion query).
fn stage_occlusion_single<'t>(
    bvh: &'t TinyBvh,
    rays: Rays<'_>,
    chunks: Vec<Range<usize>>,
) -> Box<dyn StagedRays<bool> + 't> {
    staged_by(
        chunks,
        |range| TinyRays::stage(bvh, &rays.slice(range)),
        move |staged: &mut TinyRays, out: &mut [bool]| staged.occluded(bvh, out),
    )
}

impl Kernel for SingleTracer {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        count_rays(hits.len(), stats);
        TinyRays::stage(&self.bvh, &rays).intersect(&self.bvh, hits);
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        count_rays(occluded.len(), stats);
        TinyRays::stage(&self.bvh, &rays).occluded(&self.bvh, occluded);
    }

    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        let bvh = &*self.bvh;
        Some(staged_by(
            chunks,
            |range| TinyRays::stage(bvh, &rays.slice(range)),
            move |staged: &mut TinyRays, out: &mut [Hit]| staged.intersect(bvh, out),
        ))
    }

    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        Some(stage_occlusion_single(&self.bvh, rays, chunks))
    }
}
