//! `embree3-4/8/16`, `embree4-4/8/16`: `rtcIntersectN` / `rtcOccludedN` on consecutive groups of
//! N rays of the chunk (never across an explicit packet boundary, `Rays::packets`), each staged
//! in its own `RTCRayHitN`; a partial group masks its missing lanes off. One implementation over
//! the packet type and the Embree version; the three bindgen structs only supply their lanes and
//! their calls.
//!
//! **Occlusion where packets are not native.** `rtcOccludedN` takes an `RTCRayN`, but where the
//! device's ISA has no native N-wide packets (16 below AVX-512, 8 below AVX) Embree 4 traces the
//! lanes one by one through the packet cast to a `RayHitN`, reading and writing every hit field of
//! each lane: up to 1,344 − 768 bytes past a bare `RTCRay16` (Embree 4.4's `rtcOccluded16` on an
//! AVX2 machine, which crashed the default run). There the call is given a copy of the rays in a
//! padded `RTCRayHitN` (a copy inside the clock, beside a fallback that traces 16 single rays).
//! Where the packets are native the staged `RTCRayN` is handed over as it is: staging every
//! occlusion packet as a ray-and-hit record was tried, and made `embree3-16`'s shadow rays 1.4–1.5×
//! slower on AVX-512 (conference and Šibenik, 1024², 1 thread), a weaker baseline. `guard_tests`
//! calls every entry point with its record flush against a protected page, at the machine's ISA
//! and lower ones.

use std::marker::PhantomData;
use std::ops::Range;

use super::{convert, Submission};
use crate::accel::embree::ffi::{self, RTCRay, RTCScene, RTC_INVALID_GEOMETRY_ID};
use crate::accel::embree::{EmbreeApi, EmbreeScene, Padded};
use crate::geometry::{Hit, Rays};

/// An Embree ray packet (`RTCRayN`): N lanes of rays, traced by `rtcOccludedN` (as the ray part
/// of an `RTCRayHitN`).
pub trait RayPacket: Sized + Copy {
    const WIDTH: usize;
    /// All lanes zero (a valid value: the struct is only floats and integers).
    fn zeroed() -> Self;
    fn set_ray(&mut self, lane: usize, ray: &RTCRay);
    fn tfar(&self, lane: usize) -> f32;
    /// # Safety
    /// `valid` points to `WIDTH` ints, `scene` is committed, `packet` is aligned as Embree
    /// requires, and is the start of a `Padded` ray-and-hit packet unless the scene's device runs
    /// packets of `WIDTH` natively (see the module's notes).
    unsafe fn occluded<A: EmbreeApi>(
        packet: *mut Self,
        valid: *const i32,
        scene: RTCScene,
        args: &mut A::Arguments,
    );
}

/// An Embree ray-and-hit packet (`RTCRayHitN`), traced by `rtcIntersectN`.
pub trait RayHitPacket: Sized {
    type Rays: RayPacket;
    /// All lanes zero (a valid value: the struct is only floats and integers).
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
                packet: *mut Self,
                valid: *const i32,
                scene: RTCScene,
                args: &mut A::Arguments,
            ) {
                // SAFETY: the caller's contract.
                unsafe { A::$occluded(valid, scene, args, packet) }
            }
        }

        impl RayHitPacket for ffi::$ray_hit {
            type Rays = ffi::$ray;
            fn zeroed() -> Self {
                // SAFETY: a C struct of f32 and u32 arrays: all zero bits is a valid value.
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
        if scene.native_packets(P::Rays::WIDTH) {
            // SAFETY: WIDTH valid ints, a committed scene, a packet aligned by its type, traced
            // natively (the module's notes).
            unsafe { P::Rays::occluded::<A>(packet, valid.0.as_ptr(), scene.raw(), args) };
        } else {
            let mut padded = Padded::new(P::zeroed());
            *padded.record.rays() = *packet;
            // SAFETY: as above, the rays being the first field of the padded ray-and-hit packet
            // (`repr(C)`), whose pointer carries the whole record's provenance.
            unsafe {
                P::Rays::occluded::<A>(
                    padded.as_mut_ptr().cast(),
                    valid.0.as_ptr(),
                    scene.raw(),
                    args,
                )
            };
            *packet = *padded.record.rays();
        }
        for (lane, o) in occluded.iter_mut().enumerate() {
            *o = convert::is_occluded(packet.tfar(lane));
        }
    }
}

/// The packet types the registry names.
pub type Packets4 = Packets<ffi::RTCRayHit4>;
pub type Packets8 = Packets<ffi::RTCRayHit8>;
pub type Packets16 = Packets<ffi::RTCRayHit16>;
