//! Every Embree entry point raylab calls — `rtcIntersect1/4/8/16`, `rtcOccluded1/4/8/16` of
//! Embree 3 and 4 and Embree 3's `rtcIntersect1M` / `rtcOccluded1M` — with the record raylab
//! stages for it flush against a protected page (ending at one, and starting after one), in a
//! coherent and an incoherent context, on a device of the machine's ISA and on devices forced to
//! lower ones (`isa=avx2` where the CPU has AVX-512, `isa=sse4.2`), where Embree takes the
//! fallbacks of the packet widths that ISA lacks. A library read or write past the record faults
//! here (`guard_page`); the answers are checked too.

use std::sync::Arc;

use glam::Vec3;

use super::record::RayRecord;
use super::{Packets16, Packets4, Packets8, Single, Submission};
use crate::accel::embree::ffi::{self, RTCDeviceProperty::*};
use crate::accel::embree::test_isas;
use crate::accel::embree::{Device, Embree3, EmbreeApi, EmbreeConfig, EmbreeScene};
use crate::geometry::{Hit, Ray, RayBatch, RayKind, Rays, Triangle};
use crate::guard_page::{self, Guarded, Placement};
use crate::scene::Mesh;

/// The unit square in the plane z = 0, as two triangles: 0 below the diagonal x = y, 1 above.
fn square() -> Mesh {
    let mut mesh = Mesh::default();
    mesh.push(
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)),
        0,
    );
    mesh.push(
        Triangle::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y),
        0,
    );
    mesh
}

/// 21 rays straight down from z = 1 over a 7 × 3 grid, part of it off the square, so a 16-wide
/// call is followed by a partial one (5 lanes on), an 8-wide one by two and a partial one. Every
/// third ray ends at t = 0.5, above the square: it neither hits nor is blocked.
fn rays() -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Shadow);
    for i in 0..21 {
        let (x, y) = (-0.45 + 0.3 * (i % 7) as f32, 0.15 + 0.3 * (i / 7) as f32);
        let far = if i % 3 == 2 { 0.5 } else { f32::INFINITY };
        batch.push(Ray::new(Vec3::new(x, y, 1.0), Vec3::NEG_Z, 0.0, far), i);
    }
    batch
}

/// The triangle ray `i` of `rays` hits, if any.
fn expected(rays: &Rays<'_>, i: usize) -> Option<u32> {
    let r = rays.ray(i);
    let on_square = (0.0..=1.0).contains(&r.origin.x) && (0.0..=1.0).contains(&r.origin.y);
    (on_square && r.tmax > 1.0).then_some(if r.origin.x > r.origin.y { 0 } else { 1 })
}

fn check_hits(what: &str, rays: &Rays<'_>, call: std::ops::Range<usize>, hits: &[Hit]) {
    for (i, hit) in call.zip(hits) {
        match expected(rays, i) {
            Some(prim) => assert!(
                hit.prim == prim && (hit.t - 1.0).abs() < 1e-5,
                "{what}: ray {i} hit {hit:?}, not triangle {prim} at 1"
            ),
            None => assert!(!hit.is_hit(), "{what}: ray {i} should miss, got {hit:?}"),
        }
    }
}

fn check_occlusion(what: &str, rays: &Rays<'_>, call: std::ops::Range<usize>, blocked: &[bool]) {
    for (i, &b) in call.zip(blocked) {
        assert_eq!(b, expected(rays, i).is_some(), "{what}: ray {i} occluded");
    }
}

/// Every call of submission `S`, both queries, both contexts, both placements.
fn guarded_calls<A: EmbreeApi, S: Submission<A>>(name: &str, scene: &EmbreeScene<A>) {
    let batch = rays();
    let rays = batch.view();
    for coherent in [true, false] {
        for placement in Placement::BOTH {
            for call in S::calls(rays) {
                let what = format!(
                    "{name} ({}, {placement:?}, rays {call:?})",
                    if coherent { "coherent" } else { "incoherent" }
                );
                let mut args = A::arguments(coherent);
                let mut hits = vec![Hit::MISS; call.len()];
                let mut record = Guarded::new(vec![S::stage_hits(&rays, call.clone())], placement);
                guard_page::call(&format!("intersect of {what}"), || {
                    S::intersect(scene, &mut args, &mut record.as_mut_slice()[0], &mut hits)
                });
                check_hits(&what, &rays, call.clone(), &hits);

                let mut blocked = vec![false; call.len()];
                let mut record =
                    Guarded::new(vec![S::stage_shadows(&rays, call.clone())], placement);
                guard_page::call(&format!("occlusion of {what}"), || {
                    S::occluded(
                        scene,
                        &mut args,
                        &mut record.as_mut_slice()[0],
                        &mut blocked,
                    )
                });
                check_occlusion(&what, &rays, call, &blocked);
            }
        }
    }
}

