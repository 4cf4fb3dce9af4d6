//! Embree 3 as a baseline, through bindgen (`build.rs`): a device, a scene over our mesh, and one
//! tracer generic over how rays are submitted — single rays (`embree1`), packets of 4/8/16
//! (`embree4/8/16`) and AoS streams (`embree-stream`).

mod config;
mod convert;
mod denormals;
mod device;
pub mod ffi;
mod packet;
mod record;
mod scene;
mod single;
mod stream;
mod tracer;

pub use config::{BuildQuality, EmbreeConfig};
pub use device::{version, Device};
pub use packet::{Packets, Packets16, Packets4, Packets8, RayHitPacket, RayPacket};
pub use scene::EmbreeScene;
pub use single::Single;
pub use stream::{Stream, STREAM_LENGTH};
pub use tracer::{Coherence, EmbreeTracer, Submission};
