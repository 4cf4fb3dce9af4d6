//! Scene TOML files: which geometry (a mesh file, a built-in generator, or another scene to
//! extend) and what to change about it (camera, camera path, lights, materials).
//!
//! ```toml
//! name = "conference"                  # optional; defaults to the file name
//! about = "Grynberg & Ward's conference room"
//! mesh = "conference/conference.obj"   # or builtin = "room" (+ size = 3), or extends = "room"
//!
//! [camera]                             # every field optional: missing ones keep the base's;
//!                                      # without [[camera_path]] it replaces the base's path
//! position = [-600.0, 300.0, 300.0]
//! target = [300.0, 150.0, -200.0]
//! up = [0.0, 1.0, 0.0]
//! fov = 60.0                           # vertical, degrees
//! aperture = 0.0                       # lens radius; 0 = pinhole
//! focus_distance = 900.0
//!
//! [[camera_path]]                      # keyframes; fields missing in a key keep [camera]'s
//! time = 0.0
//! position = [-600.0, 300.0, 300.0]
//!
//! [[lights]]                           # replaces the base's lights
//! type = "point"                       # or "quad" with corner, edge_u, edge_v, emission
//! position = [300.0, 600.0, -200.0]
//! intensity = [4e5, 4e5, 4e5]
//!
//! [materials]
//! all = "mirror"                       # preset for all: diffuse | mirror | glossy | glass
//! floor = { mirror = 0.5, diffuse = [0.3, 0.3, 0.3] }   # the material named "floor"
//! ```
//!
//! Parsing is strict (`deny_unknown_fields`); every error names the file and line.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::de::{self, IntoDeserializer, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use toml::Spanned;

use crate::error::{Error, Result};
use crate::scene::{Camera, CameraKey, CameraPath, Light, Material, Scene};

/// The key of `[materials]` that addresses every material.
pub const ALL_MATERIALS: &str = "all";

/// Reflectance of the `mirror` preset.
pub const MIRROR_REFLECTANCE: f32 = 0.8;
/// Phong exponent and reflectance of the `glossy` preset: "all surfaces are reflective with a
/// fairly glossy exponent" (Boulos et al. 2007, §5, the conference scene).
pub const GLOSSY: (f32, f32) = (50.0, 0.8);
/// Index of refraction and transmittance of the `glass` preset.
pub const GLASS: (f32, f32) = (1.5, 0.9);

/// The TOML schema, field for field.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub name: Option<String>,
    pub about: Option<String>,
    pub mesh: Option<Spanned<String>>,
    pub builtin: Option<Spanned<String>>,
    pub extends: Option<Spanned<String>>,
    pub size: Option<Spanned<u32>>,
    pub camera: Option<Spanned<CameraSpec>>,
    pub camera_path: Option<Vec<Spanned<CameraSpec>>>,
    pub lights: Option<Vec<Spanned<LightSpec>>>,
    pub materials: Option<BTreeMap<Spanned<String>, MaterialEntry>>,
}

/// A camera, or a camera-path key (which also has `time`). Missing fields keep the values of
/// the camera underneath.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub time: Option<f32>,
    pub position: Option<[f32; 3]>,
    pub target: Option<[f32; 3]>,
    pub up: Option<[f32; 3]>,
    pub fov: Option<f32>,
    pub aperture: Option<f32>,
    pub focus_distance: Option<f32>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightSpec {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Quad {
        corner: [f32; 3],
        edge_u: [f32; 3],
        edge_v: [f32; 3],
        emission: [f32; 3],
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Plain Lambertian: no mirror, glossy or dielectric part.
    Diffuse,
    /// A mirror coat of `MIRROR_REFLECTANCE` over the material's diffuse base.
    Mirror,
    /// A glossy coat `GLOSSY` over the diffuse base.
    Glossy,
    /// Clear glass `GLASS`: no diffuse base.
    Glass,
}

impl Preset {
    pub const ALL: [Preset; 4] = [
        Preset::Diffuse,
        Preset::Mirror,
        Preset::Glossy,
        Preset::Glass,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Diffuse => "diffuse",
            Preset::Mirror => "mirror",
            Preset::Glossy => "glossy",
            Preset::Glass => "glass",
        }
    }

    pub fn parse(name: &str) -> Option<Preset> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The names, quoted, for messages: `"diffuse", "mirror", …`.
    pub fn known() -> String {
        Self::ALL.map(|p| format!("{:?}", p.name())).join(", ")
    }

    /// What `[materials] all = "<preset>"` does: the preset on every material (Overbeck et al.
    /// 2008 §5.1: "all scene materials reflective or refractive").
    pub fn apply_to_all(self, materials: &mut [Material]) {
        let change = MaterialOverride {
            preset: Some(self),
            ..MaterialOverride::default()
        };
        materials.iter_mut().for_each(|m| change.apply(m));
    }
}

