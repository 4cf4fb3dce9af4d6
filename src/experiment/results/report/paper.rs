//! A paper's results directory, read: `results/<paper>/claims.toml` and the committed run of each
//! experiment file it lists, in `results/<paper>/<experiment>/`, with every claim judged. This
//! is the whole input of the paper's REPORT.md.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::experiment::record::digest::digest;
use crate::experiment::record::files::META_JSON;

use super::claims::{claim_line, Claims, Verdict, CLAIMS_TOML};
use super::judge::{judge, Judged, Runs};
use super::Results;

pub struct Paper {
    /// As given on the command line.
    pub dir: PathBuf,
    pub claims: Claims,
    /// Each experiment of the claims file, in its order, with its run when one is committed.
    pub runs: Vec<(String, Option<Results>)>,
    /// Each claim's verdict, in the claims file's order.
    pub judged: Vec<Judged>,
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
        let tables: Runs = runs
            .iter()
            .filter_map(|(name, run)| run.as_ref().map(|r| (name.as_str(), &r.tables[..])))
            .collect();
        let judged = claims
            .claims
            .iter()
            .map(|claim| {
                judge(claim, &tables).map_err(|message| {
                    let line = claim_line(&text, &claim.claim);
                    Error::input(&path, line, format!("{:?}: {message}", claim.claim))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let mut parts: Vec<&[u8]> = vec![text.as_bytes()];
        for (name, run) in &runs {
            parts.push(name.as_bytes());
            parts.push(run.as_ref().map_or(&[][..], |r| r.digest.as_bytes()));
        }
        let digest = digest(parts);
        Ok(Paper {
            dir: dir.to_path_buf(),
            claims,
            runs,
            judged,
            digest,
        })
    }

    /// How many claims have each verdict, in `Verdict::ALL`'s order.
    pub fn counts(&self) -> [usize; 4] {
        Verdict::ALL.map(|v| self.judged.iter().filter(|j| j.verdict == v).count())
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
