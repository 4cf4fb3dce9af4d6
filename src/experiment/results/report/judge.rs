//! A claim's verdict, computed: each test's references read from the tables computed over the
//! runs' records (`TableModel`, full precision, with each number's spread), its values compared,
//! and the verdict follows from how many tests pass, fail or fall within noise (`claims::RULE`).
//! What is printed beside the verdict is every test as written, with the values it read.

use std::collections::BTreeMap;

use super::claims::{Claim, Comparison, Expression, Reference, Term, Test, Tolerance, Verdict};
use crate::experiment::record::spread::Spread;
use crate::experiment::results::tables::{Cell, TableModel};

/// The tables of each experiment that has a run, by experiment name.
pub type Runs<'a> = BTreeMap<&'a str, &'a [TableModel]>;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    Passed,
    Failed,
    /// The outcome changes somewhere inside the spread of the values compared.
    WithinNoise,
}

impl Outcome {
    pub fn mark(self) -> &'static str {
        match self {
            Outcome::Passed => "✓",
            Outcome::Failed => "✗",
            Outcome::WithinNoise => "≈ within noise",
        }
    }
}

/// One test of a claim (one per row for a starred test): as written (references shown as
/// `[table · row · column]`), and, when its runs exist, what it read and its outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    pub rule: String,
    pub outcome: Option<(String, Outcome)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Judged {
    pub verdict: Verdict,
    pub tests: Vec<Checked>,
    /// The claim's note, its references filled with their cells (empty when not run).
    pub note: String,
    /// What the tests read on their left-hand sides: one number, or the smallest to the largest.
    pub ours: String,
    /// The claim's explanation, checked (none when it has none or its runs are missing).
    pub explanation: Option<Explained>,
}

/// An explanation's rule over the runs, and its text filled.
#[derive(Clone, Debug, PartialEq)]
pub struct Explained {
    /// Every test passed.
    pub stands: bool,
    pub tests: Vec<Checked>,
    pub text: String,
}

impl Judged {
    /// A verdict that needs an explanation: the claim differs or partly holds.
    pub fn needs_explanation(&self) -> bool {
        matches!(self.verdict, Verdict::Differs | Verdict::Partly)
    }

    /// Whether it needs one and has one that stands.
    pub fn is_explained(&self) -> bool {
        self.needs_explanation() && self.explanation.as_ref().is_some_and(|e| e.stands)
    }
}

/// Every test of `texts` (a starred one once per row of its table) checked over `runs`, the
/// left-hand values read, and whether some test's run is missing.
fn check(
    texts: &[String],
    claim: &Claim,
    runs: &Runs,
    tolerance: Option<&Tolerance>,
) -> Result<(Vec<Checked>, Vec<f64>, bool), String> {
    let mut tests = Vec::new();
    let mut read = Vec::new();
    let mut missing = false;
    for text in texts {
        let written_test = Test::parse(text)?;
        let ran = written_test
            .references()
            .iter()
            .all(|r| runs.contains_key(experiment_of(r, claim)));
        if !ran {
            missing = true;
            tests.push(Checked {
                rule: written(&written_test, tolerance),
                outcome: None,
            });
            continue;
        }
        let rows: Vec<String> = match written_test.starred() {
            Some(r) => {
                let rows: Vec<String> = table(r, claim, runs)?
                    .rows
                    .iter()
                    .map(|(label, _)| label.clone())
                    .collect();
                // No rows would leave the claim without a test: no verdict can follow from that.
                if rows.is_empty() {
                    return Err(format!("[{r}] reads every row of a table with none"));
                }
                rows
            }
            None => Vec::new(),
        };
        for (_, test) in written_test.per_row(&rows) {
            let (shown, outcome, left) = decide(&test, claim, runs, tolerance)?;
            read.push(left);
            tests.push(Checked {
                rule: written(&test, tolerance),
                outcome: Some((shown, outcome)),
            });
        }
    }
    Ok((tests, read, missing))
}

