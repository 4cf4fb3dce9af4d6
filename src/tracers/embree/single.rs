//! `embree1`: one `rtcIntersect1` / `rtcOccluded1` call per ray.

use super::record::RayRecord;
use super::Submission;
use crate::accel::embree::ffi::{RTCIntersectContext, RTCRay, RTCRayHit};
use crate::accel::embree::EmbreeScene;
use crate::geometry::{Hit, Rays};

pub struct Single;

impl Submission for Single {
    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        hits: &mut [Hit],
    ) {
        trace_one_by_one::<RTCRayHit>(scene, context, rays, hits);
    }

    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        occluded: &mut [bool],
    ) {
        trace_one_by_one::<RTCRay>(scene, context, rays, occluded);
    }
}

fn trace_one_by_one<R: RayRecord>(
    scene: &EmbreeScene,
    context: &mut RTCIntersectContext,
    rays: Rays<'_>,
    answers: &mut [R::Answer],
) {
    for (i, answer) in answers.iter_mut().enumerate() {
        let mut record = R::from_rays(&rays, i);
        // SAFETY: a committed scene and a valid context.
        unsafe { record.trace1(scene.raw(), context) };
        *answer = record.answer();
    }
}
