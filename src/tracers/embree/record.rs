//! The two single-ray records Embree traces — `RTCRayHit` for intersect, `RTCRay` for occluded —
//! behind one trait, so the single-ray tracers and Embree 3's streams each have one loop for both
//! queries.

use std::mem::size_of;

use super::convert;
use crate::accel::embree::ffi::{self, RTCIntersectContext, RTCRay, RTCRayHit, RTCScene};
use crate::accel::embree::EmbreeApi;
use crate::geometry::{Hit, Rays};

/// A single-ray Embree record, the calls that trace it and what it answers.
pub trait RayRecord: Sized {
    /// Per ray: the `Hit` (intersect) or whether the ray is blocked (occluded).
    type Answer;
    fn from_rays(rays: &Rays<'_>, i: usize) -> Self;
    fn answer(&self) -> Self::Answer;
    /// `rtcIntersect1` / `rtcOccluded1` of Embree `A`.
    ///
    /// # Safety
    /// `scene` is committed, `args` valid, and `record` points to a `Padded` record (the record
    /// types carry Embree's alignment).
    unsafe fn trace1<A: EmbreeApi>(record: *mut Self, scene: RTCScene, args: &mut A::Arguments);
    /// Embree 3's `rtcIntersect1M` / `rtcOccluded1M` over `records`, `size_of::<Self>()` bytes
    /// apart.
    ///
    /// # Safety
    /// As `trace1`, and `records.len()` fits in a u32.
    unsafe fn trace1m(records: &mut [Self], scene: RTCScene, context: &mut RTCIntersectContext);
}

impl RayRecord for RTCRayHit {
    type Answer = Hit;

    #[inline(always)]
    fn from_rays(rays: &Rays<'_>, i: usize) -> Self {
        convert::ray_hit(rays, i)
    }

    #[inline(always)]
    fn answer(&self) -> Hit {
        let h = &self.hit;
        convert::hit(self.ray.tfar, h.geomID, h.primID, h.u, h.v)
    }

    #[inline(always)]
    unsafe fn trace1<A: EmbreeApi>(record: *mut Self, scene: RTCScene, args: &mut A::Arguments) {
        A::intersect1(scene, args, record)
    }

    #[inline(always)]
    unsafe fn trace1m(records: &mut [Self], scene: RTCScene, context: &mut RTCIntersectContext) {
        let count = records.len() as u32;
        ffi::rtcIntersect1M(
            scene,
            context,
            records.as_mut_ptr(),
            count,
            size_of::<Self>(),
        )
    }
}

impl RayRecord for RTCRay {
    type Answer = bool;

    #[inline(always)]
    fn from_rays(rays: &Rays<'_>, i: usize) -> Self {
        convert::ray(rays, i)
    }

    #[inline(always)]
    fn answer(&self) -> bool {
        convert::is_occluded(self.tfar)
    }

    #[inline(always)]
    unsafe fn trace1<A: EmbreeApi>(record: *mut Self, scene: RTCScene, args: &mut A::Arguments) {
        A::occluded1(scene, args, record)
    }

    #[inline(always)]
    unsafe fn trace1m(records: &mut [Self], scene: RTCScene, context: &mut RTCIntersectContext) {
        let count = records.len() as u32;
        ffi::rtcOccluded1M(
            scene,
            context,
            records.as_mut_ptr(),
            count,
            size_of::<Self>(),
        )
    }
}
