//! Embree 3 as a baseline: one tracer over an Embree scene (`accel::embree`), generic over how
//! rays are submitted — single rays (`embree1`), packets of 4/8/16 (`embree4/8/16`) and AoS
//! streams (`embree-stream`).

mod convert;
mod denormals;
mod packet;
mod record;
mod single;
mod stream;
mod tracer;

pub use packet::{Packets, Packets16, Packets4, Packets8, RayHitPacket, RayPacket};
pub use single::Single;
pub use stream::{Stream, STREAM_LENGTH};
pub use tracer::{Coherence, EmbreeTracer, Submission};
