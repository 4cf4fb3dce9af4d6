//! Command-line replacements of an experiment's settings (`--threads`, `--resolution`, …) and
//! what a run shows while it runs.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::config::{check_threads, Experiment};
use super::shard::Shard;

/// Command-line replacements for experiment settings, for quick or scaled-down runs. Recorded in
/// meta.json, since they change what the numbers mean.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RunOverrides {
    pub output: Option<PathBuf>,
    pub threads: Option<Vec<usize>>,
    /// (width, height).
    pub resolution: Option<(u32, u32)>,
    pub frames: Option<usize>,
    pub warmup: Option<usize>,
    pub repeats: Option<usize>,
    /// Not a setting: also write every generated ray batch to `rays/` in the results directory
    /// (`run::dump`: with the triangles and soft-shadow points), for replay with `trace`, `verify --rays` or `rays = [{ file }]`.
    pub dump_rays: bool,
    /// Measure only this part of the plan (see `shard`); `raylab merge` joins the parts.
    #[serde(default)]
    pub shard: Option<Shard>,
    /// Not a setting: where the plan and the progress bar go.
    #[serde(skip)]
    pub chatter: Chatter,
    /// Set by `raylab reproduce`: the scale the run was made at (recorded in meta.json, so a
    /// report can say a run is a smoke test).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<Scale>,
}

/// `raylab reproduce --scale`: the paper's settings as the experiment file states them, or a
/// smoke test (`quick`: small images, one frame, one pass, one thread).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    #[default]
    Paper,
    Quick,
}

impl Scale {
    pub fn name(self) -> &'static str {
        match self {
            Scale::Paper => "paper",
            Scale::Quick => "quick",
        }
    }
}

/// What a run shows while it runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Chatter {
    /// The plan on standard output, the progress bar on standard error (on a terminal).
    #[default]
    Normal,
    /// Both on standard error, keeping standard output for machine-readable output (`--json`).
    Stderr,
    /// Neither (`--quiet`).
    Quiet,
}

impl Chatter {
    /// Shows `text` (the plan, a suite's outline) where this level sends it.
    pub fn say(self, text: &str) {
        match self {
            Chatter::Normal => println!("{text}"),
            Chatter::Stderr => eprintln!("{text}"),
            Chatter::Quiet => {}
        }
    }
}

impl RunOverrides {
    pub fn apply(&self, exp: &mut Experiment) -> Result<()> {
        let at_least_one = |what: &str, n: usize| match n {
            0 => Err(Error::usage(format!("{what} must be at least 1"))),
            n => Ok(n),
        };
        if let Some(output) = &self.output {
            exp.output = output.clone();
        }
        if let Some(threads) = &self.threads {
            check_threads(threads).map_err(Error::usage)?;
            exp.threads = threads.clone();
        }
        if let Some((width, height)) = self.resolution {
            exp.width = at_least_one("width", width as usize)? as u32;
            exp.height = at_least_one("height", height as usize)? as u32;
        }
        if let Some(frames) = self.frames {
            exp.frames = at_least_one("frames", frames)?;
        }
        if let Some(warmup) = self.warmup {
            exp.warmup = warmup;
        }
        if let Some(repeats) = self.repeats {
            exp.repeats = at_least_one("repeats", repeats)?;
        }
        Ok(())
    }
}
