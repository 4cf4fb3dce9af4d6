//! `embree-stream`: the AoS stream calls `rtcIntersect1M` / `rtcOccluded1M`.
//!
//! The chunk goes to Embree in streams of at most `STREAM_LENGTH` rays, converted into a
//! per-thread buffer. Embree 3 itself works through a stream in blocks of at most 64 rays
//! (`RayStreamFilter::filterAOS`: MAX_INTERNAL_STREAM_SIZE for coherent contexts, one SIMD packet
//! at a time otherwise), so this traces exactly as one call over the whole chunk would, while
//! the buffer stays in cache instead of growing with the chunk.

use std::cell::RefCell;
use std::mem::size_of;

use super::ffi::{self, RTCIntersectContext, RTCRay, RTCRayHit};
use super::{convert, EmbreeScene, Submission};
use crate::geometry::{Hit, Rays};

/// Rays per stream call: 4096 × 80 bytes of RTCRayHit = 320 KiB, within L2.
pub const STREAM_LENGTH: usize = 4096;

thread_local! {
    static RAY_HITS: RefCell<Vec<RTCRayHit>> = const { RefCell::new(Vec::new()) };
    static RAYS: RefCell<Vec<RTCRay>> = const { RefCell::new(Vec::new()) };
}

pub struct Stream;

impl Submission for Stream {
    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        hits: &mut [Hit],
    ) {
        RAY_HITS.with_borrow_mut(|stream| {
            for (c, hits) in hits.chunks_mut(STREAM_LENGTH).enumerate() {
                let first = c * STREAM_LENGTH;
                stream.clear();
                stream.extend((first..first + hits.len()).map(|i| convert::ray_hit(&rays, i)));
                // SAFETY: a committed scene, a valid context, and `stream.len()` (≤ STREAM_LENGTH,
                // fits in u32) 16-byte aligned RTCRayHit records `size_of::<RTCRayHit>()` apart.
                unsafe {
                    ffi::rtcIntersect1M(
                        scene.raw(),
                        context,
                        stream.as_mut_ptr(),
                        stream.len() as u32,
                        size_of::<RTCRayHit>(),
                    )
                };
                for (hit, rh) in hits.iter_mut().zip(stream.iter()) {
                    *hit = convert::hit(
                        rh.ray.tfar,
                        rh.hit.geomID,
                        rh.hit.primID,
                        rh.hit.u,
                        rh.hit.v,
                    );
                }
            }
        });
    }

    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        occluded: &mut [bool],
    ) {
        RAYS.with_borrow_mut(|stream| {
            for (c, occluded) in occluded.chunks_mut(STREAM_LENGTH).enumerate() {
                let first = c * STREAM_LENGTH;
                stream.clear();
                stream.extend((first..first + occluded.len()).map(|i| convert::ray(&rays, i)));
                // SAFETY: as above, with RTCRay records.
                unsafe {
                    ffi::rtcOccluded1M(
                        scene.raw(),
                        context,
                        stream.as_mut_ptr(),
                        stream.len() as u32,
                        size_of::<RTCRay>(),
                    )
                };
                for (o, ray) in occluded.iter_mut().zip(stream.iter()) {
                    *o = convert::is_occluded(ray.tfar);
                }
            }
        });
    }
}
