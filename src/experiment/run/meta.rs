//! meta.json: everything needed to know what produced a run's numbers — code version, machine,
//! ISA, library versions, the experiment file as written, the overrides and the plan.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use serde::Serialize;

use crate::accel::libraries::LIBRARIES;

use crate::experiment::plan::overrides::RunOverrides;
use crate::experiment::plan::shard::ShardMeta;
use crate::experiment::plan::Plan;
use crate::experiment::record::files::META_JSON;
use crate::experiment::record::provenance::{every_area, measured_areas, SourceTree};
use crate::experiment::record::settings;
use crate::experiment::record::utc::UtcTime;

#[derive(Debug, Serialize)]
pub struct Meta<'a> {
    pub experiment: &'a str,
    pub run_id: String,
    /// Start of the run, UTC, ISO-8601.
    pub date: String,
    pub commit: Commit,
    /// A digest per area of the source the run measured (`record::provenance`): what
    /// `raylab report --check` compares with the source of today.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured_source: Option<BTreeMap<String, String>>,
    pub hostname: String,
    pub cpu: Cpu,
    pub threads: &'a [usize],
    /// Versions of the libraries measured against, and of raylab itself.
    pub versions: BTreeMap<&'static str, String>,
    pub experiment_file: ExperimentFile<'a>,
    pub overrides: &'a RunOverrides,
    /// The run's scale against the paper settings its experiment file declares
    /// (`record::settings::label`): `paper`, `reduced`, `quick`; none without a plan.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<&'static str>,
    /// The plan of a scenes × ray kinds run (a stability run has none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plan: Option<&'a Plan>,
    /// A sharded run's part of the sweep (`raylab run --shard`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardMeta>,
    /// Seconds from the run's start to its results written (a merged sweep has none: its shards
    /// ran apart).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_seconds: Option<f64>,
    /// A merged run's shards (`raylab merge`), in shard order: where and when each was measured.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<MergedShard>,
}

/// One shard of a merged run, from its meta.json.
#[derive(Debug, Serialize)]
pub struct MergedShard {
    pub shard: String,
    pub directory: String,
    pub run_id: String,
    pub date: String,
    pub hostname: String,
    pub commit: String,
    pub cpu: String,
}

#[derive(Debug, Serialize)]
pub struct Commit {
    /// `git rev-parse HEAD` of the source tree, or "unknown" outside git.
    pub hash: String,
    /// Uncommitted changes to tracked files; `None` when unknown.
    pub dirty: Option<bool>,
}

#[derive(Debug, Serialize)]
pub struct Cpu {
    pub model: String,
    pub logical_cores: usize,
    /// SIMD extensions this CPU has.
    pub features_detected: Vec<&'static str>,
    /// SIMD extensions the binary was compiled to use unconditionally.
    pub features_compiled: Vec<&'static str>,
}

#[derive(Debug, Serialize)]
pub struct ExperimentFile<'a> {
    pub path: String,
    pub contents: &'a str,
}

/// The facts of this machine and this build, gathered now.
pub fn gather<'a>(
    experiment: &'a str,
    plan: Option<&'a Plan>,
    threads: &'a [usize],
    run_id: String,
    started: UtcTime,
    (path, contents): (&Path, &'a str),
    overrides: &'a RunOverrides,
) -> Meta<'a> {
    let mut meta = Meta {
        experiment,
        run_id,
        date: started.iso8601(),
        commit: commit(),
        measured_source: {
            // The core and the families of the tracers planned (all of them without a plan).
            let areas = plan.map_or_else(every_area, |p| {
                measured_areas(p.instances.iter().map(|i| i.tracer.as_str()))
            });
            SourceTree::this().digests(&areas)
        },
        hostname: hostname(),
        cpu: Cpu {
            model: cpu_model(),
            logical_cores: std::thread::available_parallelism().map_or(0, |n| n.get()),
            features_detected: features_detected(),
            features_compiled: features_compiled(),
        },
        threads,
        versions: versions(),
        experiment_file: ExperimentFile {
            path: path.display().to_string(),
            contents,
        },
        overrides,
        scale: None,
        plan,
        shard: None,
        wall_seconds: None,
        merged_from: Vec::new(),
    };
    if plan.is_some() {
        let recorded = serde_json::to_value(&meta).unwrap_or_default();
        meta.scale = Some(settings::label(&recorded, contents).name());
    }
    meta
}

