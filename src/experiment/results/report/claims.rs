//! `claims.toml` of a paper's results directory (`results/<paper>/claims.toml`): the paper's
//! conclusions as data. A person writes each claim (the paper's words and numbers), the
//! experiment file whose run tests it, and the tests that decide it; the verdict is computed
//! (`judge`), never written. The file also lists the paper's experiment files, whose runs live in
//! `results/<paper>/<experiment>/` and which `raylab reproduce <paper>` runs.
//!
//! It lives beside the runs it is judged against, so one directory is the whole input of the
//! paper's REPORT.md (its digest covers the claims: a changed rule changes the report).
//!
//! ```toml
//! title = "Overbeck et al. 2008: large ray packets"
//! paper = "R. Overbeck, R. Ramamoorthi, W. R. Mark. Large Ray Packets … IRT 2008."
//! experiments = ["overbeck08-table2-museum", "overbeck08-fig5"]
//! [[claims]]
//! claim = "16×16 packets render a Whitted frame at least 3× faster than 2×2 SIMD packets"
//! paper = "Table 2, museum: 3.5×"
//! experiment = "overbeck08-table2-museum"        # the run the references read by default
//! tests = ["{{Table 2 (museum) | 1 | benefit}} >= 3",
//!          "{{overbeck08-fig5 | Fig. 5 | room / primary | P 16}} < {{overbeck08-fig5 | Fig. 5 | room / primary | M 16}}"]
//! note = "optional context; may quote {{Table 2 (museum) | 1 | benefit}}"
//! ```
//!
//! A test is `EXPR OP EXPR` (`OP`: `<`, `<=`, `>`, `>=`) or `EXPR in [LOW, HIGH]`; an `EXPR` is
//! numbers and cell references joined by `*` and `/`, left to right. A reference is
//! `{{table | row | column}}` in the claim's experiment or `{{experiment | table | row | column}}`
//! in another of the paper's (a table by its title or a unique prefix of it, a row by its first
//! cell, a column by its heading); the cell's leading number is its value.

use std::fmt;
use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

pub const CLAIMS_TOML: &str = "claims.toml";

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Claims {
    pub title: String,
    pub paper: String,
    /// The paper's experiment files, by name (`experiments/<name>.toml`), in running order.
    pub experiments: Vec<String>,
    #[serde(default)]
    pub claims: Vec<Claim>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// The conclusion, in the paper's words or close to them.
    pub claim: String,
    /// The paper's numbers for it, as text.
    pub paper: String,
    /// The experiment whose run the references read unless they name another.
    pub experiment: String,
    /// All pass: holds; some: partly; none: differs.
    pub tests: Vec<String>,
    #[serde(default)]
    pub note: String,
}

/// A claim's verdict: computed from its tests over the committed runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    Holds,
    Partly,
    Differs,
    /// An experiment the claim reads has no run in the paper's directory.
    NotRun,
}

impl Verdict {
    pub const ALL: [Verdict; 4] = [
        Verdict::Holds,
        Verdict::Partly,
        Verdict::Differs,
        Verdict::NotRun,
    ];
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Holds => "holds",
            Verdict::Partly => "partly",
            Verdict::Differs => "differs",
            Verdict::NotRun => "not run",
        })
    }
}

/// How the verdict follows from the tests, printed once in every report.
pub const RULE: &str =
    "holds when every test of the claim passes, partly when some do, differs when none does; \
     not run when an experiment it reads has no run here";

impl Claims {
    /// Reads `path`: invalid TOML, an unknown field, a claim reading an experiment the file does
    /// not list, or a test that does not parse is an input error naming the file and line.
    pub fn read(path: &Path) -> Result<(Claims, String)> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let claims: Claims = toml::from_str(&text).map_err(|e| {
            let line = e.span().map(|s| line_of(&text, s.start));
            Error::input(path, line, e.message().to_string())
        })?;
        for claim in &claims.claims {
            let fail = |message: String| {
                let line = claim_line(&text, &claim.claim);
                Error::input(path, line, format!("{:?}: {message}", claim.claim))
            };
            if claim.tests.is_empty() {
                return Err(fail("no tests: a verdict needs at least one".into()));
            }
            for test in &claim.tests {
                let parsed = Test::parse(test).map_err(|m| fail(format!("{test:?}: {m}")))?;
                for reference in parsed.references() {
                    let experiment = reference.experiment.as_deref();
                    let experiment = experiment.unwrap_or(&claim.experiment);
                    if !claims.experiments.iter().any(|e| e == experiment) {
                        return Err(fail(format!(
                            "experiment {experiment:?} is not in this file's experiments"
                        )));
                    }
                }
            }
            if !claims.experiments.contains(&claim.experiment) {
                return Err(fail(format!(
                    "experiment {:?} is not in this file's experiments",
                    claim.experiment
                )));
            }
        }
        Ok((claims, text))
    }
}

