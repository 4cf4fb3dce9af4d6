//! Experiments.
pub mod config;
