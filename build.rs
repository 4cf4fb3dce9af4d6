//! Generates Rust bindings for Embree 3 (`<embree3/rtcore.h>`) with bindgen and links `embree3`.
//! When the header or libclang is missing the build stops with one line naming what to install.

use std::env;
use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::process::exit;

const INSTALL_HINT: &str = "apt-get install libembree-dev libclang-dev";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-lib=dylib=embree3");

    let builder = bindgen::Builder::default()
        .header_contents("embree_wrapper.h", "#include <embree3/rtcore.h>\n")
        // Only Embree's own items: no libc or compiler types beyond what its signatures need.
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        // Flag enums are combined with `|` (and RTC_INTERSECT_CONTEXT_FLAG_NONE == INCOHERENT == 0,
        // which a Rust enum could not hold twice), so they become bit sets.
        .bitfield_enum("RTC.*Flags")
        // Other enums become modules of constants: Embree may hand back values (errors, device
        // properties) that a Rust enum would make undefined behaviour.
        .default_enum_style(bindgen::EnumVariation::ModuleConsts)
        .derive_default(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));

    // libclang is loaded at run time and bindgen panics when it is absent; keep that panic quiet so
    // the one line below is all the user reads. (The builder is consumed, so no state a panic
    // interrupted is seen again: asserting unwind safety is sound.)
    std::panic::set_hook(Box::new(|_| {}));
    let generated = std::panic::catch_unwind(AssertUnwindSafe(move || builder.generate()));
    let _ = std::panic::take_hook();

    let bindings = match generated {
        Ok(Ok(bindings)) => bindings,
        // libclang has already printed its own diagnostic (e.g. "file not found") just above.
        Ok(Err(_)) => fail("cannot read <embree3/rtcore.h>"),
        Err(_) => fail("cannot load libclang"),
    };
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("embree3.rs");
    if let Err(err) = bindings.write_to_file(&out) {
        fail(&format!("cannot write {}: {err}", out.display()));
    }
}

fn fail(what: &str) -> ! {
    eprintln!(
        "raylab needs Embree 3 and libclang to build: {what}; install them with `{INSTALL_HINT}`"
    );
    exit(1);
}
