//! Tracing a whole batch: contiguous chunks of the batch spread over the current rayon pool, each
//! as long as the tracer asks (`Tracer::chunk_rays`). The runner's timed and counted passes,
//! verification and secondary-ray generation all go through here, so every caller splits a batch
//! the same way.

use std::ops::Range;

use rayon::prelude::*;

use crate::geometry::{Hit, RayBatch, RayKind, Rays};
use crate::stats::Counters;
use crate::tracers::kernel::Tracer;
use crate::tracers::staged::StagedRays;
use crate::tracers::visibility::VisibilityQuery;

/// Rays per work chunk of most tracers (at least; see `chunk_ranges`). 4096 = four whole 32×32 camera tiles: a multiple of 16 (and of every
/// aligned n×n block, n ≤ 32), so no packet or Morton block of primary rays straddles two chunks
/// and packet and stream tracers see the same coherent groups whatever the thread count; large
/// enough that rayon's per-chunk cost (~1 µs) is noise next to tracing 4096 rays, small enough
/// that a 1024² batch gives 256 chunks for load balancing.
pub const CHUNK_RAYS: usize = 4096;

/// Fewest chunks a batch is cut into when the tracer asks for chunks longer than `CHUNK_RAYS`: a
/// stream tracer asking for 65,536-ray chunks would otherwise get a renderer's 65,536-ray wave
/// as one chunk, on one thread. A constant, not the thread count, so the chunks (and a stream
/// tracer's streams and counters) are the same at every thread count.
const MIN_CHUNKS: usize = 8;

/// The chunks of `rays`: runs of `chunk_rays` (shortened, not below `CHUNK_RAYS` and in whole
/// 1024-ray blocks, so a batch makes `MIN_CHUNKS` of them), or, when the batch has explicit
/// packets, runs of whole packets each ending at the first packet start at or past that length,
/// so that no packet is split between two chunks.
fn chunk_ranges(rays: Rays<'_>, chunk_rays: usize) -> Vec<Range<usize>> {
    let share = rays.len().div_ceil(MIN_CHUNKS).next_multiple_of(1024);
    let length = chunk_rays.min(share.max(CHUNK_RAYS));
    packet_chunks(rays.len(), rays.packet_start, length)
}

/// Runs of `len` items, at least `at_least` long (but the last), each ending at a packet start
/// (`packet_start`: empty, or one flag per item).
fn packet_chunks(len: usize, packet_start: &[bool], at_least: usize) -> Vec<Range<usize>> {
    let mut chunks = Vec::with_capacity(len / at_least + 1);
    let mut begin = 0;
    while begin < len {
        let at_least = (begin + at_least).min(len);
        let end = if packet_start.is_empty() {
            at_least
        } else {
            (at_least..len).find(|&i| packet_start[i]).unwrap_or(len)
        };
        chunks.push(begin..end);
        begin = end;
    }
    chunks
}

/// `out` cut along `chunk_ranges(rays, chunk_rays)`, each part with its first ray's index and
/// its rays.
fn chunks<'a, 'r, T>(
    rays: Rays<'r>,
    mut out: &'a mut [T],
    chunk_rays: usize,
) -> Vec<(usize, Rays<'r>, &'a mut [T])> {
    chunk_ranges(rays, chunk_rays)
        .into_iter()
        .map(|range| {
            let (chunk, rest) = std::mem::take(&mut out).split_at_mut(range.len());
            out = rest;
            (range.start, rays.slice(range), chunk)
        })
        .collect()
}

/// One pass of `trace` over `rays`, `chunk_rays` at a time, in the current pool.
pub fn pass<T: Send>(
    rays: Rays<'_>,
    out: &mut [T],
    chunk_rays: usize,
    trace: &(dyn Fn(Rays<'_>, &mut [T]) + Sync),
) {
    chunks(rays, out, chunk_rays)
        .into_par_iter()
        .for_each(|(_, rays, chunk)| trace(rays, chunk));
}

/// `rays` in `tracer`'s own layout for closest hits, staged chunk by chunk as `pass` cuts them,
/// in the current pool (`Kernel::stage_closest`); `None` when the tracer reads `Rays` as they are.
pub fn stage_closest<'t>(
    tracer: &'t dyn Tracer,
    rays: Rays<'_>,
) -> Option<Box<dyn StagedRays<Hit> + 't>> {
    tracer.stage_closest(rays, chunk_ranges(rays, tracer.chunk_rays()))
}

/// As `stage_closest`, for occlusion.
pub fn stage_occlusion<'t>(
    tracer: &'t dyn Tracer,
    rays: Rays<'_>,
) -> Option<Box<dyn StagedRays<bool> + 't>> {
    tracer.stage_occlusion(rays, chunk_ranges(rays, tracer.chunk_rays()))
}

