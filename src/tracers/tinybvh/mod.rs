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
//! count nothing.

pub mod tile;

use std::sync::Arc;

use crate::accel::tinybvh::ffi::TinyRay;
use crate::accel::TinyBvh;
use crate::geometry::{Hit, Rays};
use crate::stats::Stats;
use crate::tracers::Kernel;

pub use tile::TileTracer;

/// Rays handed to tinybvh per call: a stack buffer of 32 KiB.
const BLOCK: usize = 256;

/// tinybvh's kernels count nothing: rays are all we count.
#[inline(always)]
fn count_rays<S: Stats>(n: usize, stats: &mut S) {
    if S::ENABLED {
        for _ in 0..n {
            stats.ray();
        }
    }
}

/// Ray `i` as `bvh` takes it, with the tmin it was shifted by; `None` for an ill-formed ray.
#[inline(always)]
fn tiny_ray(bvh: &TinyBvh, rays: &Rays<'_>, i: usize) -> Option<(TinyRay, f32)> {
    let r = rays.ray(i);
    if !r.is_well_formed() {
        return None;
    }
    let mut ray = if r.tmin > 0.0 {
        bvh.to_tiny(r.at(r.tmin), r.dir, r.tmax - r.tmin)
    } else {
        bvh.to_tiny(r.origin, r.dir, r.tmax)
    };
    // No triangle index is this: a ray still carrying it after tracing missed.
    ray.prim = Hit::NO_PRIM;
    Some((ray, r.tmin))
}

/// The hit tinybvh left in `ray`, handed over with its tmin shifted by `shift`.
#[inline(always)]
fn hit_of(bvh: &TinyBvh, ray: &TinyRay, shift: f32) -> Hit {
    if ray.prim == Hit::NO_PRIM {
        return Hit::MISS;
    }
    Hit {
        t: bvh.from_tiny(ray.t) + shift,
        prim: ray.prim,
        u: ray.u,
        v: ray.v,
    }
}

/// Single rays through one tinybvh layout: `Intersect` and `IsOccluded`, `BLOCK` rays per call.
pub struct SingleTracer {
    bvh: Arc<TinyBvh>,
}

impl SingleTracer {
    pub fn new(bvh: Arc<TinyBvh>) -> Self {
        SingleTracer { bvh }
    }
}

/// The well-formed rays of `range` in `buffer` (their tmin shifts in `shifts`, their indices in
/// `index`); how many there are.
fn gather(
    bvh: &TinyBvh,
    rays: &Rays<'_>,
    range: std::ops::Range<usize>,
    buffer: &mut [TinyRay; BLOCK],
    shifts: &mut [f32; BLOCK],
    index: &mut [usize; BLOCK],
) -> usize {
    let mut n = 0;
    for i in range {
        if let Some((ray, shift)) = tiny_ray(bvh, rays, i) {
            (buffer[n], shifts[n], index[n]) = (ray, shift, i);
            n += 1;
        }
    }
    n
}

/// Closest hits of `rays` by single rays through `bvh`.
pub(crate) fn intersect_single(bvh: &TinyBvh, rays: &Rays<'_>, hits: &mut [Hit]) {
    let mut buffer = [TinyRay::new([0.0; 3], [1.0, 0.0, 0.0], 0.0); BLOCK];
    let (mut shifts, mut index) = ([0.0; BLOCK], [0; BLOCK]);
    for start in (0..hits.len()).step_by(BLOCK) {
        let range = start..hits.len().min(start + BLOCK);
        hits[range.clone()].fill(Hit::MISS);
        let n = gather(bvh, rays, range, &mut buffer, &mut shifts, &mut index);
        bvh.intersect(&mut buffer[..n]);
        for k in 0..n {
            hits[index[k]] = hit_of(bvh, &buffer[k], shifts[k]);
        }
    }
}

impl Kernel for SingleTracer {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        count_rays(hits.len(), stats);
        intersect_single(&self.bvh, &rays, hits);
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        count_rays(occluded.len(), stats);
        occluded_single(&self.bvh, &rays, occluded);
    }
}

/// Occlusion of `rays` by single rays through `bvh`.
pub(crate) fn occluded_single(bvh: &TinyBvh, rays: &Rays<'_>, occluded: &mut [bool]) {
    let mut buffer = [TinyRay::new([0.0; 3], [1.0, 0.0, 0.0], 0.0); BLOCK];
    let (mut shifts, mut index) = ([0.0; BLOCK], [0; BLOCK]);
    let mut flags = [0u8; BLOCK];
    for start in (0..occluded.len()).step_by(BLOCK) {
        let range = start..occluded.len().min(start + BLOCK);
        occluded[range.clone()].fill(false);
        let n = gather(bvh, rays, range, &mut buffer, &mut shifts, &mut index);
        bvh.occluded(&mut buffer[..n], &mut flags[..n]);
        for k in 0..n {
            occluded[index[k]] = flags[k] != 0;
        }
    }
}
