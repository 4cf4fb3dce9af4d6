#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::{parse_nff, LoadOptions};

fuzz_target!(|data: &[u8]| {
    let _ = parse_nff(Path::new("fuzz.nff"), data, &LoadOptions::default());
});
