//! Bad input through the real binary: one clear error naming the file (and line where known),
//! exit code 2, no panic, and no results directory left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::only_run;

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch_in("cli", name)
}

/// Runs raylab in `dir`; returns (exit code, stderr).
fn raylab(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .env_remove("RAYLAB_SCENES")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "raylab panicked: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

/// Asserts exit code 2 and that stderr names `needle` (file:line) in a single error line.
fn fails_with(dir: &Path, args: &[&str], needle: &str) {
    let (code, stderr) = raylab(dir, args);
    assert_eq!(code, 2, "args {args:?}: stderr {stderr}");
    assert!(
        stderr.contains(needle),
        "args {args:?}: expected {needle:?} in {stderr:?}"
    );
    let error_lines = stderr
        .lines()
        .filter(|l| l.contains("error") || l.starts_with("raylab:"))
        .count();
    assert!(error_lines >= 1, "no error line in {stderr:?}");
}

fn render(dir: &Path, scene: &str, needle: &str) {
    fails_with(
        dir,
        &[
            "render", "--scene", scene, "--width", "8", "--height", "8", "-o", "x.png",
        ],
        needle,
    );
    assert!(!dir.join("x.png").exists());
}

#[test]
fn malformed_scene_files_name_file_and_line() {
    let dir = scratch("scene-files");
    let files: &[(&str, &str, &str)] = &[
        ("bad_vertex.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", "bad_vertex.obj:2"),
        ("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n", "nan.obj:3"),
        ("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "bad_index.obj"),
        ("empty.obj", "# nothing here\n", "empty.obj"),
        ("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 oops\n0 1 0\n3 0 1 2\n", "bad.ply:11"),
        ("bad.nff", "b 0 0 0\nf 1 1 1 1 0 0 0 1\np 3\n0 0 0\n1 0 0\n0 x 0\n", "bad.nff:6"),
        ("bad.aff", "b 0 0 0\nf 1 1 1 1 0 0 0 1\np 3\n0 0 0\n1 0 0\n", "bad.aff"),
        ("missing_include.aff", "i does_not_exist.aff\n", "does_not_exist.aff"),
    ];
    for (name, text, needle) in files {
        std::fs::write(dir.join(name), text).unwrap();
        render(&dir, name, needle);
    }
    render(&dir, "no_such_file.obj", "no_such_file.obj");
}

#[test]
fn unknown_names_are_usage_errors() {
    let dir = scratch("names");
    render(&dir, "no-such-scene", "no-such-scene");
    fails_with(
        &dir,
        &[
            "render",
            "--scene",
            "room",
            "--tracer",
            "warp-drive",
            "--width",
            "8",
            "--height",
            "8",
        ],
        "warp-drive",
    );
    fails_with(
        &dir,
        &["verify", "--scene", "room", "--tracer", "warp-drive"],
        "warp-drive",
    );
    fails_with(
        &dir,
        &[
            "render",
            "--scene",
            "room",
            "--param",
            "leaf_size=many",
            "--width",
            "8",
            "--height",
            "8",
        ],
        "leaf_size",
    );
}

fn experiment(dir: &Path, name: &str, text: &str) -> String {
    std::fs::write(dir.join(name), text).unwrap();
    name.to_string()
}

/// No results directory (not even a partial one) after a failed run.
fn no_results(dir: &Path) {
    let results = dir.join("results");
    let leftovers: Vec<_> = walk(&results);
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return vec![];
    };
    entries
        .flatten()
        .flat_map(|e| {
            let p = e.path();
            if p.is_dir() {
                let inner = walk(&p);
                if inner.is_empty() {
                    vec![p]
                } else {
                    inner
                }
            } else {
                vec![p]
            }
        })
        .collect()
}

#[test]
fn bad_experiments_fail_cleanly() {
    let dir = scratch("experiments");
    fails_with(&dir, &["run", "missing.toml"], "missing.toml");
    let bad = experiment(
        &dir,
        "syntax.toml",
        "name = \"x\"\nscenes = [\"room\"\ntracers = [\"reference\"]\n",
    );
    fails_with(&dir, &["run", &bad], "syntax.toml:");
    let unknown = experiment(
        &dir,
        "tracer.toml",
        "name = \"x\"\nscenes = [\"room\"]\ntracers = [\"warp-drive\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 8 }\n",
    );
    fails_with(&dir, &["run", &unknown], "warp-drive");
    let scene = experiment(&dir, "scene.toml", "name = \"x\"\nscenes = [\"room\", \"no-such-scene\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 8 }\n");
    fails_with(&dir, &["run", &scene], "no-such-scene");
    // Once: the same rows measured and written twice, and a pool of 100,000 threads that never
    // finished starting.
    let room = experiment(&dir, "room.toml", "name = \"x\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 8 }\n");
    fails_with(
        &dir,
        &["run", &room, "--threads", "2", "2"],
        "thread count 2 is listed twice",
    );
    fails_with(
        &dir,
        &["run", &room, "--threads", "100000"],
        "100000 threads are more than 1024",
    );
    no_results(&dir);
}

#[test]
fn whitted_render_writes_a_png_and_rejects_unknown_settings() {
    let dir = scratch("whitted");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "render",
            "--scene",
            "room",
            "--renderer",
            "whitted",
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            "w.png",
        ];
        a.extend_from_slice(extra);
        a
    };
    fails_with(&dir, &args(&["--assembly", "octants"]), "octants");
    fails_with(&dir, &args(&["--materials", "chrome"]), "chrome");
    assert!(!dir.join("w.png").exists());
    let (code, stderr) = raylab(&dir, &args(&["--materials", "glass", "--max-depth", "2"]));
    assert_eq!(code, 0, "{stderr}");
    let png = image::open(dir.join("w.png")).unwrap();
    assert_eq!((png.width(), png.height()), (16, 12));
}

