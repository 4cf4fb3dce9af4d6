//! `raylab reproduce <paper>|<experiment>|all [--scale paper|quick]`: every experiment file a
//! paper's claims list (`results/<paper>/claims.toml`; or the one file named), run in turn into
//! `results/<paper>/<experiment>/`, then the paper's REPORT.md and the index of verdicts
//! regenerated. The plan comes first, with an estimated time per file; a run at this scale that
//! `report --check` calls current (the same measured source and experiment file, from a clean
//! tree) is kept, so a killed reproduction resumes where it stopped (a run is moved into place
//! only once complete).
//! A quick (smoke-test) reproduction works in `results/.quick/<paper>/` with a copy of the
//! claims, never over the committed runs.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::Value;

use crate::error::{Error, Result};
use crate::experiment::plan::overrides::Scale;
use crate::experiment::record::files::META_JSON;
use crate::experiment::record::provenance::SourceTree;
use crate::experiment::results::report::claims::{Claims, CLAIMS_TOML};
use crate::experiment::results::report::paper::papers_under;
use crate::experiment::results::report::write;
use crate::experiment::results::staleness;
use crate::experiment::{run_experiment, Chatter, Experiment, RunOverrides};

/// Rays per second assumed for the estimate of a file never run at this scale: a conservative
/// constant, below what the slowest committed paper runs sustain per timed pass (whole Whitted and
/// path-traced frames with shading, 1–3 million rays/s on 2 threads; ray batches run at tens of
/// millions), so such estimates run long, often by 10× or more. A file run before is estimated
/// by that run's wall time instead. An estimate, not a promise: the progress line corrects it by
/// the time the finished files took.
pub const ESTIMATED_RAYS_PER_SECOND: f64 = 1.0e6;

/// Where under the results root a quick reproduction works (`results/.quick/<paper>/`).
pub const QUICK_DIR: &str = ".quick";

/// The overrides of a scale: none for the paper's settings; for `quick`, 64² images, one frame,
/// no warm-up, one pass, one thread.
pub fn overrides(scale: Scale, output: &Path) -> RunOverrides {
    let quick = scale == Scale::Quick;
    RunOverrides {
        output: Some(output.to_path_buf()),
        resolution: quick.then_some((64, 64)),
        frames: quick.then_some(1),
        warmup: quick.then_some(0),
        repeats: quick.then_some(1),
        threads: quick.then(|| vec![1]),
        scale: Some(scale),
        ..RunOverrides::default()
    }
}

/// One experiment file of a paper's plan.
#[derive(Debug)]
pub struct Step {
    pub experiment: String,
    pub file: PathBuf,
    /// Rays traced in timed and warm-up passes, from the plan's sizes (an upper bound where
    /// scenes make fewer secondary rays than camera rays).
    pub rays: u64,
    /// Its run here is from this source and scale: kept.
    pub done: bool,
    /// The wall time of the run in place at this scale, if any (from an older source, or of an
    /// older version of the file: the best estimate there is).
    pub last_seconds: Option<f64>,
}

impl Step {
    pub fn estimate_seconds(&self) -> f64 {
        self.last_seconds
            .unwrap_or(self.rays as f64 / ESTIMATED_RAYS_PER_SECOND)
    }
}

/// Rays a run of `exp` traces: the largest batch × workloads × scenes × frames × tracer
/// instances × thread counts × passes.
fn planned_rays(exp: &Experiment) -> u64 {
    let workloads = (exp.ray_kinds.len() + exp.ray_files.len() + exp.renders.len()).max(1);
    [
        workloads,
        exp.scenes.len().max(1),
        exp.frames,
        exp.instances.len().max(1),
        exp.threads.len().max(1),
        exp.warmup + exp.repeats,
    ]
    .iter()
    .fold(exp.largest_batch(), |n, &k| n.saturating_mul(k as u64))
}

/// The meta.json of the run in `dir` if it was made at `scale`.
fn run_at_scale(dir: &Path, scale: Scale) -> Option<Value> {
    let text = std::fs::read_to_string(dir.join(META_JSON)).ok()?;
    let meta = serde_json::from_str::<Value>(&text).ok()?;
    let recorded_scale = meta
        .pointer("/overrides/scale")
        .and_then(Value::as_str)
        .unwrap_or("paper");
    (recorded_scale == scale.name()).then_some(meta)
}

/// Is the run (`meta`) current: not stale by `report --check`'s rule against the source now
/// (`today`) and the file it would run (`experiment`)? At quick scale a dirty tree is allowed (a
/// smoke run is never committed).
fn is_current(meta: &Value, today: &SourceTree, experiment: &str, scale: Scale) -> bool {
    let reasons = match scale {
        Scale::Quick => staleness::source_reasons(meta, today, Some(experiment)),
        Scale::Paper => staleness::reasons(meta, today, Some(experiment)),
    };
    reasons.is_empty()
}

