//! Bad input through the real binary: one clear error naming the file (and line where known),
//! exit code 2, no panic, and no results directory left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
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
