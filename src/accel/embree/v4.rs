//! Embree 4, the second baseline: bindings generated from the headers of its release, 4.4
//! (Debian's libembree-dev 4.4.1), and the library (4.4.0) with its TBB from the embreex wheel,
//! both fetched into a cache by `.ci/fetch-embree4` (`build.rs`).
//!
//! Embree 4 exports the same C symbols as the Embree 3 that raylab links, so it is opened at run
//! time, from the absolute path recorded at build time (no LD_LIBRARY_PATH), with RTLD_DEEPBIND:
//! it and its TBB resolve their own symbols before the process's, which hold Embree 3's
//! same-named functions and the system TBB.
//!
//! The device refuses a library of another release than the headers (`Device::new`: only the
//! patch may differ). The tracers fill records of the Embree 3 layout for both versions (`api`);
//! the tests check that every struct and enum value raylab hands Embree 4 has the layout and value
//! its own bindings give it, up to the hit fields 4.3 appended, which `Padded` makes room for.

use std::ffi::{c_char, c_int, c_uint, c_void};
use std::ptr;
use std::sync::{Mutex, OnceLock};

use super::api::{EmbreeApi, SharedDevice};
use super::ffi::{
    RTCBufferType, RTCBuildQuality, RTCDevice, RTCDeviceProperty, RTCError, RTCErrorFunction,
    RTCFormat, RTCGeometry, RTCGeometryType, RTCRay, RTCRay16, RTCRay4, RTCRay8, RTCRayHit,
    RTCRayHit16, RTCRayHit4, RTCRayHit8, RTCScene, RTCSceneFlags,
};
use crate::error::{Error, Result};

/// The bindgen output (`build.rs`): types, constants, and `Embree4Library`, a table of the
/// functions raylab calls, filled by dlsym.
pub mod ffi {
    #![allow(
        non_upper_case_globals,
        non_camel_case_types,
        non_snake_case,
        dead_code,
        clippy::all
    )]
    include!(concat!(env!("OUT_DIR"), "/embree4.rs"));
}

/// The library build.rs found in the cache.
pub const LIBRARY_PATH: &str = env!("RAYLAB_EMBREE4_LIBRARY");
/// Where the library and headers came from, with their pinned versions (`.ci/fetch-embree4`).
pub const SOURCE: &str = env!("RAYLAB_EMBREE4_SOURCE");

/// glibc's RTLD_DEEPBIND (<dlfcn.h>), which libloading does not name.
const RTLD_DEEPBIND: c_int = 0x0008;

static LIBRARY: OnceLock<std::result::Result<ffi::Embree4Library, String>> = OnceLock::new();

fn open() -> std::result::Result<ffi::Embree4Library, String> {
    use libloading::os::unix::{Library, RTLD_LOCAL, RTLD_NOW};
    // SAFETY: Embree's initialisers only set up its own state (and TBB's).
    let library =
        unsafe { Library::open(Some(LIBRARY_PATH), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND) }
            .map_err(|e| format!("cannot open {LIBRARY_PATH}: {e}"))?;
    // SAFETY: the symbols have the types of the headers the bindings came from, of the
    // library's release (checked in `Device::new`).
    unsafe { ffi::Embree4Library::from_library(library) }
        .map_err(|e| format!("{LIBRARY_PATH} lacks an Embree 4 function: {e}"))
}

/// The opened library; only called after `Embree4::load` succeeded.
#[inline(always)]
fn library() -> &'static ffi::Embree4Library {
    match LIBRARY.get() {
        Some(Ok(library)) => library,
        _ => unreachable!("Embree 4 is called only through a device, created after loading it"),
    }
}

/// Embree 4's trace arguments: the coherence hint, every feature, no filter or user geometry,
/// and no ray query context (the library then uses a default one, as rtcInitRayQueryContext).
pub struct Arguments {
    intersect: ffi::RTCIntersectArguments,
    occluded: ffi::RTCOccludedArguments,
}

