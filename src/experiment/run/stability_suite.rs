//! `raylab run` of an experiment with a `[stability]` table: the numerical stability suite
//! (`verify::stability`) for every tracer instance of the file, written as stability.csv (one row
//! per case, tracer and query), tables.md (per case kind and tracer: the sums over its sweep, and
//! where anything went wrong, the rows themselves) and meta.json, all or nothing. A speed cliff
//! (`verify::stability::speed_cliffs`) fails the run (exit 1) after the results are written,
//! naming each case.
//!
//! ```toml
//! name = "stability"
//! tracers = ["reference", { name = "packet", params = { traversal = ["masked", "ranged"] } }]
//! [stability]
//! cases = ["watertight", "ill_formed"]  # default: all eight (verify::stability::CaseKind)
//! offsets = [0, 1e3, 1e5, 1e6]          # distance from the origin
//! scales = [1e-3, 1, 1e4]               # watertight mesh sizes
//! ratios = [1e3, 1e4, 1e5, 1e6]         # scale range: enclosure / object
//! bounces = 8                           # self-intersection: bounces 1 … 8
//! timeout_seconds = 60                  # per tracer and case: longer is a hang
//! ```

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::experiment::plan::config::{Experiment, StabilitySettings};
use crate::experiment::plan::overrides::RunOverrides;
use crate::experiment::record::files::{STABILITY_CSV, TABLES_MD};
use crate::experiment::record::stability_row::{write_stability, StabilityRow};
use crate::experiment::record::{results_dir, utc};
use crate::experiment::run::{meta, runner};
use crate::verify::stability::{self, CaseKind, Cliff, Contender, Outcome, Status};

/// Runs the suite for every tracer instance of `exp` and writes the results directory.
pub fn run(
    exp: &Experiment,
    settings: &StabilitySettings,
    file_text: &str,
    overrides: &RunOverrides,
) -> Result<PathBuf> {
    let started = utc::UtcTime::now();
    let contenders: Vec<Contender> = exp
        .instances
        .iter()
        .map(|i| Contender {
            label: i.to_string(),
            info: i.info,
            params: i.params.clone(),
            config: i.config,
        })
        .collect();
    let cases = stability::generate(&settings.sweep);
    overrides.chatter.say(&format!(
        "stability suite: {} cases × {} tracers (closest hit and occlusion), oracle {} robust",
        cases.len(),
        contenders.len(),
        crate::tracers::ORACLE
    ));
    let results = results_dir::PendingResults::create(&exp.output, &exp.name, &started.compact())?;
    let progress = runner::progress_bar(
        cases.len() * contenders.len(),
        overrides.chatter != crate::experiment::plan::overrides::Chatter::Quiet,
    );
    let mut outcomes = stability::run(cases, &contenders, settings.timeout, &|case, c| {
        progress.set_message(format!("{} {} {}", case.kind, case.variant, c.label));
        progress.inc(1);
    })?;
    progress.finish_and_clear();
    let cliffs = stability::speed_cliffs(&mut outcomes);

    let dir = results.dir();
    let rows: Vec<StabilityRow> = outcomes.iter().map(row).collect();
    write_stability(&dir.join(STABILITY_CSV), &rows)?;
    let report = tables_md(&exp.name, &outcomes) + &cliffs_md(&cliffs);
    overrides.chatter.say(summary(&outcomes).trim_end());
    let path = dir.join(TABLES_MD);
    std::fs::write(&path, report).map_err(|e| Error::io(&path, e))?;
    let meta = meta::gather(
        &exp.name,
        None,
        &exp.threads,
        results.run_id(),
        started,
        (&exp.path, file_text),
        overrides,
    );
    meta::write(dir, &meta)?;
    let dir = results.commit()?;
    if cliffs.is_empty() {
        return Ok(dir);
    }
    let named: Vec<String> = cliffs.iter().map(cliff_name).collect();
    Err(Error::runtime(format!(
        "stability suite: {} speed cliff{} (> {}× reference and itself nearest the origin): {}; results: {}",
        cliffs.len(),
        if cliffs.len() == 1 { "" } else { "s" },
        stability::CLIFF_RATIO,
        named.join("; "),
        dir.display()
    )))
}

