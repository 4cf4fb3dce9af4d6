//! A results directory that appears whole or not at all: everything is written into a hidden
//! sibling `.<run-id>.partial` and renamed into place at the end; dropped before that, the partial
//! directory is removed, so a failed run never leaves half-written results behind.

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
        for attempt in 1.. {
            let id = if attempt == 1 {
                run_id.to_string()
            } else {
                format!("{run_id}-{attempt}")
            };
            let target = parent.join(&id);
            let partial = parent.join(format!(".{id}.partial"));
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
}
