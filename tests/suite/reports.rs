//! Every committed reproduction report (`results/<paper>/REPORT.md`) is what
//! `raylab report --markdown` makes of the paper's claims and runs today: regenerated, it must come
//! out byte for byte the same, and so must the index of verdict counts (`results/VERDICTS.md`,
//! pasted into the README). A hand edit, a changed claim, runs.csv or tables.md, or a changed
//! generator fails here; the fix is to rerun the command in the report's first line.

use std::path::Path;

use raylab::experiment::results::report::paper::{papers_under, Paper};
use raylab::experiment::results::report::{markdown, REPORT_MD, VERDICTS_MD};

fn regenerates(file: &Path, make: impl Fn(&Path) -> (String, String)) {
    let text = std::fs::read_to_string(file)
        .unwrap_or_else(|e| panic!("{}: {e}; run `raylab report --markdown`", file.display()));
    let (dir, digest) = markdown::generated_by(&text).unwrap_or_else(|| {
        panic!(
            "{}: no generated-by header: reports are made by `raylab report --markdown`",
            file.display()
        )
    });
    assert_eq!(
        Some(dir.as_path()),
        file.parent(),
        "{} names another directory",
        file.display()
    );
    let (now, digest_now) = make(&dir);
    assert_eq!(
        digest_now,
        digest,
        "{}: the results changed since it was generated; run `raylab report --markdown {}`",
        file.display(),
        dir.display()
    );
    assert!(
        now == text,
        "{} differs from what `raylab report --markdown {}` writes",
        file.display(),
        dir.display()
    );
}

#[test]
fn every_committed_report_and_the_index_regenerate_unchanged() {
    let papers = papers_under(Path::new("results")).unwrap();
    assert!(papers.len() >= 5, "the five papers have claims: {papers:?}");
    for dir in &papers {
        regenerates(&dir.join(REPORT_MD), |d| {
            let paper = Paper::read(d).unwrap_or_else(|e| panic!("{e}"));
            (markdown::report(&paper), paper.digest)
        });
    }
    regenerates(&Path::new("results").join(VERDICTS_MD), |root| {
        let read: Vec<Paper> = papers_under(root)
            .unwrap()
            .iter()
            .map(|d| Paper::read(d).unwrap_or_else(|e| panic!("{e}")))
            .collect();
        (markdown::index(root, &read), markdown::index_digest(&read))
    });
}
