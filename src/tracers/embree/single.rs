//! `embree3-1`, `embree4-1`: one `rtcIntersect1` / `rtcOccluded1` call per ray, each ray staged
//! in its own record.

use std::ops::Range;

use super::record::RayRecord;
use super::Submission;
use crate::accel::embree::ffi::{RTCRay, RTCRayHit};
use crate::accel::embree::{EmbreeApi, EmbreeScene, Padded};
use crate::geometry::{Hit, Rays};

pub struct Single;

impl<A: EmbreeApi> Submission<A> for Single {
    type Hits = Padded<RTCRayHit>;
    type Shadows = Padded<RTCRay>;

    fn calls(rays: Rays<'_>) -> impl Iterator<Item = Range<usize>> + '_ {
        (0..rays.len()).map(|i| i..i + 1)
    }

    #[inline(always)]
    fn stage_hits(rays: &Rays<'_>, call: Range<usize>) -> Padded<RTCRayHit> {
        Padded::new(RTCRayHit::from_rays(rays, call.start))
    }

    #[inline(always)]
    fn stage_shadows(rays: &Rays<'_>, call: Range<usize>) -> Padded<RTCRay> {
        Padded::new(RTCRay::from_rays(rays, call.start))
    }

    #[inline(always)]
    fn intersect(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut Padded<RTCRayHit>,
        hits: &mut [Hit],
    ) {
        trace1::<A, RTCRayHit>(scene, args, record, hits)
    }

    #[inline(always)]
    fn occluded(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut Padded<RTCRay>,
        occluded: &mut [bool],
    ) {
        trace1::<A, RTCRay>(scene, args, record, occluded)
    }
}

#[inline(always)]
fn trace1<A: EmbreeApi, R: RayRecord>(
    scene: &EmbreeScene<A>,
    args: &mut A::Arguments,
    record: &mut Padded<R>,
    answer: &mut [R::Answer],
) {
    // SAFETY: a committed scene, valid arguments, a padded record.
    unsafe { R::trace1::<A>(record.as_mut_ptr(), scene.raw(), args) };
    answer[0] = record.record.answer();
}
