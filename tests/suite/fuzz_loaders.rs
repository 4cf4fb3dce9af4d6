//! Seeded, structure-aware fuzzing of every loader: OBJ, MTL, PLY (ASCII, binary, gzip), NFF,
//! AFF, scene TOML and experiment TOML. Each starts from small valid seeds (written here, the
//! repository's `scenes/*.toml` and `experiments/*.toml`, and with `$RAYLAB_SCENES` set the
//! first kilobytes of the shared scene files), mutates them (bit flips, token and line edits,
//! extreme numbers, huge counts, truncation, splicing, deep nesting) and runs the loader on a
//! worker thread. Any panic, any call longer than `HANG`, any call allocating more than
//! `CALL_MEMORY`, and any error that is not one exit-code-2 error naming the file fails the test,
//! with a minimized input ready for a regression test.
//!
//! Budget: `BUDGET` per loader; `RAYLAB_FUZZ_ITERS=n` runs exactly n inputs per loader instead
//! (the long run: `RAYLAB_FUZZ_ITERS=1000000 cargo test --release --test fuzz_loaders --
//! --nocapture`), and `RAYLAB_FUZZ_SEED` changes the sequence.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use raylab::experiment::Experiment;
use raylab::random::SplitMix64;
use raylab::scene::loaders::{
    parse_aff, parse_mtl, parse_nff, parse_obj, parse_ply, Files, LoadOptions,
};
use raylab::scene::scene_file::SceneFile;
use raylab::scene::Scene;
use raylab::Error;

const BUDGET: Duration = Duration::from_secs(2);
const HANG: Duration = Duration::from_secs(2);
const CALL_MEMORY: usize = 64 << 20;
/// Mutated inputs are cut to this length: memory and time must stay bounded by the input, so
/// small inputs show any blowup as clearly as large ones.
const MAX_LEN: usize = 16 << 10;

// ---- Memory: a metering allocator ----------------------------------------------------------

/// Counts the bytes the current thread holds during a loader call and refuses (so the process
/// aborts instead of swapping the machine to death) any call that reaches `HARD_MEMORY`.
struct Metered;

const HARD_MEMORY: usize = 1 << 30;

thread_local! {
    static METERING: Cell<bool> = const { Cell::new(false) };
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

impl Metered {
    /// Accounts for `grow` more bytes; false when the call would pass `HARD_MEMORY`.
    fn admit(grow: isize) -> bool {
        let metering = METERING.try_with(Cell::get).unwrap_or(false);
        if !metering {
            return true;
        }
        let live = LIVE.with(Cell::get) + grow;
        if live > HARD_MEMORY as isize {
            // Printing allocates: stop metering first.
            METERING.with(|m| m.set(false));
            eprintln!("fuzz: a loader call asked for {live} bytes; refusing (the process aborts)");
            return false;
        }
        LIVE.with(|l| l.set(live));
        PEAK.with(|p| p.set(p.get().max(live)));
        true
    }

    fn release(size: usize) {
        if METERING.try_with(Cell::get).unwrap_or(false) {
            LIVE.with(|l| l.set(l.get() - size as isize));
        }
    }
}

unsafe impl GlobalAlloc for Metered {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !Self::admit(layout.size() as isize) {
            return std::ptr::null_mut();
        }
        System.alloc(layout)
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !Self::admit(layout.size() as isize) {
            return std::ptr::null_mut();
        }
        System.alloc_zeroed(layout)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        Self::release(layout.size());
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if !Self::admit(new_size as isize - layout.size() as isize) {
            return std::ptr::null_mut();
        }
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: Metered = Metered;

/// Runs `f` and returns its result with the most bytes it held at once.
fn metered<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LIVE.with(|l| l.set(0));
    PEAK.with(|p| p.set(0));
    METERING.with(|m| m.set(true));
    let out = f();
    METERING.with(|m| m.set(false));
    (out, PEAK.with(Cell::get).max(0) as usize)
}

// ---- Targets ---------------------------------------------------------------------------------

/// What one loader call did with an input.
enum Verdict {
    Accepted,
    Refused,
    /// A broken contract: an error without the file's name or with the wrong exit code, or a
    /// scene whose material ids point nowhere.
    Broken(String),
}

struct Target {
    name: &'static str,
    seeds: Vec<Vec<u8>>,
    /// Extra words to insert: the format's keywords beyond those in the seeds.
    keywords: &'static [&'static str],
    /// Text that opens and closes one level of nesting, when the format nests.
    nest: Option<(&'static str, &'static str)>,
    /// Turns a mutated input into the loader's bytes (gzip for `.ply.gz`).
    encode: fn(&[u8]) -> Vec<u8>,
    run: fn(&[u8]) -> Verdict,
}

