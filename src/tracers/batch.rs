//! Tracing a whole batch: contiguous chunks of the batch spread over the current rayon pool. The
//! runner's timed and counted passes, verification and secondary-ray generation all go through
//! here, so every caller splits a batch the same way.

use rayon::prelude::*;

use crate::geometry::{Hit, RayBatch, Rays};
use crate::stats::Counters;
use crate::tracers::Tracer;

/// Rays per work chunk. 4096 = four whole 32×32 camera tiles: a multiple of 16 (and of every
/// aligned n×n block, n ≤ 32), so no packet or Morton block of primary rays straddles two chunks
/// and packet and stream tracers see the same coherent groups whatever the thread count; large
/// enough that rayon's per-chunk cost (~1 µs) is noise next to tracing 4096 rays, small enough
/// that a 1024² batch gives 256 chunks for load balancing.
pub const CHUNK_RAYS: usize = 4096;

/// One pass of `trace` over `rays`, chunk by chunk, in the current pool.
pub fn pass<T: Send>(rays: Rays<'_>, out: &mut [T], trace: &(dyn Fn(Rays<'_>, &mut [T]) + Sync)) {
    out.par_chunks_mut(CHUNK_RAYS)
        .enumerate()
        .for_each(|(c, chunk)| {
            let start = c * CHUNK_RAYS;
            trace(rays.slice(start..start + chunk.len()), chunk);
        });
}

/// One counting pass: each chunk counts into its own `Counters`, merged at the end.
pub fn counted_pass<T: Send>(
    rays: Rays<'_>,
    out: &mut [T],
    trace: &(dyn Fn(Rays<'_>, &mut [T], &mut Counters) + Sync),
) -> Counters {
    out.par_chunks_mut(CHUNK_RAYS)
        .enumerate()
        .map(|(c, chunk)| {
            let start = c * CHUNK_RAYS;
            let mut counters = Counters::default();
            trace(rays.slice(start..start + chunk.len()), chunk, &mut counters);
            counters
        })
        .reduce(Counters::default, |mut a, b| {
            a.merge(&b);
            a
        })
}

/// Closest hits of a whole batch.
pub fn trace_hits(tracer: &dyn Tracer, batch: &RayBatch) -> Vec<Hit> {
    let mut hits = vec![Hit::MISS; batch.len()];
    pass(batch.view(), &mut hits, &|r, h| tracer.intersect(r, h));
    hits
}

/// Occlusion flags of a whole batch.
pub fn trace_occlusion(tracer: &dyn Tracer, batch: &RayBatch) -> Vec<bool> {
    let mut flags = vec![false; batch.len()];
    pass(batch.view(), &mut flags, &|r, o| tracer.occluded(r, o));
    flags
}
