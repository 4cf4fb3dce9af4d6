//! AFF, evaluated at its first and last frame. `inc.aff` holds a mesh under a transform,
//! `self.aff` includes itself; other includes are missing.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::{parse_aff, Files, LoadOptions};

const INCLUDE: &[u8] = b"m vertices 3\n0 0 0\n1 0 0\n0 1 0\ntriangles 1\n0 1 2\n\
xs 1 1 1 0 0 1 0 0 0 -3\n{\np 3\n0 0 0\n1 0 0\n0 1 0\n}\n";

fuzz_target!(|data: &[u8]| {
    let files: Files = &|path| match path.to_str() {
        Some("inc.aff") => Ok(INCLUDE.to_vec()),
        Some("self.aff") => Ok(b"i 0 self.aff\n".to_vec()),
        _ => Err(std::io::ErrorKind::NotFound.into()),
    };
    if let Ok(scene) = parse_aff(Path::new("main.aff"), data, &LoadOptions::default(), files) {
        scene.frame(0, 2);
        scene.frame(1, 2);
    }
});