/// The 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at].matches('\n').count() + 1
}

/// The line of `text` that states the claim `claim` (`claim = "…"`), for error messages.
pub fn claim_line(text: &str, claim: &str) -> Option<usize> {
    let stated = format!("claim = {}", toml::Value::from(claim));
    text.find(&stated)
        .or_else(|| text.find(claim))
        .map(|at| line_of(text, at))
}

/// `{{[experiment |] table | row | column}}`.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    pub experiment: Option<String>,
    pub table: String,
    pub row: String,
    pub column: String,
}

impl Reference {
    pub fn parse(inner: &str) -> std::result::Result<Reference, String> {
        let parts: Vec<String> = inner.split(" | ").map(|p| p.trim().to_string()).collect();
        match &parts[..] {
            [table, row, column] => Ok(Reference {
                experiment: None,
                table: table.clone(),
                row: row.clone(),
                column: column.clone(),
            }),
            [experiment, table, row, column] => Ok(Reference {
                experiment: Some(experiment.clone()),
                table: table.clone(),
                row: row.clone(),
                column: column.clone(),
            }),
            _ => Err(format!(
                "{{{{{inner}}}}}: expected {{{{table | row | column}}}} or {{{{experiment | table | row | column}}}}"
            )),
        }
    }
}

impl fmt::Display for Reference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(e) = &self.experiment {
            write!(f, "{e} · ")?;
        }
        write!(f, "{} · {} · {}", self.table, self.row, self.column)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    Number(f64),
    Cell(Reference),
}

/// Terms joined left to right by `*` (true) or `/` (false).
#[derive(Clone, Debug, PartialEq)]
pub struct Expression {
    pub first: Term,
    pub rest: Vec<(bool, Term)>,
}

impl Expression {
    fn parse(text: &str) -> std::result::Result<Expression, String> {
        let mut terms = Vec::new();
        let mut ops = Vec::new();
        let mut rest = text.trim();
        loop {
            let (term, after) = match rest.strip_prefix("{{") {
                Some(inside) => {
                    let end = inside.find("}}").ok_or("unclosed {{")?;
                    (
                        Term::Cell(Reference::parse(&inside[..end])?),
                        &inside[end + 2..],
                    )
                }
                None => {
                    let end = rest.find([' ', '*', '/']).unwrap_or(rest.len());
                    let number = rest[..end]
                        .parse::<f64>()
                        .ok()
                        .filter(|n| n.is_finite())
                        .ok_or_else(|| {
                            format!("{:?} is neither a number nor {{{{…}}}}", &rest[..end])
                        })?;
                    (Term::Number(number), &rest[end..])
                }
            };
            terms.push(term);
            rest = after.trim_start();
            match rest.chars().next() {
                None => break,
                Some('*') => ops.push(true),
                Some('/') => ops.push(false),
                Some(other) => return Err(format!("expected * or / before {other:?}")),
            }
            rest = rest[1..].trim_start();
        }
        let mut terms = terms.into_iter();
        let first = terms.next().ok_or("an empty expression")?;
        Ok(Expression {
            first,
            rest: ops.into_iter().zip(terms).collect(),
        })
    }