/// The verdict on `claim` over `runs`, a `~` bound widened by `tolerance`; a reference to a
/// missing table, row or column of a run that exists is an error (the message names it).
pub fn judge(claim: &Claim, runs: &Runs, tolerance: Option<&Tolerance>) -> Result<Judged, String> {
    let (tests, read, missing) = check(&claim.tests, claim, runs, tolerance)?;
    let count = |o: Outcome| {
        tests
            .iter()
            .filter(|t| t.outcome.as_ref().is_some_and(|(_, x)| *x == o))
            .count()
    };
    let (passed, failed, noise) = (
        count(Outcome::Passed),
        count(Outcome::Failed),
        count(Outcome::WithinNoise),
    );
    let verdict = match (missing, passed, failed, noise) {
        (true, ..) => Verdict::NotRun,
        (false, p, 0, 0) if p > 0 => Verdict::Holds,
        (false, 0, 0, _) => Verdict::WithinNoise,
        (false, 0, ..) => Verdict::Differs,
        _ => Verdict::Partly,
    };
    let note = match verdict {
        Verdict::NotRun => String::new(),
        _ => fill(&claim.note, claim, runs)?,
    };
    let low = read.iter().copied().fold(f64::INFINITY, f64::min);
    let high = read.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let ours = match read.len() {
        0 => String::new(),
        _ if low == high => number(low),
        _ => format!("{}–{}", number(low), number(high)),
    };
    let explanation = match &claim.explanation {
        Some(e) if verdict != Verdict::NotRun => {
            let (tests, _, missing) = check(&e.tests, claim, runs, None)?;
            let passed = |t: &Checked| matches!(t.outcome, Some((_, Outcome::Passed)));
            Some(Explained {
                stands: !missing && tests.iter().all(passed),
                tests,
                text: fill(&e.text, claim, runs)?,
            })
        }
        _ => None,
    };
    Ok(Judged {
        verdict,
        tests,
        note,
        ours,
        explanation,
    })
}

/// A test's values as read, its outcome, and its left-hand value.
fn decide(
    test: &Test,
    claim: &Claim,
    runs: &Runs,
    tolerance: Option<&Tolerance>,
) -> Result<(String, Outcome, f64), String> {
    let factor = tolerance.map_or(1.0, |t| t.factor);
    // A `~` bound is loosened: on the side a test wants small it grows, on the other it shrinks.
    let value = |e: &Expression, loosen: Loosen| evaluate(e, claim, runs, loosen);
    let (a, shown, outcome) = match test {
        Test::Compare(a, comparison, b) => {
            let wants_a_large = matches!(comparison, Comparison::Greater | Comparison::AtLeast);
            let (loosen_a, loosen_b) = match wants_a_large {
                true => (Loosen::Up(factor), Loosen::Down(factor)),
                false => (Loosen::Down(factor), Loosen::Up(factor)),
            };
            let (a, b) = (value(a, loosen_a)?, value(b, loosen_b)?);
            let holds = |x: f64, y: f64| comparison.holds(x, y);
            let ends = [holds(a.low, b.high), holds(a.high, b.low)];
            let outcome = outcome(holds(a.value, b.value), ends);
            let noisy = outcome == Outcome::WithinNoise;
            let shown = format!(
                "{} {} {}",
                spread(a, noisy),
                comparison.symbol(),
                spread(b, noisy)
            );
            (a, shown, outcome)
        }
        Test::Within(a, low, high, tolerant) => {
            let a = value(a, Loosen::Up(1.0))?;
            let (low, high) = match tolerant {
                true => (low / factor, high * factor),
                false => (*low, *high),
            };
            let inside = |x: f64| (low..=high).contains(&x);
            let straddles = a.low < low && a.high > high;
            let ends = match straddles {
                true => [true, false],
                false => [inside(a.low), inside(a.high)],
            };
            let outcome = outcome(inside(a.value), ends);
            let noisy = outcome == Outcome::WithinNoise;
            let shown = format!(
                "{} in [{}, {}]",
                spread(a, noisy),
                number(low),
                number(high)
            );
            (a, shown, outcome)
        }
    };
    Ok((shown, outcome, a.value))
}

