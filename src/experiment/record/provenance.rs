//! What a run measured, as source: a digest per area of the code whose speed and answers the
//! numbers depend on (tracers, acceleration structures, lanes, geometry), recorded in meta.json,
//! so that a results directory can be told stale when that code has changed since
//! (`results::staleness`, `raylab report --check`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::digest::digest;

/// The areas of `src/` a measurement depends on.
pub const MEASURED: &[&str] = &["tracers", "accel", "lanes", "geometry"];

/// Every `.rs` file under `dir`, sorted by path.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            rust_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// The digest of each measured area of the source tree at `src` (relative paths and contents of
/// its `.rs` files, in path order); `None` when the tree cannot be read (a binary run away from
/// its source).
pub fn source_digests(src: &Path) -> Option<BTreeMap<String, String>> {
    MEASURED
        .iter()
        .map(|area| {
            let root = src.join(area);
            let mut files = Vec::new();
            rust_files(&root, &mut files).ok()?;
            files.sort();
            let mut parts: Vec<Vec<u8>> = Vec::new();
            for file in &files {
                let name = file.strip_prefix(src).ok()?.to_string_lossy().into_owned();
                parts.push(name.into_bytes());
                parts.push(std::fs::read(file).ok()?);
            }
            Some((area.to_string(), digest(parts.iter().map(Vec::as_slice))))
        })
        .collect()
}

/// The digests of the source this binary was built from (its crate's `src/`, read now).
pub fn this_source() -> Option<BTreeMap<String, String>> {
    source_digests(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_to_one_area_changes_its_digest_only() {
        let src = std::env::temp_dir().join(format!("raylab-provenance-{}", std::process::id()));
        for area in MEASURED {
            std::fs::create_dir_all(src.join(area).join("deep")).unwrap();
            std::fs::write(src.join(area).join("a.rs"), format!("// {area}")).unwrap();
            std::fs::write(src.join(area).join("deep/b.rs"), "fn b() {}").unwrap();
        }
        let before = source_digests(&src).unwrap();
        assert_eq!(before.len(), MEASURED.len());
        std::fs::write(src.join("lanes/deep/b.rs"), "fn b() { }").unwrap();
        // Not Rust source: not measured.
        std::fs::write(src.join("accel/notes.txt"), "x").unwrap();
        let after = source_digests(&src).unwrap();
        let changed: Vec<&String> = MEASURED
            .iter()
            .map(|a| &after[*a])
            .zip(MEASURED.iter().map(|a| &before[*a]))
            .filter(|(a, b)| a != b)
            .map(|(a, _)| a)
            .collect();
        assert_eq!(changed, [&after["lanes"]]);
        // A renamed file changes its area's digest too.
        std::fs::rename(src.join("geometry/a.rs"), src.join("geometry/c.rs")).unwrap();
        assert_ne!(
            source_digests(&src).unwrap()["geometry"],
            before["geometry"]
        );
        assert!(source_digests(&src.join("missing")).is_none());
        std::fs::remove_dir_all(&src).unwrap();
    }
}
