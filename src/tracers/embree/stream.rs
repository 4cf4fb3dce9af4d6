//! `embree3-stream`: Embree 3's AoS stream calls `rtcIntersect1M` / `rtcOccluded1M` (Embree 4
//! has no stream API).
//!
//! The chunk goes to Embree in streams of at most `STREAM_LENGTH` rays, each staged in its own
//! buffer. Embree 3 itself works through a stream in blocks of at most 64 rays
//! (`RayStreamFilter::filterAOS`: MAX_INTERNAL_STREAM_SIZE for coherent contexts, one SIMD packet
//! at a time otherwise), so this traces exactly as one call over the whole chunk would, while
//! a stream stays in cache instead of growing with the chunk.

use std::ops::Range;

use super::record::RayRecord;
use super::Submission;
use crate::accel::embree::ffi::{RTCIntersectContext, RTCRay, RTCRayHit};
use crate::accel::embree::{Embree3, EmbreeScene};
use crate::geometry::{Hit, Rays};

/// Rays per stream call: 4096 × 80 bytes of RTCRayHit = 320 KiB, within L2.
pub const STREAM_LENGTH: usize = 4096;

pub struct Stream;

impl Submission<Embree3> for Stream {
    type Hits = Vec<RTCRayHit>;
    type Shadows = Vec<RTCRay>;

    /// Streams ignore explicit packets: Embree regroups a stream itself.
    fn calls(rays: Rays<'_>) -> impl Iterator<Item = Range<usize>> + '_ {
        let len = rays.len();
        (0..len)
            .step_by(STREAM_LENGTH)
            .map(move |start| start..(start + STREAM_LENGTH).min(len))
    }

    fn stage_hits(rays: &Rays<'_>, call: Range<usize>) -> Vec<RTCRayHit> {
        stage(rays, call)
    }

    fn stage_shadows(rays: &Rays<'_>, call: Range<usize>) -> Vec<RTCRay> {
        stage(rays, call)
    }

    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        stream: &mut Vec<RTCRayHit>,
        hits: &mut [Hit],
    ) {
        trace1m(scene, context, stream, hits)
    }

    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        stream: &mut Vec<RTCRay>,
        occluded: &mut [bool],
    ) {
        trace1m(scene, context, stream, occluded)
    }
}

fn stage<R: RayRecord>(rays: &Rays<'_>, call: Range<usize>) -> Vec<R> {
    call.map(|i| R::from_rays(rays, i)).collect()
}

fn trace1m<R: RayRecord>(
    scene: &EmbreeScene,
    context: &mut RTCIntersectContext,
    stream: &mut [R],
    answers: &mut [R::Answer],
) {
    // SAFETY: a committed scene, a valid context, and at most STREAM_LENGTH records.
    unsafe { R::trace1m(stream, scene.raw(), context) };
    for (answer, record) in answers.iter_mut().zip(stream.iter()) {
        *answer = record.answer();
    }
}