/// Refused is right when the error has exit code 2 and names the file at fault: `file`, or
/// for AFF any file it includes (`file` is then a list of names separated by `|`).
fn verdict_of_error(file: &str, err: Error) -> Verdict {
    let text = err.to_string();
    if err.exit_code() != 2 || !file.split('|').any(|f| text.contains(f)) {
        Verdict::Broken(format!(
            "error without the file name or exit code 2: {text}"
        ))
    } else {
        Verdict::Refused
    }
}

fn verdict_of_scene(file: &str, result: raylab::Result<Scene>) -> Verdict {
    match result {
        Ok(scene) => {
            let ids = &scene.mesh.material_ids;
            if ids.len() != scene.triangle_count()
                || ids.iter().any(|&m| m as usize >= scene.materials.len())
            {
                return Verdict::Broken("material ids do not match the materials".into());
            }
            // Animated scenes must also evaluate: their first and last frames.
            if scene.is_animated() || scene.camera_path.is_some() {
                for index in [0, 2] {
                    let frame = scene.frame(index, 3);
                    if frame.mesh.len() != scene.triangle_count() {
                        return Verdict::Broken("a frame changes the triangle count".into());
                    }
                }
            }
            Verdict::Accepted
        }
        Err(e) => verdict_of_error(file, e),
    }
}

fn identity(bytes: &[u8]) -> Vec<u8> {
    bytes.to_vec()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(bytes).unwrap();
    gz.finish().unwrap()
}

const OBJ_LIBRARY: &[u8] =
    b"newmtl red\nKd 1 0 0\nnewmtl glass\nNi 1.5\nd 0.1\nillum 7\nKs 1 1 1\n";

fn run_obj(bytes: &[u8]) -> Verdict {
    // `m.mtl` is a real library; any other name an empty one (a missing one only warns).
    let files: Files = &|path: &Path| {
        Ok(if path == Path::new("m.mtl") {
            OBJ_LIBRARY.to_vec()
        } else {
            Vec::new()
        })
    };
    verdict_of_scene("fuzz.obj", parse_obj(Path::new("fuzz.obj"), bytes, files))
}

fn run_mtl(bytes: &[u8]) -> Verdict {
    match parse_mtl(Path::new("fuzz.mtl"), bytes) {
        Ok(_) => Verdict::Accepted,
        Err(e) => verdict_of_error("fuzz.mtl", e),
    }
}

fn run_ply(bytes: &[u8]) -> Verdict {
    verdict_of_scene("fuzz.ply", parse_ply(Path::new("fuzz.ply"), bytes))
}

fn run_ply_gz(bytes: &[u8]) -> Verdict {
    verdict_of_scene("fuzz.ply.gz", parse_ply(Path::new("fuzz.ply.gz"), bytes))
}

fn run_nff(bytes: &[u8]) -> Verdict {
    let options = LoadOptions::default();
    verdict_of_scene(
        "fuzz.nff",
        parse_nff(Path::new("fuzz.nff"), bytes, &options),
    )
}

const AFF_INCLUDE: &[u8] =
    b"fm 0 0 0 0.9 0.1 0.1 0 0 0 1 0.5 1.33\nm vertices 3\n0 0 0\n1 0 0\n0 1 0\n\
triangles 1\n0 1 2\nxs 1 1 1 0 0 1 0 0 0 -3\n{\np 3\n0 0 0\n1 0 0\n0 1 0\n}\n";

fn run_aff(bytes: &[u8]) -> Verdict {
    // `inc.aff` holds a mesh, `self.aff` includes itself, `main.aff` is the input again (a
    // cycle); anything else is missing.
    let input = bytes.to_vec();
    let files: Files = &move |path: &Path| match path.to_str() {
        Some("inc.aff") => Ok(AFF_INCLUDE.to_vec()),
        Some("self.aff") => Ok(b"i 0 self.aff\n".to_vec()),
        Some("main.aff") => Ok(input.clone()),
        _ => Err(std::io::ErrorKind::NotFound.into()),
    };
    let options = LoadOptions::default();
    verdict_of_scene(
        "main.aff|inc.aff|self.aff",
        parse_aff(Path::new("main.aff"), bytes, &options, files),
    )
}

fn run_scene_toml(bytes: &[u8]) -> Verdict {
    let file = "fuzz-scene.toml";
    let text = String::from_utf8_lossy(bytes).into_owned();
    let parsed = SceneFile::parse(Path::new(file), text).and_then(|f| {
        f.base()?;
        // A scene with two materials and a triangle to apply the file to.
        let mut scene = parse_obj(
            Path::new("base.obj"),
            b"mtllib m.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            &|_| Ok(OBJ_LIBRARY.to_vec()),
        )?;
        f.apply(&mut scene)?;
        Ok(scene)
    });
    verdict_of_scene(file, parsed)
}

