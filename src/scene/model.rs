//! The scene model every loader and generator produces, and every tracer and renderer consumes.

use std::borrow::Cow;
use std::sync::Arc;

use glam::Vec3;

use super::{Camera, CameraPath};
use crate::geometry::{Aabb, Triangle};

/// Surface description. A material may combine a diffuse base with mirror, glossy and dielectric
/// parts; the renderers read what they support.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Lambertian albedo.
    pub diffuse: Vec3,
    /// Perfect mirror reflectance (0 = none).
    pub mirror: f32,
    /// Phong-lobe glossy reflection: exponent and reflectance; `None` when not glossy.
    pub glossy: Option<(f32, f32)>,
    /// Dielectric: index of refraction and transmittance; `None` when opaque.
    pub dielectric: Option<(f32, f32)>,
    pub emission: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            diffuse: Vec3::splat(0.7),
            mirror: 0.0,
            glossy: None,
            dielectric: None,
            emission: Vec3::ZERO,
        }
    }
}

impl Material {
    pub fn diffuse(name: &str, colour: Vec3) -> Self {
        Material {
            name: name.into(),
            diffuse: colour,
            ..Material::default()
        }
    }

    pub fn is_reflective(&self) -> bool {
        self.mirror > 0.0 || self.glossy.is_some()
    }

    pub fn is_refractive(&self) -> bool {
        self.dielectric.is_some()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    /// A parallelogram `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1], emitting `emission` (radiance).
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        emission: Vec3,
    },
}

impl Light {
    /// A point to aim a shadow ray at, from a sample `(s, t)` in [0,1)²: the point light itself,
    /// or that point on the quad.
    pub fn sample_point(&self, s: f32, t: f32) -> Vec3 {
        match *self {
            Light::Point { position, .. } => position,
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => corner + edge_u * s + edge_v * t,
        }
    }
}

/// Triangle soup with a material index per triangle. Triangle `i` is primitive id `i` everywhere:
/// in hits, in Embree's geometry and in verification.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub triangles: Vec<Triangle>,
    pub material_ids: Vec<u32>,
}

impl Mesh {
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    pub fn push(&mut self, tri: Triangle, material: u32) {
        self.triangles.push(tri);
        self.material_ids.push(material);
    }

    pub fn append(&mut self, other: &Mesh) {
        self.triangles.extend_from_slice(&other.triangles);
        self.material_ids.extend_from_slice(&other.material_ids);
    }

    pub fn bounds(&self) -> Aabb {
        self.triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
    }
}

/// Geometry that changes over time. `mesh_at(time)` returns the whole triangle soup at that
/// time, with the same triangle count and order at every time so primitive ids stay stable.
pub trait Animation: Send + Sync + std::fmt::Debug {
    /// Length of the animation in seconds.
    fn duration(&self) -> f32;
    fn mesh_at(&self, time: f32) -> Mesh;
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// Where it came from: a file path or `builtin:<generator>`.
    pub source: String,
    /// Geometry at time 0 (for static scenes, the geometry).
    pub mesh: Mesh,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub camera_path: Option<CameraPath>,
    pub animation: Option<Arc<dyn Animation>>,
}

/// One frame of a scene: the geometry and camera at one instant.
#[derive(Clone, Debug)]
pub struct Frame<'a> {
    pub index: usize,
    pub time: f32,
    pub mesh: Cow<'a, Mesh>,
    pub camera: Camera,
}

impl Scene {
    pub fn triangle_count(&self) -> usize {
        self.mesh.len()
    }

    /// The first quad (area) light: the light of the soft-shadow workload.
    pub fn quad_light(&self) -> Option<&Light> {
        self.lights.iter().find(|l| matches!(l, Light::Quad { .. }))
    }

    pub fn is_animated(&self) -> bool {
        self.animation.is_some()
    }

    /// Length in seconds of whatever moves: the geometry or the camera.
    pub fn duration(&self) -> f32 {
        let geometry = self.animation.as_ref().map_or(0.0, |a| a.duration());
        let camera = self.camera_path.as_ref().map_or(0.0, |p| p.duration());
        geometry.max(camera)
    }

    /// Frame `index` of `count` frames spread evenly over the scene's duration (frame 0 at time 0,
    /// the last frame at the end). Static geometry is borrowed, not copied.
    pub fn frame(&self, index: usize, count: usize) -> Frame<'_> {
        let time = if count > 1 {
            self.duration() * index as f32 / (count - 1) as f32
        } else {
            0.0
        };
        let mesh = match &self.animation {
            Some(a) => Cow::Owned(a.mesh_at(time)),
            None => Cow::Borrowed(&self.mesh),
        };
        let camera = self
            .camera_path
            .as_ref()
            .and_then(|p| p.camera_at(time))
            .unwrap_or(self.camera);
        Frame {
            index,
            time,
            mesh,
            camera,
        }
    }

    pub fn material_of(&self, prim: u32) -> &Material {
        &self.materials[self.mesh.material_ids[prim as usize] as usize]
    }
}
