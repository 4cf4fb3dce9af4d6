//! How an Embree scene is built: the `quality` and `robust` parameters of `AccelKind::Embree`.

use std::fmt;
use std::str::FromStr;

use super::ffi::{RTCBuildQuality, RTCSceneFlags};
use crate::error::Result;
use crate::params::Params;

/// Embree's build qualities. `Refit` keeps the tree's topology and only refits its boxes when
/// the vertices move (`EmbreeScene::refit`), for per-frame animation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BuildQuality {
    Low,
    /// Embree's own default for scenes and geometries ("rtcSetSceneBuildQuality").
    #[default]
    Medium,
    High,
    Refit,
}

impl BuildQuality {
    pub fn name(self) -> &'static str {
        match self {
            BuildQuality::Low => "low",
            BuildQuality::Medium => "medium",
            BuildQuality::High => "high",
            BuildQuality::Refit => "refit",
        }
    }

    /// The scene's build quality. Embree honours a geometry's own quality (and so refitting)
    /// only in the two-level structure it builds at scene quality LOW ("rtcSetGeometryBuildQuality").
    pub(super) fn scene(self) -> RTCBuildQuality::Type {
        use RTCBuildQuality::*;
        match self {
            BuildQuality::Low | BuildQuality::Refit => RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => RTC_BUILD_QUALITY_HIGH,
        }
    }

    pub(super) fn geometry(self) -> RTCBuildQuality::Type {
        use RTCBuildQuality::*;
        match self {
            BuildQuality::Low => RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => RTC_BUILD_QUALITY_HIGH,
            BuildQuality::Refit => RTC_BUILD_QUALITY_REFIT,
        }
    }
}

impl FromStr for BuildQuality {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        [
            BuildQuality::Low,
            BuildQuality::Medium,
            BuildQuality::High,
            BuildQuality::Refit,
        ]
        .into_iter()
        .find(|q| q.name() == s)
        .ok_or(())
    }
}

impl fmt::Display for BuildQuality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct EmbreeConfig {
    pub quality: BuildQuality,
    /// RTC_SCENE_FLAG_ROBUST: watertight-style traversal and intersection, slower. Off by default
    /// as in Embree; verification turns it on.
    pub robust: bool,
}

impl EmbreeConfig {
    pub const PARAMS: &'static [&'static str] = &["quality", "robust"];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = EmbreeConfig::default();
        Ok(EmbreeConfig {
            quality: p.get_or("quality", d.quality)?,
            robust: p.get_or("robust", d.robust)?,
        })
    }

    pub(super) fn scene_flags(&self) -> RTCSceneFlags {
        let mut flags = RTCSceneFlags::RTC_SCENE_FLAG_NONE;
        if self.robust {
            flags |= RTCSceneFlags::RTC_SCENE_FLAG_ROBUST;
        }
        // As in Embree's dynamic-scene tutorial: geometry that changes every frame.
        if self.quality == BuildQuality::Refit {
            flags |= RTCSceneFlags::RTC_SCENE_FLAG_DYNAMIC;
        }
        flags
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_parse_and_reject_bad_values() {
        let c = EmbreeConfig::from_params(&Params::new()).unwrap();
        assert_eq!(
            c,
            EmbreeConfig {
                quality: BuildQuality::Medium,
                robust: false
            }
        );
        let c = EmbreeConfig::from_params(
            &Params::new()
                .with("quality", "refit")
                .with("robust", "true"),
        )
        .unwrap();
        assert_eq!(
            c,
            EmbreeConfig {
                quality: BuildQuality::Refit,
                robust: true
            }
        );
        assert_eq!(c.scene_flags().0, 4 | 1);
        assert_eq!(c.quality.scene(), RTCBuildQuality::RTC_BUILD_QUALITY_LOW);
        assert_eq!(
            c.quality.geometry(),
            RTCBuildQuality::RTC_BUILD_QUALITY_REFIT
        );
        assert!(EmbreeConfig::from_params(&Params::new().with("quality", "best")).is_err());
        assert!(EmbreeConfig::from_params(&Params::new().with("robust", "yes")).is_err());
    }
}