pub struct Embree4;

static EMBREE4_DEVICE: SharedDevice<Embree4> = Mutex::new(None);

impl EmbreeApi for Embree4 {
    const NAME: &'static str = "Embree 4";
    const HEADER_VERSION: isize = ffi::RTC_VERSION as isize;
    type Arguments = Arguments;

    fn load() -> Result<()> {
        match LIBRARY.get_or_init(open) {
            Ok(_) => Ok(()),
            Err(why) => Err(Error::runtime(format!("Embree 4 is unavailable: {why}"))),
        }
    }

    fn shared_device() -> &'static SharedDevice<Self> {
        &EMBREE4_DEVICE
    }

    /// As rtcInitIntersectArguments / rtcInitOccludedArguments, with the hint.
    fn arguments(coherent: bool) -> Arguments {
        use ffi::RTCRayQueryFlags as Flags;
        let flags = if coherent {
            Flags::RTC_RAY_QUERY_FLAG_COHERENT
        } else {
            Flags::RTC_RAY_QUERY_FLAG_INCOHERENT
        };
        let feature_mask = ffi::RTCFeatureFlags::RTC_FEATURE_FLAG_ALL;
        Arguments {
            intersect: ffi::RTCIntersectArguments {
                flags,
                feature_mask,
                context: ptr::null_mut(),
                filter: None,
                intersect: None,
            },
            occluded: ffi::RTCOccludedArguments {
                flags,
                feature_mask,
                context: ptr::null_mut(),
                filter: None,
                occluded: None,
            },
        }
    }

    unsafe fn new_device(config: *const c_char) -> RTCDevice {
        library().rtcNewDevice(config).cast()
    }
    unsafe fn release_device(device: RTCDevice) {
        library().rtcReleaseDevice(device.cast())
    }
    unsafe fn device_error(device: RTCDevice) -> RTCError::Type {
        library().rtcGetDeviceError(device.cast())
    }
    unsafe fn set_device_error_function(
        device: RTCDevice,
        error: RTCErrorFunction,
        user: *mut c_void,
    ) {
        library().rtcSetDeviceErrorFunction(device.cast(), error, user)
    }
    unsafe fn device_property(device: RTCDevice, property: RTCDeviceProperty::Type) -> isize {
        library().rtcGetDeviceProperty(device.cast(), property)
    }

    unsafe fn new_scene(device: RTCDevice) -> RTCScene {
        library().rtcNewScene(device.cast()).cast()
    }
    unsafe fn set_scene_flags(scene: RTCScene, flags: RTCSceneFlags) {
        library().rtcSetSceneFlags(scene.cast(), ffi::RTCSceneFlags(flags.0))
    }
    unsafe fn set_scene_build_quality(scene: RTCScene, quality: RTCBuildQuality::Type) {
        library().rtcSetSceneBuildQuality(scene.cast(), quality)
    }
    unsafe fn commit_scene(scene: RTCScene) {
        library().rtcCommitScene(scene.cast())
    }
    unsafe fn release_scene(scene: RTCScene) {
        library().rtcReleaseScene(scene.cast())
    }

    unsafe fn new_geometry(device: RTCDevice, kind: RTCGeometryType::Type) -> RTCGeometry {
        library().rtcNewGeometry(device.cast(), kind).cast()
    }
    unsafe fn set_geometry_build_quality(geometry: RTCGeometry, quality: RTCBuildQuality::Type) {
        library().rtcSetGeometryBuildQuality(geometry.cast(), quality)
    }
    unsafe fn set_geometry_time_step_count(geometry: RTCGeometry, steps: c_uint) {
        library().rtcSetGeometryTimeStepCount(geometry.cast(), steps)
    }
    unsafe fn set_new_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
        format: RTCFormat::Type,
        stride: usize,
        count: usize,
    ) -> *mut c_void {
        library().rtcSetNewGeometryBuffer(geometry.cast(), kind, slot, format, stride, count)
    }
    unsafe fn geometry_buffer_data(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    ) -> *mut c_void {
        library().rtcGetGeometryBufferData(geometry.cast(), kind, slot)
    }
    unsafe fn update_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    ) {
        library().rtcUpdateGeometryBuffer(geometry.cast(), kind, slot)
    }
    unsafe fn commit_geometry(geometry: RTCGeometry) {
        library().rtcCommitGeometry(geometry.cast())
    }
    unsafe fn attach_geometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint {
        library().rtcAttachGeometry(scene.cast(), geometry.cast())
    }
    unsafe fn release_geometry(geometry: RTCGeometry) {
        library().rtcReleaseGeometry(geometry.cast())
    }

    #[inline(always)]
    unsafe fn intersect1(scene: RTCScene, args: &mut Arguments, rayhit: *mut RTCRayHit) {
        library().rtcIntersect1(scene.cast(), rayhit.cast(), &mut args.intersect)
    }
    #[inline(always)]
    unsafe fn occluded1(scene: RTCScene, args: &mut Arguments, ray: *mut RTCRay) {
        library().rtcOccluded1(scene.cast(), ray.cast(), &mut args.occluded)
    }
    #[inline(always)]
    unsafe fn intersect4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        rayhit: *mut RTCRayHit4,
    ) {
        library().rtcIntersect4(valid, scene.cast(), rayhit.cast(), &mut args.intersect)
    }
    #[inline(always)]
    unsafe fn intersect8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        rayhit: *mut RTCRayHit8,
    ) {
        library().rtcIntersect8(valid, scene.cast(), rayhit.cast(), &mut args.intersect)
    }
    #[inline(always)]
    unsafe fn intersect16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        rayhit: *mut RTCRayHit16,
    ) {
        library().rtcIntersect16(valid, scene.cast(), rayhit.cast(), &mut args.intersect)
    }
    #[inline(always)]
    unsafe fn occluded4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        ray: *mut RTCRay4,
    ) {
        library().rtcOccluded4(valid, scene.cast(), ray.cast(), &mut args.occluded)
    }
    #[inline(always)]
    unsafe fn occluded8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        ray: *mut RTCRay8,
    ) {
        library().rtcOccluded8(valid, scene.cast(), ray.cast(), &mut args.occluded)
    }
    #[inline(always)]
    unsafe fn occluded16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Arguments,
        ray: *mut RTCRay16,
    ) {
        library().rtcOccluded16(valid, scene.cast(), ray.cast(), &mut args.occluded)
    }
}

