//! `embree3-1`, `embree4-1`: one `rtcIntersect1` / `rtcOccluded1` call per ray.

use super::record::RayRecord;
use super::Submission;
use crate::accel::embree::ffi::{RTCRay, RTCRayHit};
use crate::accel::embree::{EmbreeApi, EmbreeScene, Padded};
use crate::geometry::{Hit, Rays};

pub struct Single;

impl<A: EmbreeApi> Submission<A> for Single {
    fn intersect(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        rays: Rays<'_>,
        hits: &mut [Hit],
    ) {
        trace_one_by_one::<A, RTCRayHit>(scene, args, rays, hits);
    }

    fn occluded(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        rays: Rays<'_>,
        occluded: &mut [bool],
    ) {
        trace_one_by_one::<A, RTCRay>(scene, args, rays, occluded);
    }
}

fn trace_one_by_one<A: EmbreeApi, R: RayRecord>(
    scene: &EmbreeScene<A>,
    args: &mut A::Arguments,
    rays: Rays<'_>,
    answers: &mut [R::Answer],
) {
    for (i, answer) in answers.iter_mut().enumerate() {
        let mut record = Padded::new(R::from_rays(&rays, i));
        // SAFETY: a committed scene, valid arguments, a padded record.
        unsafe { R::trace1::<A>(record.as_mut_ptr(), scene.raw(), args) };
        *answer = record.record.answer();
    }
}
