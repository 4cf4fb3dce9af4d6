//! A claim's verdict, computed: each test's references read from the runs' tables.md, its
//! values compared, and the verdict follows from how many tests pass (`claims::RULE`). What is
//! printed beside the verdict is every test as written, with the values it read.

use std::collections::BTreeMap;

use super::blocks::{self, Block, Table};
use super::claims::{Claim, Expression, Reference, Term, Test, Verdict};

/// The tables.md blocks of each experiment that has a run, by experiment name.
pub type Runs<'a> = BTreeMap<&'a str, &'a [Block]>;

/// One test of a claim: as written (references shown as `[table · row · column]`), and, when
/// its runs exist, what it read and whether it passed.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    pub rule: String,
    pub outcome: Option<(String, bool)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Judged {
    pub verdict: Verdict,
    pub tests: Vec<Checked>,
    /// The claim's note, its references filled with their cells (empty when not run).
    pub note: String,
}

/// The verdict on `claim` over `runs`; a reference to a missing table, row or column of a run
/// that exists is an error (the message names it).
pub fn judge(claim: &Claim, runs: &Runs) -> Result<Judged, String> {
    let mut tests = Vec::new();
    let mut passed = 0;
    let mut missing = false;
    for text in &claim.tests {
        let test = Test::parse(text)?;
        let rule = written(&test);
        let ran = test
            .references()
            .iter()
            .all(|r| runs.contains_key(experiment_of(r, claim)));
        if !ran {
            missing = true;
            tests.push(Checked {
                rule,
                outcome: None,
            });
            continue;
        }
        let value = |e: &Expression| evaluate(e, claim, runs);
        let (shown, pass) = match &test {
            Test::Compare(a, comparison, b) => {
                let (a, b) = (value(a)?, value(b)?);
                (
                    format!("{} {} {}", number(a), comparison.symbol(), number(b)),
                    comparison.holds(a, b),
                )
            }
            Test::Within(a, low, high) => {
                let a = value(a)?;
                (
                    format!("{} in [{}, {}]", number(a), number(*low), number(*high)),
                    (*low..=*high).contains(&a),
                )
            }
        };
        passed += usize::from(pass);
        tests.push(Checked {
            rule,
            outcome: Some((shown, pass)),
        });
    }
    let verdict = match (missing, passed) {
        (true, _) => Verdict::NotRun,
        (false, 0) => Verdict::Differs,
        (false, n) if n == claim.tests.len() => Verdict::Holds,
        (false, _) => Verdict::Partly,
    };
    let note = match verdict {
        Verdict::NotRun => String::new(),
        _ => fill(&claim.note, claim, runs)?,
    };
    Ok(Judged {
        verdict,
        tests,
        note,
    })
}

fn experiment_of<'a>(reference: &'a Reference, claim: &'a Claim) -> &'a str {
    reference.experiment.as_deref().unwrap_or(&claim.experiment)
}

/// A number as a reader wants it: up to three decimals, no trailing zeros.
fn number(x: f64) -> String {
    let text = format!("{x:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    text.to_string()
}

/// An expression as a reader reads it: references as `[table · row · column]`.
fn shown(e: &Expression) -> String {
    let term = |t: &Term| match t {
        Term::Number(n) => number(*n),
        Term::Cell(r) => format!("[{r}]"),
    };
    let mut out = term(&e.first);
    for (times, t) in &e.rest {
        out += if *times { " × " } else { " / " };
        out += &term(t);
    }
    out
}

/// The test as a reader reads it.
fn written(test: &Test) -> String {
    match test {
        Test::Compare(a, c, b) => format!("{} {} {}", shown(a), c.symbol(), shown(b)),
        Test::Within(a, low, high) => {
            format!("{} in [{}, {}]", shown(a), number(*low), number(*high))
        }
    }
}

fn evaluate(e: &Expression, claim: &Claim, runs: &Runs) -> Result<f64, String> {
    let term = |t: &Term| match t {
        Term::Number(n) => Ok(*n),
        Term::Cell(r) => {
            let cell = lookup(r, claim, runs)?;
            leading_number(cell).ok_or_else(|| format!("[{r}] is {cell:?}, not a number"))
        }
    };
    let mut value = term(&e.first)?;
    for (times, t) in &e.rest {
        value = if *times {
            value * term(t)?
        } else {
            value / term(t)?
        };
    }
    match value.is_finite() {
        true => Ok(value),
        false => Err(format!("{} is not finite", shown(e))),
    }
}

/// The number a cell starts with: `3.5×`, `2.4 (8 cores)`, `70 / 47 / 86` give 3.5, 2.4, 70.
fn leading_number(cell: &str) -> Option<f64> {
    let end = cell
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || c == 'e'
                || (c == '-' && i == 0)
                || (c == '+' && i > 0))
        })
        .map_or(cell.len(), |(i, _)| i);
    cell[..end].parse::<f64>().ok().filter(|x| x.is_finite())
}

/// `text` with each `{{reference}}` replaced by its cell.
pub fn fill(text: &str, claim: &Claim, runs: &Runs) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("{{") {
        out.push_str(&rest[..start]);
        let end = rest[start..]
            .find("}}")
            .ok_or_else(|| format!("unclosed {{{{ in {text:?}"))?;
        let reference = Reference::parse(&rest[start + 2..start + end])?;
        out.push_str(lookup(&reference, claim, runs)?);
        rest = &rest[start + end + 2..];
    }
    out.push_str(rest);
    Ok(out)
}

