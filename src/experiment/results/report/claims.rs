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
//!
//! A claim that differs or partly holds may carry its `explanation`: tests of the same grammar
//! over the run's counts and unit costs (the cost model, `record::cost_model`) and a text that
//! says what they show. The explanation stands when every one of its tests passes; the report
//! prints it beside the verdict and counts the claims that differ with none that stands.
//!
//! ```toml
//! explanation = { tests = ["{{Table 1 | * | bound from box tests}} < 3.34"],
//!                 text = "box tests are {{Table 1 | conference | box share}} of a packet's time" }
//! ```

use std::fmt;
use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

pub const CLAIMS_TOML: &str = "claims.toml";

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Claims {
    pub title: String,
    /// The citation.
    pub paper: String,
    /// The paper's text, a file name in `../shared/papers/`: every claim's `quote` is in it.
    pub paper_text: Option<String>,
    /// The paper's experiment files, by name (`experiments/<name>.toml`), in running order.
    pub experiments: Vec<String>,
    /// The one widening a test may use (`~N`), declared once with its reason.
    pub tolerance: Option<Tolerance>,
    /// The paper's quantitative items.
    #[serde(default)]
    pub claims: Vec<Claim>,
    /// The paper's items a CPU here cannot reproduce, each with the reason.
    #[serde(default)]
    pub not_reproducible: Vec<NotReproducible>,
    /// raylab's own targets (against Embree, tinybvh, …): judged alike, counted apart.
    #[serde(default)]
    pub targets: Vec<Claim>,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// A `~` lower bound is divided by it, a `~` upper bound multiplied.
    pub factor: f64,
    pub reason: String,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// The paper's item it tests (`O1`, `Bt5`); none for a target.
    pub item: Option<String>,
    /// The conclusion, in the paper's words or close to them.
    pub claim: String,
    /// The paper's numbers for it, as text.
    pub paper: String,
    /// The paper's own words for it, verbatim from `paper_text`: every number a test uses is in it.
    pub quote: Option<String>,
    /// The experiment whose run the references read unless they name another.
    pub experiment: String,
    /// All pass: holds; some: partly; none: differs (see `RULE`).
    pub tests: Vec<String>,
    #[serde(default)]
    pub note: String,
    /// Why it differs or partly holds, by rule.
    pub explanation: Option<Explanation>,
}

/// A rule over the run's counts and unit costs that explains a gap, and what it shows.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Explanation {
    /// Tests like a claim's: the explanation stands when all pass.
    pub tests: Vec<String>,
    /// What the rule shows; `{{references}}` are filled from the tables.
    pub text: String,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NotReproducible {
    pub item: String,
    pub claim: String,
    pub paper: String,
    pub reason: String,
}

/// A claim's verdict: computed from its tests over the committed runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    Holds,
    Partly,
    Differs,
    /// Every test's difference lies inside the spread of the values it compares.
    WithinNoise,
    /// An experiment the claim reads has no run in the paper's directory.
    NotRun,
}

impl Verdict {
    pub const ALL: [Verdict; 5] = [
        Verdict::Holds,
        Verdict::Partly,
        Verdict::Differs,
        Verdict::WithinNoise,
        Verdict::NotRun,
    ];
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Holds => "holds",
            Verdict::Partly => "partly",
            Verdict::Differs => "differs",
            Verdict::WithinNoise => "within noise",
            Verdict::NotRun => "not run",
        })
    }
}

/// How the verdict follows from the tests, printed once in every report.
pub const RULE: &str =
    "a test is within noise when its outcome changes somewhere inside the spread of the values it \
     compares (each time from its fastest to its median pass, carried through ratios); a claim \
     holds when every test passes, is within noise when every test is, differs when none passes, \
     and partly holds otherwise; not run when an experiment it reads has no run here";

