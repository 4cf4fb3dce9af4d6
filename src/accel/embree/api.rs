//! The calls raylab makes into Embree, as one trait that Embree 3 (linked, `ffi`) and Embree 4
//! (loaded at run time, `v4`) implement, so the device, the scene and the tracers are written once
//! for both versions. Signatures use the Embree 3 bindings' types: handles are opaque pointers,
//! the enum values raylab passes are the same numbers in both versions, and the ray and hit records
//! have the same layout (all checked by `v4`'s tests).

use std::ffi::{c_char, c_uint, c_void};
use std::sync::{Arc, Mutex};

use super::ffi::{
    self, RTCBufferType, RTCBuildQuality, RTCDevice, RTCDeviceProperty, RTCError, RTCErrorFunction,
    RTCFormat, RTCGeometry, RTCGeometryType, RTCIntersectContextFlags, RTCRay, RTCRay16, RTCRay4,
    RTCRay8, RTCRayHit, RTCRayHit16, RTCRayHit4, RTCRayHit8, RTCScene, RTCSceneFlags,
};
use super::Device;
use crate::error::Result;

/// The process-wide device of one Embree version (`Device::shared`).
pub type SharedDevice<A> = Mutex<Option<Arc<Device<A>>>>;

/// One Embree version's entry points. Every `unsafe fn` has the contract of the C function it
/// forwards to (Embree's API reference), and may only be called after `load` succeeded.
#[allow(clippy::missing_safety_doc)]
pub trait EmbreeApi: Sized + 'static {
    /// "Embree 3", "Embree 4": how messages and meta.json name it.
    const NAME: &'static str;
    /// `RTC_VERSION` of the headers the bindings were generated from (e.g. 30000 + 100 · 13 + 5).
    const HEADER_VERSION: isize;
    /// What a trace call takes besides the scene and the rays: Embree 3's intersect context,
    /// Embree 4's intersect and occluded arguments.
    type Arguments;

    /// Makes the library callable; an error says why it cannot be (Embree 4 not fetched).
    fn load() -> Result<()>;
    fn shared_device() -> &'static SharedDevice<Self>;
    /// Arguments with Embree's defaults and the coherence hint.
    fn arguments(coherent: bool) -> Self::Arguments;

    unsafe fn new_device(config: *const c_char) -> RTCDevice;
    unsafe fn release_device(device: RTCDevice);
    unsafe fn device_error(device: RTCDevice) -> RTCError::Type;
    unsafe fn set_device_error_function(
        device: RTCDevice,
        error: RTCErrorFunction,
        user: *mut c_void,
    );
    unsafe fn device_property(device: RTCDevice, property: RTCDeviceProperty::Type) -> isize;

    unsafe fn new_scene(device: RTCDevice) -> RTCScene;
    unsafe fn set_scene_flags(scene: RTCScene, flags: RTCSceneFlags);
    unsafe fn set_scene_build_quality(scene: RTCScene, quality: RTCBuildQuality::Type);
    unsafe fn commit_scene(scene: RTCScene);
    unsafe fn release_scene(scene: RTCScene);

    unsafe fn new_geometry(device: RTCDevice, kind: RTCGeometryType::Type) -> RTCGeometry;
    unsafe fn set_geometry_build_quality(geometry: RTCGeometry, quality: RTCBuildQuality::Type);
    unsafe fn set_geometry_time_step_count(geometry: RTCGeometry, steps: c_uint);
    unsafe fn set_new_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
        format: RTCFormat::Type,
        stride: usize,
        count: usize,
    ) -> *mut c_void;
    unsafe fn geometry_buffer_data(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    ) -> *mut c_void;
    unsafe fn update_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    );
    unsafe fn commit_geometry(geometry: RTCGeometry);
    unsafe fn attach_geometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    unsafe fn release_geometry(geometry: RTCGeometry);

    /// The library may write past the Embree 3 record into its `Padded` tail (Embree ≥ 4.3).
    unsafe fn intersect1(scene: RTCScene, args: &mut Self::Arguments, rayhit: *mut RTCRayHit);
    unsafe fn occluded1(scene: RTCScene, args: &mut Self::Arguments, ray: *mut RTCRay);
    unsafe fn intersect4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit4,
    );
    unsafe fn intersect8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit8,
    );
    unsafe fn intersect16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit16,
    );
    unsafe fn occluded4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay4,
    );
    unsafe fn occluded8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay8,
    );
    unsafe fn occluded16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay16,
    );
}

/// A ray record of the Embree 3 layout, which the tracers fill for both versions, followed by
/// room for what Embree 4 appends to the hit: since 4.3 its hits end with
/// `instPrimID[RTC_MAX_INSTANCE_LEVEL_COUNT]` after `instID` (instance arrays), which the 4.4
/// library writes on every intersect (and, on ISAs without native N-wide packets, on every
/// occlusion of a packet: `tracers::embree::packet`). 16 words hold it for packets of up to 16
/// lanes (`v4`'s tests check each padded record covers its Embree 4 binding); Embree 3 never
/// touches them. Pointers handed to Embree must come from `as_mut_ptr`, whose provenance covers
/// the tail.
#[repr(C)]
pub struct Padded<T> {
    pub record: T,
    tail: [u32; 16],
}

impl<T> Padded<T> {
    #[inline(always)]
    pub fn new(record: T) -> Self {
        Padded {
            record,
            tail: [0; 16],
        }
    }