/// Embree 3's streams: every ray's record in one guarded stream.
fn guarded_streams(name: &str, scene: &EmbreeScene<Embree3>) {
    let batch = rays();
    let rays = batch.view();
    let all = 0..rays.len();
    for coherent in [true, false] {
        for placement in Placement::BOTH {
            let what = format!(
                "{name} ({}, {placement:?})",
                if coherent { "coherent" } else { "incoherent" }
            );
            let mut context = Embree3::arguments(coherent);
            let staged = all.clone().map(|i| ffi::RTCRayHit::from_rays(&rays, i));
            let mut stream = Guarded::new(staged.collect(), placement);
            // SAFETY: a committed scene, a valid context, 21 records.
            guard_page::call(&format!("rtcIntersect1M of {what}"), || unsafe {
                ffi::RTCRayHit::trace1m(stream.as_mut_slice(), scene.raw(), &mut context)
            });
            let hits: Vec<Hit> = stream.as_mut_slice().iter().map(|r| r.answer()).collect();
            check_hits(&what, &rays, all.clone(), &hits);

            let staged = all.clone().map(|i| ffi::RTCRay::from_rays(&rays, i));
            let mut stream = Guarded::new(staged.collect(), placement);
            // SAFETY: as above.
            guard_page::call(&format!("rtcOccluded1M of {what}"), || unsafe {
                ffi::RTCRay::trace1m(stream.as_mut_slice(), scene.raw(), &mut context)
            });
            let blocked: Vec<bool> = stream.as_mut_slice().iter().map(|r| r.answer()).collect();
            check_occlusion(&what, &rays, all.clone(), &blocked);
        }
    }
}

/// A scene of the square on a device of `isa`, and which packet widths that device runs natively.
fn scene_on<A: EmbreeApi>(isa: Option<&str>) -> (EmbreeScene<A>, [isize; 3]) {
    let device = Device::<A>::with_config(isa).unwrap();
    let native = [
        RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED,
        RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED,
        RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED,
    ]
    .map(|p| device.property(p));
    let scene = EmbreeScene::build(Arc::new(device), &square(), EmbreeConfig::default()).unwrap();
    (scene, native)
}

/// Every packet entry point of Embree `A` on every ISA; returns the native widths seen per ISA.
fn every_entry_point<A: EmbreeApi>(streams: impl Fn(&str, &EmbreeScene<A>)) -> Vec<[isize; 3]> {
    let mut natives = Vec::new();
    for isa in test_isas() {
        let (scene, native) = scene_on::<A>(isa);
        let on = |call: &str| format!("{} {call} at {}", A::NAME, isa.unwrap_or("native ISA"));
        guarded_calls::<A, Single>(&on("1"), &scene);
        guarded_calls::<A, Packets4>(&on("4"), &scene);
        guarded_calls::<A, Packets8>(&on("8"), &scene);
        guarded_calls::<A, Packets16>(&on("16"), &scene);
        streams(&on("1M"), &scene);
        natives.push(native);
    }
    natives
}

/// The lower ISAs really are exercised: forced to AVX2 a device has no native 16-wide packets,
/// forced to SSE4.2 no native 8-wide ones, so `rtcOccluded16` / `rtcOccluded8` take the fallback.
fn assert_lower_isas_lack_wide_packets(natives: &[[isize; 3]]) {
    let isas = test_isas();
    for (isa, native) in isas.iter().zip(natives) {
        match isa {
            Some("isa=avx2") => assert_eq!(native, &[1, 1, 0], "{isa:?}"),
            Some("isa=sse4.2") => assert_eq!(native, &[1, 0, 0], "{isa:?}"),
            _ => assert_eq!(native[0], 1, "{isa:?}"),
        }
    }
}

#[test]
fn embree_3_reads_and_writes_only_the_records_raylab_stages_on_every_isa() {
    let natives = every_entry_point::<Embree3>(guarded_streams);
    assert_lower_isas_lack_wide_packets(&natives);
}

#[cfg(embree4)]
#[test]
fn embree_4_reads_and_writes_only_the_records_raylab_stages_on_every_isa() {
    use crate::accel::embree::Embree4;
    // Embree 4 has no stream API.
    let natives = every_entry_point::<Embree4>(|_, _| {});
    assert_lower_isas_lack_wide_packets(&natives);
}
