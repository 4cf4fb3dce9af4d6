//! A paper's results directory, read: `results/<paper>/claims.toml` and the committed run of each
//! experiment file it lists, in `results/<paper>/<experiment>/`, each run's tables computed from
//! its records, and every claim judged. With the experiment files whose `[[tables]]` lay out the
//! runs, this is the whole input of the paper's REPORT.md.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::experiment::plan::table_spec::TableSpec;
use crate::experiment::record::digest::digest;
use crate::experiment::record::files::{META_JSON, RUNS_CSV};
use crate::experiment::record::selection::read_rows;
use crate::experiment::record::settings::{label, Label};
use crate::experiment::results::tables::{run_tables, Cell, TableModel};

use super::blocks::{self, Block};
use super::claims::{claim_line, Claim, Claims, Test, Verdict, CLAIMS_TOML};
use super::judge::{judge, Judged, Runs};
use super::Results;

pub struct Paper {
    /// As given on the command line.
    pub dir: PathBuf,
    pub claims: Claims,
    /// Each experiment of the claims file, in its order, with its run when one is committed.
    pub runs: Vec<(String, Option<Results>)>,
    /// The tables of each run, in `runs`' order (none without a run).
    pub tables: Vec<Vec<TableModel>>,
    /// Each run's scale against its experiment file's paper settings, in `runs`' order.
    pub scales: Vec<Option<Label>>,
    /// Each paper claim's verdict, in the claims file's order.
    pub judged: Vec<Judged>,
    /// Each target's verdict, in the claims file's order.
    pub judged_targets: Vec<Judged>,
    /// `digest` of the claims file and every run's files: what a report was made from.
    pub digest: String,
}

impl Paper {
    pub fn is_paper(dir: &Path) -> bool {
        dir.join(CLAIMS_TOML).is_file()
    }

    /// Reads `dir`. A subdirectory that is not one of the claims file's experiments, or a claim
    /// quoting a cell its run does not have, is an input error naming claims.toml and the line.
    pub fn read(dir: &Path) -> Result<Paper> {
        let path = dir.join(CLAIMS_TOML);
        if !path.is_file() {
            return Err(Error::usage(format!(
                "{}: not a paper's results directory (no {CLAIMS_TOML})",
                dir.display()
            )));
        }
        let (claims, text) = Claims::read(&path)?;
        for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let sub = entry.map_err(|e| Error::io(dir, e))?.path();
            let name = sub.file_name().map(|n| n.to_string_lossy().into_owned());
            let listed = name
                .as_ref()
                .is_some_and(|n| claims.experiments.contains(n));
            if sub.join(META_JSON).is_file() && !listed {
                return Err(Error::input(
                    &path,
                    None,
                    format!(
                        "{} holds a run of an experiment this file does not list",
                        sub.display()
                    ),
                ));
            }
        }
        let runs: Vec<(String, Option<Results>)> = claims
            .experiments
            .iter()
            .map(|name| {
                let run_dir = dir.join(name);
                let run = match run_dir.join(META_JSON).is_file() {
                    true => Some(Results::read(&run_dir)?),
                    false => None,
                };
                Ok((name.clone(), run))
            })
            .collect::<Result<_>>()?;
        let mut tables = Vec::new();
        let mut layouts = Vec::new();
        for (_, run) in &runs {
            let (models, layout) = match run {
                Some(run) => computed_tables(run)?,
                None => (Vec::new(), String::new()),
            };
            tables.push(models);
            layouts.push(layout);
        }
        let by_experiment: Runs = runs
            .iter()
            .zip(&tables)
            .filter(|((_, run), _)| run.is_some())
            .map(|((name, _), models)| (name.as_str(), &models[..]))
            .collect();
        let scales = runs
            .iter()
            .zip(&layouts)
            .map(|((_, run), layout)| run.as_ref().map(|r| label(&r.meta, layout)))
            .collect();
        let tolerance = claims.tolerance.as_ref();
        let judge_all = |list: &[Claim]| {
            list.iter()
                .map(|claim| {
                    judge(claim, &by_experiment, tolerance).map_err(|message| {
                        let line = claim_line(&text, &claim.claim);
                        Error::input(&path, line, format!("{:?}: {message}", claim.claim))
                    })
                })
                .collect::<Result<Vec<_>>>()
        };
        let judged = judge_all(&claims.claims)?;
        let judged_targets = judge_all(&claims.targets)?;
        let mut parts: Vec<&[u8]> = vec![text.as_bytes()];
        for ((name, run), layout) in runs.iter().zip(&layouts) {
            parts.push(name.as_bytes());
            parts.push(run.as_ref().map_or(&[][..], |r| r.digest.as_bytes()));
            parts.push(layout.as_bytes());
        }
        let digest = digest(parts);
        Ok(Paper {
            dir: dir.to_path_buf(),
            claims,
            runs,
            tables,
            scales,
            judged,
            judged_targets,
            digest,
        })
    }

    /// How many of `judged` have each verdict, in `Verdict::ALL`'s order.
    pub fn counts(judged: &[Judged]) -> [usize; 5] {
        Verdict::ALL.map(|v| judged.iter().filter(|j| j.verdict == v).count())
    }

    /// The experiments `claim` reads whose runs fall short of the paper's settings.
    pub fn reduced_runs_of(&self, claim: &Claim) -> Vec<&str> {
        let mut read = vec![claim.experiment.clone()];
        for test in claim.tests.iter().filter_map(|t| Test::parse(t).ok()) {
            read.extend(
                test.references()
                    .iter()
                    .filter_map(|r| r.experiment.clone()),
            );
        }
        self.runs
            .iter()
            .zip(&self.scales)
            .filter(|((name, _), scale)| {
                matches!(scale, Some(Label::Reduced(_))) && read.contains(name)
            })
            .map(|((name, _), _)| name.as_str())
            .collect()
    }

    /// The paper's directory name (`overbeck2008`).
    pub fn name(&self) -> String {
        self.dir
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    }
}

