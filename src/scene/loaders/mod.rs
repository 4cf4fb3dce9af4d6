//! Scene file loaders, chosen by file extension.

use std::path::Path;

use crate::error::{Error, Result};
use crate::scene::Scene;

/// Loads a scene file (OBJ, PLY, PLY.GZ, NFF, AFF) into a `Scene`.
pub fn load(path: &Path) -> Result<Scene> {
    Err(Error::input(path, None, "unsupported scene file format"))
}
