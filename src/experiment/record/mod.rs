//! The record of a run, the bottom room of `experiment/`: what a measurement is once taken — one
//! typed row per measurement (`run_row`, runs.csv), per BVH depth of a counted batch
//! (`histogram_row`), per sampled check (`check_row`) and per case of the stability suite
//! (`stability_row`) — the file names of a results
//! directory, how rows are selected and reduced for tables and figures, and how a results
//! directory is written all at once or not at all, the spread of a timed number over its
//! passes (`spread`), and the unit costs fitted over a run's rows (`cost_model`). `plan`, `run`
//! and `results` all import it; it imports none of them.

pub mod check_row;
pub mod cost_model;
pub mod csv_file;
pub mod digest;
pub mod files;
pub mod heatmap_file;
pub mod heatmap_set;
pub mod histogram_row;
pub mod provenance;
pub mod results_dir;
pub mod run_row;
pub mod selection;
pub mod settings;
pub mod spread;
pub mod stability_row;
pub mod utc;

pub use check_row::CheckRow;
pub use histogram_row::HistogramRow;
pub use run_row::{Best, RunRow};

/// Everything a run (or a merged sweep) measured, as rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Records {
    pub runs: Vec<RunRow>,
    pub histograms: Vec<HistogramRow>,
    pub checks: Vec<CheckRow>,
}
