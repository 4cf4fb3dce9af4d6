//! The summary of a run, computed from its results directory alone (runs.csv, verify.csv,
//! meta.json), so it can be printed again (`raylab summary DIR`) or recomputed for any directory of
//! those files. Per scene and ray kind, at the run's largest thread count: the fastest of our
//! tracers (the from-scratch ones after the papers: everything but the baselines — Embree, obvhs,
//! tinybvh — and the reference tracer), Embree at its best, their ratio, the baseline best (the
//! fastest production baseline: Embree at its best or the fastest configuration of obvhs or
//! tinybvh) and its ratio, our tracer's box and triangle tests per ray (the counters that explain
//! the ratio), the obvhs and reference speeds beside them, and whether our tracer's hits were
//! checked against Embree in the run (`sampled_check`).
//!
//! Every speed is over all of the run's frames: rays summed over frames / the fastest pass summed
//! over frames, per tracer configuration (tracer + parameters). Embree's side is the
//! `embree_best_seconds` column summed over frames — the fastest Embree configuration of each
//! frame, whatever it was — so the ratio never flatters us. Only ray batches, the soft-shadow
//! query and ray files are summarised; render workloads are in runs.csv.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::accel::AccelKind;
use crate::error::{Error, Result};
use crate::tracers::registry::{is_embree, role_of};
use crate::tracers::{Role, TracerInfo};

use crate::experiment::record::csv_file::{read_typed, Cells};
use crate::experiment::record::files::META_JSON;
use crate::experiment::record::files::VERIFY_CSV;
use crate::experiment::record::files::{self, RUNS_CSV};
use crate::experiment::record::selection::{read_rows, Row};
use crate::experiment::record::CheckRow;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub experiment: String,
    pub run_id: String,
    pub date: String,
    pub commit: String,
    pub cpu: String,
    /// The run's wall-clock time (meta.json), when it has one.
    pub wall_seconds: Option<f64>,
    /// The thread count summarised: the largest the run measured unless one was asked for.
    pub threads: usize,
    /// Whether `threads` is the run's largest.
    pub largest_threads: bool,
    pub frames: usize,
    pub rows: Vec<SummaryRow>,
    /// Sampled-check totals over every tracer instance, ray kind, scene and frame.
    pub checked: Checks,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SummaryRow {
    pub scene: String,
    pub triangles: u64,
    pub ray_kind: String,
    /// Rays over all frames.
    pub rays: u64,
    /// The fastest of our tracers.
    pub ours: Option<Contender>,
    pub embree_best: Option<EmbreeBest>,
    /// Embree-best's seconds over ours (> 1: ours faster).
    pub x_embree_best: Option<f64>,
    /// The fastest production baseline on these rays: Embree at its best, or the fastest
    /// configuration of another baseline library (obvhs, tinybvh) when it beats Embree.
    pub baseline_best: Option<EmbreeBest>,
    /// Baseline-best's seconds over ours (> 1: ours faster).
    pub x_baseline_best: Option<f64>,
    pub obvhs: Option<Contender>,
    pub reference: Option<Contender>,
}

/// One tracer configuration over all frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Contender {
    pub tracer: String,
    pub parameters: String,
    pub seconds: f64,
    pub mrays_per_s: f64,
    pub aabb_tests_per_ray: Option<f64>,
    pub triangle_tests_per_ray: Option<f64>,
    /// Its sampled check against Embree on these rays; `None` when not checked.
    pub checked: Option<Checks>,
}

/// A best configuration over all frames: Embree's (`embree_best`) or any baseline's
/// (`baseline_best`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EmbreeBest {
    /// The fastest Embree configuration of each frame, distinct ones joined by " / "; for another
    /// baseline, its tracer and parameters.
    pub config: String,
    pub seconds: f64,
    pub mrays_per_s: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Checks {
    pub rays: u64,
    pub ties: u64,
    pub unexplained: u64,
    /// The unexplained ones by the f64 truth's judgement (`verify::Judgement`); a verify.csv
    /// written before the truth judged counts them all undecided.
    pub ours_right: u64,
    pub ours_wrong: u64,
    pub rounding: u64,
    pub undecided: u64,
}

impl Checks {
    fn add(&mut self, other: Checks) {
        self.rays += other.rays;
        self.ties += other.ties;
        self.unexplained += other.unexplained;
        self.ours_right += other.ours_right;
        self.ours_wrong += other.ours_wrong;
        self.rounding += other.rounding;
        self.undecided += other.undecided;
    }

    /// Disagreements a reader must look at, shown in bold: ours wrong (they fail verification)
    /// and undecided (reported with their rays).
    fn needing_a_look(&self) -> u64 {
        self.ours_wrong + self.undecided
    }
}

