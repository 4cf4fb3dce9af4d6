//! OBJ; every `mtllib` resolves to one small library, so materials are exercised too.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::parse_obj;

const LIBRARY: &[u8] = b"newmtl red\nKd 1 0 0\nnewmtl glass\nNi 1.5\nd 0.1\n";

fuzz_target!(|data: &[u8]| {
    let _ = parse_obj(Path::new("fuzz.obj"), data, &|_| Ok(LIBRARY.to_vec()));
});
