//! `scenes = [...]`: scenes by name, with a size for the generated ones, each at most once.

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::source::Source;
use super::ExperimentFile;

/// A scene by name, with the size for generated scenes (`None`: the generator's default).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<u32>,
}

impl From<String> for SceneSpec {
    fn from(name: String) -> Self {
        SceneSpec { name, size: None }
    }
}

/// The file's scenes; none only for a stability suite, which makes its own.
pub(super) fn scenes(src: &Source, file: &ExperimentFile, suite: bool) -> Result<Vec<SceneSpec>> {
    let scenes: Vec<SceneSpec> = file.scenes.get_ref().iter().map(|s| s.0.clone()).collect();
    if scenes.is_empty() && !suite {
        return Err(src.input_error(&file.scenes.span(), "no scenes"));
    }
    if let Some(twice) = scenes
        .iter()
        .enumerate()
        .find(|(i, s)| scenes[..*i].contains(s))
    {
        let size = twice
            .1
            .size
            .map_or(String::new(), |s| format!(" at size {s}"));
        return Err(src.input_error(
            &file.scenes.span(),
            format!("scene {}{size} is listed twice", twice.1.name),
        ));
    }
    Ok(scenes)
}
