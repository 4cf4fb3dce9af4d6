//! A results directory that appears whole or not at all: everything is written into a hidden
//! sibling `.<run-id>.<pid>.partial` and renamed into place at the end; dropped before that, the
//! partial directory is removed, so a failed run never leaves half-written results behind. A run
//! killed outright cannot clean up: the next run in the same place removes partial directories
//! whose process is gone (and says so), and leaves those of runs still going.

use std::fs;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub struct PendingResults {
    partial: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl PendingResults {
    /// Claims `<output>/<experiment>/<run_id>` — or `<run_id>-2`, `-3`... when taken — and
    /// creates its partial directory.
    pub fn create(output: &Path, experiment: &str, run_id: &str) -> Result<PendingResults> {
        let parent = output.join(experiment);
        fs::create_dir_all(&parent).map_err(|e| Error::io(&parent, e))?;
        remove_abandoned(&parent);
        let pid = std::process::id();
        for attempt in 1.. {
            let id = if attempt == 1 {
                run_id.to_string()
            } else {
                format!("{run_id}-{attempt}")
            };
            let target = parent.join(&id);
            let partial = parent.join(format!(".{id}.{pid}.partial"));
            if target.exists() {
                continue;
            }
            // create_dir (not _all) fails if another run claimed the name first.
            match fs::create_dir(&partial) {
                Ok(()) => {
                    return Ok(PendingResults {
                        partial,
                        target,
                        committed: false,
                    })
                }
                Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(Error::io(&partial, e)),
            }
        }
        unreachable!("the attempt counter is unbounded")
    }

    /// Where to write the files while the run is in progress.
    pub fn dir(&self) -> &Path {
        &self.partial
    }

    /// The run id finally used (the name of the results directory).
    pub fn run_id(&self) -> String {
        self.target
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    }

    /// Moves the finished results into place and returns their directory.
    pub fn commit(mut self) -> Result<PathBuf> {
        fs::rename(&self.partial, &self.target).map_err(|e| Error::io(&self.target, e))?;
        self.committed = true;
        Ok(self.target.clone())
    }
}

/// Removes the partial directories in `parent` left by runs that were killed: those whose
/// process no longer exists. Where that cannot be known (no `/proc`), it only reports them.
fn remove_abandoned(parent: &Path) {
    let Ok(entries) = fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = partial_owner(&name) else {
            continue;
        };
        let path = entry.path();
        let proc = Path::new("/proc");
        if !proc.is_dir() {
            eprintln!(
                "raylab: {} holds partial results of an earlier run",
                path.display()
            );
        } else if pid.is_none_or(|pid| !proc.join(pid.to_string()).exists()) {
            match fs::remove_dir_all(&path) {
                Ok(()) => eprintln!(
                    "raylab: removed {}: partial results of an interrupted run",
                    path.display()
                ),
                Err(e) => eprintln!("raylab: cannot remove {}: {e}", path.display()),
            }
        }
    }
}

/// For a partial directory's name, `Some(owner pid)` (`None` inside: an older name without one).
fn partial_owner(name: &str) -> Option<Option<u32>> {
    let stem = name.strip_prefix('.')?.strip_suffix(".partial")?;
    Some(stem.rsplit_once('.').and_then(|(_, pid)| pid.parse().ok()))
}

impl Drop for PendingResults {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: the run has already failed, and that error is the one to report.
            let _ = fs::remove_dir_all(&self.partial);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("raylab-results-dir-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn commit_renames_and_taken_ids_get_a_suffix() {
        let out = scratch("commit");
        let first = PendingResults::create(&out, "exp", "20240101T000000Z").unwrap();
        fs::write(first.dir().join("runs.csv"), "x").unwrap();
        let second = PendingResults::create(&out, "exp", "20240101T000000Z").unwrap();
        assert_eq!(second.run_id(), "20240101T000000Z-2");
        let path = first.commit().unwrap();
        assert_eq!(path, out.join("exp/20240101T000000Z"));
        assert_eq!(fs::read_to_string(path.join("runs.csv")).unwrap(), "x");
        drop(second);
        let third = PendingResults::create(&out, "exp", "20240101T000000Z").unwrap();
        assert_eq!(third.run_id(), "20240101T000000Z-2");
        drop(third);
        let mut left: Vec<String> = fs::read_dir(out.join("exp"))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, ["20240101T000000Z"]);
        fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn partial_directories_of_dead_runs_are_removed_and_live_ones_kept() {
        let out = scratch("abandoned");
        let parent = out.join("exp");
        // A pid far above Linux's limit (2²²) belongs to no process.
        let dead = parent.join(".20240101T000000Z.99999999.partial");
        let old_style = parent.join(".20240101T000001Z.partial");
        let live = parent.join(format!(".20240101T000002Z.{}.partial", std::process::id()));
        for dir in [&dead, &old_style, &live] {
            fs::create_dir_all(dir).unwrap();
        }
        let pending = PendingResults::create(&out, "exp", "20240101T000003Z").unwrap();
        assert!(!dead.exists() && !old_style.exists());
        assert!(live.exists());
        assert_eq!(partial_owner(".x.12.partial"), Some(Some(12)));
        assert_eq!(partial_owner("20240101T000000Z"), None);
        drop(pending);
        let _ = fs::remove_dir_all(&out);
    }
}
