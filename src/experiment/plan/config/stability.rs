//! `[stability]`: the numerical stability suite's sweep, run instead of scenes × ray kinds.

use std::time::Duration;

use serde::Deserialize;

use crate::error::Result;
use crate::verify::stability::{CaseKind, Sweep};

use super::source::Source;
use super::ExperimentFile;

/// `[stability]`: what the numerical stability suite sweeps; every key has a default.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StabilitySpec {
    cases: Option<Vec<String>>,
    offsets: Option<Vec<f64>>,
    scales: Option<Vec<f64>>,
    ratios: Option<Vec<f64>>,
    bounces: Option<u32>,
    timeout_seconds: Option<f64>,
}

/// The stability suite's sweep and the time limit of one tracer on one case.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilitySettings {
    pub sweep: Sweep,
    pub timeout: Duration,
}

impl StabilitySpec {
    fn settings(&self, seed: u64) -> std::result::Result<StabilitySettings, String> {
        let d = Sweep::default();
        let kinds = match &self.cases {
            None => d.kinds,
            Some(names) => names
                .iter()
                .map(|n| {
                    CaseKind::parse(n).ok_or_else(|| {
                        let known: Vec<&str> = CaseKind::ALL.iter().map(|k| k.name()).collect();
                        format!("unknown case {n:?} (known: {})", known.join(", "))
                    })
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        let finite = |what: &str, v: &Option<Vec<f64>>, default: Vec<f64>, min: f64| {
            let v = v.clone().unwrap_or(default);
            match v
                .iter()
                .find(|x| !(x.is_finite() && **x >= min && **x <= 1e30))
            {
                Some(x) => Err(format!("{what}: {x} is not a number in [{min}, 1e30]")),
                None if v.is_empty() => Err(format!("{what}: empty list")),
                None => Ok(v),
            }
        };
        let bounces = self.bounces.unwrap_or(d.bounces);
        if !(1..=64).contains(&bounces) {
            return Err(format!("bounces = {bounces}: 1 to 64"));
        }
        let timeout = self.timeout_seconds.unwrap_or(60.0);
        if !(timeout > 0.0 && timeout <= 86_400.0) {
            return Err(format!(
                "timeout_seconds = {timeout}: more than 0, at most a day"
            ));
        }
        Ok(StabilitySettings {
            sweep: Sweep {
                kinds,
                offsets: finite("offsets", &self.offsets, d.offsets, 0.0)?,
                scales: finite("scales", &self.scales, d.scales, 1e-30)?,
                ratios: finite("ratios", &self.ratios, d.ratios, 1.0)?,
                bounces,
                seed,
            },
            timeout: Duration::from_secs_f64(timeout),
        })
    }
}

/// The suite's settings, if the file has a `[stability]` table; it generates its own meshes and
/// rays, so scenes, rays, render and resolution are refused beside it.
pub(super) fn stability(src: &Source, file: &ExperimentFile) -> Result<Option<StabilitySettings>> {
    let Some(spec) = &file.stability else {
        return Ok(None);
    };
    let given = [
        ("scenes", !file.scenes.get_ref().is_empty()),
        ("rays", file.rays.is_some()),
        ("render", file.render.is_some()),
        ("resolution", file.resolution.is_some()),
    ];
    if let Some((key, _)) = given.iter().find(|(_, given)| *given) {
        return Err(src.usage_error(
            &spec.span(),
            format!("a [stability] experiment generates its own cases: remove `{key}`"),
        ));
    }
    spec.get_ref()
        .settings(file.seed)
        .map(Some)
        .map_err(|e| src.usage_error(&spec.span(), format!("stability: {e}")))
}