fn run_experiment_toml(bytes: &[u8]) -> Verdict {
    let file = "fuzz-experiment.toml";
    let text = String::from_utf8_lossy(bytes);
    match Experiment::parse(Path::new(file), &text) {
        Ok(_) => Verdict::Accepted,
        Err(e) => verdict_of_error(file, e),
    }
}

// ---- Seeds -------------------------------------------------------------------------------------

const OBJ_SEEDS: &[&str] = &[
    "mtllib m.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n\
     vn 0 0 1\nusemtl red\ng one\ns off\nf 1/1/1 2/2/1 3/3/1\nf 1//1 3//1 4//1\nusemtl glass\n\
     f -4 -3 -2 -1\n",
    "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 1.5 0\nv 1.5 1.5 0\nv 1.5 0.5 0\nf 1 2 3 4 5 6 7\n\
     l 1 2\np 3\n",
    "v 0 0 0 1\nv 1 0 0 0.5 0.5 0.5\nv 0 1 0\nf 1/1 2/2 3/3\nusemtl nowhere\nf 3 2 1\n",
];

const MTL_SEEDS: &[&str] = &[
    "# library\nnewmtl red\nKd 0.8 0.1 0.1\nKs 0 0 0\nnewmtl shiny\nKd 0.2\nKs 0.3 0.6 0.9\nNs 50\n\
     newmtl mirror\nKs 0.9 0.9 0.9\nillum 3\nnewmtl glass\nKa 0 0 0\nNi 1.5\nd -halo 0.25\n\
     newmtl lamp\nKe 4 4 2\nnewmtl veil\nTr 0.5\nmap_Kd veil.ppm\n",
];

const PLY_HEADER: &str =
    "ply\nformat {format} 1.0\ncomment seed\nobj_info none\nelement vertex 5\n\
    property uchar flag\nproperty float x\nproperty double y\nproperty float z\nelement face 2\n\
    property int tag\nproperty list uchar uint vertex_indices\nelement edge 1\n\
    property list ushort short pair\nend_header\n";

const SQUARE: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [2.0, 0.0, 0.0],
    [2.0, 2.0, 0.0],
    [0.0, 2.0, 0.0],
    [1.0, 1.0, 5.0],
];

fn ply_ascii() -> Vec<u8> {
    let mut text = PLY_HEADER.replace("{format}", "ascii");
    for v in SQUARE {
        text += &format!("7 {} {} {}\n", v[0], v[1], v[2]);
    }
    text += "-1 3 0 1 4\n-1 4 0 1 2 3\n2 0 1\n";
    text.into_bytes()
}

fn ply_binary(big_endian: bool) -> Vec<u8> {
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = PLY_HEADER.replace("{format}", format).into_bytes();
    let mut put = |bytes: &[u8]| {
        let mut b = bytes.to_vec();
        if big_endian {
            b.reverse();
        }
        out.extend_from_slice(&b);
    };
    for v in SQUARE {
        put(&[7]);
        put(&v[0].to_le_bytes());
        put(&f64::from(v[1]).to_le_bytes());
        put(&v[2].to_le_bytes());
    }
    for face in [&[0u32, 1, 4][..], &[0, 1, 2, 3]] {
        put(&(-1i32).to_le_bytes());
        put(&[face.len() as u8]);
        for &i in face {
            put(&i.to_le_bytes());
        }
    }
    put(&2u16.to_le_bytes());
    put(&0i16.to_le_bytes());
    put(&1i16.to_le_bytes());
    out
}

const NFF_SEEDS: &[&str] = &[
    "b 0.1 0.2 0.3\nv\nfrom 0 -5 1\nat 0 0 1\nup 0 0 1\nangle 40\n\
     hither 0.1\nresolution 64 48\nl 1 2 3\nl -1 -2 3 0.5 0.25 1\nf 1 0.5 0.25 0.8 0.2 30 0 1\n\
     p 6\n0 0 0\n2 0 0\n2 1 0\n1 1 0\n1 2 0\n0 2 0\nf 0.9 0.9 0.9 0.1 0.5 100 0.7 1.5\npp 3\n\
     0 0 1 0 0 1\n1 0 1 0 0 1\n0 1 1 0 0 1\ns 0 0 5 0.5\nc 0 0 0 0.1 0 0 2 0.1\nc 0 0 0 1 0 0 1 0\n\
     Q 0\n",
];

