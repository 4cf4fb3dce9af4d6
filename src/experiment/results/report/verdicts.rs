//! `verdicts.toml` beside a committed results directory's files: what a human concluded about
//! each of the paper's conclusions from those results. The words are the human's; every number
//! they rest on is quoted from the results' tables by reference, `{{table | row | column}}` (a
//! table by its title or a unique prefix of it, a row by its first cell, a column by its heading),
//! and filled in when the report is generated, so a number in a verdict always traces to a run.
//!
//! ```toml
//! title = "Overbeck et al. 2008: large ray packets"   # the report's title (optional)
//! paper = "R. Overbeck, R. Ramamoorthi, W. R. Mark. Large Ray Packets for Real-Time Whitted Ray Tracing. IRT 2008."
//! [[verdicts]]
//! conclusion = "Partition traversal tests fewer boxes than masked traversal"
//! verdict = "holds"            # holds | differs | cannot be tested
//! because = "{{Table 2 | kitchen | ratio}}× fewer box tests on the kitchen"
//! ```

use std::fmt;
use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

use super::blocks::Table;

pub const VERDICTS_TOML: &str = "verdicts.toml";

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Verdicts {
    pub title: Option<String>,
    pub paper: Option<String>,
    #[serde(default)]
    pub verdicts: Vec<Verdict>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Verdict {
    pub conclusion: String,
    pub verdict: Judgement,
    pub because: String,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum Judgement {
    #[serde(rename = "holds")]
    Holds,
    #[serde(rename = "differs")]
    Differs,
    #[serde(rename = "cannot be tested")]
    CannotBeTested,
}

impl fmt::Display for Judgement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Judgement::Holds => "holds",
            Judgement::Differs => "differs",
            Judgement::CannotBeTested => "cannot be tested",
        })
    }
}

impl Verdicts {
    /// Reads `path`; invalid TOML or an unknown field is an input error naming the file and line.
    pub fn read(path: &Path) -> Result<Verdicts> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        toml::from_str(&text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start].lines().count().max(1));
            Error::input(path, line, e.message().to_string())
        })
    }

    /// Every verdict's `because` with its `{{table | row | column}}` references replaced by the
    /// cells of `tables`; an unknown or ambiguous reference is an input error naming `path`
    /// and the line of the verdict that makes it.
    pub fn resolve(&self, tables: &[&Table], path: &Path, text: &str) -> Result<Vec<String>> {
        self.verdicts
            .iter()
            .map(|v| {
                fill(&v.because, tables).map_err(|message| {
                    let line = text
                        .find(&v.because)
                        .map(|at| text[..at].lines().count().max(1));
                    Error::input(path, line, format!("{:?}: {message}", v.conclusion))
                })
            })
            .collect()
    }
}

/// `because` with each reference replaced by its cell.
fn fill(because: &str, tables: &[&Table]) -> std::result::Result<String, String> {
    let mut out = String::new();
    let mut rest = because;
    while let Some(start) = rest.find("{{") {
        out.push_str(&rest[..start]);
        let end = rest[start..]
            .find("}}")
            .ok_or_else(|| format!("unclosed {{{{ in {because:?}"))?;
        let reference = &rest[start + 2..start + end];
        out.push_str(lookup(reference, tables)?);
        rest = &rest[start + end + 2..];
    }
    out.push_str(rest);
    Ok(out)
}

fn lookup<'a>(reference: &str, tables: &[&'a Table]) -> std::result::Result<&'a str, String> {
    let parts: Vec<&str> = reference.split(" | ").map(str::trim).collect();
    let [title, row, column] = parts[..] else {
        return Err(format!(
            "{{{{{reference}}}}}: expected {{{{table | row | column}}}}"
        ));
    };
    let exact: Vec<&&Table> = tables.iter().filter(|t| t.title == title).collect();
    let candidates = match exact.is_empty() {
        true => tables
            .iter()
            .filter(|t| t.title.starts_with(title))
            .collect(),
        false => exact,
    };
    let table = match candidates[..] {
        [one] => one,
        [] => return Err(format!("no table titled {title:?} in tables.md")),
        _ => return Err(format!("{title:?} names {} tables", candidates.len())),
    };
    table.cell(row, column).ok_or_else(|| {
        format!(
            "table {:?} has no cell at row {row:?}, column {column:?}",
            table.title
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::results::report::blocks::{parse, tables};

    #[test]
    fn references_are_filled_from_the_tables_and_bad_ones_name_the_line() {
        let md = "## Table 2: kitchen\n| scene | ratio |\n|---|---:|\n| kitchen | 3.10 |\n\
                  ## Table 2b\n| scene | ratio |\n|---|---:|\n| museum | 0.90 |\n";
        let blocks = parse(md);
        let tables: Vec<&Table> = tables(&blocks).collect();
        let text = "[[verdicts]]\nconclusion = \"fewer tests\"\nverdict = \"holds\"\n\
                    because = \"{{Table 2: | kitchen | ratio}}× fewer, {{Table 2b | museum | ratio}}× there\"\n\
                    [[verdicts]]\nconclusion = \"c\"\nverdict = \"cannot be tested\"\nbecause = \"{{Table 2 | kitchen | ratio}}\"\n";
        let verdicts: Verdicts = toml::from_str(text).unwrap();
        assert_eq!(verdicts.verdicts[1].verdict, Judgement::CannotBeTested);
        let path = Path::new("verdicts.toml");
        let e = verdicts.resolve(&tables, path, text).unwrap_err();
        // "Table 2" is the prefix of both titles; the error is on the second verdict's line.
        assert!(e.to_string().contains("names 2 tables"), "{e}");
        assert!(e.to_string().contains("verdicts.toml:8"), "{e}");
        let first = Verdicts {
            verdicts: verdicts.verdicts[..1].to_vec(),
            ..verdicts.clone()
        };
        assert_eq!(
            first.resolve(&tables, path, text).unwrap(),
            ["3.10× fewer, 0.90× there"]
        );
        for (bad, why) in [
            ("{{Table 3 | kitchen | ratio}}", "no table titled"),
            (
                "{{Table 2b | kitchen | ratio}}",
                "no cell at row \"kitchen\"",
            ),
            ("{{Table 2b | museum}}", "expected"),
            ("{{Table 2b | museum | ratio", "unclosed"),
        ] {
            let e = fill(bad, &tables).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }

    #[test]
    fn unknown_fields_and_judgements_are_errors_with_a_line() {
        let dir = std::env::temp_dir().join(format!("raylab-verdicts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(VERDICTS_TOML);
        std::fs::write(
            &path,
            "[[verdicts]]\nconclusion = \"c\"\nverdict = \"mostly\"\nbecause = \"\"\n",
        )
        .unwrap();
        let e = Verdicts::read(&path).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("verdicts.toml:3"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