impl Claims {
    /// Reads `path`: invalid TOML, an unknown field, a claim reading an experiment the file does
    /// not list, a test that does not parse, a paper claim without its item or quote, a test
    /// number its quote does not state, or a `~` without a declared tolerance is an input error
    /// naming the file and line.
    pub fn read(path: &Path) -> Result<(Claims, String)> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let claims: Claims = toml::from_str(&text).map_err(|e| {
            let line = e.span().map(|s| line_of(&text, s.start));
            Error::input(path, line, e.message().to_string())
        })?;
        let fail = |claim: &str, message: String| {
            Error::input(
                path,
                claim_line(&text, claim),
                format!("{claim:?}: {message}"),
            )
        };
        if let Some(t) = &claims.tolerance {
            if !(t.factor.is_finite() && t.factor >= 1.0) {
                return Err(Error::input(
                    path,
                    None,
                    format!("tolerance factor {} must be a finite number ≥ 1", t.factor),
                ));
            }
        }
        for (claim, of_paper) in claims.all() {
            let fail = |message: String| fail(&claim.claim, message);
            if claim.tests.is_empty() {
                return Err(fail("no tests: a verdict needs at least one".into()));
            }
            match (of_paper, &claim.item, &claim.quote) {
                (true, None, _) => return Err(fail("a paper's claim names its item".into())),
                (true, _, None) => {
                    return Err(fail("a paper's claim quotes the paper (quote)".into()))
                }
                (true, _, _) if claims.paper_text.is_none() => {
                    return Err(fail("quotes need the file's paper_text".into()))
                }
                (false, Some(_), _) | (false, _, Some(_)) => {
                    return Err(fail("a target has no item or quote".into()))
                }
                _ => {}
            }
            if !claims.experiments.contains(&claim.experiment) {
                return Err(fail(format!(
                    "experiment {:?} is not in this file's experiments",
                    claim.experiment
                )));
            }
            if claim
                .explanation
                .as_ref()
                .is_some_and(|e| e.tests.is_empty())
            {
                return Err(fail("an explanation without tests: it needs a rule".into()));
            }
            // (test, whether it is the explanation's: its bounds are the model's arithmetic, not
            // the paper's numbers, so its quote does not state them).
            let explaining = claim.explanation.iter().flat_map(|e| &e.tests);
            let all = (claim.tests.iter().map(|t| (t, false))).chain(explaining.map(|t| (t, true)));
            for (test, explains) in all {
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
                if parsed.is_tolerant() && claims.tolerance.is_none() {
                    return Err(fail(format!(
                        "{test:?} widens a bound with ~ but the file declares no tolerance"
                    )));
                }
                if let Some(quote) = claim.quote.as_ref().filter(|_| !explains) {
                    let stated = allowed_numbers(quote);
                    let unstated = parsed
                        .numbers()
                        .into_iter()
                        .find(|&n| n != 0.0 && n != 1.0 && !stated.iter().any(|&s| same(s, n)));
                    if let Some(n) = unstated {
                        return Err(fail(format!(
                            "{test:?} uses {n}, a number its quote does not state"
                        )));
                    }
                }
            }
        }
        Ok((claims, text))
    }

    /// Every claim, the paper's (true) then the targets (false).
    pub fn all(&self) -> impl Iterator<Item = (&Claim, bool)> {
        let paper = self.claims.iter().map(|c| (c, true));
        paper.chain(self.targets.iter().map(|c| (c, false)))
    }
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// The numbers written in `text` (`3.34–6.11×` gives 3.34 and 6.11; `1,024` gives 1024).
pub fn numbers_in(text: &str) -> Vec<f64> {
    stated_numbers(text).into_iter().map(|(n, _)| n).collect()
}

/// The numbers a test may use from its quote: each number as written, and a percentage `p%` also
/// as the fraction p/100 and the factor 1 + p/100 ("30% faster": × 1.3).
fn allowed_numbers(quote: &str) -> Vec<f64> {
    let mut out = Vec::new();
    for (n, percent) in stated_numbers(quote) {
        out.push(n);
        if percent {
            out.extend([n / 100.0, 1.0 + n / 100.0]);
        }
    }
    out
}

/// Numbers a paper writes as words ("a factor of two").
const NUMBER_WORDS: [(&str, f64); 12] = [
    ("two", 2.0),
    ("three", 3.0),
    ("four", 4.0),
    ("five", 5.0),
    ("six", 6.0),
    ("seven", 7.0),
    ("eight", 8.0),
    ("nine", 9.0),
    ("ten", 10.0),
    ("twice", 2.0),
    ("half", 0.5),
    ("hundred", 100.0),
];

/// The numbers of `text`, each with whether a `%` follows it: written in digits, or as a word of
/// `NUMBER_WORDS`.
fn stated_numbers(text: &str) -> Vec<(f64, bool)> {
    let words = text.split(|c: char| !c.is_alphabetic()).filter_map(|w| {
        let w = w.to_lowercase();
        NUMBER_WORDS
            .iter()
            .find(|(name, _)| *name == w)
            .map(|&(_, n)| (n, false))
    });
    let mut out: Vec<(f64, bool)> = words.collect();
    let mut current = String::new();
    let chars: Vec<char> = text.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        let digit_next = chars.get(i + 1).is_some_and(char::is_ascii_digit);
        let thousands = c == ',' && !current.is_empty() && digit_next;
        if c.is_ascii_digit() || (c == '.' && digit_next) {
            current.push(c);
        } else if !thousands && !current.is_empty() {
            let percent = chars[i..].iter().find(|c| **c != ' ') == Some(&'%');
            out.extend(current.parse::<f64>().ok().map(|n| (n, percent)));
            current.clear();
        }
    }
    out.extend(current.parse::<f64>().ok().map(|n| (n, false)));
    out
}