const AFF_SEEDS: &[&str] = &[
    "% animated\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 50\nhither 0.01\nresolution 80 60\n\
     am 0.3 0.3 0.3\nl 0 5 0 0.2 0.2 0.2\na 0 2 3\nd 1\n\
     fm 0.1 0.1 0.1 0.5 0.6 0.7 0.3 0.3 0.6 40 0 1\ni 0 inc.aff\ni 2 missing.aff\nx mover\n{\n\
     tt wood.ppm\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n}\nxs 2 2 2 0 0 1 90 10 0 0\n{\nx mover\n{\n\
     ttp t.ppm\n0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n}\n}\n\
     tpa 2\n0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n2\n0 0 4 0 0 1\n1 0 4 0 0 1\n0 1 4 0 0 1\n\
     k mover\n{\ntransl 5\n-1 0 0 0 0 0 0\n0 0 0 0 0 0 0\n1 2 0 0 0 0 0\n2 2 4 0 0 0 0\n\
     3 2 4 0 0 0 0\nscale 4\n-1 1 1 1 0 0 0\n0 1 1 1 0 0 0\n2 2 2 2 0 0 0\n3 1 1 1 0 0 0\n}\n\
     k camera\n{\ntransl 4\n-1 0 0 10 0 0 0\n0 0 0 10 0 0 0\n2 0 0 10 0 0 0\n3 0 0 10 0 0 0\n\
     rot 4\n-1 0 1 0 90 0 0 0\n0 0 1 0 90 0 0 0\n2 0 1 0 90 0 0 0\n3 0 1 0 90 0 0 0\n}\n",
    "m vertices 4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\nnormals 4\n0 0 1\n0 0 1\n0 0 1\n0 0 1\n\
     texturecoords 4 floor.ppm\n0 0\n1 0\n1 1\n0 1\ntriangles 2\n0 1 2 0 1 2 0 1 2\n\
     0 2 3 0 2 3 0 2 3\ni 0 self.aff\n",
];

const SCENE_TOML_SEEDS: &[&str] = &[r#"name = "office"
builtin = "room"
size = 2

[camera]
position = [1.0, 2.0, 3.0]
target = [4.0, 2.0, 3.0]
fov = 50.0

[[camera_path]]
time = 0.0

[[camera_path]]
time = 2.5
position = [1.0, 2.0, 8.0]

[[lights]]
type = "point"
position = [5.0, 5.5, 5.0]
intensity = [10.0, 20.0, 30.0]

[[lights]]
type = "quad"
corner = [4.0, 5.9, 4.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
emission = [5.0, 5.0, 5.0]

[materials]
all = "diffuse"
red = { preset = "glass", ior = 1.33 }
"#];

const EXPERIMENT_TOML_SEEDS: &[&str] = &[
    "name = \"t\"\nscenes = [\"room\", { name = \"rings\", size = 2 }]\nrays = [\"primary\"]\n\
     resolution = { width = 8, height = 4 }\ntracers = [\"reference\", \"embree-best\"]\n",
];

/// The repository's files under `dir` whose names end in `suffix`.
fn repository_files(dir: &str, suffix: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.retain(|p| p.to_string_lossy().ends_with(suffix));
    files.sort();
    files.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}

/// The first kilobytes (cut at a line end) of up to 8 files ending in `suffix` under the
/// `$RAYLAB_SCENES` directories, inflated when gzip-compressed; none without it.
fn shared_snippets(suffix: &str) -> Vec<Vec<u8>> {
    const SNIPPET: usize = 4 << 10;
    let Some(roots) = std::env::var_os("RAYLAB_SCENES") else {
        return Vec::new();
    };
    let mut found = Vec::new();
    let mut dirs: Vec<PathBuf> = std::env::split_paths(&roots).collect();
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                dirs.push(path);
            } else if path.to_string_lossy().to_lowercase().ends_with(suffix) {
                found.push(path);
            }
        }
    }
    found.truncate(8);
    found
        .iter()
        .filter_map(|path| {
            let file = std::fs::File::open(path).ok()?;
            let mut head = Vec::new();
            let reader: Box<dyn std::io::Read> = if suffix.ends_with(".gz") {
                Box::new(flate2::read::GzDecoder::new(file))
            } else {
                Box::new(file)
            };
            reader.take(SNIPPET as u64).read_to_end(&mut head).ok()?;
            if let Some(end) = head.iter().rposition(|&b| b == b'\n') {
                head.truncate(end + 1);
            }
            Some(head)
        })
        .collect()
}

fn strings(seeds: &[&str]) -> Vec<Vec<u8>> {
    seeds.iter().map(|s| s.as_bytes().to_vec()).collect()
}

