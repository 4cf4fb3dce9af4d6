//! What a run measured, as source: a digest per area of the code whose speed and answers its
//! numbers depend on, recorded in meta.json, so that a results directory can be told stale when
//! that code has changed since (`results::staleness`, `raylab report --check`).
//!
//! The areas are the shared measured core (`CORE`: what every run's numbers depend on, whatever it
//! traces) and the source of each tracer family the run measured (`TracerInfo::source`). A run is
//! stale only when one of *its* areas changed: a change to `tracers/multi_frusta` leaves a run
//! that measured only packets current.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::digest::digest;
use crate::tracers::registry::{TracerInfo, TRACERS};

/// The shared measured core, paths under `src/` (folders or files): the structures (and the
/// baselines' bindings), the SIMD lanes, rays and triangle tests, the counters, the renderers and
/// wavefront that run inside the clock, the timing harness, the built-in scenes, and the tracer
/// layer every family runs through (its trait, chunking, staging, the soft-shadow query and the
/// registry that parses configurations).
pub const CORE: &[&str] = &[
    "accel",
    "experiment/run/passes.rs",
    "geometry",
    "lanes",
    "render",
    "scene/builtin",
    "stats.rs",
    "tracers/chunked.rs",
    "tracers/kernel.rs",
    "tracers/mod.rs",
    "tracers/registry.rs",
    "tracers/staged.rs",
    "tracers/visibility.rs",
];

/// The areas a run of `tracers` (registry names) measured: the core and their families' source,
/// sorted, each once. A name the registry does not know adds nothing (the run would have refused
/// it).
pub fn measured_areas<'a>(tracers: impl IntoIterator<Item = &'a str>) -> Vec<&'static str> {
    let mut areas: Vec<&'static str> = CORE.to_vec();
    for name in tracers {
        if let Ok(info) = TracerInfo::find(name) {
            areas.extend(info.source);
        }
    }
    areas.sort_unstable();
    areas.dedup();
    areas
}

/// The areas of every family this build has: what a run that does not say which tracers it
/// measured (the stability suite measures them all) depends on.
pub fn every_area() -> Vec<&'static str> {
    measured_areas(TRACERS.iter().map(|t| t.name))
}