/// Changes to one material: a preset first, then the fields given.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverride {
    pub preset: Option<Preset>,
    pub diffuse: Option<[f32; 3]>,
    pub mirror: Option<f32>,
    pub glossy: Option<GlossySpec>,
    pub dielectric: Option<DielectricSpec>,
    pub emission: Option<[f32; 3]>,
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlossySpec {
    pub exponent: f32,
    pub reflectance: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DielectricSpec {
    pub ior: f32,
    pub transmittance: f32,
}

/// One entry of `[materials]`: a preset name (`"mirror"`) or a table of overrides.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialEntry(pub MaterialOverride);

/// A preset by its `name()`, so the names live in one place.
impl<'de> Deserialize<'de> for Preset {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Preset::parse(&name).ok_or_else(|| {
            de::Error::custom(format!(
                "unknown preset {name:?} (known: {})",
                Preset::known()
            ))
        })
    }
}

impl<'de> Deserialize<'de> for MaterialEntry {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct EntryVisitor;
        impl<'de> Visitor<'de> for EntryVisitor {
            type Value = MaterialEntry;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(
                    f,
                    "a preset ({}) or a table of material fields",
                    Preset::known()
                )
            }
            fn visit_str<E: de::Error>(self, name: &str) -> std::result::Result<MaterialEntry, E> {
                let preset = Preset::deserialize(name.into_deserializer())?;
                Ok(MaterialEntry(MaterialOverride {
                    preset: Some(preset),
                    ..MaterialOverride::default()
                }))
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<MaterialEntry, A::Error> {
                MaterialOverride::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(MaterialEntry)
            }
        }
        deserializer.deserialize_any(EntryVisitor)
    }
}

/// Where a scene file's geometry comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Base {
    /// A mesh file path as written (resolved by `library`).
    Mesh(String),
    /// A built-in generator and the file's size for it.
    Builtin(String, Option<u32>),
    /// Another scene (by name or path), with the file's size passed on to it.
    Extends(String, Option<u32>),
}

/// A parsed scene file: its path and text (to turn byte spans into line numbers) and its spec.
#[derive(Debug)]
pub struct SceneFile {
    pub path: PathBuf,
    text: String,
    pub spec: SceneSpec,
}

