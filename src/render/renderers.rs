//! The list of renderers by name, as data: the `renderer` of an experiment's `render` table and
//! of `raylab render --renderer`, the keys each reads, and the parser that checks a set of them
//! and returns the renderer's typed settings. Adding a renderer is one entry here (and its
//! `RenderWorkload` variant, which the runner renders).

use std::fmt;

use crate::error::{Error, Result};
use crate::params::{concat_keys, Params};
use crate::render::distribution::{DrtSettings, Integrator};
use crate::render::whitted::WhittedSettings;

/// Checks one combination of a renderer's settings and returns them typed.
type Parse = fn(&Params) -> Result<RenderWorkload>;

pub struct RendererInfo {
    pub name: &'static str,
    /// The keys it reads besides `renderer`.
    pub keys: &'static [&'static str],
    pub about: &'static str,
    pub parse: Parse,
}

/// The keys a distribution or path workload reads besides its renderer's (`DrtSettings::KEYS`).
const WORKLOAD_KEYS: [&str; 2] = ["shutter", "rmse"];

/// The keys of a distribution or path workload: `DrtSettings::KEYS`, then `WORKLOAD_KEYS`.
const SAMPLED_KEYS: [&str; DrtSettings::KEYS.len() + WORKLOAD_KEYS.len()] =
    concat_keys(&DrtSettings::KEYS, &WORKLOAD_KEYS);

pub const RENDERERS: &[RendererInfo] = &[
    RendererInfo {
        name: "whitted",
        keys: &WhittedSettings::KEYS,
        about: "Whitted ray tracing with packet assembly (Boulos 2007 §3, Overbeck 2008 §5–6)",
        parse: |params| WhittedSettings::from_params(params).map(RenderWorkload::Whitted),
    },
    RendererInfo {
        name: "distribution",
        keys: &SAMPLED_KEYS,
        about: "distribution ray tracing (Boulos 2007 §4): depth of field, glossy, soft shadows, motion blur",
        parse: |params| {
            DistributionWorkload::from_params(Integrator::Distribution, params)
                .map(RenderWorkload::Distribution)
        },
    },
    RendererInfo {
        name: "path",
        keys: &SAMPLED_KEYS,
        about: "Monte Carlo path tracing (Gribble & Ramani 2008 §4): Lambertian, dielectric and coupled glossy materials, thin lens, next-event estimation, Russian roulette",
        parse: |params| {
            DistributionWorkload::from_params(Integrator::Path, params)
                .map(RenderWorkload::Distribution)
        },
    },
];

impl RendererInfo {
    /// The renderer `name` names.
    pub fn find(name: &str) -> Result<&'static RendererInfo> {
        RENDERERS
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| Error::usage(format!("render needs renderer = {}", spelled_out())))
    }
}

/// The renderers' names as a message lists them: `"a", "b" or "c"`.
fn spelled_out() -> String {
    let names: Vec<String> = RENDERERS.iter().map(|r| format!("{:?}", r.name)).collect();
    match names.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// One combination of a `render` grid: rendering a frame with one renderer and its settings.
#[derive(Clone, Debug, PartialEq)]
pub enum RenderWorkload {
    Whitted(WhittedSettings),
    Distribution(DistributionWorkload),
}

/// A distribution ray tracing workload (Boulos et al. 2007 §4) or, with `settings.integrator`
/// `Path`, a path tracing one (Gribble & Ramani 2008 §4). Its `settings` carry no image size: the
/// runner renders at the experiment's resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistributionWorkload {
    pub settings: DrtSettings,
    /// Shutter interval in seconds of the scene's animation from the frame's time (motion blur);
    /// the tracers then run over the moving geometry (`render::motion`).
    pub shutter: Option<f32>,
    /// Whether frame rows carry the RMSE against the cached high-spp reference image (`rmse =
    /// false` in the `render` table skips the reference, for workloads measured for speed only).
    pub rmse: bool,
}