    fn terms(&self) -> impl Iterator<Item = &Term> {
        std::iter::once(&self.first).chain(self.rest.iter().map(|(_, t)| t))
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Comparison {
    Less,
    AtMost,
    Greater,
    AtLeast,
}

impl Comparison {
    const ALL: [(&'static str, Comparison); 4] = [
        (" <= ", Comparison::AtMost),
        (" >= ", Comparison::AtLeast),
        (" < ", Comparison::Less),
        (" > ", Comparison::Greater),
    ];

    pub fn holds(self, a: f64, b: f64) -> bool {
        match self {
            Comparison::Less => a < b,
            Comparison::AtMost => a <= b,
            Comparison::Greater => a > b,
            Comparison::AtLeast => a >= b,
        }
    }

    pub fn symbol(self) -> &'static str {
        match self {
            Comparison::Less => "<",
            Comparison::AtMost => "≤",
            Comparison::Greater => ">",
            Comparison::AtLeast => "≥",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Test {
    Compare(Expression, Comparison, Expression),
    Within(Expression, f64, f64),
}

impl Test {
    pub fn parse(text: &str) -> std::result::Result<Test, String> {
        if let Some((value, range)) = text.rsplit_once(" in ") {
            let range = range.trim();
            let inner = range
                .strip_prefix('[')
                .and_then(|r| r.strip_suffix(']'))
                .ok_or("a range is written [LOW, HIGH]")?;
            let bounds: Vec<f64> = inner
                .split(',')
                .map(|b| {
                    b.trim()
                        .parse::<f64>()
                        .map_err(|_| format!("{b:?} is not a number"))
                })
                .collect::<std::result::Result<_, _>>()?;
            let [low, high] = bounds[..] else {
                return Err("a range is written [LOW, HIGH]".into());
            };
            if !(low.is_finite() && high.is_finite()) {
                return Err(format!(
                    "a range's bounds must be finite (got [{low}, {high}])"
                ));
            }
            if low > high {
                return Err(format!("empty range [{low}, {high}]"));
            }
            return Ok(Test::Within(Expression::parse(value)?, low, high));
        }
        for (symbol, comparison) in Comparison::ALL {
            if let Some((a, b)) = text.split_once(symbol) {
                return Ok(Test::Compare(
                    Expression::parse(a)?,
                    comparison,
                    Expression::parse(b)?,
                ));
            }
        }
        Err("expected EXPR < EXPR (or <=, >, >=) or EXPR in [LOW, HIGH]".into())
    }

    pub fn references(&self) -> Vec<&Reference> {
        let expressions: Vec<&Expression> = match self {
            Test::Compare(a, _, b) => vec![a, b],
            Test::Within(a, _, _) => vec![a],
        };
        expressions
            .into_iter()
            .flat_map(Expression::terms)
            .filter_map(|t| match t {
                Term::Cell(r) => Some(r),
                Term::Number(_) => None,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tests_parse_into_expressions_comparisons_and_ranges() {
        let t = Test::parse("{{Table 2 | 1 | benefit}} / {{fig5 | Fig. 5 | room | P 16}} >= 3")
            .unwrap();
        let Test::Compare(a, Comparison::AtLeast, b) = &t else {
            panic!("{t:?}")
        };
        assert_eq!(
            b,
            &Expression {
                first: Term::Number(3.0),
                rest: vec![]
            }
        );
        assert_eq!(a.rest.len(), 1);
        assert!(!a.rest[0].0, "a division");
        let refs = t.references();
        assert_eq!(refs.len(), 2);
        assert_eq!(refs[0].experiment, None);
        assert_eq!(refs[1].experiment.as_deref(), Some("fig5"));
        assert_eq!(refs[1].to_string(), "fig5 · Fig. 5 · room · P 16");
        let w = Test::parse("{{T | r | c}} * 2 in [0.5, 4]").unwrap();
        assert!(matches!(w, Test::Within(_, 0.5, 4.0)), "{w:?}");
        for (bad, why) in [
            ("{{T | r | c}} = 3", "expected EXPR"),
            ("{{T | r}} < 3", "expected {{table"),
            ("{{T | r | c}} < three", "neither a number"),
            ("{{T | r | c < 3", "unclosed"),
            ("{{T | r | c}} in [4, 1]", "empty range"),
            ("{{T | r | c}} in [NaN, 1]", "must be finite"),
            ("{{T | r | c}} in 1..4", "[LOW, HIGH]"),
            ("{{T | r | c}} + 1 < 3", "expected * or /"),
        ] {
            let e = Test::parse(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }

    #[test]
    fn a_claim_on_an_unlisted_experiment_or_without_tests_is_an_error_with_its_line() {
        let dir = std::env::temp_dir().join(format!("raylab-claims-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(CLAIMS_TOML);
        let head = "title = \"t\"\npaper = \"p\"\nexperiments = [\"a\"]\n";
        for (body, why, line) in [
            (
                "[[claims]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"b\"\ntests = [\"1 < 2\"]\n",
                "\"b\" is not in",
                5,
            ),
            (
                "[[claims]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"{{b | T | r | c}} < 2\"]\n",
                "\"b\" is not in",
                5,
            ),
            (
                "[[claims]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = []\n",
                "no tests",
                5,
            ),
            (
                "[[claims]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\nverdict = \"holds\"\ntests = [\"1 < 2\"]\n",
                "unknown field",
                8,
            ),
        ] {
            std::fs::write(&path, format!("{head}{body}")).unwrap();
            let e = Claims::read(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(why), "{e}");
            assert!(e.to_string().contains(&format!("claims.toml:{line}")), "{e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
