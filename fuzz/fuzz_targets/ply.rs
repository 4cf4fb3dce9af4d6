//! PLY: ASCII or binary, and gzip-compressed when the input starts with gzip's magic bytes.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::parse_ply;

fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(&[0x1f, 0x8b]) {
        "fuzz.ply.gz"
    } else {
        "fuzz.ply"
    };
    let _ = parse_ply(Path::new(name), data);
});
