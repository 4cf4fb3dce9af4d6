//! Running a plan: per scene and frame, build the structures, generate the workloads once, time
//! and count every tracer on the same rays (`runner`, `passes`), check sampled hits against the
//! oracle (`sampled_check`), run the stability suite (`stability_suite`), and gather the run's
//! provenance (`meta`). It produces rows (`record`); it never reads `results`.

pub mod bench;
pub mod case;
pub mod dump;
pub mod meta;
pub mod passes;
pub mod runner;
pub mod sampled_check;
pub mod stability_suite;
