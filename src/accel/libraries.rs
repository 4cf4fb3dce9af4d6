//! The production libraries raylab measures against, one row each: the name meta.json records its
//! version under, the build parameters of its structures, the cfg that builds it in, what to do
//! when a build lacks it, and its version as this build runs it. A new library is a folder under
//! `accel/` for its structure, a row here, and its tracers in `tracers::registry` (README,
//! *Adding a baseline library*).

use crate::accel::embree::{self, Embree3, EmbreeConfig};
use crate::accel::ObvhsQuality;

pub struct Library {
    /// Its key in meta.json's `versions`.
    pub name: &'static str,
    /// The parameters its structures are built with (`AccelKind::params`).
    pub params: &'static [&'static str],
    /// The cfg `build.rs` sets when it builds the library in; `None`: every build has it (a
    /// Rust dependency, or a system library the build requires).
    pub cfg: Option<&'static str>,
    /// Whether this build has it.
    pub built: bool,
    /// What to do to get it into a build without it.
    pub hint: &'static str,
    /// Its version as this build runs it (asked of the library at run time where it can say),
    /// or why this build has none.
    pub version: fn() -> String,
}

pub const LIBRARIES: &[Library] = &[
    Library {
        name: "embree",
        params: EmbreeConfig::PARAMS,
        cfg: None,
        built: true,
        hint: "apt-get install libembree-dev libclang-dev",
        version: embree3_version,
    },
    Library {
        name: "embree4",
        params: EmbreeConfig::PARAMS,
        cfg: Some("embree4"),
        built: embree::EMBREE4_BUILT,
        hint: embree::EMBREE4_HINT,
        version: embree4_version,
    },
    Library {
        name: "obvhs",
        params: ObvhsQuality::PARAMS,
        cfg: None,
        built: true,
        hint: "a dependency in Cargo.toml",
        version: obvhs_version,
    },
    Library {
        name: "tinybvh",
        params: TINYBVH_PARAMS,
        cfg: Some("tinybvh"),
        built: TINYBVH_BUILT,
        hint: TINYBVH_HINT,
        version: tinybvh_version,
    },
];

/// Whether this build has the tinybvh tracers (`build.rs` compiled the shim over the header of
/// the cache `.ci/fetch-tinybvh` fills).
pub const TINYBVH_BUILT: bool = cfg!(tinybvh);

/// What to do to get tinybvh into a build without it.
pub const TINYBVH_HINT: &str = "tinybvh was not built into this raylab: run `bash \
     .ci/fetch-tinybvh`, make sure a C++ compiler (g++) is installed, and rebuild (with the \
     default feature `tinybvh`)";

#[cfg(tinybvh)]
const TINYBVH_PARAMS: &[&str] = crate::accel::TinyBvhConfig::PARAMS;
#[cfg(not(tinybvh))]
const TINYBVH_PARAMS: &[&str] = &[];

/// The library actually loaded, asked at run time; a build without it says why.
fn embree3_version() -> String {
    embree::version::<Embree3>().unwrap_or_else(|e| format!("unavailable: {e}"))
}

/// The Embree 4 library loaded, the headers it was built against and where both came from; or
/// why this build has none.
#[cfg(embree4)]
fn embree4_version() -> String {
    use crate::accel::embree::{v4, Embree4, EmbreeApi};
    let headers = std::ffi::CStr::from_bytes_with_nul(v4::ffi::RTC_VERSION_STRING)
        .ok()
        .and_then(|c| c.to_str().ok())
        .unwrap_or("?");
    match embree::version::<Embree4>() {
        // `Device::new` refuses a library of another release than the headers.
        Ok(library) => format!("{library} (headers {headers}, its release; {})", v4::SOURCE),
        Err(e) => format!("unavailable: {e} ({} headers {headers})", Embree4::NAME),
    }
}

#[cfg(not(embree4))]
fn embree4_version() -> String {
    format!("not built: {}", embree::EMBREE4_HINT)
}

/// The tinybvh compiled into this build and where its header came from; or why there is none.
fn tinybvh_version() -> String {
    #[cfg(tinybvh)]
    return format!(
        "{} ({}, compiled -march={})",
        crate::accel::tinybvh::version(),
        crate::accel::tinybvh::SOURCE,
        env!("RAYLAB_TINYBVH_MARCH")
    );
    #[cfg(not(tinybvh))]
    format!("not built: {TINYBVH_HINT}")
}

/// obvhs's version in the lock file the binary was built with.
fn obvhs_version() -> String {
    locked_version(CARGO_LOCK, "obvhs").unwrap_or_else(|| "unknown".into())
}

/// The lock file the binary was built with: the exact versions of its dependencies.
const CARGO_LOCK: &str = include_str!("../../Cargo.lock");

/// The locked version of `package`, if it is a dependency.
fn locked_version(lock: &str, package: &str) -> Option<String> {
    let name_line = format!("name = \"{package}\"");
    let mut lines = lock.lines();
    lines.find(|l| l.trim() == name_line)?;
    let version = lines
        .next()?
        .trim()
        .strip_prefix("version = \"")?
        .strip_suffix('"')?;
    Some(version.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locked_versions_come_from_the_lock_file() {
        let lock = "[[package]]\nname = \"obvhs\"\nversion = \"0.4.0\"\n\n[[package]]\nname = \"obvhs-extra\"\nversion = \"9\"\n";
        assert_eq!(locked_version(lock, "obvhs").as_deref(), Some("0.4.0"));
        assert_eq!(locked_version(lock, "glam"), None);
        assert_eq!(obvhs_version(), "0.4.0");
    }

    /// Every row names a library once, and a library a build lacks says why in its version.
    #[test]
    fn each_library_is_one_row_and_a_missing_one_says_why() {
        let mut names: Vec<&str> = LIBRARIES.iter().map(|l| l.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), LIBRARIES.len());
        for library in LIBRARIES {
            let version = (library.version)();
            assert_eq!(
                !library.built,
                version.starts_with("not built: "),
                "{version}"
            );
            assert!(library.built || library.cfg.is_some(), "{}", library.name);
        }
    }
}