/// The plan of the paper in `paper_dir`, its experiment files read from `experiments`.
pub fn plan(paper_dir: &Path, experiments: &Path, scale: Scale) -> Result<Vec<Step>> {
    let (claims, _) = Claims::read(&paper_dir.join(CLAIMS_TOML))?;
    // Without the source to compare with, no run counts as current.
    let today = SourceTree::this();
    let today = today.is_readable().then_some(today);
    claims
        .experiments
        .iter()
        .map(|name| {
            let file = experiments.join(format!("{name}.toml"));
            let mut exp = Experiment::load(&file)?;
            overrides(scale, paper_dir).apply(&mut exp)?;
            let text = std::fs::read_to_string(&file).map_err(|e| Error::io(&file, e))?;
            let last = run_at_scale(&paper_dir.join(name), scale);
            Ok(Step {
                experiment: name.clone(),
                rays: planned_rays(&exp),
                done: match (&last, &today) {
                    (Some(meta), Some(today)) => is_current(meta, today, &text, scale),
                    _ => false,
                },
                last_seconds: last.and_then(|m| m.get("wall_seconds")?.as_f64()),
                file,
            })
        })
        .collect()
}

fn minutes(seconds: f64) -> String {
    match seconds {
        s if s < 60.0 => format!("{s:.0} s"),
        s if s < 3600.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

/// The papers `which` names, each with the one experiment file to run if it names one: `all`,
/// a paper's directory name under `results`, or an experiment file a paper's claims list.
fn select(which: &str, results: &Path) -> Result<Vec<(PathBuf, Option<String>)>> {
    let papers = papers_under(results)?;
    if which == "all" {
        return Ok(papers.into_iter().map(|p| (p, None)).collect());
    }
    let dir = results.join(which);
    if dir.join(CLAIMS_TOML).is_file() {
        return Ok(vec![(dir, None)]);
    }
    for paper in &papers {
        let (claims, _) = Claims::read(&paper.join(CLAIMS_TOML))?;
        if claims.experiments.iter().any(|e| e == which) {
            return Ok(vec![(paper.clone(), Some(which.to_string()))]);
        }
    }
    let known: Vec<String> = papers
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    Err(Error::usage(format!(
        "reproduce {which}: no {} and no paper lists an experiment {which} (papers: {}, or all)",
        dir.join(CLAIMS_TOML).display(),
        known.join(", ")
    )))
}

/// Reproduces what `which` names (`select`), then regenerates their
/// reports and `results/VERDICTS.md`. Returns the report paths (none for a `dry_run`, which
/// prints the plans only).
pub fn reproduce(
    which: &str,
    results: &Path,
    experiments: &Path,
    scale: Scale,
    dry_run: bool,
    chatter: Chatter,
) -> Result<Vec<PathBuf>> {
    let papers = select(which, results)?;
    let root = match scale {
        Scale::Paper => results.to_path_buf(),
        Scale::Quick => results.join(QUICK_DIR),
    };
    let mut reports = Vec::new();
    for (source, only) in &papers {
        let paper = &root.join(source.file_name().unwrap_or_default());
        if paper != source {
            std::fs::create_dir_all(paper).map_err(|e| Error::io(paper, e))?;
            let claims = paper.join(CLAIMS_TOML);
            std::fs::copy(source.join(CLAIMS_TOML), &claims).map_err(|e| Error::io(&claims, e))?;
        }
        let mut steps = plan(paper, experiments, scale)?;
        steps.retain(|s| only.as_ref().is_none_or(|name| &s.experiment == name));
        let mut text = format!(
            "reproduce {} at {} scale (estimates: the last run's wall time, else {} rays/s):\n",
            paper.display(),
            scale.name(),
            ESTIMATED_RAYS_PER_SECOND
        );
        for s in &steps {
            text += &format!(
                "  {:<28} {:>16} rays  ~{:>8} {:<10} {}\n",
                s.experiment,
                s.rays,
                minutes(s.estimate_seconds()),
                if s.last_seconds.is_some() {
                    "(last run)"
                } else {
                    ""
                },
                if s.done {
                    "done at this source"
                } else {
                    "to run"
                }
            );
        }
        chatter.say(&text);
        if dry_run {
            continue;
        }
        let todo: Vec<&Step> = steps.iter().filter(|s| !s.done).collect();
        let (mut estimated_done, mut took) = (0.0, 0.0);
        for (i, step) in todo.iter().enumerate() {
            let left: f64 = todo[i..].iter().map(|s| s.estimate_seconds()).sum();
            // Scale what is left by how the finished files compared with their estimates.
            let correction = if estimated_done > 0.0 {
                took / estimated_done
            } else {
                1.0
            };
            chatter.say(&format!(
                "[{}/{}] {}: time left ~{}",
                i + 1,
                todo.len(),
                step.experiment,
                minutes(left * correction)
            ));
            let clock = Instant::now();
            let staging = paper.join(format!(".{}.partial", step.experiment));
            let _ = std::fs::remove_dir_all(&staging);
            let mut run_overrides = overrides(scale, &staging);
            run_overrides.chatter = chatter;
            let made = run_experiment(&step.file, &run_overrides)?;
            let target = paper.join(&step.experiment);
            if target.exists() {
                std::fs::remove_dir_all(&target).map_err(|e| Error::io(&target, e))?;
            }
            std::fs::rename(&made, &target).map_err(|e| Error::io(&target, e))?;
            std::fs::remove_dir_all(&staging).map_err(|e| Error::io(&staging, e))?;
            estimated_done += step.estimate_seconds();
            took += clock.elapsed().as_secs_f64();
        }
        reports.push(write(std::slice::from_ref(paper), true, None)?);
    }
    if !dry_run {
        reports.push(write(&[root], true, None)?);
    }
    Ok(reports)
}
