//! The names of the files a results directory holds, in one place: the run writes them, the
//! results room reads them back, and `raylab summary`/`report` find them by these names.

/// One row per measurement (`run_row::RunRow`).
pub const RUNS_CSV: &str = "runs.csv";
/// Box and triangle tests per BVH depth, for the ray batches.
pub const HISTOGRAMS_CSV: &str = "histograms.csv";
/// One row per sampled check of a tracer against the oracle.
pub const VERIFY_CSV: &str = "verify.csv";
/// Commit, CPU, ISA, library versions, the experiment file and the plan.
pub const META_JSON: &str = "meta.json";
/// The experiment's paper-vs-ours tables.
pub const TABLES_MD: &str = "tables.md";
/// The run's summary, recomputed from the files above.
pub const SUMMARY_MD: &str = "summary.md";
/// The stability suite's rows (an experiment with `[stability]`).
pub const STABILITY_CSV: &str = "stability.csv";
/// A shard's heat-map panels (`heatmap_file`), drawn by `raylab merge`.
pub const HEATMAPS_BIN: &str = "heatmaps.bin";
/// Where `--dump-rays` writes the generated batches.
pub const RAYS_DIR: &str = "rays";
