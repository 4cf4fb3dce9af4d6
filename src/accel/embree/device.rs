//! The Embree device: owns Embree's build threads and reports errors. One device per Embree
//! version serves the whole process (`Device::shared`), since creating one starts a thread pool;
//! scenes keep it alive.

use std::ffi::{c_char, c_void, CStr, CString};
use std::marker::PhantomData;
use std::ptr;
use std::sync::{Arc, Mutex, PoisonError};

use super::api::{Embree3, EmbreeApi};
use super::ffi;
use crate::error::{Error, Result};

/// Errors Embree reported through its callback since the last `Device::check`.
type ErrorLog = Mutex<Vec<String>>;

pub struct Device<A: EmbreeApi = Embree3> {
    raw: ffi::RTCDevice,
    // Boxed so the address handed to Embree as the callback's user pointer never moves.
    errors: Box<ErrorLog>,
    /// Whether the device's ISA runs packets of 4, 8 and 16 rays natively
    /// (`RTC_DEVICE_PROPERTY_NATIVE_RAY{4,8,16}_SUPPORTED`): 16 needs AVX-512, 8 AVX.
    native_packets: [bool; 3],
    api: PhantomData<A>,
}

// SAFETY: Embree's device API is thread-safe; the error log behind the callback is a Mutex.
unsafe impl<A: EmbreeApi> Send for Device<A> {}
unsafe impl<A: EmbreeApi> Sync for Device<A> {}

impl<A: EmbreeApi> Device<A> {
    /// A new device with Embree's default configuration (all hardware threads for builds, the
    /// best ISA of this CPU), once the library is checked to be the release of our headers.
    pub fn new() -> Result<Self> {
        Self::with_config(None)
    }

    /// A new device with Embree's configuration string (`rtcNewDevice`), e.g. `"isa=avx2"` to
    /// run Embree's AVX2 kernels on an AVX-512 machine, or `None` for the defaults.
    pub fn with_config(config: Option<&str>) -> Result<Self> {
        A::load()?;
        let config = config
            .map(|c| CString::new(c).map_err(|_| Error::usage("an Embree config has no NUL")))
            .transpose()?;
        // SAFETY: a NUL-terminated config string, or null for the defaults.
        let raw = unsafe { A::new_device(config.as_ref().map_or(ptr::null(), |c| c.as_ptr())) };
        if raw.is_null() {
            // SAFETY: with a null device Embree reports the error of device creation.
            let code = unsafe { A::device_error(ptr::null_mut()) };
            return Err(Error::runtime(format!(
                "{} could not create a device: {}",
                A::NAME,
                error_name(code)
            )));
        }
        let mut device = Device {
            raw,
            errors: Box::default(),
            native_packets: [false; 3],
            api: PhantomData,
        };
        let log: *const ErrorLog = &*device.errors;
        // SAFETY: the log outlives the device: it is dropped after rtcReleaseDevice in Drop.
        unsafe { A::set_device_error_function(raw, Some(record_error), log as *mut c_void) };
        use ffi::RTCDeviceProperty::*;
        device.native_packets = [
            RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED,
            RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED,
            RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED,
        ]
        .map(|p| device.property(p) == 1);
        let library = device.property(RTC_DEVICE_PROPERTY_VERSION);
        if !same_release(library, A::HEADER_VERSION) {
            return Err(Error::usage(format!(
                "{} library {} is not the release of the headers raylab was built with ({}): \
                 its records may have another layout; fetch both of one release \
                 (`bash .ci/fetch-embree4`) and rebuild",
                A::NAME,
                device.version(),
                dotted(A::HEADER_VERSION)
            )));
        }
        Ok(device)
    }

    /// The process-wide device of this version, created on first use with the configuration
    /// `RAYLAB_EMBREE_CONFIG` gives, if any (`shared_config`).
    pub fn shared() -> Result<Arc<Self>> {
        let mut slot = A::shared_device()
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(device) = &*slot {
            return Ok(device.clone());
        }
        let config = shared_config();
        if let Some(config) = &config {
            check_isa(config)?;
        }
        let device = Arc::new(Device::with_config(config.as_deref())?);
        *slot = Some(device.clone());
        Ok(device)
    }

