//! Our rays and hits to and from Embree's: tnear/tfar from tmin/tmax (ill-formed rays disabled), every mask bit set (ray
//! masks are compiled into the Debian library, so a zero mask would miss everything), the ray's time
//! (motion blur; 0 without a time lane);
//! back, tfar is the hit distance, primID our triangle index, and (u, v) already our convention
//! (`Triangle::point(u, v)`).

use crate::accel::embree::ffi::{RTCHit, RTCRay, RTCRayHit, RTC_INVALID_GEOMETRY_ID};
use crate::geometry::{Hit, Rays, LARGEST_COORDINATE};

/// Every ray sees every geometry.
pub const ALL_MASK_BITS: u32 = u32::MAX;

/// What Embree is handed for a ray that is not well formed (`Ray::is_well_formed`), or that it
/// would reject: a valid ray with an empty interval (tnear > tfar ≥ 0), which hits nothing and
/// is not occluded — raylab's defined answer for such rays.
const DISABLED: RTCRay = RTCRay {
    org_x: 0.0,
    org_y: 0.0,
    org_z: 0.0,
    tnear: 1.0,
    dir_x: 1.0,
    dir_y: 0.0,
    dir_z: 0.0,
    time: 0.0,
    tfar: 0.0,
    mask: ALL_MASK_BITS,
    id: 0,
    flags: 0,
};

#[inline(always)]
pub fn ray(rays: &Rays<'_>, i: usize) -> RTCRay {
    let r = rays.ray(i);
    let in_range = r.origin.abs().max(r.dir.abs()).max_element() <= LARGEST_COORDINATE;
    if !(r.is_well_formed() && in_range) {
        return DISABLED;
    }
    RTCRay {
        org_x: rays.ox[i],
        org_y: rays.oy[i],
        org_z: rays.oz[i],
        tnear: rays.tmin[i],
        dir_x: rays.dx[i],
        dir_y: rays.dy[i],
        dir_z: rays.dz[i],
        time: rays.time(i),
        tfar: rays.tmax[i],
        mask: ALL_MASK_BITS,
        id: 0,
        flags: 0,
    }
}

/// A ray with its hit cleared, as rtcIntersect* requires (geomID = RTC_INVALID_GEOMETRY_ID).
#[inline(always)]
pub fn ray_hit(rays: &Rays<'_>, i: usize) -> RTCRayHit {
    RTCRayHit {
        ray: ray(rays, i),
        hit: RTCHit {
            geomID: RTC_INVALID_GEOMETRY_ID,
            instID: [RTC_INVALID_GEOMETRY_ID],
            ..RTCHit::default()
        },
    }
}

/// The hit of a traced ray from its final tfar and hit record fields.
#[inline(always)]
pub fn hit(tfar: f32, geom_id: u32, prim_id: u32, u: f32, v: f32) -> Hit {
    if geom_id == RTC_INVALID_GEOMETRY_ID {
        Hit::MISS
    } else {
        Hit {
            t: tfar,
            prim: prim_id,
            u,
            v,
        }
    }
}

/// rtcOccluded* marks an occluded ray by setting its tfar to −∞.
#[inline(always)]
pub fn is_occluded(tfar: f32) -> bool {
    tfar == f32::NEG_INFINITY
}
