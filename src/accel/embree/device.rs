//! The Embree device: owns Embree's build threads and reports errors. One device per Embree
//! version serves the whole process (`Device::shared`), since creating one starts a thread pool;
//! scenes keep it alive.

use std::ffi::{c_char, c_void, CStr};
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
    api: PhantomData<A>,
}

// SAFETY: Embree's device API is thread-safe; the error log behind the callback is a Mutex.
unsafe impl<A: EmbreeApi> Send for Device<A> {}
unsafe impl<A: EmbreeApi> Sync for Device<A> {}

impl<A: EmbreeApi> Device<A> {
    /// A new device with Embree's default configuration (all hardware threads for builds), once
    /// the library is checked to be the major version of our headers and at least as new.
    pub fn new() -> Result<Self> {
        A::load()?;
        // SAFETY: a null config string selects the defaults.
        let raw = unsafe { A::new_device(ptr::null()) };
        if raw.is_null() {
            // SAFETY: with a null device Embree reports the error of device creation.
            let code = unsafe { A::device_error(ptr::null_mut()) };
            return Err(Error::runtime(format!(
                "{} could not create a device: {}",
                A::NAME,
                error_name(code)
            )));
        }
        let device = Device {
            raw,
            errors: Box::default(),
            api: PhantomData,
        };
        let log: *const ErrorLog = &*device.errors;
        // SAFETY: the log outlives the device: it is dropped after rtcReleaseDevice in Drop.
        unsafe { A::set_device_error_function(raw, Some(record_error), log as *mut c_void) };
        let library = device.property(ffi::RTCDeviceProperty::RTC_DEVICE_PROPERTY_VERSION);
        if !version_fits(library, A::HEADER_VERSION) {
            return Err(Error::runtime(format!(
                "{} library {} does not fit the headers raylab was built with ({})",
                A::NAME,
                device.version(),
                dotted(A::HEADER_VERSION)
            )));
        }
        Ok(device)
    }

    /// The process-wide device of this version, created on first use.
    pub fn shared() -> Result<Arc<Self>> {
        let mut slot = A::shared_device()
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(device) = &*slot {
            return Ok(device.clone());
        }
        let device = Arc::new(Device::new()?);
        *slot = Some(device.clone());
        Ok(device)
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

/// The Embree library version, via the shared device.
pub fn version<A: EmbreeApi>() -> Result<String> {
    Ok(Device::<A>::shared()?.version())
}

/// Whether a library of `RTC_VERSION` `library` serves code built against headers of `header`:
/// the same major version, and not older (a newer minor version keeps the API; what it appends
/// to the records is what `api::Padded` makes room for).
fn version_fits(library: isize, header: isize) -> bool {
    library / 10000 == header / 10000 && library >= header
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

#[cfg(test)]
mod tests {
    use super::*;
    use ffi::RTCDeviceProperty::*;

    #[test]
    fn versions_fit_same_major_not_older() {
        assert!(version_fits(31305, 31305));
        assert!(version_fits(40400, 40200));
        assert!(!version_fits(40100, 40200), "older than the headers");
        assert!(!version_fits(31305, 40200), "another major version");
        assert!(!version_fits(50000, 40200));
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
