#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::experiment::Experiment;

fuzz_target!(|data: &[u8]| {
    let _ = Experiment::parse(Path::new("fuzz.toml"), &String::from_utf8_lossy(data));
});