/// Passed or failed as the numbers shown say, unless the two extreme ends of the spreads disagree.
fn outcome(holds: bool, ends: [bool; 2]) -> Outcome {
    match (ends[0] == ends[1], holds) {
        (false, _) => Outcome::WithinNoise,
        (true, true) => Outcome::Passed,
        (true, false) => Outcome::Failed,
    }
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

/// A value, with the range it spans when that range decided the outcome.
fn spread(x: Spread, with_range: bool) -> String {
    match with_range && !x.is_exact() {
        true => format!(
            "{} (spread {}–{})",
            number(x.value),
            number(x.low),
            number(x.high)
        ),
        false => number(x.value),
    }
}

/// An expression as a reader reads it: references as `[table · row · column]`.
fn shown(e: &Expression) -> String {
    let term = |t: &Term| match t {
        Term::Number(n) => number(*n),
        Term::Tolerant(n) => format!("~{}", number(*n)),
        Term::Cell(r) => format!("[{r}]"),
    };
    let mut out = term(&e.first);
    for (times, t) in &e.rest {
        out += if *times { " × " } else { " / " };
        out += &term(t);
    }
    out
}

/// The test as a reader reads it, with the tolerance beside it when it widens a bound.
fn written(test: &Test, tolerance: Option<&Tolerance>) -> String {
    let text = match test {
        Test::Compare(a, c, b) => format!("{} {} {}", shown(a), c.symbol(), shown(b)),
        Test::Within(a, low, high, tolerant) => {
            let mark = if *tolerant { "~" } else { "" };
            format!(
                "{} in {mark}[{}, {}]",
                shown(a),
                number(*low),
                number(*high)
            )
        }
    };
    match (test.is_tolerant(), tolerance) {
        (true, Some(t)) => format!("{text} (tolerance ×{}: {})", number(t.factor), t.reason),
        _ => text,
    }
}

/// Which way a `~` bound moves: multiplied (an upper bound) or divided (a lower one) by the factor.
#[derive(Clone, Copy)]
enum Loosen {
    Up(f64),
    Down(f64),
}

fn evaluate(e: &Expression, claim: &Claim, runs: &Runs, loosen: Loosen) -> Result<Spread, String> {
    let term = |t: &Term| match t {
        Term::Number(n) => Ok(Spread::exact(*n)),
        Term::Tolerant(n) => Ok(Spread::exact(match loosen {
            Loosen::Up(factor) => n * factor,
            Loosen::Down(factor) => n / factor,
        })),
        Term::Cell(r) => match lookup(r, claim, runs)? {
            Cell::Number { value, .. } => Ok(*value),
            other => {
                let text = other.shown();
                leading_number(&text)
                    .map(Spread::exact)
                    .ok_or_else(|| format!("[{r}] is {text:?}, not a number"))
            }
        },
    };
    let mut value = term(&e.first)?;
    for (times, t) in &e.rest {
        value = match times {
            true => value.times(term(t)?),
            false => value.divided_by(term(t)?),
        };
    }
    match value.value.is_finite() && value.low.is_finite() && value.high.is_finite() {
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

/// `text` with each `{{reference}}` replaced by its cell, as the table shows it.
pub fn fill(text: &str, claim: &Claim, runs: &Runs) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("{{") {
        out.push_str(&rest[..start]);
        let end = rest[start..]
            .find("}}")
            .ok_or_else(|| format!("unclosed {{{{ in {text:?}"))?;
        let reference = Reference::parse(&rest[start + 2..start + end])?;
        out.push_str(&lookup(&reference, claim, runs)?.shown());
        rest = &rest[start + end + 2..];
    }
    out.push_str(rest);
    Ok(out)
}

/// The table a reference names: by its title, else by a unique prefix of it.
fn table<'a>(
    reference: &Reference,
    claim: &Claim,
    runs: &Runs<'a>,
) -> Result<&'a TableModel, String> {
    let experiment = experiment_of(reference, claim);
    let tables: &'a [TableModel] = runs
        .get(experiment)
        .ok_or_else(|| format!("no run of {experiment}"))?;
    let title = reference.table.as_str();
    let exact: Vec<&'a TableModel> = tables.iter().filter(|t| t.title == title).collect();
    let candidates = match exact.is_empty() {
        true => tables
            .iter()
            .filter(|t| t.title.starts_with(title))
            .collect(),
        false => exact,
    };
    match candidates[..] {
        [one] => Ok(one),
        [] => Err(format!(
            "no table titled {title:?} in {experiment}'s tables"
        )),
        _ => Err(format!(
            "{title:?} names {} tables in {experiment}'s tables",
            candidates.len()
        )),
    }
}

