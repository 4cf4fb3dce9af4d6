//! Every tracer — from-scratch or baseline — behind one trait, so the runner, the verifier and
//! the benchmarks treat them alike. Adding a tracer is adding a file and one line in `registry.rs`.

pub mod chunked;
pub mod coherent_grid;
pub mod embree;
pub mod grid_dda;
pub mod kernel;
pub mod multi_frusta;
pub mod obvhs;
pub mod packet;
pub mod reference;
pub mod registry;
pub mod staged;
pub mod stream;
#[cfg(tinybvh)]
pub mod tinybvh;
pub mod visibility;
pub mod wide_single;

pub use crate::params::Params;
pub use kernel::{Kernel, SingleRayKernel, Tracer};
pub use registry::{
    build_tracer, make_tracer, oracle_params, tracer_for_frame, tracer_for_mesh, Role,
    TracerConfig, TracerInfo, ORACLE, TRACERS,
};
pub use staged::StagedRays;
pub use visibility::VisibilityQuery;