fn target(name: &'static str) -> Target {
    let target = |seeds, keywords, nest, encode, run| Target {
        name,
        seeds,
        keywords,
        nest,
        encode,
        run,
    };
    match name {
        "obj" => target(
            [strings(OBJ_SEEDS), shared_snippets(".obj")].concat(),
            &[
                "mtllib", "m.mtl", "usemtl", "red", "glass", "1/1/1", "1//1", "-1/-1",
            ][..],
            None,
            identity as fn(&[u8]) -> Vec<u8>,
            run_obj as fn(&[u8]) -> Verdict,
        ),
        "mtl" => target(
            [strings(MTL_SEEDS), shared_snippets(".mtl")].concat(),
            &[
                "newmtl", "Kd", "Ks", "Ke", "Ka", "Ns", "Ni", "d", "Tr", "illum", "-halo",
            ],
            None,
            identity,
            run_mtl,
        ),
        "ply" => target(
            [
                vec![ply_ascii(), ply_binary(false), ply_binary(true)],
                shared_snippets(".ply"),
            ]
            .concat(),
            &[
                "element",
                "vertex",
                "face",
                "property",
                "list",
                "char",
                "uchar",
                "short",
                "ushort",
                "int",
                "uint",
                "float",
                "double",
                "int8",
                "uint32",
                "float64",
                "vertex_index",
                "binary_little_endian",
                "binary_big_endian",
                "ascii",
                "end_header",
                "1000000000",
                "4294967295",
            ],
            None,
            identity,
            run_ply,
        ),
        "ply.gz" => target(
            [
                vec![ply_ascii(), ply_binary(false)],
                shared_snippets(".ply.gz"),
            ]
            .concat(),
            &[
                "element",
                "vertex",
                "face",
                "property",
                "list",
                "end_header",
            ],
            None,
            gzip,
            run_ply_gz,
        ),
        "nff" => target(
            [strings(NFF_SEEDS), shared_snippets(".nff")].concat(),
            &[
                "v", "b", "l", "f", "p", "pp", "s", "c", "Q", "from", "at", "up", "angle",
            ],
            None,
            identity,
            run_nff,
        ),
        "aff" => target(
            [strings(AFF_SEEDS), shared_snippets(".aff")].concat(),
            &[
                "fm",
                "am",
                "m",
                "tt",
                "ttp",
                "tpa",
                "i",
                "d",
                "xs",
                "x",
                "k",
                "a",
                "la",
                "{",
                "}",
                "transl",
                "rot",
                "scale",
                "visibility",
                "inc.aff",
                "self.aff",
                "main.aff",
                "camera",
                "mover",
            ],
            Some(("xs 1 1 1 0 0 1 0 0 0 0\n{\n", "}\n")),
            identity,
            run_aff,
        ),
        "scene.toml" => target(
            [
                strings(SCENE_TOML_SEEDS),
                repository_files("scenes", ".toml"),
            ]
            .concat(),
            &[
                "[",
                "]",
                "{",
                "}",
                "=",
                "\"",
                ",",
                "[[lights]]",
                "[camera]",
                "inf",
                "nan",
            ],
            Some(("x = [", "]\n")),
            identity,
            run_scene_toml,
        ),
        "experiment.toml" => target(
            [
                strings(EXPERIMENT_TOML_SEEDS),
                repository_files("experiments", ".toml"),
            ]
            .concat(),
            &[
                "[",
                "]",
                "{",
                "}",
                "=",
                "\"",
                ",",
                "[params]",
                "[[render]]",
                "inf",
                "nan",
            ],
            Some(("p = { q = ", "}\n")),
            identity,
            run_experiment_toml,
        ),
        _ => unreachable!("no target {name}"),
    }
}

// ---- Mutation --------------------------------------------------------------------------------

/// Values that break parsers: extremes, non-finite spellings, off-by-one sizes, huge counts.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "1000000000",
    "1e9",
    "1e38",
    "3.5e38",
    "-3.5e38",
    "1e309",
    "-1e309",
    "1e-45",
    "1e-400",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "infinity",
    "0.5",
    "1.5",
    "-0.0",
    "0x10",
    "1_000",
    "+1",
    ".",
    "-",
    "e",
    "1e",
    "1.",
];

fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

fn pick<'a, T>(rng: &mut SplitMix64, items: &'a [T]) -> &'a T {
    &items[below(rng, items.len())]
}

/// Byte ranges of the whitespace-separated words of `bytes`.
fn words(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, b) in bytes.iter().enumerate() {
        match (b.is_ascii_whitespace(), start) {
            (true, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, bytes.len()));
    }
    out
}

/// Byte ranges of the lines of `bytes`, each with its `\n`.
fn lines(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < bytes.len() {
        out.push((start, bytes.len()));
    }
    out
}

fn splice(out: &mut Vec<u8>, range: (usize, usize), with: &[u8]) {
    out.splice(range.0..range.1, with.iter().copied());
}

struct Mutator<'t> {
    target: &'t Target,
    /// Words of every seed plus the target's keywords and `NUMBERS`.
    dictionary: Vec<Vec<u8>>,
    /// Seed lines, for splicing.
    seed_lines: Vec<Vec<u8>>,
}

