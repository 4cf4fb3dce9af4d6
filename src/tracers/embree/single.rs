//! `embree1`: one `rtcIntersect1` / `rtcOccluded1` call per ray.

use super::ffi::{self, RTCIntersectContext};
use super::{convert, EmbreeScene, Submission};
use crate::geometry::{Hit, Rays};

pub struct Single;

impl Submission for Single {
    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        hits: &mut [Hit],
    ) {
        for (i, hit) in hits.iter_mut().enumerate() {
            let mut rh = convert::ray_hit(&rays, i);
            // SAFETY: a committed scene, a valid context and a 16-byte aligned RTCRayHit.
            unsafe { ffi::rtcIntersect1(scene.raw(), context, &mut rh) };
            *hit = convert::hit(
                rh.ray.tfar,
                rh.hit.geomID,
                rh.hit.primID,
                rh.hit.u,
                rh.hit.v,
            );
        }
    }

    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        occluded: &mut [bool],
    ) {
        for (i, o) in occluded.iter_mut().enumerate() {
            let mut ray = convert::ray(&rays, i);
            // SAFETY: as above, with an RTCRay.
            unsafe { ffi::rtcOccluded1(scene.raw(), context, &mut ray) };
            *o = convert::is_occluded(ray.tfar);
        }
    }
}