/// Every paper's directory directly under `root`, in name order.
pub fn papers_under(root: &Path) -> Result<Vec<PathBuf>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)
        .map_err(|e| Error::io(root, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| Paper::is_paper(p))
        .collect();
    dirs.sort();
    Ok(dirs)
}

/// The `[[tables]]` of an experiment file, the only part a report needs.
#[derive(Deserialize)]
struct Layout {
    #[serde(default)]
    tables: Vec<TableSpec>,
}

/// A run's tables and the text of the layout they were computed with: a run with runs.csv is laid
/// out by the `[[tables]]` of its experiment file as it is today (the path meta.json records,
/// from the repository root), so a claim may read a table added after the run; a run without
/// (the stability suite's) by the tables.md it wrote, as text.
fn computed_tables(run: &Results) -> Result<(Vec<TableModel>, String)> {
    if run.data.as_ref().is_none_or(|(name, _)| *name != RUNS_CSV) {
        return Ok((written_tables(&run.tables), String::new()));
    }
    let path = PathBuf::from(run.text("/experiment_file/path"));
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let layout: Layout = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| text[..s.start].matches('\n').count() + 1);
        Error::input(&path, line, e.message().to_string())
    })?;
    for table in &layout.tables {
        table
            .check()
            .map_err(|e| Error::input(&path, None, e.to_string()))?;
    }
    let rows = read_rows(&run.dir.join(RUNS_CSV))?;
    Ok((run_tables(&layout.tables, &rows), text))
}

/// The tables of a tables.md, their cells as written.
fn written_tables(blocks: &[Block]) -> Vec<TableModel> {
    blocks::tables(blocks)
        .map(|t| TableModel {
            title: t.title.clone(),
            caption: String::new(),
            row_header: t.header.first().cloned().unwrap_or_default(),
            columns: t.header.iter().skip(1).cloned().collect(),
            rows: t
                .rows
                .iter()
                .map(|r| {
                    let label = r.first().cloned().unwrap_or_default();
                    let cells = r.iter().skip(1).map(|c| Cell::Text(c.clone())).collect();
                    (label, cells)
                })
                .collect(),
        })
        .collect()
}
