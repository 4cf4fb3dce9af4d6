//! Claims are checked against what their experiment files declare, whether or not a run is
//! committed: every experiment a claims file lists exists as `experiments/<name>.toml`, and every
//! reference names a declared table (by its title or a unique prefix), one of its columns, and,
//! where the file lists its rows, one of its rows (an experiment that declares no tables, the
//! stability suite, is judged against its committed run's by the report). A typo is caught here, not on the day of the
//! run, and a table renamed in an experiment file is caught before its next run reads "not run".
//! Every paper claim's quote is the paper's own text (`Claims::read` checks that the tests' numbers
//! are the quote's).

use std::path::Path;

use raylab::experiment::plan::table_spec::TableSpec;
use raylab::experiment::results::report::claims::{
    normalised, numbers_in, Claims, Test, CLAIMS_TOML, EVERY_ROW,
};
use raylab::experiment::results::report::paper::papers_under;
use raylab::experiment::Experiment;

/// The `[[tables]]` of an experiment file: (title, row labels when listed, column labels).
fn declared_tables(experiment: &str) -> Vec<(String, Option<Vec<String>>, Vec<String>)> {
    let path = Path::new("experiments").join(format!("{experiment}.toml"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (listed in a claims file)", path.display()));
    let file: toml::Value = toml::from_str(&text).unwrap();
    let labels = |v: &toml::Value| -> Vec<String> {
        v.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.get("label")?.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    file.get("tables")
        .and_then(toml::Value::as_array)
        .map(|tables| {
            tables
                .iter()
                .map(|t| {
                    let title = t["title"].as_str().unwrap().to_string();
                    let rows = t.get("rows").filter(|r| r.is_array()).map(labels);
                    (title, rows, labels(&t["columns"]))
                })
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn references_name_declared_tables_rows_and_columns() {
    let mut checked = 0;
    for dir in papers_under(Path::new("results")).unwrap() {
        let (claims, _) = Claims::read(&dir.join(CLAIMS_TOML)).unwrap_or_else(|e| panic!("{e}"));
        for experiment in &claims.experiments {
            declared_tables(experiment);
        }
        for (claim, _) in claims.all() {
            for test in &claim.tests {
                for r in Test::parse(test).unwrap().references() {
                    let experiment = r.experiment.as_deref().unwrap_or(&claim.experiment);
                    let tables = declared_tables(experiment);
                    // The stability suite's tables are made by its code, not declared: the
                    // report judges them against the committed run.
                    if tables.is_empty() && dir.join(experiment).join("meta.json").is_file() {
                        continue;
                    }
                    let exact: Vec<_> = tables.iter().filter(|t| t.0 == r.table).collect();
                    let matching: Vec<_> = match exact.is_empty() {
                        true => tables
                            .iter()
                            .filter(|t| t.0.starts_with(&r.table))
                            .collect(),
                        false => exact,
                    };
                    let where_ = format!("{}: {:?}: [{r}]", dir.display(), claim.claim);
                    let [(_, rows, columns)] = matching[..] else {
                        panic!("{where_}: {} tables of {experiment} match", matching.len())
                    };
                    assert!(
                        columns.contains(&r.column),
                        "{where_}: no column {:?} in {columns:?}",
                        r.column
                    );
                    if let (Some(rows), false) = (rows, r.row == EVERY_ROW) {
                        assert!(
                            rows.contains(&r.row),
                            "{where_}: no row {:?} in {rows:?}",
                            r.row
                        );
                    }
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 0, "no reference was checked");
}

/// Where the papers' texts are: `RAYLAB_PAPERS`, else `papers/` beside the scene directory
/// (`RAYLAB_SCENES`), else `../shared/papers` beside the repository.
fn papers_dir() -> Option<std::path::PathBuf> {
    let candidates = [
        std::env::var_os("RAYLAB_PAPERS").map(std::path::PathBuf::from),
        std::env::var_os("RAYLAB_SCENES").map(|s| Path::new(&s).join("..").join("papers")),
        Some(Path::new("..").join("shared").join("papers")),
    ];
    candidates.into_iter().flatten().find(|d| d.is_dir())
}

/// Each paper report's claims, its paper's text file and that text (a report with paper claims
/// names its text).
fn claims_and_paper_texts(
    papers: &Path,
) -> Vec<(std::path::PathBuf, Claims, std::path::PathBuf, String)> {
    let mut out = Vec::new();
    for dir in papers_under(Path::new("results")).unwrap() {
        let (claims, _) = Claims::read(&dir.join(CLAIMS_TOML)).unwrap_or_else(|e| panic!("{e}"));
        let Some(file) = &claims.paper_text else {
            assert!(
                claims.claims.is_empty(),
                "{}: claims without paper_text",
                dir.display()
            );
            continue;
        };
        let path = papers.join(file);
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        out.push((dir, claims, path, text));
    }
    out
}

/// Each paper claim's `quote` is in its paper's text, matched without regard to case, line breaks
/// or runs of spaces: the range a test uses is the paper's own. A quote typed from memory, or a
/// number moved, fails here.
#[test]
fn every_quote_is_the_papers_own_text() {
    let Some(papers) = papers_dir() else {
        eprintln!("no papers directory (RAYLAB_PAPERS, RAYLAB_SCENES/../papers, ../shared/papers): quotes not checked");
        return;
    };
    let mut checked = 0;
    for (dir, claims, path, text) in claims_and_paper_texts(&papers) {
        let text = normalised(&text);
        for claim in &claims.claims {
            let quote = normalised(claim.quote.as_deref().unwrap());
            assert!(
                text.contains(&quote),
                "{}: {:?}: the quote {quote:?} is not in {}",
                dir.display(),
                claim.claim,
                path.display()
            );
            checked += 1;
        }
    }
    assert!(checked > 0, "no quote was checked");
}

/// The metrics that are times, or derived from times: their values carry a spread.
const TIMED: &[&str] = &[
    "seconds_min",
    "seconds_median",
    "mrays_per_s",
    "build_plus_trace_seconds",
    "embree_best_seconds",
    "baseline_best_seconds",
    "x_embree_best",
    "x_baseline_best",
];

/// Whether `column` of `table` is a time or computed from one.
fn is_timed(table: &TableSpec, column: &str) -> bool {
    fn timed(table: &TableSpec, column: &str, depth: usize) -> bool {
        let Some(c) = table.columns.iter().find(|c| c.label == column) else {
            return false;
        };
        if depth > table.columns.len() || c.paper.is_some() || c.text.is_some() {
            return false;
        }
        let parts: Vec<&String> = c.inputs().collect();
        match parts.is_empty() {
            true => c
                .metric
                .as_ref()
                .or(table.metric.as_ref())
                .is_some_and(|m| TIMED.contains(&m.as_str())),
            false => parts.iter().any(|p| timed(table, p, depth + 1)),
        }
    }
    timed(table, column, 0)
}

/// A claim that compares times compares their spread too, which needs passes to spread over:
/// every experiment whose timed cell a claim or target reads runs at least 5 repeats (issue 43).
#[test]
fn every_compared_time_comes_from_at_least_five_repeats() {
    let mut timed_references = 0;
    for dir in papers_under(Path::new("results")).unwrap() {
        let (claims, _) = Claims::read(&dir.join(CLAIMS_TOML)).unwrap_or_else(|e| panic!("{e}"));
        for (claim, _) in claims.all() {
            for test in &claim.tests {
                for r in Test::parse(test).unwrap().references() {
                    let name = r.experiment.as_deref().unwrap_or(&claim.experiment);
                    let path = Path::new("experiments").join(format!("{name}.toml"));
                    let exp = Experiment::load(&path).unwrap_or_else(|e| panic!("{e}"));
                    let exact = exp.tables.iter().find(|t| t.title == r.table);
                    let table =
                        exact.or_else(|| exp.tables.iter().find(|t| t.title.starts_with(&r.table)));
                    let Some(table) = table else { continue };
                    if is_timed(table, &r.column) {
                        timed_references += 1;
                        assert!(
                            exp.repeats >= 5,
                            "{}: {:?} compares [{r}], a time, but {name} runs {} repeats",
                            dir.display(),
                            claim.claim,
                            exp.repeats
                        );
                    }
                }
            }
        }
    }
    assert!(timed_references > 0, "no claim reads a time");
}

/// The paper's numbers that tables print beside ours (`paper = { … }` columns), which claims
/// compare with, are numbers the paper's text states.
#[test]
fn every_paper_column_number_is_in_the_papers_text() {
    let Some(papers) = papers_dir() else {
        eprintln!("no papers directory: paper columns not checked");
        return;
    };
    let mut checked = 0;
    for (_, claims, paper, text) in claims_and_paper_texts(&papers) {
        let stated = numbers_in(&text);
        for name in &claims.experiments {
            let path = Path::new("experiments").join(format!("{name}.toml"));
            let exp = Experiment::load(&path).unwrap_or_else(|e| panic!("{e}"));
            for table in &exp.tables {
                for column in &table.columns {
                    for (row, value) in column.paper.iter().flatten() {
                        let text = match value {
                            toml::Value::String(s) => s.clone(),
                            other => other.to_string(),
                        };
                        for n in numbers_in(&text) {
                            assert!(
                                stated.iter().any(|s| (s - n).abs() <= 1e-9 * n.abs().max(1.0)),
                                "{name}: table {:?}, column {:?}, row {row:?}: {n} is not a number of {}",
                                table.title,
                                column.label,
                                paper.display()
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(checked > 0, "no paper column was checked");
}