#[test]
fn absurd_sizes_are_refused_before_allocating() {
    let dir = scratch("absurd");
    let huge = ["--width", "1000000", "--height", "1000000"];
    let mut args = vec!["render", "--scene", "room"];
    args.extend(huge);
    fails_with(&dir, &args, "needs an estimated");
    fails_with(
        &dir,
        &[
            "verify",
            "--scene",
            "room",
            "--tracer",
            "reference",
            "--resolution",
            "4000000",
        ],
        "needs an estimated",
    );
    let exp = experiment(
        &dir,
        "huge.toml",
        "name = \"x\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\nresolution = { width = 4000000, height = 4000000 }\n",
    );
    fails_with(&dir, &["run", &exp], "huge.toml");
    no_results(&dir);
}

#[test]
fn empty_sizes_and_wrong_outputs_are_refused_before_the_work() {
    let dir = scratch("empty-sizes");
    // Once: a PASS on zero rays (exit 0), and a render that failed (exit 1) only when writing.
    let verify = [
        "verify",
        "--scene",
        "room",
        "--tracer",
        "reference",
        "--out",
        "res",
    ];
    for (extra, message) in [
        (
            &["--resolution", "0"][..],
            "raylab: --resolution must be at least 1",
        ),
        (
            &["--frames", "0"][..],
            "raylab: --frames must be at least 1",
        ),
        (
            &["--max-distance-error", "NaN"][..],
            "raylab: --max-distance-error must be a number ≥ 0, not NaN",
        ),
    ] {
        let args: Vec<&str> = verify.iter().chain(extra).copied().collect();
        let (code, stderr) = raylab(&dir, &args);
        assert_eq!((code, stderr.trim()), (2, message), "{args:?}");
    }
    assert!(!dir.join("res").exists());
    let render = ["render", "--scene", "room"];
    for (extra, message) in [
        (
            &["--width", "0", "--height", "8", "-o", "x.png"][..],
            "raylab: --width must be at least 1",
        ),
        (
            &["--width", "8", "--height", "0", "-o", "x.png"][..],
            "raylab: --height must be at least 1",
        ),
        (
            &["--width", "8", "--height", "8", "-o", "x.txt"][..],
            "raylab: --output x.txt: the image is a PNG, so its name must end in .png",
        ),
    ] {
        let args: Vec<&str> = render.iter().chain(extra).copied().collect();
        let (code, stderr) = raylab(&dir, &args);
        assert_eq!((code, stderr.trim()), (2, message), "{args:?}");
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn bad_stability_experiments_name_file_and_line() {
    let dir = scratch("stability");
    let case = experiment(
        &dir,
        "case.toml",
        "name = \"s\"\ntracers = [\"reference\"]\n\n[stability]\ncases = [\"wobbly\"]\n",
    );
    fails_with(&dir, &["run", &case], "case.toml:4");
    let mixed = experiment(
        &dir,
        "mixed.toml",
        "name = \"s\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\n[stability]\n",
    );
    fails_with(&dir, &["run", &mixed], "remove `scenes`");
    let nan = experiment(
        &dir,
        "nan.toml",
        "name = \"s\"\ntracers = [\"reference\"]\n[stability]\noffsets = [nan]\n",
    );
    fails_with(&dir, &["run", &nan], "offsets");
    no_results(&dir);
}

#[test]
fn dumped_rays_replay_with_trace_verify_and_experiments() {
    use raylab::geometry::ray_file::{hits_csv, read_rays};
    use raylab::tracers::chunked::trace_hits;

    let dir = scratch("ray-files");
    let exp = experiment(
        &dir,
        "dump.toml",
        "name = \"dump\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\nrays = [\"primary\", \"shadow\"]\n\
         resolution = { width = 32, height = 32 }\nwarmup = 0\nrepeats = 1\n",
    );
    let (code, stderr) = raylab(&dir, &["run", &exp, "--dump-rays"]);
    assert_eq!(code, 0, "{stderr}");
    let rays = only_run(&dir.join("results"), "dump").join("rays");
    let (primary, shadow) = (
        rays.join("room-f0-primary.rays"),
        rays.join("room-f0-shadow.rays"),
    );
    assert!(shadow.exists(), "{:?}", walk(&rays));

    // The dump holds exactly the camera rays the run generated.
    let scene = raylab::scene::library::load_scene("room", None).unwrap();
    let frame = scene.frame(0, 1);
    let batch = read_rays(&primary).unwrap();
    let camera = raylab::render::rays::primary_rays(&frame.camera, 32, 32);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(batch.len(), 32 * 32);
    for (read, made) in [
        (&batch.ox, &camera.ox),
        (&batch.dz, &camera.dz),
        (&batch.tmin, &camera.tmin),
        (&batch.tmax, &camera.tmax),
    ] {
        assert_eq!(bits(read), bits(made));
    }

    // `trace` answers as the reference tracer does on those rays, line for line.
    let (code, stderr) = raylab(
        &dir,
        &[
            "trace",
            "--scene",
            "room",
            "--tracer",
            "reference",
            "--rays",
            primary.to_str().unwrap(),
            "--out",
            "hits.csv",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let reference =
        raylab::tracers::tracer_for_frame("reference", &raylab::tracers::Params::new(), &frame)
            .unwrap();
    let hits = trace_hits(reference.as_ref(), &batch);
    assert!(hits.iter().filter(|h| h.is_hit()).count() > 512);
    let written = std::fs::read_to_string(dir.join("hits.csv")).unwrap();
    assert_eq!(written, hits_csv(&hits));

    // `verify --rays` passes another tracer on the dumped shadow rays.
    let (code, stderr) = raylab(
        &dir,
        &[
            "verify",
            "--scene",
            "room",
            "--tracer",
            "obvhs",
            "--rays",
            shadow.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{stderr}");

    // An experiment replays the file (path relative to the experiment file).
    std::fs::create_dir_all(dir.join("replay")).unwrap();
    std::fs::copy(&primary, dir.join("replay/camera.rays")).unwrap();
    let replay = experiment(
        &dir,
        "replay/replay.toml",
        "name = \"replay\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\n\
         rays = [\"primary\", { file = \"camera.rays\" }]\n\
         resolution = { width = 32, height = 32 }\nwarmup = 0\nrepeats = 1\n",
    );
    let (code, stderr) = raylab(&dir, &["run", &replay]);
    assert_eq!(code, 0, "{stderr}");
    let runs =
        std::fs::read_to_string(only_run(&dir.join("results"), "replay").join("runs.csv")).unwrap();
    let file_row = runs
        .lines()
        .find(|l| l.contains(",file:camera.rays,"))
        .unwrap_or_else(|| panic!("no file row in {runs}"));
    assert!(file_row.contains(",1024,"), "{file_row}");
}

#[test]
fn bad_ray_files_fail_with_their_byte_offset() {
    let dir = scratch("bad-ray-files");
    // A header claiming 1024 rays, cut 100 bytes in: rays 0 and 1 whole, ray 2 from byte 88.
    let mut bytes = b"RAYLABRY".to_vec();
    bytes.extend_from_slice(&1u32.to_le_bytes());
    bytes.extend_from_slice(&0u32.to_le_bytes());
    bytes.extend_from_slice(&1024u64.to_le_bytes());
    bytes.resize(100, 0);
    std::fs::write(dir.join("cut.rays"), &bytes).unwrap();
    std::fs::write(
        dir.join("bad.csv"),
        "ox,oy,oz,dx,dy,dz,tmin,tmax\n0,0,0,0,0,1,0\n",
    )
    .unwrap();
    let trace = |file: &'static str| ["trace", "--scene", "room", "--rays", file];
    fails_with(&dir, &trace("cut.rays"), "cut.rays: byte offset 88");
    fails_with(&dir, &trace("bad.csv"), "bad.csv:2");
    fails_with(&dir, &trace("missing.rays"), "missing.rays");
    fails_with(
        &dir,
        &[
            "verify", "--scene", "room", "--tracer", "obvhs", "--rays", "cut.rays",
        ],
        "cut.rays: byte offset 88",
    );
    for (name, entry, needle) in [
        ("cut.toml", "{ file = \"cut.rays\" }", "byte offset 88"),
        (
            "missing.toml",
            "{ file = \"missing.rays\" }",
            "missing.rays",
        ),
        ("typo.toml", "{ fiel = \"cut.rays\" }", "typo.toml:4"),
    ] {
        let exp = experiment(
            &dir,
            name,
            &format!(
                "name = \"x\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\nrays = [\"primary\", {entry}]\n\
                 resolution = {{ width = 8, height = 8 }}\n"
            ),
        );
        fails_with(&dir, &["run", &exp, "--dump-rays"], needle);
    }
    no_results(&dir);
    assert!(!dir.join("results/verify").exists());
}

/// Ill-formed rays are valid ray-file content: every tracer traces them without aborting (Embree's
/// linked build asserts on non-finite or huge components and on a negative tmin) and answers a ray
/// that is not well formed (`Ray::is_well_formed`) with a miss; Embree answers all of them so.
#[test]
fn ill_formed_rays_are_traced_without_aborting() {
    let dir = scratch("ill-formed-rays");
    std::fs::write(
        dir.join("ill.csv"),
        "ox,oy,oz,dx,dy,dz,tmin,tmax\n\
         NaN,1,8,0,0,-1,0,inf\n0,1,8,0,inf,-1,0,inf\n0,1,8,0,0,-1e30,0,inf\n\
         0,1,8,0,0,-1,NaN,inf\n0,1,8,0,0,-1,-1,inf\n0,1,8,0,0,-1,0,NaN\n-inf,1,8,0,0,-1,0,inf\n",
    )
    .unwrap();
    // Ray 2 (a huge but finite direction) is well formed; ray 4 has a negative tmin.
    let ill_formed = [0, 1, 3, 4, 5, 6];
    for tracer in [
        "reference",
        "obvhs",
        "packet",
        "cgt",
        "grid-dda",
        "stream",
        "embree1",
        "embree8",
        "embree16",
        "embree-stream",
    ] {
        for query in [&[][..], &["--occluded"][..]] {
            let out = format!("{tracer}{}.csv", query.len());
            let mut args = vec![
                "trace", "--scene", "room", "--tracer", tracer, "--rays", "ill.csv", "--out", &out,
            ];
            args.extend_from_slice(query);
            let (code, stderr) = raylab(&dir, &args);
            assert_eq!(code, 0, "{tracer} {query:?}: {stderr}");
            let answers = std::fs::read_to_string(dir.join(&out)).unwrap();
            let answered: Vec<&str> = answers
                .lines()
                .skip(1)
                .map(|l| l.split(',').nth(1).unwrap_or(""))
                .collect();
            assert_eq!(answered.len(), 7, "{tracer}: {answers}");
            for (i, answer) in answered.iter().enumerate() {
                if ill_formed.contains(&i) || tracer.starts_with("embree") {
                    assert_eq!(*answer, "0", "{tracer} {query:?} ray {i}: {answers}");
                }
            }
        }
    }
}

#[test]
fn shards_merge_and_reports_refuse_bad_input() {
    let dir = scratch("shards");
    let exp = experiment(
        &dir,
        "tiny.toml",
        "name = \"tiny\"\nscenes = [{ name = \"room\", size = 1 }]\n\
         tracers = [\"reference\", \"obvhs\"]\nrays = [\"primary\"]\n\
         resolution = { width = 16, height = 16 }\nthreads = [1]\nwarmup = 0\nrepeats = 1\n",
    );
    for bad in ["2/2", "1", "x/3"] {
        fails_with(&dir, &["run", &exp, "--shard", bad], bad);
    }
    no_results(&dir);
    for i in 0..2 {
        let out = format!("s{i}");
        let (code, stderr) = raylab(
            &dir,
            &["run", &exp, "--shard", &format!("{i}/2"), "--out", &out],
        );
        assert_eq!(code, 0, "{stderr}");
    }
    let s0 = only_run(&dir.join("s0"), "tiny");
    let s1 = only_run(&dir.join("s1"), "tiny");
    let (s0, s1) = (s0.to_str().unwrap(), s1.to_str().unwrap());
    fails_with(&dir, &["merge", s0], "shard 1/2 missing");
    fails_with(&dir, &["merge", s0, s1, s1], "shard 1/2 given twice");
    no_results(&dir);
    let (code, stderr) = raylab(&dir, &["merge", s1, s0]);
    assert_eq!(code, 0, "{stderr}");
    let merged = only_run(&dir.join("results"), "tiny");
    // One row per tracer, both in the merged runs.csv, in plan order.
    let runs = std::fs::read_to_string(merged.join("runs.csv")).unwrap();
    let tracers: Vec<&str> = runs
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(4).unwrap())
        .collect();
    assert_eq!(tracers, ["reference", "obvhs"]);
    fails_with(&dir, &["report", "no-such-dir"], "no-such-dir");
    fails_with(
        &dir,
        &["report", "--markdown", s0, s1],
        "one directory at a time",
    );
    // A run directory is no paper; a paper's claims file with a bad field names its line.
    fails_with(
        &dir,
        &["report", "--markdown", merged.to_str().unwrap()],
        "claims.toml",
    );
    std::fs::write(
        merged.join("claims.toml"),
        "title = \"t\"\npaper = \"p\"\nexperiments = 1\n",
    )
    .unwrap();
    fails_with(
        &dir,
        &["report", "--markdown", merged.to_str().unwrap()],
        "claims.toml:3",
    );
}

/// `report --check` exits 1 on a stale run (here: one with no record of its source), and 0 with
/// `--stale-ok`, naming it both times; `--stale-ok` alone is a usage error.
#[test]
fn report_check_exits_1_on_a_stale_run_and_0_when_stale_is_ok() {
    let dir = scratch("stale-ok");
    let run = dir.join("results/exp/20260101T000000Z");
    std::fs::create_dir_all(&run).unwrap();
    std::fs::write(
        run.join("meta.json"),
        r#"{ "commit": { "hash": "abc", "dirty": false } }"#,
    )
    .unwrap();
    for (args, code) in [
        (&["report", "--check", "results"][..], 1),
        (&["report", "--check", "--stale-ok", "results"][..], 0),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {stdout}");
        assert!(
            stdout.contains("no record of the source it measured"),
            "{args:?}: {stdout}"
        );
    }
    let (code, _) = raylab(&dir, &["report", "--stale-ok", "results"]);
    assert_eq!(code, 2, "--stale-ok needs --check");
}

/// `raylab bench` times a tracer on a ray file, with its counters, in the line `tools/ab` and
/// `tools/callgrind` parse; a missing file, no threads, an unknown tracer and an empty sample are
/// exit 2.
#[test]
fn bench_times_a_ray_file_and_refuses_bad_input() {
    use raylab::geometry::ray_file::{write_rays, RayFileFormat};
    use raylab::geometry::{Ray, RayBatch, RayKind};
    let dir = scratch("bench");
    let mut batch = RayBatch::new(RayKind::Primary);
    for x in [0.3f32, 0.6] {
        let origin = glam::Vec3::new(x, 0.5, 0.5);
        batch.push(Ray::new(origin, -glam::Vec3::Y, 0.0, f32::INFINITY), 0);
    }
    let file = dir.join("two.rays");
    write_rays(&file, batch.view(), RayFileFormat::Binary).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args([
            "bench",
            "--scene",
            "room",
            "--rays",
            "two.rays",
            "--counters",
        ])
        .args([
            "--tracer",
            "packet",
            "--param",
            "packet=2",
            "--repeats",
            "2",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.starts_with("packet packet=2: 2 rays, 1 thread: min "),
        "{stdout}"
    );
    assert!(stdout.contains(" Mrays/s; per ray: "), "{stdout}");
    fails_with(
        &dir,
        &["bench", "--scene", "room", "--rays", "none.rays"],
        "none.rays",
    );
    fails_with(
        &dir,
        &[
            "bench",
            "--scene",
            "room",
            "--rays",
            "two.rays",
            "--threads",
            "0",
        ],
        "--threads",
    );
    fails_with(
        &dir,
        &[
            "bench", "--scene", "room", "--rays", "two.rays", "--tracer", "nope",
        ],
        "nope",
    );
}
