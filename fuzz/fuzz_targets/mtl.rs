#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::parse_mtl;

fuzz_target!(|data: &[u8]| {
    let _ = parse_mtl(Path::new("fuzz.mtl"), data);
});
