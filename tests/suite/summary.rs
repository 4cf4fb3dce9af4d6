//! The run summary through the real binary: printed at the end of a run and saved as summary.md,
//! printed again identically by `raylab summary DIR`, the same numbers as JSON with `--json`,
//! `--quiet` for scripts, and a clear exit-2 error for a directory that holds no results.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::only_run;

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch_in("summary", name)
}

fn raylab(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .env_remove("RAYLAB_SCENES")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "raylab panicked: {stderr}");
    out
}

fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// The packet tracer and Embree on a small built-in scene: one frame, primary and shadow rays.
const EXPERIMENT: &str = "name = \"small\"\nscenes = [{ name = \"room\", size = 1 }]\n\
    tracers = [{ name = \"packet\", params = { traversal = \"ranged\", packet = 8 } }, \"obvhs\", \"reference\", \"embree16\"]\n\
    rays = [\"primary\", \"shadow\"]\nresolution = { width = 128, height = 128 }\n\
    frames = 1\nthreads = [1]\nwarmup = 0\nrepeats = 1\n";

/// The one results directory under `root`.
#[test]
fn a_run_prints_and_saves_its_summary_and_summary_prints_it_again() {
    let dir = scratch("run");
    std::fs::write(dir.join("small.toml"), EXPERIMENT).unwrap();
    let out = raylab(&dir, &["run", "small.toml", "--out", "res"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = stdout(&out);
    let results = only_run(&dir.join("res"), "small");
    let saved = std::fs::read_to_string(results.join("summary.md")).unwrap();
    // The plan, then the summary, then the results directory.
    assert!(printed.contains(&saved), "{printed}");
    assert!(
        printed.ends_with(&format!(
            "results: res/small/{}\n",
            results.file_name().unwrap().to_str().unwrap()
        )),
        "{printed}"
    );

    let again = raylab(&dir, &["summary", results.to_str().unwrap()]);
    assert!(again.status.success());
    assert_eq!(stdout(&again), saved);

    // 128² = 16,384 primary rays: the packet tracer is the fastest (only) paper tracer, checked
    // on 4 blocks of 1024 rays with no unexplained disagreement.
    let line = saved
        .lines()
        .find(|l| l.starts_with("| room (") && l.contains("| primary |"))
        .unwrap();
    assert!(
        line.contains("| packet packet=8;traversal=ranged |"),
        "{line}"
    );
    assert!(line.contains("| embree3-16 (context coherent) |"), "{line}");
    assert!(line.contains("| yes: 4096 rays, "), "{line}");

    // JSON: the same numbers, rounded as the table rounds them.
    let json = raylab(&dir, &["summary", "--json", results.to_str().unwrap()]);
    let value: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let rows = value["rows"].as_array().unwrap();
    let table_rows: Vec<&str> = saved
        .lines()
        .filter(|l| l.starts_with("| room ("))
        .collect();
    assert_eq!(rows.len(), table_rows.len());
    for (row, line) in rows.iter().zip(&table_rows) {
        let cells: Vec<&str> = line.split(" | ").collect();
        let mrays = row["ours"]["mrays_per_s"].as_f64().unwrap();
        assert_eq!(cells[3], format!("{mrays:.1}"), "{line}");
        let x = row["x_embree_best"].as_f64().unwrap();
        assert_eq!(cells[7], format!("{x:.2}×"), "{line}");
        assert_eq!(row["ours"]["checked"]["unexplained"], 0);
    }
    assert_eq!(value["results"], results.to_str().unwrap());
    assert_eq!(value["threads"], 1);
}

#[test]
fn quiet_and_json_runs_are_for_scripts() {
    let dir = scratch("scripts");
    std::fs::write(dir.join("small.toml"), EXPERIMENT).unwrap();
    let quiet = raylab(&dir, &["run", "small.toml", "--out", "quiet", "--quiet"]);
    assert!(quiet.status.success());
    let results = only_run(&dir.join("quiet"), "small");
    assert_eq!(
        stdout(&quiet),
        format!(
            "{}\n",
            Path::new("quiet/small")
                .join(results.file_name().unwrap())
                .display()
        )
    );
    assert!(
        quiet.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );

    let json = raylab(&dir, &["run", "small.toml", "--out", "json", "--json"]);
    assert!(json.status.success());
    let value: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let results = only_run(&dir.join("json"), "small");
    assert_eq!(
        value["results"],
        Path::new("json/small")
            .join(results.file_name().unwrap())
            .to_str()
            .unwrap()
    );
    assert_eq!(value["experiment"], "small");
    // The plan went to standard error.
    assert!(String::from_utf8_lossy(&json.stderr).contains("experiment small"));
}

#[test]
fn a_directory_without_results_is_a_usage_error() {
    let dir = scratch("not-results");
    for target in [dir.to_str().unwrap(), "no/such/dir"] {
        let out = raylab(&dir, &["summary", target]);
        assert_eq!(out.status.code(), Some(2));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("raylab: {target}: not a results directory")),
            "{stderr}"
        );
        assert!(out.stdout.is_empty());
    }
}