impl DistributionWorkload {
    /// One combination of a distribution or path `render` grid: the renderer's settings and the
    /// workload's shutter interval (motion blur), or what is wrong with them.
    fn from_params(integrator: Integrator, params: &Params) -> Result<DistributionWorkload> {
        let mut settings = params.clone();
        let shutter = match settings.0.remove("shutter") {
            None => None,
            Some(value) => match value.parse::<f32>() {
                Ok(s) if s > 0.0 && s.is_finite() => Some(s),
                _ => {
                    return Err(Error::usage(format!(
                        "render shutter = {value:?} is not valid (a shutter interval > 0 s)"
                    )))
                }
            },
        };
        let rmse = match settings.0.remove("rmse").as_deref() {
            None | Some("true") => true,
            Some("false") => false,
            Some(value) => {
                return Err(Error::usage(format!(
                    "render rmse = {value:?} is not valid (true or false)"
                )))
            }
        };
        let settings = DrtSettings::from_params(integrator, &settings, &WORKLOAD_KEYS)?;
        if rmse && settings.tiles != 1 {
            return Err(Error::usage(
                "render tiles traces part of the image: its error is not the frame's (set rmse = false)",
            ));
        }
        Ok(DistributionWorkload {
            settings,
            shutter,
            rmse,
        })
    }

    /// The same workload at another sample count, or with other refinements (filter, retrace)
    /// of interleaved soft shadows: the points of one error-vs-time plot.
    pub fn same_but_spp(&self, other: &DistributionWorkload) -> bool {
        let with_spp = |w: &DistributionWorkload| DrtSettings {
            spp: 0,
            soft_shadows: w.settings.soft_shadows.map(|m| m.unrefined()),
            ..w.settings
        };
        with_spp(self) == with_spp(other)
            && self.shutter == other.shutter
            && self.rmse == other.rmse
    }
}

impl fmt::Display for RenderWorkload {
    /// Every setting, defaults included, except the per-kind depth limits, which appear only when
    /// set (unset they are `max_depth`): the `render` column of runs.csv.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let camera = |v: Option<f32>| v.map_or("camera".to_string(), |v| v.to_string());
        let limit =
            |key: &str, depth: Option<u32>| depth.map_or(String::new(), |d| format!(";{key}={d}"));
        match self {
            RenderWorkload::Whitted(s) => write!(
                f,
                "renderer=whitted;assembly={};materials={};max_depth={}{}{};packet={};pruning={};shadows={}",
                s.assembly,
                s.materials.map_or("scene", |p| p.name()),
                s.max_depth,
                limit("max_reflection_depth", s.max_reflection_depth),
                limit("max_refraction_depth", s.max_refraction_depth),
                s.packet,
                s.pruning.map_or("false".to_string(), |t| t.to_string()),
                s.shadows
            ),
            RenderWorkload::Distribution(w) => write!(
                f,
                "renderer={};aperture={};focus={};max_depth={}{}{};shutter={};spp={}{}{}",
                w.settings.integrator.name(),
                camera(w.settings.aperture),
                camera(w.settings.focus_distance),
                w.settings.max_depth,
                if w.settings.passes { ";order=passes" } else { "" },
                if w.rmse { "" } else { ";rmse=false" },
                w.shutter.map_or("none".to_string(), |s| s.to_string()),
                w.settings.spp,
                match w.settings.tiles {
                    1 => String::new(),
                    n => format!(";tiles={n}"),
                },
                w.settings.soft_shadows.map_or(String::new(), |m| format!(
                    ";shadows=interleaved;sets={};filter={};retrace={}",
                    m.sets.name(),
                    m.filter,
                    m.retrace
                ))
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_match_the_integrators() {
        for (i, r) in RENDERERS.iter().enumerate() {
            assert!(
                RENDERERS[..i].iter().all(|s| s.name != r.name),
                "{}",
                r.name
            );
            let workload = (r.parse)(&Params::new()).unwrap();
            if let RenderWorkload::Distribution(w) = workload {
                assert_eq!(w.settings.integrator.name(), r.name);
            }
            assert!(workload
                .to_string()
                .starts_with(&format!("renderer={};", r.name)));
        }
        assert_eq!(
            RendererInfo::find("bidirectional")
                .err()
                .unwrap()
                .to_string(),
            "render needs renderer = \"whitted\", \"distribution\" or \"path\""
        );
    }

    #[test]
    fn every_key_is_read() {
        for r in RENDERERS {
            let err = (r.parse)(&Params::new().with("no_such_key", 1)).unwrap_err();
            for key in r.keys {
                assert!(err.to_string().contains(key), "{}: {key} in {err}", r.name);
            }
        }
    }
}
