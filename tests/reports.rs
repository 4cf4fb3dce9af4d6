//! Every committed reproduction report (`results/**/REPORT.md`) is what `raylab report --markdown`
//! makes of the results beside it today: regenerated from its results directory, it must come out
//! byte for byte the same. A hand edit, a changed runs.csv or tables.md, or a changed generator
//! fails here; the fix is to rerun the command in the report's first line.

use std::path::{Path, PathBuf};

use raylab::experiment::results::report::{markdown, Results, REPORT_MD};

fn reports(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            reports(&path, found);
        } else if path.file_name().is_some_and(|n| n == REPORT_MD) {
            found.push(path);
        }
    }
}

#[test]
fn every_committed_report_regenerates_unchanged() {
    let mut found = Vec::new();
    reports(Path::new("results"), &mut found);
    assert!(!found.is_empty(), "no results/**/REPORT.md");
    for report in found {
        let text = std::fs::read_to_string(&report).unwrap();
        let (dir, digest) = markdown::generated_by(&text).unwrap_or_else(|| {
            panic!(
                "{}: no generated-by header: reports are made by `raylab report --markdown`",
                report.display()
            )
        });
        assert_eq!(
            Some(dir.as_path()),
            report.parent(),
            "{} names another directory",
            report.display()
        );
        let results = Results::read(&dir).unwrap();
        assert_eq!(
            results.digest,
            digest,
            "{}: the results changed since the report was generated; run `raylab report --markdown {}`",
            report.display(),
            dir.display()
        );
        assert!(
            markdown::report(&results) == text,
            "{} differs from what `raylab report --markdown {}` writes",
            report.display(),
            dir.display()
        );
    }
}
