//! raylab: a research testbed for coherent ray tracing. See README.md for the map.
//!
//! Data flows one way: experiment → plan → scene → acceleration structure → ray batches →
//! tracer → stats → CSV → plots.

pub mod accel;
pub mod error;
pub mod experiment;
pub mod geometry;
#[cfg(test)]
mod guard_page;
pub mod lanes;
pub mod memory;
pub mod params;
pub mod random;
pub mod render;
pub mod scene;
pub mod stats;
#[doc(hidden)]
pub mod test_util;
pub mod tracers;
pub mod verify;

pub use error::{Error, Result};
