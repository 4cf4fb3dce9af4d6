//! Embree 3's side of the structures: the bindgen bindings (`build.rs`), the device, and a scene
//! over our mesh with its build quality. The tracers that submit rays to it live in
//! `tracers::embree`.

mod config;
mod device;
pub mod ffi;
mod scene;

pub use config::{BuildQuality, EmbreeConfig};
pub use device::{version, Device};
pub use scene::EmbreeScene;
