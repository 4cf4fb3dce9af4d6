//! Built-in scene generators: embedded, no files needed. Each takes an integer `size` that sweeps
//! the triangle count from about a thousand to a million or more, sets materials, point lights and
//! a camera, and either a camera path (static scenes) or an `Animation` (marbles, deforming, toys).
//!
//! | generator | size          | triangles               | ~1K      | default    | ≥ 1M           |
//! |-----------|---------------|-------------------------|----------|------------|----------------|
//! | room      | n subdivision | 96·n²                   | 3: 864   | 3: 864     | 103: 1,018,464 |
//! | rings     | s levels      | 1920·s(s+1)(2s+1)/6 + 2 | 1: 1,922 | 4: 57,602  | 12: 1,248,002  |
//! | balls     | L depth       | 18·(9^(L+1) − 1) + 2    | 1: 1,442 | 3: 118,082 | 4: 1,062,866   |
//! | marbles   | N marbles     | 80·N + 10               | 12: 970  | 110: 8,810 | 12500: 1000010 |
//! | deforming | n × n flag    | 2·n² + 26               | 22: 994  | 96: 18,458 | 708: 1,002,554 |
//! | toys      | N toys        | 2080·N + 2              | 1: 2,082 | 5: 10,402  | 481: 1,000,482 |
//!
//! Each generator's `triangle_count` gives the exact count without generating.

pub mod balls;
pub mod deforming;
pub mod marble_physics;
pub mod marbles;
pub mod rings;
pub mod room;
pub mod toys;

use crate::error::{Error, Result};
use std::sync::Arc;

use glam::Vec3;

use crate::scene::{Animation, Camera, CameraKey, CameraPath, Light, Material, Mesh, Scene};

/// What the integer `size` of a generator means and which values it accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeKnob {
    pub default: u32,
    pub min: u32,
    pub max: u32,
    /// What the number counts, for help texts ("subdivisions per face edge", ...).
    pub meaning: &'static str,
}

/// One generator: its name, a one-line description, its size knob, the exact triangle count for a
/// size (without generating), and the generator itself.
#[derive(Clone, Copy, Debug)]
pub struct Generator {
    pub name: &'static str,
    pub about: &'static str,
    pub size: SizeKnob,
    pub triangle_count: fn(u32) -> usize,
    pub build: fn(u32) -> Scene,
}

pub const GENERATORS: &[Generator] = &[
    room::GENERATOR,
    rings::GENERATOR,
    balls::GENERATOR,
    marbles::GENERATOR,
    deforming::GENERATOR,
    toys::GENERATOR,
];

/// `(name, about)` of every generator, in the order of `GENERATORS`.
pub const BUILTINS: &[(&str, &str)] = &names_and_about::<{ GENERATORS.len() }>();

const fn names_and_about<const N: usize>() -> [(&'static str, &'static str); N] {
    let mut out = [("", ""); N];
    let mut i = 0;
    while i < N {
        out[i] = (GENERATORS[i].name, GENERATORS[i].about);
        i += 1;
    }
    out
}

pub fn find(name: &str) -> Option<&'static Generator> {
    GENERATORS.iter().find(|g| g.name == name)
}