impl SceneFile {
    pub fn read(path: &Path) -> Result<SceneFile> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        SceneFile::parse(path, text)
    }

    pub fn parse(path: &Path, text: String) -> Result<SceneFile> {
        match toml::from_str::<SceneSpec>(&text) {
            Ok(spec) => Ok(SceneFile {
                path: path.to_path_buf(),
                text,
                spec,
            }),
            Err(e) => {
                let line = e.span().map(|s| line_of(&text, s.start));
                Err(Error::input(path, line, e.message()))
            }
        }
    }

    /// The scene's name: `name = ...`, or the file name without `.toml`.
    pub fn name(&self) -> String {
        self.spec.name.clone().unwrap_or_else(|| {
            self.path
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
        })
    }

    /// An error at the line where `span` starts.
    pub fn error_at(&self, span: Range<usize>, message: impl Into<String>) -> Error {
        Error::at_line(&self.path, line_of(&self.text, span.start), message)
    }

    /// Exactly one of `mesh`, `builtin`, `extends`; `size` only with the latter two.
    pub fn base(&self) -> Result<Base> {
        let spec = &self.spec;
        let given: Vec<&Spanned<String>> = [&spec.mesh, &spec.builtin, &spec.extends]
            .into_iter()
            .flatten()
            .collect();
        match given.as_slice() {
            [] => {
                return Err(Error::input(
                    &self.path,
                    None,
                    "a scene file needs one of `mesh = \"<file>\"`, `builtin = \"<generator>\"` or `extends = \"<scene>\"`",
                ))
            }
            [_] => {}
            [_, second, ..] => {
                return Err(self.error_at(second.span(), "give only one of `mesh`, `builtin` and `extends`"));
            }
        }
        let size = spec.size.as_ref().map(|s| *s.get_ref());
        if let Some(mesh) = &spec.mesh {
            if let Some(size) = &spec.size {
                return Err(self.error_at(
                    size.span(),
                    "`size` applies to `builtin` (or `extends`) scenes, not to a mesh file",
                ));
            }
            return Ok(Base::Mesh(mesh.get_ref().clone()));
        }
        if let Some(builtin) = &spec.builtin {
            return Ok(Base::Builtin(builtin.get_ref().clone(), size));
        }
        let extends = spec
            .extends
            .as_ref()
            .map(|e| e.get_ref().clone())
            .unwrap_or_default();
        Ok(Base::Extends(extends, size))
    }

    /// Applies the file's name, camera, camera path, lights and material overrides to `scene`
    /// (built from the file's base).
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        let spec = &self.spec;
        scene.name = self.name();
        if let Some(camera) = &spec.camera {
            if camera.get_ref().time.is_some() {
                return Err(self.error_at(
                    camera.span(),
                    "`time` belongs in [[camera_path]] keys, not in [camera]",
                ));
            }
            scene.camera = self.camera(camera, scene.camera)?;
            // A [camera] without keys of its own is the view of every frame: the base's path
            // (the built-ins fly through theirs) would otherwise override it at every frame.
            if spec.camera_path.is_none() {
                scene.camera_path = None;
            }
        }
        if let Some(keys) = &spec.camera_path {
            scene.camera_path = self.camera_path(keys, scene.camera)?;
        }
        if let Some(lights) = &spec.lights {
            scene.lights = lights
                .iter()
                .map(|l| self.light(l))
                .collect::<Result<_>>()?;
        }
        if let Some(materials) = &spec.materials {
            self.override_materials(materials, &mut scene.materials)?;
        }
        Ok(())
    }

    fn camera(&self, spec: &Spanned<CameraSpec>, base: Camera) -> Result<Camera> {
        let s = spec.get_ref();
        let camera = Camera {
            position: s.position.map_or(base.position, Vec3::from),
            target: s.target.map_or(base.target, Vec3::from),
            up: s.up.map_or(base.up, Vec3::from),
            fov_y_deg: s.fov.unwrap_or(base.fov_y_deg),
            aperture: s.aperture.unwrap_or(base.aperture),
            focus_distance: s.focus_distance.unwrap_or(base.focus_distance),
        };
        let finite = [camera.position, camera.target, camera.up]
            .iter()
            .all(|v| v.is_finite());
        let problem = if !finite {
            Some("camera vectors must be finite")
        } else if camera.position == camera.target {
            Some("camera position and target coincide")
        } else if camera.up.length_squared() == 0.0 {
            Some("camera `up` is the zero vector")
        } else if !(camera.fov_y_deg > 0.0 && camera.fov_y_deg < 180.0) {
            Some("`fov` must lie strictly between 0 and 180 degrees")
        } else if !(camera.aperture >= 0.0 && camera.focus_distance > 0.0) {
            Some("`aperture` must be ≥ 0 and `focus_distance` > 0")
        } else {
            None
        };
        match problem {
            Some(message) => Err(self.error_at(spec.span(), message)),
            None => Ok(camera),
        }
    }

    /// Keys inherit from `base`; times must start at ≥ 0 and never decrease. No keys: no path.
    fn camera_path(
        &self,
        keys: &[Spanned<CameraSpec>],
        base: Camera,
    ) -> Result<Option<CameraPath>> {
        let mut path = CameraPath { keys: Vec::new() };
        for key in keys {
            let Some(time) = key.get_ref().time else {
                return Err(
                    self.error_at(key.span(), "a [[camera_path]] key needs `time` (seconds)")
                );
            };
            let previous = path.keys.last().map_or(0.0, |k| k.time);
            if time.is_nan() || time < previous {
                return Err(self.error_at(
                    key.span(),
                    format!("key time {time} must be ≥ 0 and ≥ the previous key's {previous}"),
                ));
            }
            path.keys.push(CameraKey {
                time,
                camera: self.camera(key, base)?,
            });
        }
        Ok((!path.keys.is_empty()).then_some(path))
    }

    fn light(&self, spec: &Spanned<LightSpec>) -> Result<Light> {
        let non_negative = |c: [f32; 3]| c.iter().all(|x| x.is_finite() && *x >= 0.0);
        let finite = |v: [f32; 3]| v.iter().all(|x| x.is_finite());
        let (light, ok) = match *spec.get_ref() {
            LightSpec::Point {
                position,
                intensity,
            } => (
                Light::Point {
                    position: position.into(),
                    intensity: intensity.into(),
                },
                finite(position) && non_negative(intensity),
            ),
            LightSpec::Quad {
                corner,
                edge_u,
                edge_v,
                emission,
            } => (
                Light::Quad {
                    corner: corner.into(),
                    edge_u: edge_u.into(),
                    edge_v: edge_v.into(),
                    emission: emission.into(),
                },
                finite(corner) && finite(edge_u) && finite(edge_v) && non_negative(emission),
            ),
        };
        if ok {
            Ok(light)
        } else {
            Err(self.error_at(
                spec.span(),
                "light positions must be finite and its intensity/emission ≥ 0",
            ))
        }
    }

    /// `all` first, then each named material; naming a material the scene lacks is an error.
    fn override_materials(
        &self,
        entries: &BTreeMap<Spanned<String>, MaterialEntry>,
        materials: &mut [Material],
    ) -> Result<()> {
        let all = entries
            .iter()
            .filter(|(name, _)| name.get_ref() == ALL_MATERIALS);
        let named = entries
            .iter()
            .filter(|(name, _)| name.get_ref() != ALL_MATERIALS);
        for (name, MaterialEntry(change)) in all.chain(named) {
            validate(change).map_err(|message| self.error_at(name.span(), message))?;
            let mut matched = false;
            for material in materials.iter_mut() {
                if name.get_ref() == ALL_MATERIALS || &material.name == name.get_ref() {
                    change.apply(material);
                    matched = true;
                }
            }
            if !matched {
                let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                return Err(self.error_at(
                    name.span(),
                    format!(
                        "the scene has no material named '{}' (it has: {})",
                        name.get_ref(),
                        known.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }
}

impl MaterialOverride {
    pub fn apply(&self, m: &mut Material) {
        match self.preset {
            None => {}
            Some(Preset::Diffuse) => {
                m.mirror = 0.0;
                m.glossy = None;
                m.dielectric = None;
            }
            Some(Preset::Mirror) => {
                m.mirror = MIRROR_REFLECTANCE;
                m.glossy = None;
                m.dielectric = None;
            }
            Some(Preset::Glossy) => {
                m.mirror = 0.0;
                m.glossy = Some(GLOSSY);
                m.dielectric = None;
            }
            Some(Preset::Glass) => {
                m.diffuse = Vec3::ZERO;
                m.mirror = 0.0;
                m.glossy = None;
                m.dielectric = Some(GLASS);
            }
        }
        if let Some(d) = self.diffuse {
            m.diffuse = d.into();
        }
        if let Some(r) = self.mirror {
            m.mirror = r;
        }
        if let Some(g) = self.glossy {
            m.glossy = Some((g.exponent, g.reflectance));
        }
        if let Some(d) = self.dielectric {
            m.dielectric = Some((d.ior, d.transmittance));
        }
        if let Some(e) = self.emission {
            m.emission = e.into();
        }
    }
}

fn validate(change: &MaterialOverride) -> std::result::Result<(), &'static str> {
    let unit = |x: f32| (0.0..=1.0).contains(&x);
    let colour =
        |c: Option<[f32; 3]>| c.is_none_or(|c| c.iter().all(|x| x.is_finite() && *x >= 0.0));
    if !colour(change.diffuse) || !colour(change.emission) {
        return Err("colours must be finite and ≥ 0");
    }
    if !change.mirror.is_none_or(unit) {
        return Err("`mirror` must lie in [0, 1]");
    }
    if !change
        .glossy
        .is_none_or(|g| g.exponent > 0.0 && unit(g.reflectance))
    {
        return Err("`glossy` needs exponent > 0 and reflectance in [0, 1]");
    }
    if !change
        .dielectric
        .is_none_or(|d| d.ior > 0.0 && unit(d.transmittance))
    {
        return Err("`dielectric` needs ior > 0 and transmittance in [0, 1]");
    }
    Ok(())
}

/// 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn parse(text: &str) -> Result<SceneFile> {
        SceneFile::parse(Path::new("scenes/test.toml"), text.to_string())
    }

    const HAND_WRITTEN: &str = r#"
name = "office"
builtin = "room"
size = 2

[camera]
position = [1.0, 2.0, 3.0]
target = [4.0, 2.0, 3.0]
fov = 50.0

[[camera_path]]
time = 0.0

[[camera_path]]
time = 2.5
position = [1.0, 2.0, 8.0]

[[lights]]
type = "point"
position = [5.0, 5.5, 5.0]
intensity = [10.0, 20.0, 30.0]

[[lights]]
type = "quad"
corner = [4.0, 5.9, 4.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
emission = [5.0, 5.0, 5.0]

[materials]
all = "diffuse"
red = { preset = "glass", ior = 1.33 }
"#;

    #[test]
    fn a_hand_written_file_sets_camera_path_lights_and_materials() {
        // Unknown key inside a material table: rejected with its line (line 32 is `red = ...`).
        let err = parse(HAND_WRITTEN).unwrap_err().to_string();
        assert!(
            err.starts_with("scenes/test.toml:32:") && err.contains("ior"),
            "{err}"
        );

        let text = HAND_WRITTEN.replace(
            "ior = 1.33",
            "dielectric = { ior = 1.33, transmittance = 1.0 }",
        );
        let file = parse(&text).unwrap();
        assert_eq!(file.base().unwrap(), Base::Builtin("room".into(), Some(2)));
        let mut scene = builtin::generate("room", Some(2)).unwrap();
        file.apply(&mut scene).unwrap();

        assert_eq!(scene.name, "office");
        let camera = Camera {
            position: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(4.0, 2.0, 3.0),
            fov_y_deg: 50.0,
            // Not given: kept from the room's camera.
            up: Vec3::Y,
            aperture: 0.0,
            focus_distance: 1.0,
        };
        assert_eq!(scene.camera, camera);
        let path = scene.camera_path.unwrap();
        assert_eq!(path.keys.len(), 2);
        assert_eq!(path.keys[0], CameraKey { time: 0.0, camera });
        assert_eq!(path.keys[1].time, 2.5);
        assert_eq!(path.keys[1].camera.position, Vec3::new(1.0, 2.0, 8.0));
        assert_eq!(path.keys[1].camera.target, camera.target);
        assert_eq!(
            scene.lights,
            [
                Light::Point {
                    position: Vec3::new(5.0, 5.5, 5.0),
                    intensity: Vec3::new(10.0, 20.0, 30.0),
                },
                Light::Quad {
                    corner: Vec3::new(4.0, 5.9, 4.0),
                    edge_u: Vec3::new(2.0, 0.0, 0.0),
                    edge_v: Vec3::new(0.0, 0.0, 2.0),
                    emission: Vec3::splat(5.0),
                },
            ]
        );
        // `all = "diffuse"` took the mirror off the floor; then red became clear glass.
        assert!(scene.materials.iter().all(|m| !m.is_reflective()));
        let red = scene.materials.iter().find(|m| m.name == "red").unwrap();
        assert_eq!(
            (red.diffuse, red.dielectric),
            (Vec3::ZERO, Some((1.33, 1.0)))
        );
        assert_eq!(
            scene.materials.iter().filter(|m| m.is_refractive()).count(),
            1
        );
    }

    #[test]
    fn all_reflective_puts_a_mirror_on_every_material() {
        let file = parse("builtin = \"rings\"\nsize = 1\n[materials]\nall = \"mirror\"\n").unwrap();
        let mut scene = builtin::generate("rings", Some(1)).unwrap();
        let diffuse_before: Vec<Vec3> = scene.materials.iter().map(|m| m.diffuse).collect();
        file.apply(&mut scene).unwrap();
        assert_eq!(scene.materials.len(), 7);
        for (m, d) in scene.materials.iter().zip(diffuse_before) {
            assert_eq!(
                (m.mirror, m.glossy, m.dielectric, m.diffuse),
                (MIRROR_REFLECTANCE, None, None, d)
            );
        }
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let cases = [
            // An unclosed array is noticed at the end of the file.
            ("builtin = \"room\"\nsize = [\n", 3, "expected `]`"),
            ("builtin = \"room\"\n\ncolour = 3\n", 3, "colour"),
            (
                "builtin = \"room\"\n[camera]\nfov = 10.0\nzoom = 2\n",
                4,
                "zoom",
            ),
            (
                "builtin = \"room\"\n[[lights]]\ntype = \"spot\"\n",
                3,
                "spot",
            ),
            (
                "builtin = \"room\"\n[materials]\nall = \"chrome\"\n",
                3,
                "chrome",
            ),
            ("mesh = \"a.obj\"\nbuiltin = \"room\"\n", 2, "only one"),
            ("mesh = \"a.obj\"\nsize = 3\n", 2, "size"),
        ];
        for (text, line, word) in cases {
            let err = parse(text).and_then(|f| f.base()).unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("scenes/test.toml:{line}:")),
                "{text:?} → {err}"
            );
            assert!(err.contains(word), "{text:?} → {err}");
        }
        let err = parse("name = \"x\"\n")
            .unwrap()
            .base()
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("scenes/test.toml: ") && err.contains("extends"),
            "{err}"
        );

        // Semantic errors found while applying also carry the line.
        let mut scene = builtin::generate("room", Some(1)).unwrap();
        let apply = |text: &str, scene: &mut Scene| {
            parse(text).unwrap().apply(scene).unwrap_err().to_string()
        };
        let err = apply(
            "builtin = \"room\"\n[materials]\ncarpet = \"mirror\"\n",
            &mut scene,
        );
        assert!(
            err.starts_with("scenes/test.toml:3:")
                && err.contains("carpet")
                && err.contains("floor"),
            "{err}"
        );
        let err = apply(
            "builtin = \"room\"\n[materials]\nfloor = { mirror = 2.0 }\n",
            &mut scene,
        );
        assert!(
            err.starts_with("scenes/test.toml:3:") && err.contains("[0, 1]"),
            "{err}"
        );
        let err = apply("builtin = \"room\"\n\n[camera]\nfov = 190.0\n", &mut scene);
        assert!(
            err.starts_with("scenes/test.toml:3:") && err.contains("fov"),
            "{err}"
        );
        let err = apply(
            "builtin = \"room\"\n[[camera_path]]\ntime = 1.0\n[[camera_path]]\ntime = 0.5\n",
            &mut scene,
        );
        assert!(
            err.starts_with("scenes/test.toml:4:") && err.contains("0.5"),
            "{err}"
        );
    }

    #[test]
    fn a_camera_without_keys_replaces_the_base_camera_path() {
        // The room flies along its camera path; a [camera] over it was once silently ignored.
        let mut scene = builtin::generate("room", None).unwrap();
        assert!(scene.camera_path.is_some());
        let file = parse("extends = \"room\"\n[camera]\nposition = [0.5, 5.0, 0.5]\n").unwrap();
        file.apply(&mut scene).unwrap();
        assert!(scene.camera_path.is_none());
        for (index, count) in [(0, 1), (1, 3)] {
            let frame = scene.frame(index, count);
            assert_eq!(frame.camera.position, Vec3::new(0.5, 5.0, 0.5));
        }
    }

    #[test]
    fn line_numbers_count_from_one() {
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 4), 3);
        assert_eq!(line_of("a\nb\nc", 99), 3);
    }
}
