//! `rays = [...]`: ray kinds by name and `{ file = "…" }` ray files, in file order, each once.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Deserializer};

use crate::error::Result;
use crate::geometry::RayKind;

use super::source::Source;
use super::ExperimentFile;

/// A `rays = [{ file = "…" }]` entry: the path as written, and resolved against the experiment
/// file's directory.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RayFileSpec {
    /// As written in the experiment (the `file:<name>` of runs.csv's ray_kind).
    pub name: String,
    pub path: PathBuf,
}

/// A `rays` entry: a ray kind by name, or `{ file = "…" }`.
pub(super) enum RayEntry {
    Kind(String),
    File(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RayFileTable {
    file: String,
}

impl From<String> for RayEntry {
    fn from(name: String) -> Self {
        RayEntry::Kind(name)
    }
}

impl<'de> Deserialize<'de> for RayEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        RayFileTable::deserialize(d).map(|t| RayEntry::File(t.file))
    }
}

/// The file's ray kinds and ray files.
pub(super) fn rays(
    src: &Source,
    file: &ExperimentFile,
) -> Result<(Vec<RayKind>, Vec<RayFileSpec>)> {
    let mut ray_kinds = Vec::new();
    let mut ray_files: Vec<RayFileSpec> = Vec::new();
    let no_rays = Vec::new();
    let rays = file.rays.as_ref().map_or(&no_rays, |r| r.get_ref());
    for entry in rays {
        let name = match &entry.get_ref().0 {
            RayEntry::Kind(name) => name,
            RayEntry::File(name) => {
                if name.is_empty() {
                    return Err(src.input_error(&entry.span(), "ray file: empty path"));
                }
                if !ray_files.iter().any(|f| &f.name == name) {
                    let dir = src.path.parent().unwrap_or(Path::new(""));
                    ray_files.push(RayFileSpec {
                        name: name.clone(),
                        path: dir.join(name),
                    });
                }
                continue;
            }
        };
        let kind = RayKind::parse(name).ok_or_else(|| {
            let known: Vec<&str> = RayKind::ALL.iter().map(|k| k.name()).collect();
            src.usage_error(
                &entry.span(),
                format!(
                    "unknown ray kind {name:?} (known: {}, or {{ file = \"…\" }})",
                    known.join(", ")
                ),
            )
        })?;
        if !ray_kinds.contains(&kind) {
            ray_kinds.push(kind);
        }
    }
    Ok((ray_kinds, ray_files))
}
