//! Scenes: the model (triangles, materials, lights, camera, animation), the file loaders and the
//! built-in generators, and name lookup through `scenes/` and `$RAYLAB_SCENES`.

pub mod camera;
pub mod loaders;
pub mod model;

pub use camera::{Camera, CameraKey, CameraPath};
pub use model::{Animation, Frame, Light, Material, Mesh, Scene};
