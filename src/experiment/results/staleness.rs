//! `raylab report --check PATH…`: which results directories under the paths are no longer
//! evidence. A run is stale when it was made from a dirty tree (or one whose state is unknown),
//! when it has no record of the source it measured, when that source — the shared measured core
//! and the families of the tracers it ran (`record::provenance`), each area as the run recorded
//! it — has changed since, when its experiment file now asks for something else, or when it is
//! labelled the paper's scale while a setting falls short of the paper's (`record::settings`).
//! The rule, not a person, says which runs must be re-run before their numbers are quoted;
//! `reproduce` redoes exactly those.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};
use crate::experiment::record::files::META_JSON;
use crate::experiment::record::provenance::{SourceTree, CORE};
use crate::experiment::record::settings::{label, labelled_paper, Label};

/// A results directory and why it is stale (empty: it is not).
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub dir: PathBuf,
    pub reasons: Vec<String>,
}

/// Every results directory (a directory with a meta.json) at or under `path`, in path order.
fn runs_under(path: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    if path.join(META_JSON).is_file() {
        out.push(path.to_path_buf());
        return Ok(());
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| Error::io(path, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    entries.sort();
    entries.iter().try_for_each(|p| runs_under(p, out))
}

/// Why the run whose meta.json is `meta` is stale against the source tree `today` and the
/// experiment file's contents now (`experiment_now`; `None`: not known, not compared).
pub fn reasons(meta: &Value, today: &SourceTree, experiment_now: Option<&str>) -> Vec<String> {
    let commit = meta.pointer("/commit/hash").and_then(Value::as_str);
    let mut reasons = match meta.pointer("/commit/dirty").and_then(Value::as_bool) {
        Some(false) => Vec::new(),
        Some(true) => vec![format!(
            "made from a dirty tree (commit {})",
            commit.unwrap_or("unknown")
        )],
        None => vec!["made from a tree whose state is unknown".to_string()],
    };
    reasons.extend(source_reasons(meta, today, experiment_now));
    reasons
}

/// Why the run measured something other than what its experiment file and the source would
/// measure now (`reasons` without the tree's state).
pub fn source_reasons(
    meta: &Value,
    today: &SourceTree,
    experiment_now: Option<&str>,
) -> Vec<String> {
    let mut reasons = Vec::new();
    match meta.get("measured_source").and_then(Value::as_object) {
        None => reasons.push("no record of the source it measured".to_string()),
        Some(then) => {
            // Each area the run recorded (older runs recorded whole folders: `tracers`), in
            // meta.json's order.
            let changed: Vec<&str> = then
                .iter()
                .filter(|(area, digest)| digest.as_str() != today.digest(area).as_deref())
                .map(|(area, _)| area.as_str())
                .collect();
            if !changed.is_empty() {
                reasons.push(format!(
                    "the code it measured changed since: {}",
                    changed.join(", ")
                ));
            }
            // The shared core grew since (a file split out of one the run recorded, say): what
            // the run did not record, it cannot vouch for. An area recorded whole by an older
            // run (`tracers`) covers the files under it.
            let covered = |area: &str| {
                then.keys()
                    .any(|t| t == area || area.starts_with(&format!("{t}/")))
            };
            let unrecorded: Vec<&str> = CORE.iter().copied().filter(|a| !covered(a)).collect();
            if !unrecorded.is_empty() {
                reasons.push(format!(
                    "it did not record the measured core's {}",
                    unrecorded.join(", ")
                ));
            }
        }
    }
    let then = meta
        .pointer("/experiment_file/contents")
        .and_then(Value::as_str);
    if let (Some(then), Some(now)) = (then, experiment_now) {
        if then != now {
            reasons.push("its experiment file changed since".to_string());
        }
    }
    if let Some(now) = experiment_now {
        if let (true, Label::Reduced(short)) = (labelled_paper(meta), label(meta, now)) {
            reasons.push(format!(
                "labelled paper scale, but below the paper's settings: {}",
                short.join(", ")
            ));
        }
    }
    reasons
}

/// Why the run whose meta.json is `meta` is stale against `today`, its experiment file read from
/// where the run recorded it (`reasons`).
pub fn reasons_now(meta: &Value, today: &SourceTree) -> Vec<String> {
    reasons(meta, today, experiment_now(meta).as_deref())
}

/// A run's status in one phrase: "current", or "stale: " and why.
pub fn status(reasons: &[String]) -> String {
    match reasons.is_empty() {
        true => "current".to_string(),
        false => format!("stale: {}", reasons.join("; ")),
    }
}

/// The experiment file the run (`meta`) recorded, as it reads now (from the working directory the
/// run was made in: `None` when it cannot be read from here).
fn experiment_now(meta: &Value) -> Option<String> {
    let path = meta
        .pointer("/experiment_file/path")
        .and_then(Value::as_str)?;
    std::fs::read_to_string(path).ok()
}

/// The verdict on every results directory under `paths`; a path with none is a usage error.
pub fn check(paths: &[PathBuf]) -> Result<Vec<Verdict>> {
    let today = SourceTree::this();
    if !today.is_readable() {
        return Err(Error::runtime(format!(
            "cannot read the source tree at {} to compare with",
            today.path().display()
        )));
    }
    let mut verdicts = Vec::new();
    for path in paths {
        let mut runs = Vec::new();
        runs_under(path, &mut runs)?;
        if runs.is_empty() {
            return Err(Error::usage(format!(
                "{}: no results directory (no {META_JSON}) there",
                path.display()
            )));
        }
        for dir in runs {
            let file = dir.join(META_JSON);
            let text = std::fs::read_to_string(&file).map_err(|e| Error::io(&file, e))?;
            let meta: Value = serde_json::from_str(&text)
                .map_err(|e| Error::input(&file, Some(e.line()), e.to_string()))?;
            verdicts.push(Verdict {
                reasons: reasons_now(&meta, &today),
                dir,
            });
        }
    }
    Ok(verdicts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::record::provenance::measured_areas;

    /// A scratch source tree holding every area a run of packets, Embree or mft measures.
    fn scratch_tree(name: &str) -> (PathBuf, SourceTree) {
        let src = std::env::temp_dir().join(format!("raylab-stale-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&src);
        for area in measured_areas(["packet", "embree3-16", "mft"]) {
            let file = if area.ends_with(".rs") {
                src.join(area)
            } else {
                src.join(area).join("mod.rs")
            };
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(&file, format!("// {area}")).unwrap();
        }
        let tree = SourceTree::at(&src);
        (src, tree)
    }

    /// A clean run's meta.json that measured `tracers`, recorded against `tree`.
    fn run_of(tracers: &[&str], tree: &SourceTree) -> Value {
        serde_json::json!({
            "commit": { "hash": "abc", "dirty": false },
            "measured_source": tree.digests(&measured_areas(tracers.iter().copied())).unwrap(),
        })
    }

    #[test]
    fn dirty_unknown_unrecorded_and_changed_runs_are_stale_a_clean_current_one_is_not() {
        let (src, now) = scratch_tree("reasons");
        let clean = run_of(&["packet"], &now);
        assert!(reasons(&clean, &now, None).is_empty());

        let mut dirty = clean.clone();
        dirty["commit"]["dirty"] = Value::Bool(true);
        assert_eq!(
            reasons(&dirty, &now, None),
            ["made from a dirty tree (commit abc)"]
        );

        let mut unknown = clean.clone();
        unknown["commit"] = serde_json::json!({ "hash": "unknown", "dirty": null });
        assert_eq!(
            reasons(&unknown, &now, None),
            ["made from a tree whose state is unknown"]
        );

        let mut old = clean.clone();
        old.as_object_mut().unwrap().remove("measured_source");
        assert_eq!(
            reasons(&old, &now, None),
            ["no record of the source it measured"]
        );

        let mut changed = clean.clone();
        changed["measured_source"]["lanes"] = Value::from("lanes-then");
        changed["measured_source"]["tracers/packet"] = Value::from("packet-then");
        assert_eq!(
            reasons(&changed, &now, None),
            ["the code it measured changed since: lanes, tracers/packet"]
        );

        let mut recorded = clean.clone();
        recorded["experiment_file"] = serde_json::json!({ "path": "e.toml", "contents": "a = 1" });
        assert!(reasons(&recorded, &now, Some("a = 1")).is_empty());
        assert_eq!(
            reasons(&recorded, &now, Some("a = 2")),
            ["its experiment file changed since"]
        );
        // Labelled the paper's scale (reproduce --scale paper) at 512² where the paper used 1024².
        let paper = "paper_settings = { width = 1024, height = 1024 }\n";
        let mut reduced = clean.clone();
        reduced["experiment_file"] = serde_json::json!({ "path": "e.toml", "contents": paper });
        reduced["overrides"] = serde_json::json!({ "scale": "paper" });
        reduced["plan"] = serde_json::json!({ "width": 512, "height": 512, "frames": 1 });
        assert_eq!(
            reasons(&reduced, &now, Some(paper)),
            ["labelled paper scale, but below the paper's settings: width 512 < 1024, height 512 < 1024"]
        );
        // Labelled reduced when it ran: honest, not stale.
        reduced["scale"] = Value::from("reduced");
        assert!(reasons(&reduced, &now, Some(paper)).is_empty());
        assert_eq!(
            source_reasons(&dirty, &now, None),
            Vec::<String>::new(),
            "the tree's state is not the source's"
        );
        std::fs::remove_dir_all(&src).unwrap();
    }

    /// Staleness per family (issue 46): on a scratch tree, a change to `tracers/multi_frusta`
    /// makes the run that measured mft stale and leaves the one of packets alone; a change to the
    /// shared core (the lanes) makes both stale.
    #[test]
    fn a_change_to_one_family_makes_only_the_runs_that_measured_it_stale() {
        let (src, before) = scratch_tree("family");
        let packets = run_of(&["packet", "embree3-16"], &before);
        let mft = run_of(&["mft"], &before);
        // A run recorded before staleness per family (whole folders) is compared by folder.
        let whole = serde_json::json!({
            "commit": { "hash": "abc", "dirty": false },
            "measured_source": before.digests(&["accel", "geometry", "lanes", "tracers"]).unwrap(),
        });
        std::fs::write(src.join("tracers/multi_frusta/mod.rs"), "// changed").unwrap();
        let after = SourceTree::at(&src);
        assert!(reasons(&packets, &after, None).is_empty());
        assert_eq!(
            reasons(&mft, &after, None),
            ["the code it measured changed since: tracers/multi_frusta"]
        );
        std::fs::write(src.join("lanes/mod.rs"), "// changed").unwrap();
        let core = SourceTree::at(&src);
        assert_eq!(
            reasons(&packets, &core, None),
            ["the code it measured changed since: lanes"]
        );
        assert_eq!(
            reasons(&mft, &core, None),
            ["the code it measured changed since: lanes, tracers/multi_frusta"]
        );
        // It did not record the areas the core has gained since, so it cannot vouch for them.
        assert_eq!(
            reasons(&whole, &core, None),
            [
                "the code it measured changed since: lanes, tracers",
                "it did not record the measured core's experiment/run/passes.rs, render, \
                 scene/builtin, stats.rs"
            ]
        );
        std::fs::remove_dir_all(&src).unwrap();
    }

    #[test]
    fn runs_are_found_under_a_tree_and_a_path_without_any_is_refused() {
        let root = std::env::temp_dir().join(format!("raylab-staleness-{}", std::process::id()));
        let run = root.join("paper/exp/20260101T000000Z");
        std::fs::create_dir_all(run.join("rays")).unwrap();
        let meta = run_of(&["reference"], &SourceTree::this());
        std::fs::write(run.join(META_JSON), meta.to_string()).unwrap();
        let verdicts = check(std::slice::from_ref(&root)).unwrap();
        assert_eq!(
            verdicts,
            [Verdict {
                dir: run.clone(),
                reasons: Vec::new()
            }]
        );
        let empty = root.join("empty");
        std::fs::create_dir_all(&empty).unwrap();
        assert!(matches!(check(&[empty]), Err(Error::Usage(_))));
        std::fs::remove_dir_all(&root).unwrap();
    }
}