/// The names of all generators, comma-separated, for error messages.
pub fn known_names() -> String {
    GENERATORS
        .iter()
        .map(|g| g.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Generates the built-in scene `name` at `size` (its default when `None`).
/// Memory a triangle costs once loaded and built over: the mesh (40 bytes), a BVH (nodes and
/// indices), a grid's references and Embree's copy, rounded up.
const BYTES_PER_TRIANGLE: u64 = 512;

pub fn generate(name: &str, size: Option<u32>) -> Result<Scene> {
    let generator = find(name).ok_or_else(|| {
        Error::usage(format!(
            "unknown built-in scene '{name}' (built-ins: {})",
            known_names()
        ))
    })?;
    let size = generator.checked_size(size)?;
    // The mesh and a structure over it; a few hundred bytes a triangle.
    let triangles = (generator.triangle_count)(size) as u64;
    crate::memory::check(
        &format!("built-in scene '{name}' at size {size} ({triangles} triangles)"),
        triangles.saturating_mul(BYTES_PER_TRIANGLE),
    )?;
    Ok((generator.build)(size))
}

impl Generator {
    /// `size`, or the default when `None`; an error naming the valid range when out of it.
    pub fn checked_size(&self, size: Option<u32>) -> Result<u32> {
        let knob = &self.size;
        let size = size.unwrap_or(knob.default);
        if (knob.min..=knob.max).contains(&size) {
            Ok(size)
        } else {
            Err(Error::usage(format!(
                "built-in scene '{}': size {size} is out of range {}..={} (size = {})",
                self.name, knob.min, knob.max, knob.meaning
            )))
        }
    }
}

/// A static scene of generator `g`, flown through along `keys` (seconds, camera).
fn static_scene(
    g: &Generator,
    mesh: Mesh,
    materials: Vec<Material>,
    lights: Vec<Light>,
    camera: Camera,
    keys: &[(f32, Camera)],
) -> Scene {
    let keys = keys
        .iter()
        .map(|&(time, camera)| CameraKey { time, camera })
        .collect();
    Scene {
        camera_path: Some(CameraPath { keys }),
        ..still_scene(g, mesh, materials, lights, camera)
    }
}

/// An animated scene of generator `g` seen from a fixed camera; its mesh is the animation's
/// first frame.
fn animated_scene(
    g: &Generator,
    animation: impl Animation + 'static,
    materials: Vec<Material>,
    lights: Vec<Light>,
    camera: Camera,
) -> Scene {
    let mesh = animation.mesh_at(0.0);
    Scene {
        animation: Some(Arc::new(animation)),
        ..still_scene(g, mesh, materials, lights, camera)
    }
}

/// A scene of generator `g` without motion: named after it, from `builtin:<name>`.
fn still_scene(
    g: &Generator,
    mesh: Mesh,
    materials: Vec<Material>,
    lights: Vec<Light>,
    camera: Camera,
) -> Scene {
    Scene {
        name: g.name.into(),
        source: format!("builtin:{}", g.name),
        mesh,
        materials,
        lights,
        camera,
        camera_path: None,
        animation: None,
    }
}

/// Point lights at `positions` whose equal shares add up to unit irradiance at `lit` (our
/// lights fall off as 1/d²).
fn point_lights(positions: &[Vec3], lit: Vec3) -> Vec<Light> {
    let share = positions.len() as f32;
    positions
        .iter()
        .map(|&position| Light::Point {
            position,
            intensity: Vec3::splat(position.distance_squared(lit) / share),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_lists_every_generator_and_rejects_unknown_names_and_sizes() {
        let names: Vec<&str> = BUILTINS.iter().map(|b| b.0).collect();
        assert_eq!(
            names,
            ["room", "rings", "balls", "marbles", "deforming", "toys"]
        );
        let err = generate("nope", None).unwrap_err().to_string();
        assert!(
            err.contains("nope") && err.contains("room, rings, balls, marbles, deforming, toys"),
            "{err}"
        );
        let err = generate("balls", Some(99)).unwrap_err().to_string();
        assert!(err.contains("out of range 1..=5"), "{err}");
        assert!(generate("room", Some(0)).is_err());
    }

    #[test]
    fn every_generator_matches_its_count_and_source_at_its_default_size() {
        for g in GENERATORS {
            let scene = generate(g.name, None).unwrap();
            assert_eq!(
                scene.triangle_count(),
                (g.triangle_count)(g.size.default),
                "{}",
                g.name
            );
            assert_eq!(scene.source, format!("builtin:{}", g.name));
            assert_eq!(scene.name, g.name);
            assert!(!scene.lights.is_empty());
            assert_eq!(scene.mesh.material_ids.len(), scene.mesh.triangles.len());
            let materials = scene.materials.len() as u32;
            assert!(scene.mesh.material_ids.iter().all(|&m| m < materials));
            assert!(scene.mesh.triangles.iter().all(|t| t.is_finite()));
            assert!(
                scene.duration() >= 4.0,
                "{} lasts {}",
                g.name,
                scene.duration()
            );
        }
    }
}