fn cliff_name(c: &Cliff) -> String {
    format!(
        "{} on {} {} at {:e}: {:.3} s, {:.0}× reference, {:.0}× itself",
        c.tracer, c.kind, c.variant, c.magnitude, c.seconds, c.vs_reference, c.vs_origin
    )
}

/// tables.md's speed-cliff section (empty without cliffs).
fn cliffs_md(cliffs: &[Cliff]) -> String {
    if cliffs.is_empty() {
        return String::new();
    }
    let mut md = String::from("\n## Speed cliffs (failures)\n\n");
    for c in cliffs {
        let _ = writeln!(md, "- {}", cliff_name(c));
    }
    md
}

fn status(o: &Outcome) -> (&'static str, String) {
    match &o.status {
        Status::Answered => ("answered", String::new()),
        Status::Refused(why) => ("refused", why.clone()),
        Status::Crashed(why) => ("crashed", why.clone()),
        Status::Hung => ("hung", String::new()),
    }
}

/// The suite's outcome `o` as its stability.csv row.
fn row(o: &Outcome) -> StabilityRow {
    let (status, note) = status(o);
    StabilityRow {
        case: o.kind.name().to_string(),
        variant: o.variant.clone(),
        magnitude: o.magnitude,
        tracer: o.tracer.clone(),
        query: o.query.name().to_string(),
        status: status.to_string(),
        note,
        counts: [
            o.rays,
            o.must_hit,
            o.leaks,
            o.missed,
            o.false_hits,
            o.rounding,
            o.unexplained,
            o.unexplained_tracer_right,
            o.unexplained_oracle_right,
            o.unexplained_rounding,
            o.unexplained_both_wrong,
        ],
        seconds: o.seconds,
        relative_time: o.relative_time,
        slowdown: o.slowdown,
    }
}

/// Sums over the sweep of one case kind and tracer.
#[derive(Default)]
struct Totals {
    rays: usize,
    must_hit: usize,
    leaks: usize,
    wrong: usize,
    false_hits: usize,
    unexplained: usize,
    tracer_right: usize,
    oracle_right: usize,
    rounding: usize,
    both_wrong: usize,
    crashes: usize,
    hangs: usize,
    refused: usize,
    worst_slowdown: Option<f64>,
    worst_relative_time: Option<f64>,
}

impl Totals {
    fn add(&mut self, o: &Outcome) {
        self.rays += o.rays;
        self.must_hit += o.must_hit;
        self.leaks += o.leaks;
        self.wrong += o.missed + o.false_hits;
        self.false_hits += o.false_hits;
        self.unexplained += o.unexplained;
        self.tracer_right += o.unexplained_tracer_right;
        self.oracle_right += o.unexplained_oracle_right;
        self.rounding += o.unexplained_rounding;
        self.both_wrong += o.unexplained_both_wrong;
        match o.status {
            Status::Answered => {}
            Status::Refused(_) => self.refused += 1,
            Status::Crashed(_) => self.crashes += 1,
            Status::Hung => self.hangs += 1,
        }
        if let Some(s) = o.slowdown {
            self.worst_slowdown = Some(self.worst_slowdown.map_or(s, |w: f64| w.max(s)));
        }
        if let Some(r) = o.relative_time {
            self.worst_relative_time = Some(self.worst_relative_time.map_or(r, |w: f64| w.max(r)));
        }
    }

    /// Nothing the f64 truth calls wrong, no leak, crash or hang.
    fn clean(&self) -> bool {
        self.leaks + self.wrong + self.crashes + self.hangs == 0
    }
}

fn totals(outcomes: &[Outcome]) -> BTreeMap<(CaseKind, &str), Totals> {
    let mut by: BTreeMap<(CaseKind, &str), Totals> = BTreeMap::new();
    for o in outcomes {
        by.entry((o.kind, o.tracer.as_str())).or_default().add(o);
    }
    by
}

