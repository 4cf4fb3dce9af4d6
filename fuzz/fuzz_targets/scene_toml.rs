//! Scene TOML: parsed, its base checked, and applied to a small scene with two materials.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use raylab::scene::loaders::parse_obj;
use raylab::scene::scene_file::SceneFile;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data).into_owned();
    let Ok(file) = SceneFile::parse(Path::new("fuzz.toml"), text) else {
        return;
    };
    let _ = file.base();
    let mut scene = parse_obj(
        Path::new("base.obj"),
        b"mtllib m.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        &|_| Ok(b"newmtl red\nKd 1 0 0\n".to_vec()),
    )
    .expect("the base scene loads");
    let _ = file.apply(&mut scene);
});