fn lookup<'a>(reference: &Reference, claim: &Claim, runs: &Runs<'a>) -> Result<&'a Cell, String> {
    let table = table(reference, claim, runs)?;
    table
        .cell(&reference.row, &reference.column)
        .ok_or_else(|| {
            format!(
                "table {:?} of {} has no cell at row {:?}, column {:?}",
                table.title,
                experiment_of(reference, claim),
                reference.row,
                reference.column
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::results::report::claims::Explanation;

    fn claim(tests: &[&str], note: &str) -> Claim {
        Claim {
            item: None,
            claim: "c".into(),
            paper: String::new(),
            quote: None,
            experiment: "a".into(),
            tests: tests.iter().map(|t| t.to_string()).collect(),
            note: note.into(),
            explanation: None,
        }
    }

    fn n(value: f64) -> Cell {
        Cell::Number {
            value: Spread::exact(value),
            decimals: 1,
        }
    }

    /// A time of `value` whose median pass took `median`.
    fn timed(value: f64, median: f64) -> Cell {
        Cell::Number {
            value: Spread {
                value,
                low: value,
                high: median,
            },
            decimals: 1,
        }
    }

    fn table(title: &str, columns: &[&str], rows: Vec<(&str, Vec<Cell>)>) -> TableModel {
        TableModel {
            title: title.into(),
            caption: String::new(),
            row_header: String::new(),
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows: rows.into_iter().map(|(l, c)| (l.to_string(), c)).collect(),
        }
    }

    fn museum() -> Vec<TableModel> {
        vec![table(
            "Table 2: museum",
            &["benefit", "P ms", "R ms"],
            vec![
                ("1", vec![Cell::Text("1.4×".into()), n(451.3), n(433.0)]),
                ("2", vec![n(1.2), n(285.7), n(292.4)]),
            ],
        )]
    }

    #[test]
    fn verdicts_follow_from_how_many_tests_pass() {
        let a = museum();
        let b = [
            table("Fig. 5", &["x"], vec![("room", vec![Cell::Missing])]),
            table("Empty", &["x"], vec![]),
        ];
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
            None,
        )
        .unwrap();
        assert_eq!(partly.verdict, Verdict::Partly);
        assert_eq!(
            partly.tests[0],
            Checked {
                rule: "[Table 2 · 1 · P ms] < [Table 2 · 1 · R ms]".into(),
                outcome: Some(("451.3 < 433".into(), Outcome::Failed)),
            }
        );
        assert_eq!(
            partly.tests[1].outcome,
            Some(("285.7 < 292.4".into(), Outcome::Passed))
        );
        assert_eq!(partly.note, "P 285.7 ms");
        assert_eq!(partly.ours, "285.7–451.3");
        let holds = judge(
            &claim(
                &["{{Table 2 | 1 | benefit}} / {{Table 2 | 2 | benefit}} in [1.1, 1.2]"],
                "",
            ),
            &runs,
            None,
        )
        .unwrap();
        assert_eq!(holds.verdict, Verdict::Holds);
        assert_eq!(
            holds.tests[0].outcome,
            Some(("1.167 in [1.1, 1.2]".into(), Outcome::Passed))
        );
        let differs = judge(&claim(&["{{Table 2 | * | benefit}} >= 3"], ""), &runs, None).unwrap();
        assert_eq!(differs.verdict, Verdict::Differs);
        assert_eq!(differs.tests.len(), 2, "one test per row");
        assert_eq!(differs.tests[1].rule, "[Table 2 · 2 · benefit] ≥ 3");
        // An experiment without a run: not run, whatever the others say.
        let not_run = judge(
            &claim(
                &["{{Table 2 | 1 | benefit}} >= 1", "{{c | T | r | x}} > 0"],
                "{{c | T | r | x}}",
            ),
            &runs,
            None,
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
            ("{{b | Empty | * | x}} > 0", "a table with none"),
        ] {
            let e = judge(&claim(&[test], ""), &runs, None).unwrap_err();
            assert!(e.contains(why), "{test}: {e}");
        }
    }

    /// The museum's benefit 1.2 at 2 threads fails "≥ 3"; an explanation stands only when every
    /// one of its tests passes, on a claim that differs or partly holds.
    #[test]
    fn an_explanation_stands_when_its_rule_passes_and_fills_its_text() {
        let a = museum();
        let runs: Runs = [("a", &a[..])].into_iter().collect();
        let explained = |tests: &[&str], claim_tests: &[&str]| {
            let mut c = claim(claim_tests, "");
            c.explanation = Some(Explanation {
                tests: tests.iter().map(|t| t.to_string()).collect(),
                text: "P takes {{Table 2 | 2 | P ms}} ms".into(),
            });
            judge(&c, &runs, None).unwrap()
        };
        let differs = ["{{Table 2 | 2 | benefit}} >= 3"];
        let stands = explained(&["{{Table 2 | * | P ms}} / 100 > 2"], &differs);
        assert_eq!(stands.verdict, Verdict::Differs);
        let e = stands.explanation.as_ref().unwrap();
        assert!(e.stands && stands.is_explained());
        assert_eq!(e.text, "P takes 285.7 ms");
        assert_eq!(e.tests.len(), 2, "one test per row");
        // Row 2 (285.7 ms) passes, row 1 (451.3) fails "< 300": the rule does not stand.
        let fails = explained(&["{{Table 2 | * | P ms}} < 300"], &differs);
        assert!(!fails.explanation.as_ref().unwrap().stands);
        assert!(fails.needs_explanation() && !fails.is_explained());
        // A claim that holds needs none, whatever its explanation says.
        let holds = explained(
            &["{{Table 2 | 2 | P ms}} < 300"],
            &["{{Table 2 | 2 | benefit}} > 1"],
        );
        assert_eq!(holds.verdict, Verdict::Holds);
        assert!(!holds.needs_explanation() && !holds.is_explained());
        // An explanation that reads a table the run lacks is an error naming it.
        let mut c = claim(&differs, "");
        c.explanation = Some(Explanation {
            tests: vec!["{{Table 9 | 1 | x}} > 0".into()],
            text: String::new(),
        });
        assert!(judge(&c, &runs, None).unwrap_err().contains("Table 9"));
    }

    fn outcomes(judged: &Judged) -> Vec<Outcome> {
        let outcome = |t: &Checked| t.outcome.as_ref().map(|(_, o)| *o);
        judged.tests.iter().filter_map(outcome).collect()
    }

    /// 100 ms against 103 ms is a pass on the fastest passes, but the first time's median pass
    /// took 106 ms: within noise. A ratio's spread decides a bound the same way.
    #[test]
    fn a_difference_inside_the_spread_is_within_noise_and_counts_as_neither() {
        let t = [table(
            "T",
            &["a", "b", "c"],
            vec![
                (
                    "x",
                    vec![
                        timed(100.0, 106.0),
                        timed(103.0, 104.0),
                        timed(200.0, 201.0),
                    ],
                ),
                (
                    "y",
                    vec![
                        timed(100.0, 101.0),
                        timed(103.0, 104.0),
                        timed(300.0, 330.0),
                    ],
                ),
            ],
        )];
        let runs: Runs = [("a", &t[..])].into_iter().collect();
        let judged = judge(&claim(&["{{T | * | a}} < {{T | * | b}}"], ""), &runs, None).unwrap();
        assert_eq!(outcomes(&judged), [Outcome::WithinNoise, Outcome::Passed]);
        assert_eq!(judged.verdict, Verdict::Partly);
        assert_eq!(
            judged.tests[0].outcome.as_ref().unwrap().0,
            "100 (spread 100–106) < 103 (spread 103–104)"
        );
        // c / a: 2 (x: spread 200/106 … 201/100) and 3 (y: 300/101 … 330/100 = 2.97 … 3.3).
        let bound = judge(
            &claim(&["{{T | * | c}} / {{T | * | a}} >= 3"], ""),
            &runs,
            None,
        )
        .unwrap();
        assert_eq!(outcomes(&bound), [Outcome::Failed, Outcome::WithinNoise]);
        assert_eq!(bound.verdict, Verdict::Differs);
        let only_noise =
            judge(&claim(&["{{T | x | a}} < {{T | x | b}}"], ""), &runs, None).unwrap();
        assert_eq!(only_noise.verdict, Verdict::WithinNoise);
        // A range bound inside the spread is noise too.
        let within = judge(
            &claim(&["{{T | y | c}} / 100 in [3, 3.2]"], ""),
            &runs,
            None,
        )
        .unwrap();
        assert_eq!(within.verdict, Verdict::WithinNoise);
    }

    #[test]
    fn a_tolerant_bound_is_loosened_by_the_declared_factor_and_says_so() {
        let a = museum();
        let runs: Runs = [("a", &a[..])].into_iter().collect();
        let tolerance = Tolerance {
            factor: 1.25,
            reason: "15 years of hardware".into(),
        };
        // 1.2 against "≥ 1.5": fails as written, passes as ~1.5 (1.5 / 1.25 = 1.2).
        let strict = judge(
            &claim(&["{{Table 2 | 2 | benefit}} >= 1.5"], ""),
            &runs,
            Some(&tolerance),
        )
        .unwrap();
        assert_eq!(strict.verdict, Verdict::Differs);
        let loose = judge(
            &claim(&["{{Table 2 | 2 | benefit}} >= ~1.5"], ""),
            &runs,
            Some(&tolerance),
        )
        .unwrap();
        assert_eq!(loose.verdict, Verdict::Holds);
        assert_eq!(
            loose.tests[0].rule,
            "[Table 2 · 2 · benefit] ≥ ~1.5 (tolerance ×1.25: 15 years of hardware)"
        );
        let upper = judge(
            &claim(&["{{Table 2 | 2 | benefit}} in ~[0.5, 1]"], ""),
            &runs,
            Some(&tolerance),
        )
        .unwrap();
        assert_eq!(
            upper.tests[0].outcome.as_ref().unwrap().0,
            "1.2 in [0.4, 1.25]"
        );
        assert_eq!(upper.verdict, Verdict::Holds);
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