const RUNS_NEEDS: &[&str] = &[
    "scene",
    "triangles",
    "frame",
    "tracer",
    "parameters",
    "structure",
    "render",
    "ray_kind",
    "threads",
    "rays",
    "seconds_min",
    "counted_rays",
    "aabb_tests",
    "triangle_tests",
    "embree_best_seconds",
    "embree_best_config",
];

/// A CSV of `path` with its columns checked; cells are read through `Cells`.
struct Table<'a> {
    path: &'a Path,
    rows: Vec<Row>,
}

impl<'a> Table<'a> {
    fn read(path: &'a Path, needs: &[&str]) -> Result<Table<'a>> {
        let rows = read_rows(path)?;
        if let Some(first) = rows.first() {
            if let Some(missing) = needs.iter().find(|c| !first.contains_key(**c)) {
                return Err(Error::input(
                    path,
                    None,
                    format!("no column {missing:?}: not a raylab results file"),
                ));
            }
        }
        Ok(Table { path, rows })
    }

    /// The cell of row `i` parsed as a number (by the record's `Cells`); `None` when empty.
    fn number<T: std::str::FromStr>(&self, i: usize, column: &str) -> Result<Option<T>> {
        // Row i is on line i + 2: the header is line 1.
        Cells(&self.rows[i])
            .optional(column)
            .map_err(|e| Error::at_line(self.path, i + 2, e))
    }

    fn required<T: std::str::FromStr>(&self, i: usize, column: &str) -> Result<T> {
        self.number(i, column)?
            .ok_or_else(|| Error::at_line(self.path, i + 2, format!("{column} is empty")))
    }

    fn text(&self, i: usize, column: &str) -> &str {
        &self.rows[i][column]
    }
}

/// A seconds value read from a file: finite and not negative, or the file is wrong.
fn seconds(table: &Table, i: usize, column: &str, value: f64) -> Result<f64> {
    match value.is_finite() && value >= 0.0 {
        true => Ok(value),
        false => Err(Error::at_line(
            table.path,
            i + 2,
            format!("{column} = {value} is not a time"),
        )),
    }
}

/// Scene, triangles, ray kind: one summary row.
type GroupKey = (String, u64, String);
/// Tracer, parameters: one configuration.
type ConfigKey = (String, String);

#[derive(Default)]
struct ConfigTotals {
    rays: u64,
    seconds: f64,
    counted_rays: u64,
    aabb_tests: Option<u64>,
    triangle_tests: Option<u64>,
}

#[derive(Default)]
struct GroupTotals {
    configs: BTreeMap<ConfigKey, ConfigTotals>,
    /// Per frame: Embree-best seconds and configuration.
    embree: BTreeMap<u64, Option<(f64, String)>>,
}

impl Summary {
    /// The summary of the results directory `dir`, at the run's largest thread count.
    pub fn read(dir: &Path) -> Result<Summary> {
        Self::read_at(dir, None)
    }

    /// The summary of `dir` at `threads` (`None`: the run's largest thread count); a thread count
    /// the run did not measure is a usage error naming the ones it did.
    pub fn read_at(dir: &Path, threads: Option<usize>) -> Result<Summary> {
        let runs_path = dir.join(RUNS_CSV);
        let meta_path = dir.join(META_JSON);
        if !files::exists(&runs_path) || !meta_path.is_file() {
            return Err(Error::usage(format!(
                "{}: not a results directory of `raylab run` (needs {RUNS_CSV} and {META_JSON})",
                dir.display()
            )));
        }
        let meta = read_meta(&meta_path)?;
        let runs = Table::read(&runs_path, RUNS_NEEDS)?;
        let verify_path = dir.join(VERIFY_CSV);
        let checks = match files::exists(&verify_path) {
            true => read_checks(&verify_path)?,
            false => BTreeMap::new(),
        };
        let mut summary = summarise(&runs, &checks, threads)?;
        if summary.rows.is_empty() && threads.is_some() {
            let measured = match thread_counts(&runs)? {
                counts if counts.is_empty() => "none outside renders".to_string(),
                counts => counts,
            };
            return Err(Error::usage(format!(
                "{}: no ray batch measured at {} thread{} (batches measured at: {measured})",
                runs_path.display(),
                summary.threads,
                plural(summary.threads),
            )));
        }
        summary.experiment = meta.experiment;
        summary.run_id = meta.run_id;
        summary.date = meta.date;
        summary.commit = meta.commit;
        summary.cpu = meta.cpu;
        summary.wall_seconds = meta.wall_seconds;
        Ok(summary)
    }

