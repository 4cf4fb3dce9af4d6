//! `embree3-stream`: Embree 3's AoS stream calls `rtcIntersect1M` / `rtcOccluded1M` (Embree 4
//! has no stream API).
//!
//! The chunk goes to Embree in streams of at most `STREAM_LENGTH` rays, converted into a
//! per-thread buffer. Embree 3 itself works through a stream in blocks of at most 64 rays
//! (`RayStreamFilter::filterAOS`: MAX_INTERNAL_STREAM_SIZE for coherent contexts, one SIMD packet
//! at a time otherwise), so this traces exactly as one call over the whole chunk would, while
//! the buffer stays in cache instead of growing with the chunk.

use std::cell::RefCell;
use std::thread::LocalKey;

use super::record::RayRecord;
use super::Submission;
use crate::accel::embree::ffi::{RTCIntersectContext, RTCRay, RTCRayHit};
use crate::accel::embree::{Embree3, EmbreeScene};
use crate::geometry::{Hit, Rays};

/// Rays per stream call: 4096 × 80 bytes of RTCRayHit = 320 KiB, within L2.
pub const STREAM_LENGTH: usize = 4096;

thread_local! {
    static RAY_HITS: RefCell<Vec<RTCRayHit>> = const { RefCell::new(Vec::new()) };
    static RAYS: RefCell<Vec<RTCRay>> = const { RefCell::new(Vec::new()) };
}

/// A record type with its per-thread stream buffer.
trait Buffered: RayRecord + 'static {
    fn buffer() -> &'static LocalKey<RefCell<Vec<Self>>>;
}

impl Buffered for RTCRayHit {
    fn buffer() -> &'static LocalKey<RefCell<Vec<Self>>> {
        &RAY_HITS
    }
}

impl Buffered for RTCRay {
    fn buffer() -> &'static LocalKey<RefCell<Vec<Self>>> {
        &RAYS
    }
}

pub struct Stream;

impl Submission<Embree3> for Stream {
    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        hits: &mut [Hit],
    ) {
        trace_in_streams::<RTCRayHit>(scene, context, rays, hits);
    }

    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        occluded: &mut [bool],
    ) {
        trace_in_streams::<RTCRay>(scene, context, rays, occluded);
    }
}

fn trace_in_streams<R: Buffered>(
    scene: &EmbreeScene,
    context: &mut RTCIntersectContext,
    rays: Rays<'_>,
    answers: &mut [R::Answer],
) {
    R::buffer().with_borrow_mut(|stream| {
        for (c, answers) in answers.chunks_mut(STREAM_LENGTH).enumerate() {
            let first = c * STREAM_LENGTH;
            stream.clear();
            stream.extend((first..first + answers.len()).map(|i| R::from_rays(&rays, i)));
            // SAFETY: a committed scene, a valid context, and at most STREAM_LENGTH records.
            unsafe { R::trace1m(stream, scene.raw(), context) };
            for (answer, record) in answers.iter_mut().zip(stream.iter()) {
                *answer = record.answer();
            }
        }
    });
}