impl<'t> Mutator<'t> {
    fn new(target: &'t Target) -> Self {
        let mut dictionary: Vec<Vec<u8>> = target
            .keywords
            .iter()
            .chain(NUMBERS)
            .map(|w| w.as_bytes().to_vec())
            .collect();
        let mut seed_lines = Vec::new();
        for seed in &target.seeds {
            dictionary.extend(words(seed).iter().map(|&(s, e)| seed[s..e].to_vec()));
            seed_lines.extend(lines(seed).iter().map(|&(s, e)| seed[s..e].to_vec()));
        }
        dictionary.sort();
        dictionary.dedup();
        dictionary.retain(|w| w.len() <= 64);
        Mutator {
            target,
            dictionary,
            seed_lines,
        }
    }

    fn mutate(&self, rng: &mut SplitMix64, parent: &[u8]) -> Vec<u8> {
        let mut out = parent.to_vec();
        for _ in 0..1 + below(rng, 4) {
            self.mutate_once(rng, &mut out);
        }
        out.truncate(MAX_LEN);
        out
    }

    fn mutate_once(&self, rng: &mut SplitMix64, out: &mut Vec<u8>) {
        let ws = words(out);
        let ls = lines(out);
        let len = out.len();
        match below(rng, 14) {
            0 if len > 0 => {
                let i = below(rng, len);
                out[i] ^= 1 << below(rng, 8);
            }
            1 if len > 0 => {
                let i = below(rng, len);
                out[i] = *pick(rng, b"\0\xff\x80\n\r\t {}[]\"'=#%/-.,:09eE\\");
            }
            2 if !ws.is_empty() => splice(out, *pick(rng, &ws), b""),
            3 if !ws.is_empty() => {
                let (s, e) = *pick(rng, &ws);
                let word = [&out[s..e], b" "].concat();
                splice(out, (s, s), &word);
            }
            4 => {
                let at = ws.get(below(rng, ws.len() + 1)).map_or(len, |w| w.0);
                let sep: &[u8] = if rng.next_u64().is_multiple_of(2) {
                    b" "
                } else {
                    b"\n"
                };
                let word = [pick(rng, &self.dictionary).as_slice(), sep].concat();
                splice(out, (at, at), &word);
            }
            5 if !ws.is_empty() => {
                // Prefer a word that is a number: counts, indices, coordinates.
                let numeric: Vec<_> = ws
                    .iter()
                    .filter(|&&(s, e)| {
                        std::str::from_utf8(&out[s..e]).is_ok_and(|w| w.parse::<f64>().is_ok())
                    })
                    .copied()
                    .collect();
                let range = *pick(rng, if numeric.is_empty() { &ws } else { &numeric });
                splice(out, range, pick(rng, NUMBERS).as_bytes());
            }
            6 => out.truncate(below(rng, len + 1)),
            7 => {
                let at = ls.get(below(rng, ls.len() + 1)).map_or(len, |l| l.0);
                let line = pick(rng, &self.seed_lines).clone();
                splice(out, (at, at), &line);
            }
            8 if !ls.is_empty() => splice(out, *pick(rng, &ls), b""),
            9 if !ls.is_empty() => {
                let (s, e) = *pick(rng, &ls);
                let line = out[s..e].to_vec();
                let times = 1 + below(rng, 64);
                splice(out, (s, s), &line.repeat(times));
            }
            10 if ls.len() > 1 => {
                let (a, b) = (*pick(rng, &ls), *pick(rng, &ls));
                let (first, second) = if a.0 < b.0 { (a, b) } else { (b, a) };
                if first.1 <= second.0 {
                    let (x, y) = (
                        out[first.0..first.1].to_vec(),
                        out[second.0..second.1].to_vec(),
                    );
                    splice(out, second, &x);
                    splice(out, first, &y);
                }
            }
            11 => {
                if let Some((open, close)) = self.target.nest {
                    let depth = 1 + below(rng, 2000);
                    let at = ls.get(below(rng, ls.len() + 1)).map_or(len, |l| l.0);
                    let text = [open.repeat(depth), close.repeat(depth)].concat();
                    splice(out, (at, at), text.as_bytes());
                }
            }
            12 if !ws.is_empty() => {
                let (s, e) = *pick(rng, &ws);
                let other = *pick(rng, &ws);
                let word = out[other.0..other.1].to_vec();
                splice(out, (s, e), &word);
            }
            13 if len > 0 => {
                // Binary bodies: an extreme 1-, 2-, 4- or 8-byte value anywhere.
                let value = (*pick(rng, &[0u64, u64::MAX, 0x7fff_ffff, 0x8000_0000, 1 << 30]))
                    .to_le_bytes();
                let n = *pick(rng, &[1usize, 2, 4, 8]);
                let at = below(rng, len);
                let end = (at + n).min(len);
                out[at..end].copy_from_slice(&value[..end - at]);
            }
            _ => {}
        }
    }
}