    /// The Markdown table: what `summary.md` holds and the run prints.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let wall = self
            .wall_seconds
            .map_or(String::new(), |w| format!(", {w:.0} s wall"));
        let _ = writeln!(
            s,
            "**{}** run {} ({}{wall}), commit {}, {}\n",
            self.experiment, self.run_id, self.date, self.commit, self.cpu
        );
        if self.rows.is_empty() {
            // Every row is a render's (path bounces, Whitted generations): no plain batches.
            let _ = writeln!(
                s,
                "The run traced no plain ray batches, only the rays of renders: its results are \
                 in its tables (tables.md) and runs.csv."
            );
            return s;
        }
        let _ = writeln!(
            s,
            "At {} thread{}{}, over {} frame{}: Mrays/s = rays / fastest pass, both summed over frames. \
             Ours = the fastest of the papers' tracers; × = Embree best's time / ours (> 1: ours faster); \
             baseline best = the fastest production baseline (Embree best, obvhs, tinybvh); \
             tests per ray are ours; checked = ours against Embree (robust) on sampled rays.\n",
            self.threads,
            plural(self.threads),
            if self.largest_threads { " (the run's largest)" } else { "" },
            self.frames,
            plural(self.frames)
        );
        // The obvhs and reference columns only when the run measured them.
        let with_obvhs = self.rows.iter().any(|r| r.obvhs.is_some());
        let with_reference = self.rows.iter().any(|r| r.reference.is_some());
        let optional = |cells: [&str; 2]| {
            [(with_obvhs, cells[0]), (with_reference, cells[1])]
                .into_iter()
                .filter(|(shown, _)| *shown)
                .map(|(_, cell)| format!(" {cell} |"))
                .collect::<String>()
        };
        let _ = writeln!(
            s,
            "| scene | rays | ours: fastest | Mrays/s | box / tri tests per ray | Embree best | Mrays/s | × Embree best | baseline best | Mrays/s | × baseline best |{} checked against Embree |",
            optional(["obvhs Mrays/s", "reference Mrays/s"])
        );
        let _ = writeln!(
            s,
            "|---|---|---|---:|---:|---|---:|---:|---|---:|---:|{}---|",
            optional(["---:", "---:"]).replace(' ', "")
        );
        for r in &self.rows {
            let ours = r.ours.as_ref();
            let tests = ours.and_then(|o| Some((o.aabb_tests_per_ray?, o.triangle_tests_per_ray?)));
            let _ = writeln!(
                s,
                "| {} ({} tris) | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |{} {} |",
                r.scene,
                r.triangles,
                r.ray_kind,
                ours.map_or("—".into(), |o| configuration(&o.tracer, &o.parameters)),
                mrays(ours.map(|o| o.mrays_per_s)),
                tests.map_or("—".into(), |(b, t)| format!("{b:.1} / {t:.1}")),
                r.embree_best.as_ref().map_or("—", |e| e.config.as_str()),
                mrays(r.embree_best.as_ref().map(|e| e.mrays_per_s)),
                r.x_embree_best.map_or("—".into(), |x| format!("{x:.2}×")),
                r.baseline_best.as_ref().map_or("—", |e| e.config.as_str()),
                mrays(r.baseline_best.as_ref().map(|e| e.mrays_per_s)),
                r.x_baseline_best.map_or("—".into(), |x| format!("{x:.2}×")),
                optional([
                    &mrays(r.obvhs.as_ref().map(|o| o.mrays_per_s)),
                    &mrays(r.reference.as_ref().map(|o| o.mrays_per_s)),
                ]),
                ours.map_or("—".into(), |o| checked(o.checked)),
            );
        }
        let c = self.checked;
        let _ = writeln!(
            s,
            "\nSampled check, every tracer of the run: {} rays compared with Embree, {} ties, {} disagreement{} no tie explains, judged by the f64 truth: {} ours right, {} ours wrong, {} both within rounding, {} undecided.",
            c.rays,
            c.ties,
            c.unexplained,
            plural(c.unexplained as usize),
            c.ours_right,
            c.ours_wrong,
            c.rounding,
            c.undecided
        );
        s
    }