/// Every `.rs` file at `path` (the file itself, or those under a folder), sorted.
fn rust_files(path: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    if path.is_file() {
        out.push(path.to_path_buf());
        return Ok(());
    }
    for entry in std::fs::read_dir(path)? {
        let path = entry?.path();
        if path.is_dir() {
            rust_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// A source tree whose areas are digested on demand, each once.
pub struct SourceTree {
    src: PathBuf,
    digests: RefCell<BTreeMap<String, Option<String>>>,
}

impl SourceTree {
    pub fn at(src: &Path) -> SourceTree {
        SourceTree {
            src: src.to_path_buf(),
            digests: RefCell::default(),
        }
    }

    /// The source this binary was built from (its crate's `src/`, read now).
    pub fn this() -> SourceTree {
        SourceTree::at(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
    }

    /// Whether the tree is there to read (a binary run away from its source has none).
    pub fn is_readable(&self) -> bool {
        self.src.is_dir()
    }

    pub fn path(&self) -> &Path {
        &self.src
    }

    /// The digest of `area` (relative paths and contents of its `.rs` files, in path order);
    /// `None` when it cannot be read.
    pub fn digest(&self, area: &str) -> Option<String> {
        if let Some(known) = self.digests.borrow().get(area) {
            return known.clone();
        }
        let computed = self.compute(area);
        self.digests
            .borrow_mut()
            .insert(area.to_string(), computed.clone());
        computed
    }

    fn compute(&self, area: &str) -> Option<String> {
        let mut files = Vec::new();
        rust_files(&self.src.join(area), &mut files).ok()?;
        files.sort();
        let mut parts: Vec<Vec<u8>> = Vec::new();
        for file in &files {
            let name = file.strip_prefix(&self.src).ok()?.to_string_lossy();
            parts.push(name.into_owned().into_bytes());
            parts.push(std::fs::read(file).ok()?);
        }
        Some(digest(parts.iter().map(Vec::as_slice)))
    }

    /// The digest of each of `areas`; `None` when one cannot be read.
    pub fn digests(&self, areas: &[&str]) -> Option<BTreeMap<String, String>> {
        areas
            .iter()
            .map(|area| Some((area.to_string(), self.digest(area)?)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("raylab-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn a_change_to_one_area_changes_its_digest_only() {
        let src = scratch("provenance");
        for area in ["lanes", "geometry", "tracers/packet"] {
            std::fs::create_dir_all(src.join(area).join("deep")).unwrap();
            std::fs::write(src.join(area).join("a.rs"), format!("// {area}")).unwrap();
            std::fs::write(src.join(area).join("deep/b.rs"), "fn b() {}").unwrap();
        }
        std::fs::write(src.join("stats.rs"), "// counters").unwrap();
        let areas = ["geometry", "lanes", "stats.rs", "tracers/packet"];
        let before = SourceTree::at(&src).digests(&areas).unwrap();
        assert_eq!(before.len(), 4);
        std::fs::write(src.join("lanes/deep/b.rs"), "fn b() { }").unwrap();
        // Not Rust source: not measured.
        std::fs::write(src.join("tracers/packet/notes.txt"), "x").unwrap();
        let after = SourceTree::at(&src).digests(&areas).unwrap();
        let changed: Vec<&String> = after
            .iter()
            .filter(|(area, digest)| before[*area] != **digest)
            .map(|(area, _)| area)
            .collect();
        assert_eq!(changed, ["lanes"]);
        // A renamed file changes its area's digest too; a file is an area of its own.
        std::fs::rename(src.join("geometry/a.rs"), src.join("geometry/c.rs")).unwrap();
        std::fs::write(src.join("stats.rs"), "// counters, renamed").unwrap();
        let renamed = SourceTree::at(&src);
        assert_ne!(renamed.digest("geometry").unwrap(), before["geometry"]);
        assert_ne!(renamed.digest("stats.rs").unwrap(), before["stats.rs"]);
        assert!(renamed.digests(&["missing"]).is_none());
        std::fs::remove_dir_all(&src).unwrap();
    }

    #[test]
    fn a_run_measures_the_core_and_the_families_of_its_tracers() {
        let packet = measured_areas(["packet", "embree3-16", "nonsense"]);
        assert!(CORE.iter().all(|a| packet.contains(a)));
        assert!(packet.contains(&"tracers/packet") && packet.contains(&"tracers/embree"));
        assert!(!packet.contains(&"tracers/multi_frusta"));
        let mft = measured_areas(["mft"]);
        assert!(mft.contains(&"tracers/multi_frusta") && mft.contains(&"tracers/packet"));
        let every = every_area();
        assert!(every.contains(&"tracers/coherent_grid") && every.contains(&"tracers/stream"));
        // Every area exists in this tree.
        let tree = SourceTree::this();
        assert!(tree.digests(&every).is_some(), "an area names no source");
    }

    /// Each family's source names every other family it imports (`crate::tracers::…`), so a
    /// change to that family makes its runs stale too; the tracer layer's shared files are core.
    #[test]
    fn each_family_declares_the_families_it_imports() {
        let tree = SourceTree::this();
        for info in TRACERS {
            let mut files = Vec::new();
            for area in info.source {
                rust_files(&tree.path().join(area), &mut files).unwrap();
            }
            for file in files {
                let text = std::fs::read_to_string(&file).unwrap();
                for (at, _) in text.match_indices("crate::tracers::") {
                    let rest = &text[at + "crate::tracers::".len()..];
                    let modules: Vec<&str> = match rest.strip_prefix('{') {
                        Some(list) => list[..list.find('}').unwrap()]
                            .split(',')
                            .map(|m| m.trim().split("::").next().unwrap())
                            .collect(),
                        None => vec![rest
                            .split(|c: char| !c.is_alphanumeric() && c != '_')
                            .next()
                            .unwrap()],
                    };
                    for module in modules {
                        let (folder, single) =
                            (format!("tracers/{module}"), format!("tracers/{module}.rs"));
                        let root = tree.path();
                        if !root.join(&folder).is_dir() && !root.join(&single).is_file() {
                            // An item of `tracers/mod.rs` (core), not a module.
                            continue;
                        }
                        let declared = |a: &&str| **a == folder || **a == single;
                        assert!(
                            info.source.iter().any(declared) || CORE.iter().any(declared),
                            "{} imports tracers::{module} ({}) but its source does not name it",
                            info.name,
                            file.display()
                        );
                    }
                }
            }
        }
    }
}
