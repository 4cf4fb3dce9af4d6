//! `embree3-4/8/16`, `embree4-4/8/16`: `rtcIntersectN` / `rtcOccludedN` on consecutive groups of
//! N rays of the chunk (never across an explicit packet boundary, `Rays::packets`), each staged
//! in its own `RTCRayHitN` / `RTCRayN`; a partial group masks its missing lanes off. One implementation over the packet type and the Embree
//! version; the three bindgen structs only supply their lanes and their calls.

use std::marker::PhantomData;
use std::ops::Range;

use super::{convert, Submission};
use crate::accel::embree::ffi::{self, RTCRay, RTCScene, RTC_INVALID_GEOMETRY_ID};
use crate::accel::embree::{EmbreeApi, EmbreeScene, Padded};
use crate::geometry::{Hit, Rays};

/// An Embree ray packet (`RTCRayN`): N lanes of rays, traced by `rtcOccludedN`.
pub trait RayPacket: Sized {
    const WIDTH: usize;
    /// All lanes zero (a valid value: the struct is only floats and integers).
    fn zeroed() -> Self;
    fn set_ray(&mut self, lane: usize, ray: &RTCRay);
    fn tfar(&self, lane: usize) -> f32;
    /// # Safety
    /// `valid` points to `WIDTH` ints, `scene` is committed, `self` is aligned as Embree requires.
    unsafe fn occluded<A: EmbreeApi>(
        &mut self,
        valid: *const i32,
        scene: RTCScene,
        args: &mut A::Arguments,
    );
}

/// An Embree ray-and-hit packet (`RTCRayHitN`), traced by `rtcIntersectN`.
pub trait RayHitPacket: Sized {
    type Rays: RayPacket;
    fn zeroed() -> Self;
    fn rays(&mut self) -> &mut Self::Rays;
    /// Marks lane `lane` as not yet hit, as rtcIntersectN requires.
    fn clear_hit(&mut self, lane: usize);
    fn hit(&self, lane: usize) -> Hit;
    /// # Safety
    /// As `RayPacket::occluded`, with `packet` pointing to a `Padded` packet.
    unsafe fn intersect<A: EmbreeApi>(
        packet: *mut Self,
        valid: *const i32,
        scene: RTCScene,
        args: &mut A::Arguments,
    );
}

macro_rules! embree_packet {
    ($width:literal, $ray:ident, $ray_hit:ident, $occluded:ident, $intersect:ident) => {
        impl RayPacket for ffi::$ray {
            const WIDTH: usize = $width;
            fn zeroed() -> Self {
                // SAFETY: a C struct of f32 and u32 arrays: all zero bits is a valid value.
                unsafe { std::mem::zeroed() }
            }
            #[inline(always)]
            fn set_ray(&mut self, lane: usize, r: &RTCRay) {
                self.org_x[lane] = r.org_x;
                self.org_y[lane] = r.org_y;
                self.org_z[lane] = r.org_z;
                self.tnear[lane] = r.tnear;
                self.dir_x[lane] = r.dir_x;
                self.dir_y[lane] = r.dir_y;
                self.dir_z[lane] = r.dir_z;
                self.time[lane] = r.time;
                self.tfar[lane] = r.tfar;
                self.mask[lane] = r.mask;
                self.id[lane] = r.id;
                self.flags[lane] = r.flags;
            }
            #[inline(always)]
            fn tfar(&self, lane: usize) -> f32 {
                self.tfar[lane]
            }
            #[inline(always)]
            unsafe fn occluded<A: EmbreeApi>(
                &mut self,
                valid: *const i32,
                scene: RTCScene,
                args: &mut A::Arguments,
            ) {
                // SAFETY: the caller's contract.
                unsafe { A::$occluded(valid, scene, args, self) }
            }
        }

        impl RayHitPacket for ffi::$ray_hit {
            type Rays = ffi::$ray;
            fn zeroed() -> Self {
                // SAFETY: as for the ray packet.
                unsafe { std::mem::zeroed() }
            }
            #[inline(always)]
            fn rays(&mut self) -> &mut ffi::$ray {
                &mut self.ray
            }
            #[inline(always)]
            fn clear_hit(&mut self, lane: usize) {
                self.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
                self.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
            }
            #[inline(always)]
            fn hit(&self, lane: usize) -> Hit {
                let h = &self.hit;
                convert::hit(
                    self.ray.tfar[lane],
                    h.geomID[lane],
                    h.primID[lane],
                    h.u[lane],
                    h.v[lane],
                )
            }
            #[inline(always)]
            unsafe fn intersect<A: EmbreeApi>(
                packet: *mut Self,
                valid: *const i32,
                scene: RTCScene,
                args: &mut A::Arguments,
            ) {
                // SAFETY: the caller's contract.
                unsafe { A::$intersect(valid, scene, args, packet) }
            }
        }
    };
}