    /// Whether packets of `width` (4, 8 or 16) rays run natively on this device's ISA; where not,
    /// Embree traces their lanes one by one through the packet taken as a ray-and-hit packet.
    pub fn native_packets(&self, width: usize) -> bool {
        match width {
            4 => self.native_packets[0],
            8 => self.native_packets[1],
            16 => self.native_packets[2],
            _ => false,
        }
    }

    pub(crate) fn raw(&self) -> ffi::RTCDevice {
        self.raw
    }

    /// `Err` with every message Embree reported since the last check (during `what`), and clears
    /// them.
    pub fn check(&self, what: &str) -> Result<()> {
        let mut errors = self.errors.lock().unwrap_or_else(PoisonError::into_inner);
        if errors.is_empty() {
            return Ok(());
        }
        let message = format!("Embree failed while {what}: {}", errors.join("; "));
        errors.clear();
        Err(Error::runtime(message))
    }

    pub fn property(&self, property: ffi::RTCDeviceProperty::Type) -> isize {
        // SAFETY: a valid device; an unknown property sets an error and returns 0.
        unsafe { A::device_property(self.raw, property) }
    }

    /// The library's version, e.g. "3.13.5", from the device (not from the header we compiled
    /// against): the one recorded in meta.json.
    pub fn version(&self) -> String {
        dotted(self.property(ffi::RTCDeviceProperty::RTC_DEVICE_PROPERTY_VERSION))
    }
}

impl<A: EmbreeApi> Drop for Device<A> {
    fn drop(&mut self) {
        // SAFETY: the device was created by rtcNewDevice and is released once.
        unsafe { A::release_device(self.raw) };
    }
}

/// The environment variable whose value configures the shared devices of both versions, e.g.
/// `isa=avx2` to measure and check Embree's AVX2 kernels on an AVX-512 machine (meta.json records
/// it): Embree's `rtcNewDevice` configuration string.
pub const CONFIG_VARIABLE: &str = "RAYLAB_EMBREE_CONFIG";

/// The configuration of the shared devices: `RAYLAB_EMBREE_CONFIG`, when set and not empty.
pub fn shared_config() -> Option<String> {
    std::env::var(CONFIG_VARIABLE)
        .ok()
        .filter(|c| !c.is_empty())
}

/// The ISA names Embree's `isa=` and `max_isa=` settings take (Embree 3 and 4).
const ISA_NAMES: &[&str] = &["sse2", "sse4.2", "avx", "avx2", "avx512", "avx512skx"];

/// Refuses an `isa=` or `max_isa=` value Embree does not know: Embree ignores it silently and
/// runs its default ISA, while meta.json would record the value asked for.
fn check_isa(config: &str) -> Result<()> {
    for setting in config.split(',') {
        let Some((key, value)) = setting.split_once('=') else {
            continue;
        };
        let (key, value) = (key.trim(), value.trim());
        if (key == "isa" || key == "max_isa") && !ISA_NAMES.contains(&value) {
            return Err(Error::usage(format!(
                "{CONFIG_VARIABLE}: {key}={value} is not an ISA Embree knows (known: {})",
                ISA_NAMES.join(", ")
            )));
        }
    }
    Ok(())
}

/// The Embree library version, via the shared device.
pub fn version<A: EmbreeApi>() -> Result<String> {
    Ok(Device::<A>::shared()?.version())
}

/// Whether a library of `RTC_VERSION` `library` is of the release (major.minor) of headers of
/// `header`: Embree changes records and signatures only between minor versions (4.3 appended
/// `instPrimID` to every hit), never in a patch release, so only a patch may differ.
fn same_release(library: isize, header: isize) -> bool {
    library / 100 == header / 100
}

/// `RTC_VERSION` 31305 as "3.13.5".
fn dotted(version: isize) -> String {
    format!(
        "{}.{}.{}",
        version / 10000,
        version / 100 % 100,
        version % 100
    )
}

