//! What to run: the experiment file parsed into typed settings (`config`), checked, and turned into
//! a plan of exactly the structures, ray kinds and render workloads it needs (`plan`), with the
//! command-line overrides, the shard of a sweep, and the declared paper tables and figures.
//! Imports only `record` among the experiment rooms.

pub mod config;
pub mod figure_spec;
pub mod overrides;
pub mod plan;
#[doc(hidden)]
pub mod quad_scenes;
pub mod render_pruning;
pub mod shard;
pub mod table_spec;