embree_packet!(4, RTCRay4, RTCRayHit4, occluded4, intersect4);
embree_packet!(8, RTCRay8, RTCRayHit8, occluded8, intersect8);
embree_packet!(16, RTCRay16, RTCRayHit16, occluded16, intersect16);

/// Embree's valid mask: −1 for an active lane, 0 for an inactive one; room and alignment for the
/// widest packet.
#[repr(C, align(64))]
struct ValidMask([i32; 16]);

impl ValidMask {
    /// The first `active` lanes on.
    #[inline(always)]
    fn first(active: usize) -> Self {
        ValidMask(std::array::from_fn(
            |lane| if lane < active { -1 } else { 0 },
        ))
    }
}

/// Rays in packets of `P`'s width.
pub struct Packets<P>(PhantomData<fn() -> P>);

impl<A: EmbreeApi, P: RayHitPacket + Send + 'static> Submission<A> for Packets<P>
where
    P::Rays: Send,
{
    type Hits = Padded<P>;
    type Shadows = P::Rays;

    fn calls(rays: Rays<'_>) -> impl Iterator<Item = Range<usize>> + '_ {
        rays.packets(P::Rays::WIDTH)
    }

    #[inline(always)]
    fn stage_hits(rays: &Rays<'_>, call: Range<usize>) -> Padded<P> {
        let mut packet = Padded::new(P::zeroed());
        for (lane, i) in call.enumerate() {
            packet.record.rays().set_ray(lane, &convert::ray(rays, i));
            packet.record.clear_hit(lane);
        }
        packet
    }

    #[inline(always)]
    fn stage_shadows(rays: &Rays<'_>, call: Range<usize>) -> P::Rays {
        let mut packet = P::Rays::zeroed();
        for (lane, i) in call.enumerate() {
            packet.set_ray(lane, &convert::ray(rays, i));
        }
        packet
    }

    #[inline(always)]
    fn intersect(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        packet: &mut Padded<P>,
        hits: &mut [Hit],
    ) {
        let valid = ValidMask::first(hits.len());
        // SAFETY: WIDTH valid ints, a committed scene, a padded packet aligned by its type.
        unsafe { P::intersect::<A>(packet.as_mut_ptr(), valid.0.as_ptr(), scene.raw(), args) };
        for (lane, hit) in hits.iter_mut().enumerate() {
            *hit = packet.record.hit(lane);
        }
    }

    #[inline(always)]
    fn occluded(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        packet: &mut P::Rays,
        occluded: &mut [bool],
    ) {
        let valid = ValidMask::first(occluded.len());
        // SAFETY: as above.
        unsafe { packet.occluded::<A>(valid.0.as_ptr(), scene.raw(), args) };
        for (lane, o) in occluded.iter_mut().enumerate() {
            *o = convert::is_occluded(packet.tfar(lane));
        }
    }
}

/// The packet types the registry names.
pub type Packets4 = Packets<ffi::RTCRayHit4>;
pub type Packets8 = Packets<ffi::RTCRayHit8>;
pub type Packets16 = Packets<ffi::RTCRayHit16>;