/// Writes `meta` as meta.json into `dir`.
pub fn write(dir: &Path, meta: &Meta) -> crate::error::Result<()> {
    let path = dir.join(META_JSON);
    let json = serde_json::to_string_pretty(meta)
        .map_err(|e| crate::error::Error::runtime(format!("meta.json: {e}")))?;
    std::fs::write(&path, json + "\n").map_err(|e| crate::error::Error::io(&path, e))
}

/// The commit of the source tree this binary was built from, read when the run starts.
pub fn commit() -> Commit {
    commit_of(Path::new(env!("CARGO_MANIFEST_DIR")))
}

/// The commit of the git tree at `dir`. Changes under `results/` do not make it dirty: they are
/// what runs write (a reproduction regenerates its reports between runs), not what they measure.
fn commit_of(dir: &Path) -> Commit {
    let git = |args: &[&str]| -> Option<String> {
        let out = Command::new("git")
            .arg("-C")
            .arg(dir)
            .args(args)
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    let status = [
        "status",
        "--porcelain",
        "--untracked-files=no",
        "--",
        ".",
        ":(exclude)results",
    ];
    match git(&["rev-parse", "HEAD"]) {
        Some(hash) => Commit {
            hash,
            dirty: git(&status).map(|s| !s.is_empty()),
        },
        None => Commit {
            hash: "unknown".into(),
            dirty: None,
        },
    }
}

fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| std::fs::read_to_string("/etc/hostname"))
        .map(|s| s.trim().to_string())
        .ok()
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, model)| model.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

#[cfg(target_arch = "x86_64")]
fn features_detected() -> Vec<&'static str> {
    [
        ("sse4.2", is_x86_feature_detected!("sse4.2")),
        ("avx", is_x86_feature_detected!("avx")),
        ("avx2", is_x86_feature_detected!("avx2")),
        ("fma", is_x86_feature_detected!("fma")),
        ("avx512f", is_x86_feature_detected!("avx512f")),
    ]
    .into_iter()
    .filter_map(|(name, present)| present.then_some(name))
    .collect()
}

#[cfg(not(target_arch = "x86_64"))]
fn features_detected() -> Vec<&'static str> {
    Vec::new()
}

fn features_compiled() -> Vec<&'static str> {
    [
        ("sse4.2", cfg!(target_feature = "sse4.2")),
        ("avx", cfg!(target_feature = "avx")),
        ("avx2", cfg!(target_feature = "avx2")),
        ("fma", cfg!(target_feature = "fma")),
        ("avx512f", cfg!(target_feature = "avx512f")),
        ("neon", cfg!(target_feature = "neon")),
    ]
    .into_iter()
    .filter_map(|(name, on)| on.then_some(name))
    .collect()
}

fn versions() -> BTreeMap<&'static str, String> {
    // Every library's version as this build runs it (a run without its tracers still records
    // why it is missing), and the Embree devices' configuration (`RAYLAB_EMBREE_CONFIG`, e.g. a
    // lower ISA), or Embree's default.
    let mut v: BTreeMap<&str, String> = LIBRARIES.iter().map(|l| (l.name, (l.version)())).collect();
    let config = crate::accel::embree::shared_config();
    v.insert("embree_config", config.unwrap_or_else(|| "default".into()));
    v.insert("raylab", env!("CARGO_PKG_VERSION").to_string());
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_written_do_not_make_the_tree_dirty_source_does() {
        let dir = std::env::temp_dir().join(format!("raylab-commit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for sub in ["src", "results/paper"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let git = |args: &[&str]| {
            let out = Command::new("git").arg("-C").arg(&dir).args(args).output();
            assert!(out.unwrap().status.success(), "git {args:?}");
        };
        let write = |file: &str, text: &str| std::fs::write(dir.join(file), text).unwrap();
        write("src/lib.rs", "fn a() {}");
        write("results/paper/REPORT.md", "old");
        git(&["init", "-q"]);
        git(&["add", "."]);
        let who = ["-c", "user.name=t", "-c", "user.email=t@t"];
        git(&[who.as_slice(), &["commit", "-qm", "one"]].concat());
        assert_eq!(commit_of(&dir).dirty, Some(false));
        write("results/paper/REPORT.md", "regenerated");
        assert_eq!(commit_of(&dir).dirty, Some(false));
        write("src/lib.rs", "fn b() {}");
        assert_eq!(commit_of(&dir).dirty, Some(true));
        assert_eq!(commit_of(&dir.join("missing")).hash, "unknown");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn compiled_features_are_detected_too() {
        // Whatever the binary assumes, the CPU running it must have.
        let detected = features_detected();
        for f in features_compiled().into_iter().filter(|f| *f != "neon") {
            assert!(detected.contains(&f), "{f} compiled in but not detected");
        }
    }
}