/// Embree's error callback: called from any thread inside an Embree call; must not unwind.
unsafe extern "C" fn record_error(
    log: *mut c_void,
    code: ffi::RTCError::Type,
    message: *const c_char,
) {
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated message valid for the call.
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    // SAFETY: `log` is the ErrorLog registered in `Device::new`, alive as long as the device.
    let log = unsafe { &*(log as *const ErrorLog) };
    log.lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(format!("{} ({text})", error_name(code)));
}

fn error_name(code: ffi::RTCError::Type) -> String {
    use ffi::RTCError::*;
    match code {
        RTC_ERROR_NONE => "no error code".into(),
        RTC_ERROR_UNKNOWN => "unknown error".into(),
        RTC_ERROR_INVALID_ARGUMENT => "invalid argument".into(),
        RTC_ERROR_INVALID_OPERATION => "invalid operation".into(),
        RTC_ERROR_OUT_OF_MEMORY => "out of memory".into(),
        RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU".into(),
        RTC_ERROR_CANCELLED => "cancelled".into(),
        other => format!("error code {other}"),
    }
}

/// The device configurations a test runs Embree at: the machine's own ISA, then each lower one it
/// can run (on x86-64; elsewhere its own only).
#[cfg(test)]
pub fn test_isas() -> Vec<Option<&'static str>> {
    #[allow(unused_mut)]
    let mut isas = vec![None];
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx2") {
            isas.push(Some("isa=avx2"));
        }
        if is_x86_feature_detected!("sse4.2") {
            isas.push(Some("isa=sse4.2"));
        }
    }
    isas
}

#[cfg(test)]
mod tests {
    use super::*;
    use ffi::RTCDeviceProperty::*;

    #[test]
    fn an_isa_embree_does_not_know_is_a_usage_error() {
        assert!(check_isa("isa=avx2").is_ok());
        assert!(check_isa("threads=1, max_isa = sse4.2").is_ok());
        assert!(check_isa("verbose=1").is_ok());
        let err = check_isa("isa=bogus").unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("RAYLAB_EMBREE_CONFIG"), "{err}");
    }

    #[test]
    fn only_a_patch_release_may_differ_from_the_headers() {
        assert!(same_release(31305, 31305));
        assert!(same_release(40400, 40401), "4.4.0 library, 4.4.1 headers");
        assert!(
            !same_release(40400, 40200),
            "4.3 appended instPrimID to the hit"
        );
        assert!(!same_release(40100, 40200), "older than the headers");
        assert!(!same_release(31305, 40200), "another major version");
        assert!(!same_release(50000, 40200));
        assert_eq!(dotted(31305), "3.13.5");
        assert_eq!(dotted(40400), "4.4.0");
    }

    #[test]
    fn version_is_embree_3() {
        let v = version::<Embree3>().unwrap();
        assert!(v.starts_with("3."), "{v}");
        assert_eq!(
            Device::<Embree3>::shared()
                .unwrap()
                .property(RTC_DEVICE_PROPERTY_VERSION),
            ffi::RTC_VERSION as isize,
            "the library is the version of the header we were compiled against"
        );
    }

    #[test]
    fn library_features_the_tracers_rely_on() {
        let d = Device::<Embree3>::shared().unwrap();
        // Masks compiled in: rays carry mask = 0xFFFFFFFF or they would miss every geometry.
        assert_eq!(d.property(RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED), 1);
        // Both faces hit, as in our watertight test.
        assert_eq!(d.property(RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED), 0);
        assert_eq!(d.property(RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED), 1);
        assert_eq!(
            d.property(RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED),
            1
        );
    }

    #[test]
    fn errors_reported_by_embree_become_runtime_errors() {
        let d = Device::<Embree3>::new().unwrap();
        // SAFETY: a device and an out-of-range property value: Embree reports invalid argument.
        unsafe { ffi::rtcGetDeviceProperty(d.raw(), 9999) };
        let err = d.check("reading property 9999").unwrap_err();
        assert!(matches!(err, Error::Runtime(_)));
        assert!(err.to_string().contains("invalid argument"), "{err}");
        // The log was cleared.
        assert!(d.check("nothing").is_ok());
    }
}