    /// The summary as JSON, with the results directory it was read from.
    pub fn json(&self, dir: &Path) -> String {
        let mut value = serde_json::to_value(self).expect("the summary is plain data");
        value["results"] = serde_json::Value::String(dir.display().to_string());
        serde_json::to_string_pretty(&value).expect("a JSON value serialises") + "\n"
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn configuration(tracer: &str, parameters: &str) -> String {
    match parameters.is_empty() {
        true => tracer.to_string(),
        false => format!("{tracer} {parameters}"),
    }
}

fn mrays(value: Option<f64>) -> String {
    value.map_or("—".into(), |v| format!("{v:.1}"))
}

fn checked(checks: Option<Checks>) -> String {
    match checks {
        None => "not checked".into(),
        Some(c) if c.unexplained == 0 => format!("yes: {} rays, {} ties", c.rays, c.ties),
        Some(c) if c.needing_a_look() == 0 => format!(
            "yes: {} rays, {} ties, {} ours right, {} within rounding",
            c.rays, c.ties, c.ours_right, c.rounding
        ),
        Some(c) => format!(
            "**{} ours wrong, {} undecided** of {} rays ({} ties, {} ours right, {} within rounding)",
            c.ours_wrong, c.undecided, c.rays, c.ties, c.ours_right, c.rounding
        ),
    }
}

struct MetaFacts {
    experiment: String,
    run_id: String,
    date: String,
    commit: String,
    cpu: String,
    wall_seconds: Option<f64>,
}

fn read_meta(path: &Path) -> Result<MetaFacts> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let meta: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Error::at_line(path, e.line(), e.to_string()))?;
    let text_at = |pointer: &str| -> Result<String> {
        meta.pointer(pointer)
            .and_then(|v| v.as_str())
            .map(String::from)
            .ok_or_else(|| Error::input(path, None, format!("no {pointer} string")))
    };
    let hash = text_at("/commit/hash")?;
    let dirty = meta.pointer("/commit/dirty").and_then(|v| v.as_bool());
    let cores = meta
        .pointer("/cpu/logical_cores")
        .and_then(|v| v.as_u64())
        .unwrap_or(0);
    Ok(MetaFacts {
        experiment: text_at("/experiment")?,
        run_id: text_at("/run_id")?,
        date: text_at("/date")?,
        commit: format!(
            "{}{}",
            hash.get(..7).unwrap_or(&hash),
            if dirty == Some(true) { " (dirty)" } else { "" }
        ),
        cpu: format!("{} ({cores} logical cores)", text_at("/cpu/model")?),
        wall_seconds: meta.pointer("/wall_seconds").and_then(|v| v.as_f64()),
    })
}

/// verify.csv's checks (`CheckRow`s), summed over frames per (scene, triangles, ray kind) and
/// configuration.
fn read_checks(path: &Path) -> Result<BTreeMap<(GroupKey, ConfigKey), Checks>> {
    let mut checks: BTreeMap<(GroupKey, ConfigKey), Checks> = BTreeMap::new();
    for row in read_typed(path, CheckRow::parse)? {
        let group = (row.scene, row.triangles as u64, row.ray_kind);
        checks
            .entry((group, (row.tracer, row.parameters)))
            .or_default()
            .add(Checks {
                rays: row.checked_rays as u64,
                ties: row.ties,
                unexplained: row.unexplained,
                ours_right: row.ours_right,
                ours_wrong: row.ours_wrong,
                rounding: row.rounding,
                undecided: row.undecided,
            });
    }
    Ok(checks)
}

/// The rows of runs.csv that are ray batches (not renders).
fn batch_rows(runs: &Table) -> Vec<usize> {
    (0..runs.rows.len())
        .filter(|&i| runs.text(i, "render").is_empty())
        .collect()
}

/// The thread counts the batches of runs.csv were measured at, as "1, 2".
fn thread_counts(runs: &Table) -> Result<String> {
    let mut counts = std::collections::BTreeSet::new();
    for i in batch_rows(runs) {
        counts.insert(runs.required::<usize>(i, "threads")?);
    }
    Ok(counts
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", "))
}

