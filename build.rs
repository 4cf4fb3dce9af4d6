//! Generates Rust bindings for Embree 3 (`<embree3/rtcore.h>`) with bindgen and links `embree3`.
//! When the header or libclang is missing the build stops with one line naming what to install.
//!
//! With the feature `embree4` (on by default) it also generates bindings for Embree 4 from the
//! cache `.ci/fetch-embree4` fills ($RAYLAB_EMBREE4_DIR or ~/.cache/raylab/embree4) and sets the
//! cfg `embree4`. Embree 4 exports the same C symbols as Embree 3, so it cannot be linked beside
//! it: raylab loads it at run time from the absolute path recorded here (`accel::embree::v4`).
//! Without the cache the build goes on with Embree 3 only, saying so in one warning.
//!
//! With the feature `tinybvh` (on by default) it compiles raylab's C++ shim over tinybvh
//! (`src/accel/tinybvh/shim.cpp`) against the `tiny_bvh.h` of the cache `.ci/fetch-tinybvh` fills
//! ($RAYLAB_TINYBVH_DIR or ~/.cache/raylab/tinybvh), for the CPU the crate is compiled for
//! (`-march` = rustc's `target-cpu`, `native` by `.cargo/config.toml`; its 8-wide layout needs
//! AVX2 + FMA; results are per machine anyway), and sets the cfg `tinybvh`. Without the cache or
//! a C++ compiler the build goes on without the tinybvh tracers, saying so in one warning.

use std::env;
use std::fs;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::process::exit;

const INSTALL_HINT: &str = "apt-get install libembree-dev libclang-dev";

/// The Embree 4 functions raylab calls: the bindings' loader requires every one of them.
const EMBREE4_FUNCTIONS: &str = "rtc(NewDevice|ReleaseDevice|GetDeviceError|SetDeviceErrorFunction\
|GetDeviceProperty|NewScene|SetSceneFlags|SetSceneBuildQuality|CommitScene|ReleaseScene\
|NewGeometry|SetGeometryBuildQuality|SetGeometryTimeStepCount|SetNewGeometryBuffer\
|GetGeometryBufferData|UpdateGeometryBuffer|CommitGeometry|AttachGeometry|ReleaseGeometry\
|Intersect(1|4|8|16)|Occluded(1|4|8|16))";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo::rustc-check-cfg=cfg(embree4)");
    println!("cargo::rustc-check-cfg=cfg(tinybvh)");
    println!("cargo:rustc-link-lib=dylib=embree3");
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));

    let embree3 = builder("#include <embree3/rtcore.h>\n", "rtc.*");
    match generate(embree3) {
        Ok(bindings) => write(bindings, &out.join("embree3.rs")),
        Err(what) => fail(&format!("{what} <embree3/rtcore.h>")),
    }

    if env::var_os("CARGO_FEATURE_EMBREE4").is_some() {
        match embree4(&out) {
            Ok(()) => println!("cargo:rustc-cfg=embree4"),
            Err(why) => println!(
                "cargo:warning=Embree 4 is off ({why}): raylab builds with Embree 3 only; \
                 `bash .ci/fetch-embree4` fetches it"
            ),
        }
    }

    if env::var_os("CARGO_FEATURE_TINYBVH").is_some() {
        match tinybvh() {
            Ok(()) => println!("cargo:rustc-cfg=tinybvh"),
            Err(why) => println!(
                "cargo:warning=tinybvh is off ({why}): raylab builds without the tinybvh tracers; \
                 `bash .ci/fetch-tinybvh` fetches it (and a C++ compiler builds it)"
            ),
        }
    }
}

/// The shim over the cache's `tiny_bvh.h`, compiled and linked statically.
fn tinybvh() -> Result<(), String> {
    const SHIM: &str = "src/accel/tinybvh/shim.cpp";
    println!("cargo:rerun-if-env-changed=RAYLAB_TINYBVH_DIR");
    println!("cargo:rerun-if-changed={SHIM}");
    let dir = match env::var_os("RAYLAB_TINYBVH_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env::var_os("HOME").ok_or("no HOME to find its cache in")?)
            .join(".cache/raylab/tinybvh"),
    };
    let source = fs::read_to_string(dir.join("SOURCE"))
        .map_err(|_| format!("no tinybvh cache in {}", dir.display()))?;
    println!("cargo:rerun-if-changed={}", dir.display());
    cc::Build::new()
        .cpp(true)
        .std("c++20")
        .file(SHIM)
        .include(dir.join("include"))
        .flag(format!("-march={}", target_cpu()))
        // tiny_bvh.h's own notes (e.g. on SIMD it falls back from) are not raylab's warnings.
        .warnings(false)
        .cargo_warnings(false)
        .try_compile("raylab_tinybvh")
        .map_err(|e| format!("cannot compile {SHIM}: {e}"))?;
    println!("cargo:rerun-if-env-changed=CARGO_ENCODED_RUSTFLAGS");
    println!("cargo:rustc-env=RAYLAB_TINYBVH_SOURCE={}", source.trim());
    println!("cargo:rustc-env=RAYLAB_TINYBVH_MARCH={}", target_cpu());
    Ok(())
}

