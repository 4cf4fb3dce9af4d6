//! What a run's rows say: runs.csv with the Embree-best columns, plots, error plots, the declared
//! paper tables and figures, the summary and the reports. Everything here derives from rows
//! (`record::run_row`), in memory or read back from a results directory; it never imports `run`.

pub mod embree_best;
pub mod error_plot;
pub mod figures;
pub mod heatmap;
pub mod plots;
pub mod report;
pub mod staleness;
pub mod summary;
pub mod tables;