/// The summary of runs.csv's `runs` with the checks of verify.csv (meta facts left empty).
fn summarise(
    runs: &Table,
    checks: &BTreeMap<(GroupKey, ConfigKey), Checks>,
    threads: Option<usize>,
) -> Result<Summary> {
    let batch_rows = batch_rows(runs);
    let mut largest = 0;
    for &i in &batch_rows {
        largest = largest.max(runs.required::<usize>(i, "threads")?);
    }
    let threads = threads.unwrap_or(largest);
    let mut order: Vec<GroupKey> = Vec::new();
    let mut groups: BTreeMap<GroupKey, GroupTotals> = BTreeMap::new();
    let mut frames = std::collections::BTreeSet::new();
    for &i in &batch_rows {
        if runs.required::<usize>(i, "threads")? != threads {
            continue;
        }
        let key = (
            runs.text(i, "scene").to_string(),
            runs.required(i, "triangles")?,
            runs.text(i, "ray_kind").to_string(),
        );
        let frame: u64 = runs.required(i, "frame")?;
        frames.insert(frame);
        let group = groups.entry(key.clone()).or_insert_with(|| {
            order.push(key);
            GroupTotals::default()
        });
        let embree_best = match runs.number::<f64>(i, "embree_best_seconds")? {
            Some(s) => Some((
                seconds(runs, i, "embree_best_seconds", s)?,
                runs.text(i, "embree_best_config").to_string(),
            )),
            None => None,
        };
        group.embree.entry(frame).or_insert(embree_best);
        let config = (
            runs.text(i, "tracer").to_string(),
            runs.text(i, "parameters").to_string(),
        );
        let totals = group.configs.entry(config).or_default();
        totals.rays += runs.required::<u64>(i, "rays")?;
        let s: f64 = runs.required(i, "seconds_min")?;
        totals.seconds += seconds(runs, i, "seconds_min", s)?;
        totals.counted_rays += runs.required::<u64>(i, "counted_rays")?;
        let add = |sum: Option<u64>, cell: Option<u64>| Some(sum.unwrap_or(0) + cell?);
        totals.aabb_tests = add(totals.aabb_tests, runs.number(i, "aabb_tests")?);
        totals.triangle_tests = add(totals.triangle_tests, runs.number(i, "triangle_tests")?);
    }
    let rows = order
        .into_iter()
        .map(|key| summary_row(&key, &groups[&key], checks))
        .collect();
    let mut checked = Checks::default();
    for c in checks.values() {
        checked.add(*c);
    }
    Ok(Summary {
        experiment: String::new(),
        run_id: String::new(),
        date: String::new(),
        commit: String::new(),
        cpu: String::new(),
        wall_seconds: None,
        threads,
        largest_threads: threads == largest,
        frames: frames.len(),
        rows,
        checked,
    })
}

fn summary_row(
    key: &GroupKey,
    group: &GroupTotals,
    checks: &BTreeMap<(GroupKey, ConfigKey), Checks>,
) -> SummaryRow {
    let contender = |(tracer, parameters): &ConfigKey, t: &ConfigTotals| {
        let per_ray = |count: Option<u64>| {
            count
                .filter(|_| t.counted_rays > 0)
                .map(|c| c as f64 / t.counted_rays as f64)
        };
        Contender {
            tracer: tracer.clone(),
            parameters: parameters.clone(),
            seconds: t.seconds,
            mrays_per_s: speed(t.rays, t.seconds),
            aabb_tests_per_ray: per_ray(t.aabb_tests),
            triangle_tests_per_ray: per_ray(t.triangle_tests),
            checked: checks
                .get(&(key.clone(), (tracer.clone(), parameters.clone())))
                .copied(),
        }
    };
    // The fastest configuration of the tracers `which` picks; the first listed on a tie.
    let fastest = |which: &dyn Fn(&str, &ConfigTotals) -> bool| {
        group
            .configs
            .iter()
            .filter(|((tracer, _), t)| which(tracer, t))
            .min_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds))
            .map(|(config, t)| contender(config, t))
    };
    // The registry's roles (`role_of` knows the tracers this build lacks): ours are the paper
    // tracers, and a name no build has.
    let ours =
        fastest(&|tracer, _| !matches!(role_of(tracer), Some(Role::Baseline | Role::Reference)));
    let rays = group.configs.values().map(|t| t.rays).max().unwrap_or(0);
    let embree_best = group
        .embree
        .values()
        .try_fold((0.0, Vec::<&str>::new()), |(sum, mut configs), best| {
            let (s, config) = best.as_ref()?;
            if !configs.contains(&config.as_str()) {
                configs.push(config);
            }
            Some((sum + s, configs))
        })
        .map(|(seconds, configs)| EmbreeBest {
            config: configs.join(" / "),
            seconds,
            mrays_per_s: speed(rays, seconds),
        });
    let x_embree_best = match (&ours, &embree_best) {
        (Some(o), Some(e)) if o.seconds > 0.0 => Some(e.seconds / o.seconds),
        _ => None,
    };
    // Embree at its best against every configuration of the other baselines; Embree on a tie.
    let others = group
        .configs
        .iter()
        .filter(|((tracer, _), _)| role_of(tracer) == Some(Role::Baseline) && !is_embree(tracer))
        .map(|((tracer, parameters), t)| EmbreeBest {
            config: configuration(tracer, parameters),
            seconds: t.seconds,
            mrays_per_s: speed(rays, t.seconds),
        });
    let baseline_best = embree_best
        .clone()
        .into_iter()
        .chain(others)
        .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
    let x_baseline_best = match (&ours, &baseline_best) {
        (Some(o), Some(b)) if o.seconds > 0.0 => Some(b.seconds / o.seconds),
        _ => None,
    };
    SummaryRow {
        scene: key.0.clone(),
        triangles: key.1,
        ray_kind: key.2.clone(),
        rays,
        ours,
        embree_best,
        x_embree_best,
        baseline_best,
        x_baseline_best,
        obvhs: fastest(&|tracer, _| {
            TracerInfo::find(tracer).is_ok_and(|info| info.accel == AccelKind::Obvhs)
        }),
        reference: fastest(&|tracer, _| role_of(tracer) == Some(Role::Reference)),
    }
}