/// tables.md: one table per case kind (tracers as rows, closest hit and occlusion together),
/// then every row that leaked, was wrong, crashed or hung.
fn tables_md(name: &str, outcomes: &[Outcome]) -> String {
    let mut md = format!(
        "# {name}: numerical stability\n\n\
         Oracle: {} in robust mode. *Wrong*: answers the f64 ground truth contradicts (a certain \
         hit missed, or a false hit). *Unexplained*: disagreements with the oracle that are not \
         ties, split by the f64 verdict: this tracer right / the oracle right / both within \
         rounding / both wrong. Closest-hit and occlusion answers are counted together; \
         crashes, hangs and refusals count (case, query) pairs. Slowdown: ill-formed case, time \
         of the mixed batch over its good rays alone (worst over the sweep). Time / reference: \
         closest-hit time over `reference`'s on the same case (worst over the sweep); over {}× \
         it and over {}× the tracer's own time nearest the origin is a speed cliff, listed at the \
         end and failing the run.\n",
        crate::tracers::ORACLE,
        stability::CLIFF_RATIO,
        stability::CLIFF_RATIO
    );
    let by = totals(outcomes);
    for kind in CaseKind::ALL {
        let rows: Vec<(&str, &Totals)> = by
            .iter()
            .filter(|((k, _), _)| *k == kind)
            .map(|((_, t), totals)| (*t, totals))
            .collect();
        if rows.is_empty() {
            continue;
        }
        let magnitudes: Vec<String> = {
            let mut m: Vec<f64> = outcomes
                .iter()
                .filter(|o| o.kind == kind)
                .map(|o| o.magnitude)
                .collect();
            m.sort_by(f64::total_cmp);
            m.dedup();
            m.iter().map(|x| format!("{x:e}")).collect()
        };
        let _ = write!(
            md,
            "\n## {kind} ({}: {})\n\n\
             | tracer | rays | must hit | leaks | wrong | of which false hits | unexplained | tracer right / oracle right / rounding / both wrong | crashes | hangs | refused | slowdown | time / reference |\n\
             |---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n",
            kind.magnitude_name(),
            magnitudes.join(", ")
        );
        for (tracer, t) in rows {
            let _ = writeln!(
                md,
                "| {tracer} | {} | {} | {} | {} | {} | {} | {} / {} / {} / {} | {} | {} | {} | {} | {} |",
                t.rays,
                t.must_hit,
                t.leaks,
                t.wrong,
                t.false_hits,
                t.unexplained,
                t.tracer_right,
                t.oracle_right,
                t.rounding,
                t.both_wrong,
                t.crashes,
                t.hangs,
                t.refused,
                t.worst_slowdown.map_or("".into(), |s| format!("{s:.2}")),
                t.worst_relative_time.map_or("".into(), |r| format!("{r:.2}")),
            );
        }
    }
    let bad: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| o.leaks + o.missed + o.false_hits > 0 || !matches!(o.status, Status::Answered))
        .collect();
    if !bad.is_empty() {
        md.push_str(
            "\n## Every row with a leak, a wrong answer, a crash, a hang or a refusal\n\n\
             | case | variant | magnitude | tracer | query | status | leaks | missed | false hits | note |\n\
             |---|---|---:|---|---|---|---:|---:|---:|---|\n",
        );
        for o in bad {
            let (status, note) = status(o);
            let _ = writeln!(
                md,
                "| {} | {} | {:e} | {} | {} | {status} | {} | {} | {} | {} |",
                o.kind,
                o.variant,
                o.magnitude,
                o.tracer,
                o.query.name(),
                o.leaks,
                o.missed,
                o.false_hits,
                note.replace('|', "/")
            );
        }
    }
    md
}

/// The terminal summary: per tracer, whether every case kind came out clean.
fn summary(outcomes: &[Outcome]) -> String {
    let mut per_tracer: BTreeMap<&str, Vec<(CaseKind, bool)>> = BTreeMap::new();
    for ((kind, tracer), t) in &totals(outcomes) {
        per_tracer
            .entry(tracer)
            .or_default()
            .push((*kind, t.clean()));
    }
    let mut out = String::from("\nstability (clean = no leak, wrong answer, crash or hang):\n");
    for (tracer, kinds) in per_tracer {
        let failed: Vec<&str> = kinds
            .iter()
            .filter(|(_, clean)| !clean)
            .map(|(k, _)| k.name())
            .collect();
        let verdict = if failed.is_empty() {
            "clean".to_string()
        } else {
            format!("NOT clean: {}", failed.join(", "))
        };
        let _ = writeln!(out, "  {tracer:<40} {verdict}");
    }
    out
}