/// `text` as quotes are matched against the paper: lower case, every run of whitespace one space.
pub fn normalised(text: &str) -> String {
    text.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_lowercase()
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

/// The row of a reference that stands for every row of its table: the test is run once per row.
pub const EVERY_ROW: &str = "*";

#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    Number(f64),
    /// `~N`: a bound widened by the paper's declared tolerance.
    Tolerant(f64),
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
                    let (tolerant, literal) = match rest[..end].strip_prefix('~') {
                        Some(literal) => (true, literal),
                        None => (false, &rest[..end]),
                    };
                    let number = literal
                        .parse::<f64>()
                        .ok()
                        .filter(|n| n.is_finite())
                        .ok_or_else(|| {
                            format!("{:?} is neither a number nor {{{{…}}}}", &rest[..end])
                        })?;
                    let term = match tolerant {
                        true => Term::Tolerant(number),
                        false => Term::Number(number),
                    };
                    (term, &rest[end..])
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

    pub fn terms(&self) -> impl Iterator<Item = &Term> {
        std::iter::once(&self.first).chain(self.rest.iter().map(|(_, t)| t))
    }

    pub fn terms_mut(&mut self) -> impl Iterator<Item = &mut Term> {
        std::iter::once(&mut self.first).chain(self.rest.iter_mut().map(|(_, t)| t))
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
    /// `EXPR in [LOW, HIGH]`, or `in ~[LOW, HIGH]` (true): widened by the tolerance.
    Within(Expression, f64, f64, bool),
}

impl Test {
    pub fn parse(text: &str) -> std::result::Result<Test, String> {
        if let Some((value, range)) = text.rsplit_once(" in ") {
            let range = range.trim();
            let (tolerant, range) = match range.strip_prefix('~') {
                Some(range) => (true, range),
                None => (false, range),
            };
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
            return Ok(Test::Within(Expression::parse(value)?, low, high, tolerant));
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

    fn expressions(&self) -> Vec<&Expression> {
        match self {
            Test::Compare(a, _, b) => vec![a, b],
            Test::Within(a, ..) => vec![a],
        }
    }

    pub fn references(&self) -> Vec<&Reference> {
        let terms = self.expressions().into_iter().flat_map(Expression::terms);
        terms
            .filter_map(|t| match t {
                Term::Cell(r) => Some(r),
                _ => None,
            })
            .collect()
    }

    /// Every number literal, bounds included.
    pub fn numbers(&self) -> Vec<f64> {
        let terms = self.expressions().into_iter().flat_map(Expression::terms);
        let mut numbers: Vec<f64> = terms
            .filter_map(|t| match t {
                Term::Number(n) | Term::Tolerant(n) => Some(*n),
                Term::Cell(_) => None,
            })
            .collect();
        if let Test::Within(_, low, high, _) = self {
            numbers.extend([*low, *high]);
        }
        numbers
    }

    /// Whether a bound is widened by the tolerance.
    pub fn is_tolerant(&self) -> bool {
        let mut terms = self.expressions().into_iter().flat_map(Expression::terms);
        matches!(self, Test::Within(_, _, _, true)) || terms.any(|t| matches!(t, Term::Tolerant(_)))
    }

    /// One test per row where a reference reads every row (`EVERY_ROW`): the starred references
    /// take each of `rows` in turn; the test itself when none does.
    pub fn per_row(&self, rows: &[String]) -> Vec<(Option<String>, Test)> {
        if !self.references().iter().any(|r| r.row == EVERY_ROW) {
            return vec![(None, self.clone())];
        }
        rows.iter()
            .map(|row| {
                let mut test = self.clone();
                let expressions: Vec<&mut Expression> = match &mut test {
                    Test::Compare(a, _, b) => vec![a, b],
                    Test::Within(a, ..) => vec![a],
                };
                for term in expressions.into_iter().flat_map(Expression::terms_mut) {
                    if let Term::Cell(r) = term {
                        if r.row == EVERY_ROW {
                            r.row = row.clone();
                        }
                    }
                }
                (Some(row.clone()), test)
            })
            .collect()
    }

    /// The first reference reading every row: whose table's rows a starred test steps through.
    pub fn starred(&self) -> Option<&Reference> {
        self.references().into_iter().find(|r| r.row == EVERY_ROW)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_read_from_a_quote_as_written() {
        assert_eq!(
            numbers_in("3.34–6.11× (1,024² pixels), ~30%."),
            [3.34, 6.11, 1024.0, 30.0]
        );
        assert_eq!(numbers_in("between 3x and 6x"), [3.0, 6.0]);
        assert_eq!(numbers_in("the factor of two, a 2x"), [2.0, 2.0]);
        assert_eq!(normalised("Up to\n  2X"), "up to 2x");
        assert_eq!(allowed_numbers("around 30 %, 2x"), [30.0, 0.3, 1.3, 2.0]);
    }

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
        assert!(matches!(w, Test::Within(_, 0.5, 4.0, false)), "{w:?}");
        let loose = Test::parse("{{T | * | c}} in ~[3.34, 6.11]").unwrap();
        assert!(loose.is_tolerant());
        assert_eq!(loose.numbers(), [3.34, 6.11]);
        let rows = ["a".to_string(), "b".to_string()];
        let each = loose.per_row(&rows);
        assert_eq!(each.len(), 2);
        assert_eq!(each[1].1.references()[0].row, "b");
        let bound = Test::parse("{{T | r | c}} >= ~3").unwrap();
        assert!(bound.is_tolerant());
        assert_eq!(
            bound.per_row(&rows).len(),
            1,
            "no starred row: the test itself"
        );
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
        let head = "title = \"t\"\npaper = \"p\"\npaper_text = \"p.txt\"\nexperiments = [\"a\"]\n";
        let quoted = "item = \"X1\"\nquote = \"3.34x to 6.11x faster\"\n";
        for (body, why, line) in [
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"b\"\ntests = [\"1 < 2\"]\n",
                "\"b\" is not in",
                6,
            ),
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"{{b | T | r | c}} < 2\"]\n",
                "\"b\" is not in",
                6,
            ),
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = []\n",
                "no tests",
                6,
            ),
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\nverdict = \"holds\"\ntests = [\"1 < 2\"]\n",
                "unknown field",
                9,
            ),
            (
                "[[claims]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"1 < 2\"]\n",
                "names its item",
                6,
            ),
            (
                "[[claims]]\nitem = \"X1\"\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"1 < 2\"]\n",
                "quotes the paper",
                7,
            ),
            // The paper says 3.34–6.11×: a window of 3 widens it.
            (
                &format!("[[claims]]\n{quoted}claim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"{{{{T | * | x}}}} in [3, 6.11]\"]\n"),
                "uses 3, a number its quote does not state",
                8,
            ),
            (
                &format!("[[claims]]\n{quoted}claim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"{{{{T | * | x}}}} in ~[3.34, 6.11]\"]\n"),
                "declares no tolerance",
                8,
            ),
            (
                &format!("[[targets]]\n{quoted}claim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"1 < 2\"]\n"),
                "a target has no item",
                8,
            ),
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"1 < 2\"]\nexplanation = { tests = [], text = \"t\" }\n",
                "an explanation without tests",
                6,
            ),
            (
                "[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"1 < 2\"]\nexplanation = { tests = [\"{{b | T | r | c}} < 2\"], text = \"t\" }\n",
                "\"b\" is not in",
                6,
            ),
        ] {
            std::fs::write(&path, format!("{head}{body}")).unwrap();
            let e = Claims::read(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(why), "{e}");
            assert!(e.to_string().contains(&format!("claims.toml:{line}")), "{e}");
        }
        let good = format!(
            "{head}tolerance = {{ factor = 1.5, reason = \"r\" }}\n[[claims]]\n{quoted}claim = \"c\"\npaper = \"\"\nexperiment = \"a\"\ntests = [\"{{{{T | * | x}}}} in ~[3.34, 6.11]\", \"{{{{T | r | x}}}} / 3.34 >= 1\"]\nexplanation = {{ tests = [\"{{{{T | * | y}}}} < 2.5\"], text = \"t\" }}\n"
        );
        std::fs::write(&path, good).unwrap();
        let (claims, _) = Claims::read(&path).unwrap();
        assert_eq!(claims.claims[0].item.as_deref(), Some("X1"));
        // The explanation's 2.5 is the model's bound, not a number the quote must state.
        assert_eq!(
            claims.claims[0].explanation.as_ref().unwrap().tests.len(),
            1
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
