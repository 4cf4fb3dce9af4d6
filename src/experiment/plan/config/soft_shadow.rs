//! `soft_shadow = { samples, sets }`: the light samples per shading point of the `soft_shadow`
//! query and how their interleaved sets are made.

use serde::Deserialize;

use crate::error::Result;
use crate::render::area_light::LightSampleSets;
use crate::render::interleaved::SampleTable;
use crate::tracers::visibility::LightSamples;

use super::source::Source;
use super::ExperimentFile;

/// `soft_shadow = { samples = 16 }`: the `soft_shadow` workload's light samples per point.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SoftShadowSpec {
    samples: u32,
    sets: Option<String>,
}

/// Light samples per point when the file does not say (Benthin & Wald 2009 §6 measure 4 to 64).
pub const DEFAULT_SOFT_SHADOW_SAMPLES: u32 = 16;

/// The samples per point and their sets, checked.
pub(super) fn soft_shadow(src: &Source, file: &ExperimentFile) -> Result<(u32, LightSampleSets)> {
    let Some(spec) = &file.soft_shadow else {
        return Ok((DEFAULT_SOFT_SHADOW_SAMPLES, LightSampleSets::default()));
    };
    let SoftShadowSpec { samples, sets } = spec.get_ref();
    let bad = |e: String| src.usage_error(&spec.span(), format!("soft_shadow: {e}"));
    if *samples as usize > LightSamples::MAX_PER_POINT {
        return Err(bad(format!(
            "samples = {samples} is more than {} per point",
            LightSamples::MAX_PER_POINT
        )));
    }
    let sets = match sets {
        None => LightSampleSets::default(),
        Some(name) => LightSampleSets::parse(name).map_err(|e| bad(e.to_string()))?,
    };
    SampleTable::new(*samples, 0).map_err(|e| bad(e.to_string()))?;
    sets.tile_sets(*samples, 0)
        .map_err(|e| bad(e.to_string()))?;
    Ok((*samples, sets))
}
