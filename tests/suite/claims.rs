//! Claims are checked against what their experiment files declare, whether or not a run is
//! committed: every experiment a claims file lists exists as `experiments/<name>.toml`, and every
//! reference names a declared table (by its title or a unique prefix), one of its columns, and,
//! where the file lists its rows, one of its rows (an experiment that declares no tables, the
//! stability suite, is judged against its committed run's by the report). A typo is caught here, not on the day of the
//! run, and a table renamed in an experiment file is caught before its next run reads "not run".

use std::path::Path;

use raylab::experiment::results::report::claims::{Claims, Test, CLAIMS_TOML};
use raylab::experiment::results::report::paper::papers_under;

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
        for claim in &claims.claims {
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
                    if let Some(rows) = rows {
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