// ---- Running ---------------------------------------------------------------------------------

enum Failure {
    Panic(String),
    Hang,
    Memory(usize),
    Broken(String),
}

impl Failure {
    fn same_kind(&self, other: &Failure) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other)
    }
}

struct Outcome {
    result: Result<bool, Failure>,
    elapsed: Duration,
    memory: usize,
}

thread_local! {
    static LAST_PANIC: Cell<Option<String>> = const { Cell::new(None) };
    static QUIET_PANICS: Cell<bool> = const { Cell::new(false) };
}

/// Panics on fuzz workers are recorded, not printed; other threads keep the default report.
fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if QUIET_PANICS.with(Cell::get) {
                LAST_PANIC.with(|p| p.set(Some(info.to_string())));
            } else {
                default(info);
            }
        }));
    });
}

/// A thread that runs one loader call at a time, so that a call that never returns can be
/// abandoned after `HANG`.
struct Worker {
    jobs: mpsc::Sender<Vec<u8>>,
    outcomes: mpsc::Receiver<(Result<bool, Failure>, Duration, usize)>,
}

impl Worker {
    fn new(run: fn(&[u8]) -> Verdict) -> Worker {
        install_panic_hook();
        let (jobs, job_rx) = mpsc::channel::<Vec<u8>>();
        let (outcome_tx, outcomes) = mpsc::channel();
        std::thread::spawn(move || {
            QUIET_PANICS.with(|q| q.set(true));
            for input in job_rx {
                let start = Instant::now();
                let (result, memory) = metered(|| match std::panic::catch_unwind(|| run(&input)) {
                    Ok(Verdict::Accepted) => Ok(true),
                    Ok(Verdict::Refused) => Ok(false),
                    Ok(Verdict::Broken(why)) => Err(Failure::Broken(why)),
                    Err(_) => Err(Failure::Panic(
                        LAST_PANIC.with(Cell::take).unwrap_or_default(),
                    )),
                });
                let elapsed = start.elapsed();
                let result = match result {
                    Ok(_) if memory > CALL_MEMORY => Err(Failure::Memory(memory)),
                    other => other,
                };
                if outcome_tx.send((result, elapsed, memory)).is_err() {
                    break;
                }
            }
        });
        Worker { jobs, outcomes }
    }

    fn run(&self, input: Vec<u8>) -> Outcome {
        self.jobs.send(input).expect("the fuzz worker stopped");
        match self.outcomes.recv_timeout(HANG) {
            Ok((result, elapsed, memory)) => Outcome {
                result: if elapsed > HANG {
                    Err(Failure::Hang)
                } else {
                    result
                },
                elapsed,
                memory,
            },
            Err(_) => Outcome {
                result: Err(Failure::Hang),
                elapsed: HANG,
                memory: 0,
            },
        }
    }
}

/// The smallest input found (dropping lines, then words, then bytes) that fails like `input`.
fn minimize(target: &Target, input: &[u8], failure: &Failure) -> Vec<u8> {
    let worker = Worker::new(target.run);
    let fails = |candidate: &[u8]| {
        let outcome = worker.run((target.encode)(candidate));
        matches!(outcome.result, Err(f) if f.same_kind(failure))
    };
    let mut best = input.to_vec();
    let mut trials = 0;
    for unit in [lines as fn(&[u8]) -> Vec<(usize, usize)>, words] {
        let mut i = 0;
        while i < unit(&best).len() && trials < 4000 {
            let range = unit(&best)[i];
            let mut candidate = best.clone();
            splice(&mut candidate, range, b"");
            trials += 1;
            if fails(&candidate) {
                best = candidate;
            } else {
                i += 1;
            }
        }
    }
    let mut i = 0;
    while i < best.len() && trials < 8000 {
        let mut candidate = best.clone();
        candidate.remove(i);
        trials += 1;
        if fails(&candidate) {
            best = candidate;
        } else {
            i += 1;
        }
    }
    best
}

fn iterations() -> Option<u64> {
    std::env::var("RAYLAB_FUZZ_ITERS").ok().map(|n| {
        n.parse()
            .unwrap_or_else(|_| panic!("RAYLAB_FUZZ_ITERS={n} is not a count"))
    })
}

