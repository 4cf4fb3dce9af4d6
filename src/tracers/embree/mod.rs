//! Embree 3 and Embree 4 as baselines: one tracer over an Embree scene (`accel::embree`), generic
//! over the version and over how rays are submitted — single rays (`embree3-1`, `embree4-1`),
//! packets of 4/8/16 (`embree3-4/8/16`, `embree4-4/8/16`) and Embree 3's AoS streams
//! (`embree3-stream`).

mod convert;
mod denormals;
mod packet;
mod record;
mod single;
mod stream;
mod tracer;

#[cfg(test)]
mod guard_tests;

pub use packet::{Packets, Packets16, Packets4, Packets8, RayHitPacket, RayPacket};
pub use single::Single;
pub use stream::{Stream, STREAM_LENGTH};
pub use tracer::{Coherence, EmbreeTracer, Submission};