/// rustc's `-C target-cpu` of this build (`native` unless the flags say otherwise), so the shim
/// is compiled for the same CPU as the crate: `native` for a benchmark, `x86-64-v3` (AVX2) for a
/// run under valgrind, which has no AVX-512.
fn target_cpu() -> String {
    let flags = env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let flags: Vec<&str> = flags.split('\x1f').collect();
    let mut cpu = "native".to_string();
    for (i, flag) in flags.iter().enumerate() {
        let value = match flag.strip_prefix("-C") {
            Some("") => flags.get(i + 1).copied().unwrap_or(""),
            Some(rest) => rest,
            None => continue,
        };
        if let Some(name) = value.strip_prefix("target-cpu=") {
            cpu = name.to_string();
        }
    }
    cpu
}

/// Bindings for the Embree 4 headers of the cache, loaded at run time from its library.
fn embree4(out: &Path) -> Result<(), String> {
    println!("cargo:rerun-if-env-changed=RAYLAB_EMBREE4_DIR");
    let dir = match env::var_os("RAYLAB_EMBREE4_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env::var_os("HOME").ok_or("no HOME to find its cache in")?)
            .join(".cache/raylab/embree4"),
    };
    let source = fs::read_to_string(dir.join("SOURCE"))
        .map_err(|_| format!("no Embree 4 cache in {}", dir.display()))?;
    println!("cargo:rerun-if-changed={}", dir.display());
    let library = fs::read_dir(dir.join("lib"))
        .map_err(|e| format!("{}: {e}", dir.join("lib").display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .find(|path| {
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            name.starts_with("libembree4") && name.ends_with(".so.4")
        })
        .ok_or_else(|| format!("no libembree4*.so.4 in {}", dir.join("lib").display()))?;
    let include = dir.join("include");
    let bindings = builder("#include <embree4/rtcore.h>\n", EMBREE4_FUNCTIONS)
        .clang_arg(format!("-I{}", include.display()))
        // Loaded with dlopen, every function checked present when the library is opened.
        .dynamic_library_name("Embree4Library")
        .dynamic_link_require_all(true);
    let bindings = generate(bindings).map_err(|what| format!("{what} {}", include.display()))?;
    write(bindings, &out.join("embree4.rs"));
    println!(
        "cargo:rustc-env=RAYLAB_EMBREE4_LIBRARY={}",
        library.canonicalize().unwrap_or(library).display()
    );
    println!("cargo:rustc-env=RAYLAB_EMBREE4_SOURCE={}", source.trim());
    Ok(())
}

/// A bindgen builder for `header` and the functions matching `functions`.
fn builder(header: &str, functions: &str) -> bindgen::Builder {
    bindgen::Builder::default()
        .header_contents("embree_wrapper.h", header)
        // Only Embree's own items: no libc or compiler types beyond what its signatures need.
        .allowlist_function(functions)
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        // Flag enums are combined with `|` (and RTC_INTERSECT_CONTEXT_FLAG_NONE == INCOHERENT == 0,
        // which a Rust enum could not hold twice), so they become bit sets.
        .bitfield_enum("RTC.*Flags")
        // Other enums become modules of constants: Embree may hand back values (errors, device
        // properties) that a Rust enum would make undefined behaviour.
        .default_enum_style(bindgen::EnumVariation::ModuleConsts)
        .derive_default(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
}

/// The bindings, or what went wrong ("cannot read", "cannot load libclang").
fn generate(builder: bindgen::Builder) -> Result<bindgen::Bindings, &'static str> {
    // libclang is loaded at run time and bindgen panics when it is absent; keep that panic quiet so
    // the one line of the caller is all the user reads. (The builder is consumed, so no state a
    // panic interrupted is seen again: asserting unwind safety is sound.)
    std::panic::set_hook(Box::new(|_| {}));
    let generated = std::panic::catch_unwind(AssertUnwindSafe(move || builder.generate()));
    let _ = std::panic::take_hook();
    match generated {
        Ok(Ok(bindings)) => Ok(bindings),
        // libclang has already printed its own diagnostic (e.g. "file not found") just above.
        Ok(Err(_)) => Err("cannot read"),
        Err(_) => Err("cannot load libclang to read"),
    }
}

fn write(bindings: bindgen::Bindings, path: &Path) {
    if let Err(err) = bindings.write_to_file(path) {
        fail(&format!("cannot write {}: {err}", path.display()));
    }
}

fn fail(what: &str) -> ! {
    eprintln!(
        "raylab needs Embree 3 and libclang to build: {what}; install them with `{INSTALL_HINT}`"
    );
    exit(1);
}