#[cfg(test)]
mod tests {
    use std::mem::{align_of, offset_of, size_of};

    use super::*;
    use crate::accel::embree::ffi as v3;
    use crate::accel::embree::{version, Device, Padded};

    /// The same alignment and field offsets in the Embree 3 and the Embree 4 bindings.
    macro_rules! same_fields {
        ($ty:ident { $($field:ident),* }) => {{
            assert_eq!(align_of::<v3::$ty>(), align_of::<ffi::$ty>(), stringify!($ty));
            $(assert_eq!(
                offset_of!(v3::$ty, $field),
                offset_of!(ffi::$ty, $field),
                "{}.{}", stringify!($ty), stringify!($field)
            );)*
        }};
    }

    /// `same_fields`, and the same size.
    macro_rules! same_layout {
        ($ty:ident { $($field:ident),* }) => {{
            assert_eq!(size_of::<v3::$ty>(), size_of::<ffi::$ty>(), stringify!($ty));
            same_fields!($ty { $($field),* });
        }};
    }

    /// `same_fields`, and the Embree 3 record with its `Padded` tail at least as large as
    /// Embree 4's (which appends `instPrimID`).
    macro_rules! padded_prefix {
        ($ty:ident { $($field:ident),* }) => {{
            assert!(
                size_of::<Padded<v3::$ty>>() >= size_of::<ffi::$ty>(),
                "{}: {} padded bytes hold Embree 4's {}",
                stringify!($ty), size_of::<Padded<v3::$ty>>(), size_of::<ffi::$ty>()
            );
            same_fields!($ty { $($field),* });
        }};
    }

