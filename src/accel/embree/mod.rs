//! Embree's side of the structures: the bindings (`build.rs`), the calls raylab makes (`api`,
//! implemented by Embree 3 and, with the cfg `embree4`, Embree 4 in `v4`), the device, and a scene
//! over our mesh with its build quality, and our BVH built by Embree's builder (`build_bvh`). The tracers that submit rays to it live in
//! `tracers::embree`.

mod api;
mod build_bvh;
mod config;
mod device;
pub mod ffi;
mod scene;
#[cfg(embree4)]
pub mod v4;

pub use api::{Embree3, EmbreeApi, Padded};
pub use build_bvh::build_bvh;
pub use config::{BuildQuality, EmbreeConfig};
#[cfg(test)]
pub use device::test_isas;
pub use device::{shared_config, version, Device, CONFIG_VARIABLE};
pub use scene::EmbreeScene;
#[cfg(embree4)]
pub use v4::Embree4;

/// Whether this build has Embree 4 (`build.rs` found it in the cache `.ci/fetch-embree4` fills).
pub const EMBREE4_BUILT: bool = cfg!(embree4);

/// What to do to get Embree 4 into a build without it.
pub const EMBREE4_HINT: &str =
    "Embree 4 was not built into this raylab: run `bash .ci/fetch-embree4` and rebuild \
     (with the default feature `embree4`)";