fn speed(rays: u64, seconds: f64) -> f64 {
    match seconds > 0.0 {
        true => rays as f64 / seconds / 1e6,
        false => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use std::fs;
    use std::path::PathBuf;

    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("raylab-summary-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    const META: &str = r#"{"experiment": "t", "run_id": "R1", "date": "2026-11-24T12:00:00Z",
        "commit": {"hash": "0123456789abcdef", "dirty": true},
        "cpu": {"model": "CPU X", "logical_cores": 2}}"#;

    const HEADER: &str = "scene,triangles,frame,tracer,parameters,structure,render,ray_kind,threads,rays,seconds_min,counted_rays,aabb_tests,triangle_tests,embree_best_seconds,embree_best_config";

    /// Two frames of a 1,000,000-ray primary batch and a shadow batch at 1 and 2 threads, and a
    /// render row. At 2 threads: packet 0.010 + 0.030 s (50 Mrays/s; 42M box and 5M triangle
    /// tests over 2M rays), cgt 0.05 s, obvhs 0.08 s, reference 0.10 s, Embree best 0.008 + 0.012
    /// s (100 Mrays/s, 0.5× ours). At 1 thread cgt is fastest and a render row faster still:
    /// neither is summarised.
    const RUNS: &[&str] = &[
        "room,864,0,packet,lanes=16;packet=8,bvh,,primary,2,1000000,0.010,1000000,20000000,3000000,0.008,embree16 (context coherent)",
        "room,864,0,cgt,packet=8,grid,,primary,2,1000000,0.025,1000000,9,9,0.008,embree16 (context coherent)",
        "room,864,0,obvhs,,obvhs,,primary,2,1000000,0.04,1000000,,,0.008,embree16 (context coherent)",
        "room,864,0,reference,,bvh,,primary,2,1000000,0.05,1000000,7,7,0.008,embree16 (context coherent)",
        "room,864,0,embree16,,embree,,primary,2,1000000,0.008,1000000,,,0.008,embree16 (context coherent)",
        "room,864,0,cgt,packet=8,grid,,primary,1,1000000,0.001,1000000,9,9,0.016,embree16 (context coherent)",
        "room,864,0,reference,,bvh,,shadow,2,1000000,0.1,1000000,5,5,0.01,embree1 (context incoherent)",
        "room,864,0,embree1,,embree,,shadow,2,1000000,0.01,1000000,,,0.01,embree1 (context incoherent)",
        "room,864,0,packet,lanes=16;packet=8,bvh,renderer=whitted,primary,2,1000000,0.0001,1000000,1,1,0.01,embree1",
        "room,864,1,packet,lanes=16;packet=8,bvh,,primary,2,1000000,0.030,1000000,22000000,2000000,0.012,embree16 (context coherent)",
        "room,864,1,cgt,packet=8,grid,,primary,2,1000000,0.025,1000000,9,9,0.012,embree16 (context coherent)",
        "room,864,1,obvhs,,obvhs,,primary,2,1000000,0.04,1000000,,,0.012,embree16 (context coherent)",
        "room,864,1,reference,,bvh,,primary,2,1000000,0.05,1000000,7,7,0.012,embree16 (context coherent)",
        "room,864,1,embree16,,embree,,primary,2,1000000,0.012,1000000,,,0.012,embree16 (context coherent)",
        "room,864,1,reference,,bvh,,shadow,2,1000000,0.1,1000000,5,5,0.01,embree16 (context coherent)",
        "room,864,1,embree16,,embree,,shadow,2,1000000,0.01,1000000,,,0.01,embree16 (context coherent)",
    ];

    const VERIFY: &str =
        "scene,triangles,frame,tracer,parameters,ray_kind,checked_rays,ties,unexplained\n\
        room,864,0,packet,lanes=16;packet=8,primary,4096,2,0\n\
        room,864,1,packet,lanes=16;packet=8,primary,4096,1,1\n\
        room,864,0,reference,,shadow,4096,0,0\n";

    fn results(name: &str, runs: &[&str]) -> PathBuf {
        let dir = scratch(name);
        fs::write(dir.join(META_JSON), META).unwrap();
        fs::write(
            dir.join(RUNS_CSV),
            format!("{HEADER}\n{}\n", runs.join("\n")),
        )
        .unwrap();
        fs::write(dir.join(VERIFY_CSV), VERIFY).unwrap();
        dir
    }

    #[test]
    fn a_thread_count_asked_for_summarises_its_rows_only() {
        let dir = results("threads", RUNS);
        let summary = Summary::read_at(&dir, Some(1)).unwrap();
        assert_eq!((summary.threads, summary.frames), (1, 1));
        assert!(!summary.largest_threads);
        assert_eq!(summary.rows.len(), 1);
        let row = &summary.rows[0];
        assert_eq!(row.ours.as_ref().unwrap().tracer, "cgt");
        assert!((row.x_embree_best.unwrap() - 16.0).abs() < 1e-9);
        assert!(summary.markdown().contains("At 1 thread, over 1 frame"));
        let e = Summary::read_at(&dir, Some(3)).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e
            .to_string()
            .contains("no ray batch measured at 3 threads (batches measured at: 1, 2)"));
    }

    /// tinybvh faster than Embree at its best on the primary rays (0.005 s a frame against 0.008
    /// and 0.012): it is baseline best there, named, and the ratio is against it; the obvhs column
    /// stays obvhs's; on the shadow rays Embree is still baseline best.
    #[test]
    fn a_baseline_faster_than_embree_is_baseline_best() {
        let tinybvh = [
            "room,864,0,tinybvh-8,builder=sbvh,tinybvh-bvh8-cpu,,primary,2,1000000,0.005,1000000,,,0.008,embree16 (context coherent)",
            "room,864,1,tinybvh-8,builder=sbvh,tinybvh-bvh8-cpu,,primary,2,1000000,0.005,1000000,,,0.012,embree16 (context coherent)",
            "room,864,0,tinybvh-8,builder=sbvh,tinybvh-bvh8-cpu,,shadow,2,1000000,0.05,1000000,,,0.01,embree1 (context incoherent)",
        ];
        let runs = [RUNS, &tinybvh[..]].concat();
        let summary = Summary::read(&results("baseline-best", &runs)).unwrap();
        let primary = &summary.rows[0];
        let best = primary.baseline_best.as_ref().unwrap();
        assert_eq!(best.config, "tinybvh-8 builder=sbvh");
        assert!((best.mrays_per_s - 200.0).abs() < 1e-9);
        assert!((primary.x_baseline_best.unwrap() - 0.25).abs() < 1e-12);
        assert!((primary.x_embree_best.unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(primary.obvhs.as_ref().unwrap().tracer, "obvhs");
        let shadow = &summary.rows[1];
        assert_eq!(shadow.baseline_best, shadow.embree_best);
        assert!(summary
            .markdown()
            .contains("| embree16 (context coherent) | 100.0 | 0.50× | tinybvh-8 builder=sbvh | 200.0 | 0.25× |"));
    }

    #[test]
    fn a_run_of_renders_only_says_so_instead_of_an_empty_table() {
        let summary = Summary::read(&results("renders-only", &[])).unwrap();
        assert!(summary.rows.is_empty());
        let text = summary.markdown();
        assert!(text.contains("The run traced no plain ray batches"));
        assert!(!text.contains("| scene |") && !text.contains("At 0 threads"));
    }

    #[test]
    fn a_hand_made_run_gives_the_expected_table() {
        let dir = results("table", RUNS);
        let summary = Summary::read(&dir).unwrap();
        assert_eq!((summary.threads, summary.frames), (2, 2));
        assert_eq!(summary.rows.len(), 2);
        let primary = &summary.rows[0];
        let ours = primary.ours.as_ref().unwrap();
        assert_eq!(
            (ours.tracer.as_str(), ours.parameters.as_str()),
            ("packet", "lanes=16;packet=8")
        );
        assert!((ours.seconds - 0.04).abs() < 1e-12);
        assert!((ours.mrays_per_s - 50.0).abs() < 1e-9);
        assert_eq!(ours.aabb_tests_per_ray, Some(21.0));
        assert_eq!(ours.triangle_tests_per_ray, Some(2.5));
        assert_eq!(
            ours.checked,
            Some(Checks {
                rays: 8192,
                ties: 3,
                unexplained: 1,
                ours_right: 0,
                ours_wrong: 0,
                rounding: 0,
                undecided: 1,
            })
        );
        let embree = primary.embree_best.as_ref().unwrap();
        assert_eq!(embree.config, "embree16 (context coherent)");
        assert!((embree.mrays_per_s - 100.0).abs() < 1e-9);
        assert!((primary.x_embree_best.unwrap() - 0.5).abs() < 1e-12);
        assert!((primary.obvhs.as_ref().unwrap().mrays_per_s - 25.0).abs() < 1e-9);
        assert!((primary.reference.as_ref().unwrap().mrays_per_s - 20.0).abs() < 1e-9);
        assert_eq!(
            summary.checked,
            Checks {
                rays: 12288,
                ties: 3,
                unexplained: 1,
                ours_right: 0,
                ours_wrong: 0,
                rounding: 0,
                undecided: 1,
            }
        );

        let md = summary.markdown();
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(
            lines[0],
            "**t** run R1 (2026-11-24T12:00:00Z), commit 0123456 (dirty), CPU X (2 logical cores)"
        );
        assert!(lines.contains(
            &"| room (864 tris) | primary | packet lanes=16;packet=8 | 50.0 | 21.0 / 2.5 | embree16 (context coherent) | 100.0 | 0.50× | embree16 (context coherent) | 100.0 | 0.50× | 25.0 | 20.0 | **0 ours wrong, 1 undecided** of 8192 rays (3 ties, 0 ours right, 0 within rounding) |"
        ), "{md}");
        // No paper tracer on shadow rays; Embree's best was another configuration each frame.
        assert!(lines.contains(
            &"| room (864 tris) | shadow | — | — | — | embree1 (context incoherent) / embree16 (context coherent) | 100.0 | — | embree1 (context incoherent) / embree16 (context coherent) | 100.0 | — | — | 10.0 | — |"
        ), "{md}");
        // verify.csv without the truth's columns (written before it judged): undecided.
        assert!(md.contains("12288 rays compared with Embree, 3 ties, 1 disagreement no tie explains, judged by the f64 truth: 0 ours right, 0 ours wrong, 0 both within rounding, 1 undecided."), "{md}");

        // The JSON carries the same numbers and the directory.
        let json: serde_json::Value = serde_json::from_str(&summary.json(&dir)).unwrap();
        assert_eq!(
            json["rows"][0]["ours"]["mrays_per_s"].as_f64(),
            Some(ours.mrays_per_s)
        );
        assert_eq!(
            json["rows"][0]["x_embree_best"].as_f64(),
            primary.x_embree_best
        );
        assert_eq!(json["rows"][1]["ours"], serde_json::Value::Null);
        assert_eq!(json["results"], dir.display().to_string());
    }

    #[test]
    fn columns_of_baselines_the_run_did_not_measure_are_left_out() {
        let runs: Vec<&str> = RUNS
            .iter()
            .copied()
            .filter(|r| !r.contains(",reference,"))
            .collect();
        let md = Summary::read(&results("no-reference", &runs))
            .unwrap()
            .markdown();
        assert!(md.contains("| × Embree best | baseline best | Mrays/s | × baseline best | obvhs Mrays/s | checked against Embree |\n|---|---|---|---:|---:|---|---:|---:|---|---:|---:|---:|---|\n"), "{md}");
        assert!(
            md.contains("| 0.50× | embree16 (context coherent) | 100.0 | 0.50× | 25.0 | **0 ours wrong, 1 undecided**"),
            "{md}"
        );
    }

    #[test]
    fn without_verify_csv_nothing_is_checked() {
        let dir = results("unchecked", RUNS);
        fs::remove_file(dir.join(VERIFY_CSV)).unwrap();
        let summary = Summary::read(&dir).unwrap();
        assert_eq!(summary.rows[0].ours.as_ref().unwrap().checked, None);
        assert!(summary.markdown().contains("| not checked |"));
    }

    #[test]
    fn bad_results_directories_are_named_errors() {
        let empty = scratch("empty");
        let e = Summary::read(&empty).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("not a results directory"), "{e}");

        let mut runs = RUNS.to_vec();
        let bad = RUNS[3].replace(",0.05,", ",NaN,");
        runs[3] = &bad;
        let dir = results("nan", &runs);
        let e = Summary::read(&dir).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        // Row 4 is on line 5.
        assert!(
            e.to_string()
                .contains("runs.csv:5: seconds_min = NaN is not a time"),
            "{e}"
        );

        let dir = results("words", RUNS);
        fs::write(dir.join(RUNS_CSV), "scene,rays\nroom,7\n").unwrap();
        let e = Summary::read(&dir).unwrap_err();
        assert!(e.to_string().contains("no column \"triangles\""), "{e}");
        fs::write(dir.join(META_JSON), "{ not json").unwrap();
        let e = Summary::read(&dir).unwrap_err();
        assert!(e.to_string().contains("meta.json:1"), "{e}");
    }
}