    #[test]
    fn records_have_the_embree_3_layout_the_tracers_fill() {
        same_layout!(RTCRay {
            org_x,
            org_y,
            org_z,
            tnear,
            dir_x,
            dir_y,
            dir_z,
            time,
            tfar,
            mask,
            id,
            flags
        });
        padded_prefix!(RTCHit {
            Ng_x,
            Ng_y,
            Ng_z,
            u,
            v,
            primID,
            geomID,
            instID
        });
        padded_prefix!(RTCRayHit { ray, hit });
        same_layout!(RTCRay4 {
            org_x,
            tnear,
            dir_x,
            time,
            tfar,
            mask,
            id,
            flags
        });
        padded_prefix!(RTCHit4 {
            Ng_x,
            u,
            v,
            primID,
            geomID,
            instID
        });
        padded_prefix!(RTCRayHit4 { ray, hit });
        same_layout!(RTCRay8 {
            org_x,
            tnear,
            dir_x,
            time,
            tfar,
            mask,
            id,
            flags
        });
        padded_prefix!(RTCHit8 {
            Ng_x,
            u,
            v,
            primID,
            geomID,
            instID
        });
        padded_prefix!(RTCRayHit8 { ray, hit });
        same_layout!(RTCRay16 {
            org_x,
            tnear,
            dir_x,
            time,
            tfar,
            mask,
            id,
            flags
        });
        padded_prefix!(RTCHit16 {
            Ng_x,
            u,
            v,
            primID,
            geomID,
            instID
        });
        padded_prefix!(RTCRayHit16 { ray, hit });
        // One instance level in both; Embree 4's hit ends with instPrimID, one word a lane.
        assert_eq!(ffi::RTC_MAX_INSTANCE_LEVEL_COUNT, 1);
        assert_eq!(size_of::<v3::RTCRayHit>(), 80);
        assert_eq!(offset_of!(ffi::RTCHit, instPrimID), size_of::<v3::RTCHit>());
        assert_eq!(size_of::<ffi::RTCRayHit>(), 96);
        assert_eq!(offset_of!(ffi::RTCHit16, instPrimID), 9 * 64 - 64);
        // What raylab hands Embree 4 besides records: the arguments as the 4.4 headers lay them
        // out (no minWidthDistanceFactor: RTC_MIN_WIDTH is 0).
        assert_eq!(ffi::RTC_MIN_WIDTH, 0);
        assert_eq!(size_of::<ffi::RTCIntersectArguments>(), 32);
        assert_eq!(offset_of!(ffi::RTCIntersectArguments, context), 8);
        assert_eq!(size_of::<ffi::RTCOccludedArguments>(), 32);
    }