fn lookup<'a>(reference: &Reference, claim: &Claim, runs: &Runs<'a>) -> Result<&'a str, String> {
    let experiment = experiment_of(reference, claim);
    let blocks = runs
        .get(experiment)
        .ok_or_else(|| format!("no run of {experiment}"))?;
    let tables: Vec<&'a Table> = blocks::tables(blocks).collect();
    let title = reference.table.as_str();
    let exact: Vec<&&Table> = tables.iter().filter(|t| t.title == title).collect();
    let candidates = match exact.is_empty() {
        true => tables
            .iter()
            .filter(|t| t.title.starts_with(title))
            .collect(),
        false => exact,
    };
    let table: &'a Table = match candidates[..] {
        [one] => one,
        [] => {
            return Err(format!(
                "no table titled {title:?} in {experiment}'s tables.md"
            ))
        }
        _ => {
            return Err(format!(
                "{title:?} names {} tables in {experiment}'s tables.md",
                candidates.len()
            ))
        }
    };
    table
        .cell(&reference.row, &reference.column)
        .ok_or_else(|| {
            format!(
                "table {:?} of {experiment} has no cell at row {:?}, column {:?}",
                table.title, reference.row, reference.column
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::results::report::blocks::parse;

    fn claim(tests: &[&str], note: &str) -> Claim {
        Claim {
            claim: "c".into(),
            paper: String::new(),
            experiment: "a".into(),
            tests: tests.iter().map(|t| t.to_string()).collect(),
            note: note.into(),
        }
    }

    #[test]
    fn verdicts_follow_from_how_many_tests_pass() {
        let a = parse(
            "## Table 2: museum\n| threads | benefit | P ms | R ms |\n|---|---:|---:|---:|\n\
             | 1 | 1.4× | 451.3 | 433.0 |\n| 2 | 1.2 | 285.7 | 292.4 |\n",
        );
        let b = parse("## Fig. 5\n| scene | x |\n|---|---:|\n| room | – |\n");
        let runs: Runs = [("a", &a[..]), ("b", &b[..])].into_iter().collect();
        // Partition faster than Ranged at 2 threads only: partly.
        let partly = judge(
            &claim(
                &[
                    "{{Table 2 | 1 | P ms}} < {{Table 2 | 1 | R ms}}",
                    "{{Table 2 | 2 | P ms}} < {{Table 2 | 2 | R ms}}",
                ],
                "P {{Table 2 | 2 | P ms}} ms",
            ),
            &runs,
        )
        .unwrap();
        assert_eq!(partly.verdict, Verdict::Partly);
        assert_eq!(
            partly.tests[0],
            Checked {
                rule: "[Table 2 · 1 · P ms] < [Table 2 · 1 · R ms]".into(),
                outcome: Some(("451.3 < 433".into(), false)),
            }
        );
        assert_eq!(
            partly.tests[1].outcome,
            Some(("285.7 < 292.4".into(), true))
        );
        assert_eq!(partly.note, "P 285.7 ms");
        let holds = judge(
            &claim(
                &["{{Table 2 | 1 | benefit}} / {{Table 2 | 2 | benefit}} in [1.1, 1.2]"],
                "",
            ),
            &runs,
        )
        .unwrap();
        assert_eq!(holds.verdict, Verdict::Holds);
        assert_eq!(
            holds.tests[0].outcome,
            Some(("1.167 in [1.1, 1.2]".into(), true))
        );
        let differs = judge(
            &claim(
                &[
                    "{{Table 2 | 1 | benefit}} >= 3",
                    "{{Table 2 | 2 | benefit}} * 2 >= 3",
                ],
                "",
            ),
            &runs,
        )
        .unwrap();
        assert_eq!(differs.verdict, Verdict::Differs);
        // An experiment without a run: not run, whatever the others say.
        let not_run = judge(
            &claim(
                &["{{Table 2 | 1 | benefit}} >= 1", "{{c | T | r | x}} > 0"],
                "{{c | T | r | x}}",
            ),
            &runs,
        )
        .unwrap();
        assert_eq!(not_run.verdict, Verdict::NotRun);
        assert_eq!(not_run.tests[1].outcome, None);
        for (test, why) in [
            ("{{b | Fig. 5 | room | x}} > 0", "is \"–\", not a number"),
            (
                "{{Table 3 | 1 | benefit}} > 0",
                "no table titled \"Table 3\" in a's",
            ),
            ("{{Table 2 | 3 | benefit}} > 0", "no cell at row \"3\""),
            ("{{Table 2 | 1 | benefit}} / 0 > 0", "is not finite"),
        ] {
            let e = judge(&claim(&[test], ""), &runs).unwrap_err();
            assert!(e.contains(why), "{test}: {e}");
        }
    }

    #[test]
    fn leading_numbers_of_cells() {
        for (cell, x) in [
            ("3.5×", Some(3.5)),
            ("2.4 (8 cores)", Some(2.4)),
            ("70 / 47 / 86", Some(70.0)),
            ("1.18e8", Some(1.18e8)),
            ("-0.5", Some(-0.5)),
            ("–", None),
            ("", None),
        ] {
            assert_eq!(leading_number(cell), x, "{cell}");
        }
    }
}
