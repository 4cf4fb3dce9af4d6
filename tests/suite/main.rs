//! raylab's integration tests, as one test binary: each module was a test crate of its own, and
//! each of those linked (and monomorphised the tracers into) a copy of the whole library; one
//! binary builds the library's generic code once. Fixtures shared by the modules are in `common`.
//! `cargo test --release <module>::` runs one module's tests.

mod common;

mod cgt;
mod claims;
mod cli;
mod embree;
mod embree_agreement;
mod embree_builder;
mod experiment_runs;
mod fast_tests;
mod fuzz_loaders;
mod grid;
mod heatmaps;
mod layers;
mod loaders;
mod mft;
mod packet;
mod path;
mod readme;
mod registry;
mod report_browser;
mod reports;
mod reproduce;
mod stability;
mod staged;
mod stream;
mod summary;
mod tinybvh;
mod visibility;
mod whitted;
mod wide_single;