/// One counting pass: each chunk counts into its own `Counters`, merged at the end; with
/// `per_ray`, each count also charged to its ray (`Counters::attributing`).
pub fn counted_pass<T: Send>(
    rays: Rays<'_>,
    out: &mut [T],
    chunk_rays: usize,
    per_ray: bool,
    trace: &(dyn Fn(Rays<'_>, &mut [T], &mut Counters) + Sync),
) -> Counters {
    let len = rays.len();
    let parts = chunks(rays, out, chunk_rays)
        .into_par_iter()
        .map(|(first, rays, chunk)| {
            let mut counters = chunk_counters(per_ray, rays.len());
            trace(rays, chunk, &mut counters);
            (first, counters)
        })
        .collect();
    gather(chunk_counters(per_ray, len), parts)
}

/// Counters for `rays` rays, attributing them when `per_ray`.
fn chunk_counters(per_ray: bool, rays: usize) -> Counters {
    match per_ray {
        true => Counters::attributing(rays),
        false => Counters::default(),
    }
}

/// `total` with every chunk's counters (first ray or point, counters) merged in, in order.
fn gather(mut total: Counters, parts: Vec<(usize, Counters)>) -> Counters {
    for (first, counters) in &parts {
        total.merge_at(counters, *first);
    }
    total
}

/// The chunks of a light-visibility query: whole packets of points, about `chunk_rays` rays
/// each, with their first point.
fn visibility_chunks<'a, 'q>(
    query: VisibilityQuery<'q>,
    mut out: &'a mut [u64],
    chunk_rays: usize,
) -> Vec<(usize, VisibilityQuery<'q>, &'a mut [u64])> {
    let words = query.samples.words_per_point();
    let points = chunk_rays.div_ceil(query.samples.per_point());
    packet_chunks(query.len(), query.packet_start, points)
        .into_iter()
        .map(|range| {
            let (chunk, rest) = std::mem::take(&mut out).split_at_mut(range.len() * words);
            out = rest;
            (range.start, query.slice(range), chunk)
        })
        .collect()
}

/// The shadow rays of `query` (`VisibilityQuery::rays`: point by point, sample by sample, one
/// explicit packet per packet of points) into `batch`, reusing its memory, generated in parallel
/// chunks of whole packets in the current pool: the query's rays made once for every tracer that
/// traces them as a batch. Each chunk counts its rays, then writes them in place
/// (`RayBatch::slots`).
pub fn query_rays(query: VisibilityQuery<'_>, batch: &mut RayBatch) {
    let chunks = packet_chunks(query.len(), query.packet_start, 1024);
    let (lens, timed): (Vec<usize>, Vec<bool>) = chunks
        .par_iter()
        .map(|range| {
            let chunk = query.slice(range.clone());
            (chunk.ray_count(), chunk.timed())
        })
        .unzip();
    let timed = timed.contains(&true);
    let slots = batch.slots(RayKind::SoftShadow, &lens, true, timed);
    chunks
        .into_par_iter()
        .zip(slots)
        .for_each(|(range, mut slots)| {
            let first = range.start as u32;
            query.slice(range).write_rays(&mut slots, first)
        });
}

/// One light-visibility pass, chunk by chunk, in the current pool; with `counters`, the counting
/// kernel, its per-chunk counters merged into them.
pub fn visibility_pass(
    tracer: &dyn Tracer,
    query: VisibilityQuery<'_>,
    out: &mut [u64],
    counters: Option<&mut Counters>,
) {
    let chunks = visibility_chunks(query, out, tracer.chunk_rays()).into_par_iter();
    match counters {
        None => chunks.for_each(|(_, q, o)| tracer.light_visibility(q, o)),
        Some(total) => {
            let per_ray = total.per_ray.is_some();
            let parts = chunks
                .map(|(first, q, o)| {
                    let mut counters = chunk_counters(per_ray, q.len());
                    tracer.light_visibility_counted(q, o, &mut counters);
                    (first, counters)
                })
                .collect();
            total.merge(&gather(chunk_counters(per_ray, query.len()), parts));
        }
    }
}

/// Closest hits of a whole batch.
pub fn trace_hits(tracer: &dyn Tracer, batch: &RayBatch) -> Vec<Hit> {
    let mut hits = vec![Hit::MISS; batch.len()];
    pass(batch.view(), &mut hits, tracer.chunk_rays(), &|r, h| {
        tracer.intersect(r, h)
    });
    hits
}

/// Occlusion flags of a whole batch.
pub fn trace_occlusion(tracer: &dyn Tracer, batch: &RayBatch) -> Vec<bool> {
    let mut flags = vec![false; batch.len()];
    pass(batch.view(), &mut flags, tracer.chunk_rays(), &|r, o| {
        tracer.occluded(r, o)
    });
    flags
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, RayKind};
    use glam::Vec3;

    fn batch(n: usize, packet_every: Option<usize>) -> RayBatch {
        let mut b = RayBatch::new(RayKind::Shadow);
        for i in 0..n {
            let ray = Ray::new(Vec3::ZERO, Vec3::X, 0.0, i as f32);
            match packet_every {
                Some(k) if i % k == 0 => b.push_packet_start(ray, i as u32),
                _ => b.push(ray, i as u32),
            }
        }
        b
    }

    #[test]
    fn uniform_chunks_are_chunk_rays_long() {
        let b = batch(2 * CHUNK_RAYS + 5, None);
        let lens: Vec<usize> = chunk_ranges(b.view(), CHUNK_RAYS)
            .iter()
            .map(|r| r.len())
            .collect();
        assert_eq!(lens, vec![CHUNK_RAYS, CHUNK_RAYS, 5]);
    }

    #[test]
    fn long_chunks_are_shortened_so_a_batch_makes_eight() {
        let lens = |n: usize, chunk_rays: usize| -> Vec<usize> {
            chunk_ranges(batch(n, None).view(), chunk_rays)
                .iter()
                .map(|r| r.len())
                .collect()
        };
        // A 65,536-ray wave asked in 65,536-ray chunks: 8 of 8192, not 1.
        assert_eq!(lens(65_536, 65_536), vec![8192; 8]);
        // A million rays keep the asked length; short batches keep CHUNK_RAYS.
        assert_eq!(lens(1 << 20, 65_536), vec![65_536; 16]);
        assert_eq!(lens(3 * CHUNK_RAYS, 65_536), vec![CHUNK_RAYS; 3]);
    }

    #[test]
    fn chunks_never_split_an_explicit_packet() {
        // Packets of 1000 rays: a chunk ends at the first packet start at or past 4096 rays.
        let b = batch(10_000, Some(1000));
        let ranges = chunk_ranges(b.view(), CHUNK_RAYS);
        assert_eq!(ranges, vec![0..5000, 5000..10_000]);
        // Every ray is traced exactly once, in its own slot.
        let mut out = vec![0.0f32; b.len()];
        pass(b.view(), &mut out, CHUNK_RAYS, &|r, o| {
            for (i, x) in o.iter_mut().enumerate() {
                *x = r.tmax[i];
            }
        });
        assert!(out.iter().enumerate().all(|(i, &t)| t == i as f32));
    }

    /// The query's rays made in parallel chunks, in place, over a batch holding other rays, are
    /// the rays of the serial `VisibilityQuery::rays`: order, packets, times and pixels.
    #[test]
    fn query_rays_are_the_serial_rays_in_place() {
        use crate::test_util::batch_fields;
        use crate::tracers::visibility::{LightSamples, QuadLight, ShadingPoint, ShadingPoints};
        let light = QuadLight {
            corner: Vec3::new(0.0, 4.0, 0.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
        };
        let uv = (0..32)
            .map(|i| [(i % 8) as f32 / 7.0, (i / 8) as f32 / 3.0])
            .collect();
        let samples = LightSamples::new(16, uv).unwrap();
        let mut points = ShadingPoints::default();
        // 5000 points (five chunks): every seventh faces away (no rays), every third starts a
        // packet, the later ones at a time of their own.
        for i in 0..5000 {
            let position = Vec3::new(i as f32 * 1e-3, 0.0, 1.0);
            let point = ShadingPoint {
                position,
                normal: if i % 7 == 0 { -Vec3::Y } else { Vec3::Y },
                origin: position + Vec3::Y * 1e-4,
                time: if i > 2500 { 0.25 } else { 0.0 },
                set: i % 2,
            };
            points.push(point, i % 3 == 0);
        }
        let query = VisibilityQuery::new(&points, light, &samples).unwrap();
        let mut serial = RayBatch::default();
        query.rays(&mut serial, &mut Vec::new());
        let mut parallel = batch(100_000, Some(5));
        query_rays(query, &mut parallel);
        assert_eq!(serial.len(), query.ray_count());
        assert!(!serial.time.is_empty() && serial.len() < 5000 * 16);
        assert_eq!(batch_fields(&parallel), batch_fields(&serial));
        // A query at time 0 only: no ray times, though the batch had none to drop either.
        let early = query.slice(0..2000);
        early.rays(&mut serial, &mut Vec::new());
        query_rays(early, &mut parallel);
        assert!(parallel.time.is_empty());
        assert_eq!(batch_fields(&parallel), batch_fields(&serial));
    }
}
