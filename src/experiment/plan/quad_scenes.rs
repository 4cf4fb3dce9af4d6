//! Tiny scenes for the experiment tests (unit and end-to-end, `tests/suite/experiment_runs.rs`): a unit
//! quad lit by a point light, unlit, sliding away (animated), under a quad light, or made of
//! glass, and a parser for test experiment bodies. Hidden from the docs; not part of the
//! testbed's interface.

use std::path::Path;
use std::sync::Arc;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::scene::{Animation, Camera, Light, Material, Mesh, Scene};

use super::config::{Experiment, SceneSpec};

/// A unit quad at z = 0 facing +z (two triangles), lit or not, static or spinning.
pub fn quad_scene(name: &str, lit: bool, animated: bool) -> Scene {
    let mesh = quad_mesh(0.0);
    Scene {
        name: name.into(),
        source: "test".into(),
        mesh,
        materials: vec![Material::default()],
        lights: if lit {
            vec![Light::Point {
                position: Vec3::new(0.0, 0.0, 3.0),
                intensity: Vec3::ONE,
            }]
        } else {
            vec![]
        },
        camera: Camera {
            position: Vec3::new(0.0, 0.0, 4.0),
            fov_y_deg: 30.0,
            ..Camera::default()
        },
        camera_path: None,
        animation: animated.then(|| Arc::new(Sliding) as Arc<dyn Animation>),
    }
}

fn quad_mesh(z: f32) -> Mesh {
    let (a, b, c, d) = (
        Vec3::new(-1.0, -1.0, z),
        Vec3::new(1.0, -1.0, z),
        Vec3::new(1.0, 1.0, z),
        Vec3::new(-1.0, 1.0, z),
    );
    let mut mesh = Mesh::default();
    mesh.push(Triangle { v: [a, b, c] }, 0);
    mesh.push(Triangle { v: [a, c, d] }, 0);
    mesh
}

/// The quad sliding back along −z, one unit per second.
#[derive(Debug)]
struct Sliding;
impl Animation for Sliding {
    fn duration(&self) -> f32 {
        2.0
    }
    fn mesh_at(&self, time: f32) -> Mesh {
        quad_mesh(-time)
    }
}

pub fn load_quads(spec: &SceneSpec) -> Result<Scene> {
    match spec.name.as_str() {
        "lit" => Ok(quad_scene("lit", true, false)),
        "dark" => Ok(quad_scene("dark", false, false)),
        "moving" => Ok(quad_scene("moving", true, true)),
        // A 0.5 × 0.5 quad light 3 units in front of the quad.
        "soft" => Ok(Scene {
            lights: vec![Light::Quad {
                corner: Vec3::new(-0.25, -0.25, 3.0),
                edge_u: Vec3::new(0.5, 0.0, 0.0),
                edge_v: Vec3::new(0.0, 0.5, 0.0),
                emission: Vec3::ONE,
            }],
            ..quad_scene("soft", true, false)
        }),
        "glass" => {
            let mut scene = quad_scene("glass", true, false);
            scene.materials[0].dielectric = Some((1.5, 1.0));
            Ok(scene)
        }
        other => Err(Error::usage(format!("unknown scene {other:?}"))),
    }
}

pub fn experiment(body: &str) -> Experiment {
    let text = format!("name = \"t\"\nresolution = {{ width = 8, height = 8 }}\n{body}");
    Experiment::parse(Path::new("t.toml"), &text).unwrap()
}