fn seed() -> u64 {
    std::env::var("RAYLAB_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(14)
}

/// Fuzzes one target for the budget and fails on the first panic, hang, memory blowup or broken
/// contract, with the minimized input.
fn fuzz(name: &'static str) {
    let target = target(name);
    let mutator = Mutator::new(&target);
    let mut rng = SplitMix64::new(seed() ^ raylab::random::mix64(name.len() as u64));
    let worker = Worker::new(target.run);
    // Inputs the loader accepted: mutating valid files reaches deeper than mutating seeds.
    let mut accepted_pool: Vec<Vec<u8>> = Vec::new();
    let limit = iterations();
    let start = Instant::now();
    let (mut runs, mut accepted) = (0u64, 0u64);
    let (mut slowest, mut most_memory) = (Duration::ZERO, 0usize);
    // The seeds themselves first, unmutated.
    let mut seeds = target.seeds.iter();
    loop {
        let done = match limit {
            Some(n) => runs >= n,
            None => start.elapsed() >= BUDGET,
        };
        if done {
            break;
        }
        let input = match seeds.next() {
            Some(seed) => seed.clone(),
            None => {
                let parent = if accepted_pool.is_empty() || rng.next_u64().is_multiple_of(2) {
                    pick(&mut rng, &target.seeds)
                } else {
                    pick(&mut rng, &accepted_pool)
                };
                mutator.mutate(&mut rng, parent)
            }
        };
        let outcome = worker.run((target.encode)(&input));
        runs += 1;
        slowest = slowest.max(outcome.elapsed);
        most_memory = most_memory.max(outcome.memory);
        match outcome.result {
            Ok(true) => {
                accepted += 1;
                if accepted_pool.len() < 256 {
                    accepted_pool.push(input);
                } else {
                    let i = below(&mut rng, accepted_pool.len());
                    accepted_pool[i] = input;
                }
            }
            Ok(false) => {}
            Err(failure) => {
                let what = match &failure {
                    Failure::Panic(message) => format!("panic: {message}"),
                    Failure::Hang => format!("no answer within {HANG:?}"),
                    Failure::Memory(bytes) => format!("{} MiB held at once", bytes >> 20),
                    Failure::Broken(why) => why.clone(),
                };
                let small = match failure {
                    Failure::Hang => input.clone(),
                    _ => minimize(&target, &input, &failure),
                };
                let mut shown = small.escape_ascii().to_string();
                shown.truncate(4000);
                panic!(
                    "{} loader, input {runs}: {what}\nminimized input ({} bytes): b\"{shown}\"",
                    target.name,
                    small.len(),
                );
            }
        }
    }
    println!(
        "fuzz {}: {runs} inputs in {:.1?} ({accepted} accepted, {} refused), 0 panics, 0 hangs; \
         slowest call {slowest:.1?}, most memory {:.1} MiB",
        target.name,
        start.elapsed(),
        runs - accepted,
        most_memory as f64 / f64::from(1 << 20),
    );
    assert!(runs >= target.seeds.len() as u64 || limit.is_some());
}

#[test]
fn fuzz_obj() {
    fuzz("obj");
}

#[test]
fn fuzz_mtl() {
    fuzz("mtl");
}

#[test]
fn fuzz_ply() {
    fuzz("ply");
}

#[test]
fn fuzz_ply_gz() {
    fuzz("ply.gz");
}

#[test]
fn fuzz_nff() {
    fuzz("nff");
}

#[test]
fn fuzz_aff() {
    fuzz("aff");
}

#[test]
fn fuzz_scene_toml() {
    fuzz("scene.toml");
}

#[test]
fn fuzz_experiment_toml() {
    fuzz("experiment.toml");
}

/// A PLY header may claim any count: nothing is reserved for it before the data is there.
#[test]
fn huge_claimed_counts_allocate_nothing() {
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let text = format!(
            "ply\nformat {format} 1.0\nelement vertex 1000000000\nproperty float x\n\
             property float y\nproperty float z\nelement face 1000000000\n\
             property list uint int vertex_indices\nend_header\n0 0 0\n1 0 0\n"
        );
        for path in ["huge.ply", "huge.ply.gz"] {
            let bytes = if path.ends_with(".gz") {
                gzip(text.as_bytes())
            } else {
                text.as_bytes().to_vec()
            };
            let start = Instant::now();
            let (result, memory) = metered(|| parse_ply(Path::new(path), &bytes).map(|_| ()));
            let err = result.unwrap_err().to_string();
            assert!(err.contains(path), "{err}");
            assert!(memory < 1 << 20, "{format} {path}: {memory} bytes");
            assert!(start.elapsed() < Duration::from_millis(500));
        }
    }
    // The same for the NFF family's counts.
    let options = LoadOptions::default();
    let files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
    for text in [
        "p 1000000000\n0 0 0\n",
        "m vertices 1000000000\n0 0 0\n",
        "tpa 1000000000\n0\n",
    ] {
        let (result, memory) = metered(|| {
            parse_aff(Path::new("huge.aff"), text.as_bytes(), &options, files).map(|_| ())
        });
        assert!(result.is_err());
        assert!(memory < 1 << 20, "{text}: {memory} bytes");
    }
}
