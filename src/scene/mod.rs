//! Scenes: the model (triangles, materials, lights, camera, animation), the file loaders and the
//! built-in generators, and name lookup through `scenes/` and `$RAYLAB_SCENES`.

pub mod builtin;
pub mod camera;
pub mod library;
pub mod loaders;
pub mod model;
pub mod scene_file;
pub mod tessellate;

pub use camera::{Camera, CameraKey, CameraPath};
pub use library::{list_scenes, load_scene, SceneListing, SearchPath};
pub use model::{Animation, Frame, Light, Material, Mesh, Scene};