    #[inline(always)]
    pub fn as_mut_ptr(&mut self) -> *mut T {
        (self as *mut Self).cast()
    }
}

/// Embree 3, linked (`build.rs`): the Debian library.
pub struct Embree3;

static EMBREE3_DEVICE: SharedDevice<Embree3> = Mutex::new(None);

impl EmbreeApi for Embree3 {
    const NAME: &'static str = "Embree 3";
    const HEADER_VERSION: isize = ffi::RTC_VERSION as isize;
    type Arguments = ffi::RTCIntersectContext;

    fn load() -> Result<()> {
        Ok(())
    }

    fn shared_device() -> &'static SharedDevice<Self> {
        &EMBREE3_DEVICE
    }

    fn arguments(coherent: bool) -> ffi::RTCIntersectContext {
        ffi::intersect_context(if coherent {
            RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_COHERENT
        } else {
            RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
        })
    }

    unsafe fn new_device(config: *const c_char) -> RTCDevice {
        ffi::rtcNewDevice(config)
    }
    unsafe fn release_device(device: RTCDevice) {
        ffi::rtcReleaseDevice(device)
    }
    unsafe fn device_error(device: RTCDevice) -> RTCError::Type {
        ffi::rtcGetDeviceError(device)
    }
    unsafe fn set_device_error_function(
        device: RTCDevice,
        error: RTCErrorFunction,
        user: *mut c_void,
    ) {
        ffi::rtcSetDeviceErrorFunction(device, error, user)
    }
    unsafe fn device_property(device: RTCDevice, property: RTCDeviceProperty::Type) -> isize {
        ffi::rtcGetDeviceProperty(device, property)
    }

    unsafe fn new_scene(device: RTCDevice) -> RTCScene {
        ffi::rtcNewScene(device)
    }
    unsafe fn set_scene_flags(scene: RTCScene, flags: RTCSceneFlags) {
        ffi::rtcSetSceneFlags(scene, flags)
    }
    unsafe fn set_scene_build_quality(scene: RTCScene, quality: RTCBuildQuality::Type) {
        ffi::rtcSetSceneBuildQuality(scene, quality)
    }
    unsafe fn commit_scene(scene: RTCScene) {
        ffi::rtcCommitScene(scene)
    }
    unsafe fn release_scene(scene: RTCScene) {
        ffi::rtcReleaseScene(scene)
    }

    unsafe fn new_geometry(device: RTCDevice, kind: RTCGeometryType::Type) -> RTCGeometry {
        ffi::rtcNewGeometry(device, kind)
    }
    unsafe fn set_geometry_build_quality(geometry: RTCGeometry, quality: RTCBuildQuality::Type) {
        ffi::rtcSetGeometryBuildQuality(geometry, quality)
    }
    unsafe fn set_geometry_time_step_count(geometry: RTCGeometry, steps: c_uint) {
        ffi::rtcSetGeometryTimeStepCount(geometry, steps)
    }
    unsafe fn set_new_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
        format: RTCFormat::Type,
        stride: usize,
        count: usize,
    ) -> *mut c_void {
        ffi::rtcSetNewGeometryBuffer(geometry, kind, slot, format, stride, count)
    }
    unsafe fn geometry_buffer_data(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    ) -> *mut c_void {
        ffi::rtcGetGeometryBufferData(geometry, kind, slot)
    }
    unsafe fn update_geometry_buffer(
        geometry: RTCGeometry,
        kind: RTCBufferType::Type,
        slot: c_uint,
    ) {
        ffi::rtcUpdateGeometryBuffer(geometry, kind, slot)
    }
    unsafe fn commit_geometry(geometry: RTCGeometry) {
        ffi::rtcCommitGeometry(geometry)
    }
    unsafe fn attach_geometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint {
        ffi::rtcAttachGeometry(scene, geometry)
    }
    unsafe fn release_geometry(geometry: RTCGeometry) {
        ffi::rtcReleaseGeometry(geometry)
    }

    #[inline(always)]
    unsafe fn intersect1(scene: RTCScene, args: &mut Self::Arguments, rayhit: *mut RTCRayHit) {
        ffi::rtcIntersect1(scene, args, rayhit)
    }
    #[inline(always)]
    unsafe fn occluded1(scene: RTCScene, args: &mut Self::Arguments, ray: *mut RTCRay) {
        ffi::rtcOccluded1(scene, args, ray)
    }
    #[inline(always)]
    unsafe fn intersect4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit4,
    ) {
        ffi::rtcIntersect4(valid, scene, args, rayhit)
    }
    #[inline(always)]
    unsafe fn intersect8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit8,
    ) {
        ffi::rtcIntersect8(valid, scene, args, rayhit)
    }
    #[inline(always)]
    unsafe fn intersect16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        rayhit: *mut RTCRayHit16,
    ) {
        ffi::rtcIntersect16(valid, scene, args, rayhit)
    }
    #[inline(always)]
    unsafe fn occluded4(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay4,
    ) {
        ffi::rtcOccluded4(valid, scene, args, ray)
    }
    #[inline(always)]
    unsafe fn occluded8(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay8,
    ) {
        ffi::rtcOccluded8(valid, scene, args, ray)
    }
    #[inline(always)]
    unsafe fn occluded16(
        valid: *const i32,
        scene: RTCScene,
        args: &mut Self::Arguments,
        ray: *mut RTCRay16,
    ) {
        ffi::rtcOccluded16(valid, scene, args, ray)
    }
}