    #[test]
    fn enum_values_raylab_passes_are_the_same_numbers() {
        use ffi::RTCBufferType as B4;
        use ffi::RTCBuildQuality as Q4;
        use ffi::RTCDeviceProperty as P4;
        use ffi::RTCError as E4;
        use ffi::RTCFormat as F4;
        use v3::RTCBufferType as B3;
        use v3::RTCBuildQuality as Q3;
        use v3::RTCDeviceProperty as P3;
        use v3::RTCError as E3;
        use v3::RTCFormat as F3;
        let pairs = [
            (Q3::RTC_BUILD_QUALITY_LOW, Q4::RTC_BUILD_QUALITY_LOW),
            (Q3::RTC_BUILD_QUALITY_MEDIUM, Q4::RTC_BUILD_QUALITY_MEDIUM),
            (Q3::RTC_BUILD_QUALITY_HIGH, Q4::RTC_BUILD_QUALITY_HIGH),
            (Q3::RTC_BUILD_QUALITY_REFIT, Q4::RTC_BUILD_QUALITY_REFIT),
            (B3::RTC_BUFFER_TYPE_INDEX, B4::RTC_BUFFER_TYPE_INDEX),
            (B3::RTC_BUFFER_TYPE_VERTEX, B4::RTC_BUFFER_TYPE_VERTEX),
            (F3::RTC_FORMAT_FLOAT3, F4::RTC_FORMAT_FLOAT3),
            (F3::RTC_FORMAT_UINT3, F4::RTC_FORMAT_UINT3),
            (
                v3::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE,
                ffi::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE,
            ),
            (
                P3::RTC_DEVICE_PROPERTY_VERSION,
                P4::RTC_DEVICE_PROPERTY_VERSION,
            ),
            (
                P3::RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED,
                P4::RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED,
            ),
            (
                P3::RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED,
                P4::RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED,
            ),
            (
                P3::RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED,
                P4::RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED,
            ),
            (
                E3::RTC_ERROR_INVALID_ARGUMENT,
                E4::RTC_ERROR_INVALID_ARGUMENT,
            ),
            (
                E3::RTC_ERROR_INVALID_OPERATION,
                E4::RTC_ERROR_INVALID_OPERATION,
            ),
            (E3::RTC_ERROR_OUT_OF_MEMORY, E4::RTC_ERROR_OUT_OF_MEMORY),
            (E3::RTC_ERROR_UNSUPPORTED_CPU, E4::RTC_ERROR_UNSUPPORTED_CPU),
            (E3::RTC_ERROR_CANCELLED, E4::RTC_ERROR_CANCELLED),
        ];
        for (i, (a, b)) in pairs.iter().enumerate() {
            assert_eq!(a, b, "pair {i}");
        }
        use ffi::RTCSceneFlags as S4;
        use v3::RTCSceneFlags as S3;
        assert_eq!(S3::RTC_SCENE_FLAG_NONE.0, S4::RTC_SCENE_FLAG_NONE.0);
        assert_eq!(S3::RTC_SCENE_FLAG_DYNAMIC.0, S4::RTC_SCENE_FLAG_DYNAMIC.0);
        assert_eq!(S3::RTC_SCENE_FLAG_ROBUST.0, S4::RTC_SCENE_FLAG_ROBUST.0);
        assert_eq!(v3::RTC_INVALID_GEOMETRY_ID, u32::MAX);
    }

    #[test]
    fn the_library_is_of_the_headers_release() {
        let device = Device::<Embree4>::shared().unwrap();
        let library = device.property(v3::RTCDeviceProperty::RTC_DEVICE_PROPERTY_VERSION);
        assert_eq!(library / 10000, 4, "{library}");
        assert_eq!(
            ffi::RTC_VERSION / 100,
            404,
            "the headers of Debian's libembree-dev 4.4"
        );
        assert_eq!(library / 100, 404, "the embreex 4.4 library");
        let v = version::<Embree4>().unwrap();
        assert!(v.starts_with("4."), "{v}");
        // As for Embree 3: masks compiled in, both faces hit, triangles there.
        use v3::RTCDeviceProperty::*;
        assert_eq!(device.property(RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED), 1);
        assert_eq!(
            device.property(RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED),
            0
        );
        assert_eq!(
            device.property(RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED),
            1
        );
        // Embree 3's device is another one, of another library, in the same process.
        let v3 = version::<crate::accel::embree::Embree3>().unwrap();
        assert!(v3.starts_with("3."), "{v3}");
    }

    #[test]
    fn errors_of_embree_4_are_reported() {
        let d = Device::<Embree4>::new().unwrap();
        // SAFETY: a device and an out-of-range property value: Embree reports invalid argument.
        unsafe { Embree4::device_property(d.raw(), 9999) };
        let err = d.check("reading property 9999").unwrap_err();
        assert!(err.to_string().contains("invalid argument"), "{err}");
    }
}
