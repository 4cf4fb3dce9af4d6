//! `raylab reproduce` end to end at `--scale quick` on a paper of one small experiment (the
//! built-in room, the reference tracer): the run lands in `results/.quick/<paper>/<experiment>/`
//! (never over the committed runs) recorded as quick, the report is regenerated with the claim's verdict computed from it and
//! labelled a smoke test, a second call keeps the run (resume), one experiment file can be run
//! alone, and an unknown paper is a usage
//! error naming the papers there are.

use std::fs;
use std::path::PathBuf;

use raylab::experiment::plan::overrides::Scale;
use raylab::experiment::reproduce::{plan, reproduce, QUICK_DIR};
use raylab::experiment::results::report::{REPORT_MD, VERDICTS_MD};
use raylab::experiment::Chatter;

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raylab-reproduce-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("experiments")).unwrap();
    fs::create_dir_all(dir.join("results/toy2026")).unwrap();
    dir
}

const EXPERIMENT: &str = r#"name = "tiny"
scenes = ["room"]
tracers = ["reference"]
rays = ["primary"]
resolution = { width = 512, height = 512 }
frames = 2
threads = [1, 2]
warmup = 1
repeats = 3

[[tables]]
title = "Tests per ray"
row_header = "scene"
where = { ray_kind = "primary", threads = 1 }
metric = "aabb_tests_per_ray"
rows = "scene"
columns = [{ label = "reference", where = { tracer = "reference" } }]
"#;

const CLAIMS: &str = r#"title = "Toy 2026"
paper = "A. Toy. Toys. 2026."
paper_text = "toy.txt"
experiments = ["tiny"]
[[claims]]
item = "T1"
claim = "single rays test some boxes, but not a million each"
paper = "none"
quote = "fewer than 1,000,000 boxes per ray"
experiment = "tiny"
tests = ["{{Tests per ray | room | reference}} > 0", "{{Tests per ray | room | reference}} > 1000000"]
"#;

#[test]
fn a_quick_reproduction_runs_reports_and_resumes() {
    let root = scratch();
    let (results, experiments) = (root.join("results"), root.join("experiments"));
    fs::write(experiments.join("tiny.toml"), EXPERIMENT).unwrap();
    fs::write(results.join("toy2026/claims.toml"), CLAIMS).unwrap();
    let committed = results.join("toy2026");
    let paper = results.join(QUICK_DIR).join("toy2026");
    let steps = plan(&committed, &experiments, Scale::Quick).unwrap();
    assert_eq!(steps.len(), 1);
    // 64² camera rays × 1 workload × 1 scene × 1 frame × 1 instance × 1 thread count × 1 pass.
    assert_eq!(steps[0].rays, 64 * 64);
    assert!(!steps[0].done);
    assert_eq!(steps[0].last_seconds, None);
    // At the file's own scale: 512² × 2 frames × 2 thread counts × 4 passes.
    let full = plan(&committed, &experiments, Scale::Paper).unwrap();
    assert_eq!(full[0].rays, 512 * 512 * 2 * 2 * 4);

    let quick = |paper: &str| {
        reproduce(
            paper,
            &results,
            &experiments,
            Scale::Quick,
            false,
            Chatter::Quiet,
        )
    };
    let meta = || -> serde_json::Value {
        let text = fs::read_to_string(paper.join("tiny/meta.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    };
    let written = quick("toy2026").unwrap();
    assert_eq!(
        written,
        [
            paper.join(REPORT_MD),
            results.join(QUICK_DIR).join(VERDICTS_MD)
        ]
    );
    // The committed paper directory is untouched.
    let committed_files: Vec<_> = fs::read_dir(&committed).unwrap().collect();
    assert_eq!(committed_files.len(), 1, "{committed_files:?}"); // claims.toml
    let first = meta();
    assert_eq!(
        first.pointer("/overrides/scale").and_then(|v| v.as_str()),
        Some("quick")
    );
    assert_eq!(
        first
            .pointer("/overrides/resolution/0")
            .and_then(|v| v.as_u64()),
        Some(64)
    );
    let run_id = first["run_id"].clone();
    // A file run before is estimated by that run's wall time.
    let again = plan(&paper, &experiments, Scale::Quick).unwrap();
    assert!(again[0].done);
    assert_eq!(again[0].last_seconds, first["wall_seconds"].as_f64());
    assert_eq!(again[0].estimate_seconds(), again[0].last_seconds.unwrap());
    // Nothing is left of the staging directory.
    let left: Vec<_> = fs::read_dir(&paper)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 3, "{left:?}"); // claims.toml, tiny/, REPORT.md
    let report = fs::read_to_string(paper.join(REPORT_MD)).unwrap();
    assert!(report.contains("**Quick scale (`raylab reproduce --scale quick`), a smoke test and not evidence:** tiny."), "{report}");
    assert!(
        report.contains("**The paper: 1 claims: 0 hold, 1 partly, 0 differ, 0 within noise, 0 not run; 0 of the 1 that differ or partly hold explained by a rule that stands; 0 not reproducible here.**"),
        "{report}"
    );
    assert!(
        report.contains(
            "| T1 | single rays test some boxes, but not a million each | none | **partly** |"
        ),
        "{report}"
    );
    let index = fs::read_to_string(results.join(QUICK_DIR).join(VERDICTS_MD)).unwrap();
    assert!(
        index.contains("toy2026/REPORT.md) | 1 | 0 | 1 | 0 | 0 | 0 | 0 of 1 | 0 |"),
        "{index}"
    );

    // Resumed: the run is from this source at this scale, so it is kept, not made again.
    assert!(plan(&paper, &experiments, Scale::Quick).unwrap()[0].done);
    assert!(!plan(&paper, &experiments, Scale::Paper).unwrap()[0].done);
    quick("toy2026").unwrap();
    assert_eq!(meta()["run_id"], run_id);
    // A run of an older version of the file is not current (`report --check`'s rule).
    let edited = format!("{EXPERIMENT}\n# edited\n");
    fs::write(experiments.join("tiny.toml"), &edited).unwrap();
    assert!(!plan(&paper, &experiments, Scale::Quick).unwrap()[0].done);
    fs::write(experiments.join("tiny.toml"), EXPERIMENT).unwrap();
    assert!(plan(&paper, &experiments, Scale::Quick).unwrap()[0].done);

    // One experiment file named: only it runs, in its paper; the other run is kept.
    fs::write(
        experiments.join("tiny2.toml"),
        EXPERIMENT.replace("tiny", "tiny2"),
    )
    .unwrap();
    let listed = CLAIMS.replace(r#"["tiny"]"#, r#"["tiny", "tiny2"]"#);
    fs::write(committed.join("claims.toml"), listed).unwrap();
    quick("tiny2").unwrap();
    assert!(paper.join("tiny2/meta.json").is_file());
    assert_eq!(meta()["run_id"], run_id);

    let e = quick("nope").unwrap_err();
    assert_eq!(e.exit_code(), 2);
    assert!(
        e.to_string().contains("no paper lists an experiment nope"),
        "{e}"
    );
    assert!(e.to_string().contains("papers: toy2026, or all"), "{e}");
    let _ = fs::remove_dir_all(&root);
}
