//! The record of a run: one typed row per measurement (`RunRow`, a runs.csv line) and one per
//! BVH depth of a counted ray batch (`HistogramRow`, a histograms.csv line). A run produces these
//! and nothing else; runs.csv, the Embree-best columns, plots, tables, figures, the summary, the
//! reports and `raylab merge` all derive from them, in memory or read back from the files.
//!
//! Counts a tracer cannot measure (Embree's box and triangle tests) are `None` (empty cells, not
//! zeros). Derived columns (`mrays_per_s`, per-ray counts, `build_plus_trace_seconds`,
//! `counting_overhead`, `x_embree_best`, `x_baseline_best`…) are computed from the fields when
//! written, never stored.

use std::path::Path;

use crate::error::Result;
use crate::stats::Event;

use super::csv_file::{write_csv, CellResult, Cells};
use super::selection::Row;

pub const RUNS_COLUMNS: &[&str] = &[
    "experiment",
    "scene",
    "triangles",
    "frame",
    "tracer",
    "parameters",
    "structure",
    "resolved",
    "render",
    "ray_kind",
    "bounce_depth",
    "threads",
    "rays",
    "hits",
    "seconds_min",
    "seconds_median",
    "mrays_per_s",
    "generation_seconds",
    "build_seconds",
    "build",
    "build_mtris_per_s",
    "sah_cost",
    "build_plus_trace_seconds",
    "counted_rays",
    "nodes_visited",
    "aabb_tests",
    "triangle_tests",
    "nodes_per_ray",
    "aabb_tests_per_ray",
    "triangle_tests_per_ray",
    "counting_seconds",
    "counting_overhead",
    "rmse",
    "retraced_share",
    "embree_best_seconds",
    "embree_best_seconds_median",
    "embree_best_config",
    "x_embree_best",
    "embree_best_build_plus_trace_seconds",
    "embree_best_build_plus_trace_config",
    "x_embree_best_build_plus_trace",
    "baseline_best_seconds",
    "baseline_best_seconds_median",
    "baseline_best_config",
    "x_baseline_best",
];

/// runs.csv's columns: the fixed ones, then one per `Event`.
pub fn runs_columns() -> Vec<&'static str> {
    RUNS_COLUMNS
        .iter()
        .copied()
        .chain(Event::ALL.iter().map(|e| e.name()))
        .collect()
}

/// Millions of rays per second from the fastest pass; `None` for an empty batch.
pub fn mrays_per_s(rays: usize, seconds: f64) -> Option<f64> {
    (rays > 0 && seconds > 0.0).then(|| rays as f64 / seconds / 1e6)
}

/// The fastest Embree configuration on a row's work (see `results::embree_best`).
#[derive(Clone, Debug, PartialEq)]
pub struct Best {
    pub seconds: f64,
    /// The same configuration's median pass: with `seconds`, the spread a verdict weighs.
    pub median: f64,
    /// `tracer parameters`, with the intersect context `auto` chose spelled out.
    pub config: String,
}

impl Best {
    /// `best / seconds`: how many times faster than Embree at its best (> 1 is faster).
    pub fn ratio(best: Option<&Best>, seconds: f64) -> Option<f64> {
        best.filter(|_| seconds > 0.0).map(|b| b.seconds / seconds)
    }
}

/// One runs.csv row: one tracer instance on one workload (a ray kind, one batch of a rendered
/// frame at one bounce depth, a whole frame, or a ray file) of one frame of one scene, at one
/// thread count.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRow {
    pub experiment: String,
    pub scene: String,
    pub triangles: usize,
    pub frame: usize,
    pub tracer: String,
    /// The instance's parameters as `key=value;…` (`Params`' display).
    pub parameters: String,
    pub structure: String,
    /// The configuration the instance ran, defaults included: its tracer's and its structure's
    /// (`InstancePlan::resolved`); `None` in files written before the column.
    pub resolved: Option<String>,
    /// The render workload, for the batches and frames of a rendered frame.
    pub render: Option<String>,
    /// The ray kind, the batch kind of a rendered frame, `frame`, or `file:<name>`.
    pub ray_kind: String,
    /// Camera rays 0, rays leaving their hits 1 (and deeper in a rendered frame); none for a
    /// whole frame or a ray file.
    pub bounce_depth: Option<u32>,
    pub threads: usize,
    pub rays: usize,
    pub hits: u64,
    pub seconds_min: f64,
    pub seconds_median: f64,
    /// The fastest generation of the rays this row's tracer was handed ready, not in its
    /// seconds: the soft-shadow query's shadow rays, generated once for every tracer that takes
    /// rays (a tracer answering the query natively generates its own, inside its seconds).
    /// `None` where the workload's rays are given.
    pub generation_seconds: Option<f64>,
    /// Seconds to build (or refit) the row's structure for this frame; 0 when reused.
    pub build_seconds: f64,
    /// Whether the structure was built this frame (false: reused from frame 0).
    pub built: bool,
    /// The SAH cost of the row's structure (`Bvh::sah_cost`), for our BVH only.
    pub sah_cost: Option<f64>,
    /// Rays the counting pass saw.
    pub counted_rays: u64,
    /// `None` for tracers that count rays only.
    pub nodes_visited: Option<u64>,
    pub aabb_tests: Option<u64>,
    pub triangle_tests: Option<u64>,
    /// The counting pass's seconds, on the row that ran at its thread count.
    pub counting_seconds: Option<f64>,
    pub rmse: Option<f64>,
    pub retraced_share: Option<f64>,
    /// One per `Event::ALL`, `None` where the tracer does not count internals.
    pub events: Vec<Option<u64>>,
    /// Filled from the run's Embree rows (`results::embree_best`).
    pub embree_best: Option<Best>,
    pub embree_best_build_plus_trace: Option<Best>,
    /// The fastest production baseline on the row's work (Embree best, obvhs, tinybvh), filled
    /// with `embree_best` (`results::embree_best`).
    pub baseline_best: Option<Best>,
}

fn cell<T: ToString>(value: Option<T>) -> String {
    value.map_or(String::new(), |v| v.to_string())
}

fn per_ray(count: Option<u64>, rays: u64) -> Option<f64> {
    count.filter(|_| rays > 0).map(|c| c as f64 / rays as f64)
}

impl RunRow {
    /// Build (or refit) plus the fastest pass: "rebuild + render" for this work.
    pub fn build_plus_trace_seconds(&self) -> f64 {
        self.build_seconds + self.seconds_min
    }

    /// Build (or refit) throughput in millions of triangles per second; `None` when reused.
    pub fn build_mtris_per_s(&self) -> Option<f64> {
        (self.built && self.build_seconds > 0.0)
            .then(|| self.triangles as f64 / self.build_seconds / 1e6)
    }

    /// The cells of the row, in `runs_columns()` order.
    pub fn cells(&self) -> Vec<String> {
        let counting = self.counting_seconds;
        let fixed = [
            self.experiment.clone(),
            self.scene.clone(),
            self.triangles.to_string(),
            self.frame.to_string(),
            self.tracer.clone(),
            self.parameters.clone(),
            self.structure.clone(),
            cell(self.resolved.as_ref()),
            cell(self.render.as_ref()),
            self.ray_kind.clone(),
            cell(self.bounce_depth),
            self.threads.to_string(),
            self.rays.to_string(),
            self.hits.to_string(),
            self.seconds_min.to_string(),
            self.seconds_median.to_string(),
            cell(mrays_per_s(self.rays, self.seconds_min)),
            cell(self.generation_seconds),
            self.build_seconds.to_string(),
            if self.built { "built" } else { "reused" }.to_string(),
            cell(self.build_mtris_per_s()),
            cell(self.sah_cost),
            self.build_plus_trace_seconds().to_string(),
            self.counted_rays.to_string(),
            cell(self.nodes_visited),
            cell(self.aabb_tests),
            cell(self.triangle_tests),
            cell(per_ray(self.nodes_visited, self.counted_rays)),
            cell(per_ray(self.aabb_tests, self.counted_rays)),
            cell(per_ray(self.triangle_tests, self.counted_rays)),
            cell(counting),
            cell(counting.map(|s| s / self.seconds_median)),
            cell(self.rmse),
            cell(self.retraced_share),
            cell(self.embree_best.as_ref().map(|b| b.seconds)),
            cell(self.embree_best.as_ref().map(|b| b.median)),
            cell(self.embree_best.as_ref().map(|b| &b.config)),
            cell(Best::ratio(self.embree_best.as_ref(), self.seconds_min)),
            cell(
                self.embree_best_build_plus_trace
                    .as_ref()
                    .map(|b| b.seconds),
            ),
            cell(
                self.embree_best_build_plus_trace
                    .as_ref()
                    .map(|b| &b.config),
            ),
            cell(Best::ratio(
                self.embree_best_build_plus_trace.as_ref(),
                self.build_plus_trace_seconds(),
            )),
            cell(self.baseline_best.as_ref().map(|b| b.seconds)),
            cell(self.baseline_best.as_ref().map(|b| b.median)),
            cell(self.baseline_best.as_ref().map(|b| &b.config)),
            cell(Best::ratio(self.baseline_best.as_ref(), self.seconds_min)),
        ];
        let events = self.events.iter().map(|&v| cell(v));
        fixed.into_iter().chain(events).collect()
    }

    /// The row as a field map, as `selection` reads rows for tables and figures.
    pub fn fields(&self) -> Row {
        runs_columns()
            .into_iter()
            .map(String::from)
            .zip(self.cells())
            .collect()
    }

    /// A row read back from runs.csv. The derived columns are not read: they are computed again
    /// from the fields.
    pub fn parse(cells: &Cells) -> CellResult<RunRow> {
        // A runs.csv from before a best's median column reads as without spread (median = fastest).
        let best = |seconds: &str, median: &str, config: &str| -> CellResult<Option<Best>> {
            let median = match cells.0.contains_key(median) {
                true => cells.optional(median)?,
                false => None,
            };
            Ok(
                match (cells.optional(seconds)?, cells.optional_text(config)?) {
                    (Some(seconds), Some(config)) => Some(Best {
                        seconds,
                        median: median.unwrap_or(seconds),
                        config,
                    }),
                    _ => None,
                },
            )
        };
        Ok(RunRow {
            experiment: cells.text("experiment")?,
            scene: cells.text("scene")?,
            triangles: cells.number("triangles")?,
            frame: cells.number("frame")?,
            tracer: cells.text("tracer")?,
            parameters: cells.text("parameters")?,
            structure: cells.text("structure")?,
            resolved: match cells.0.contains_key("resolved") {
                true => cells.optional_text("resolved")?,
                false => None,
            },
            render: cells.optional_text("render")?,
            ray_kind: cells.text("ray_kind")?,
            bounce_depth: cells.optional("bounce_depth")?,
            threads: cells.number("threads")?,
            rays: cells.number("rays")?,
            hits: cells.number("hits")?,
            seconds_min: cells.number("seconds_min")?,
            seconds_median: cells.number("seconds_median")?,
            generation_seconds: cells.optional("generation_seconds")?,
            build_seconds: cells.number("build_seconds")?,
            built: match cells.text("build")?.as_str() {
                "built" => true,
                "reused" => false,
                other => return Err(format!("build: {other:?} is neither built nor reused")),
            },
            // runs.csv files written before the column read as without it.
            sah_cost: match cells.0.contains_key("sah_cost") {
                true => cells.optional("sah_cost")?,
                false => None,
            },
            counted_rays: cells.number("counted_rays")?,
            nodes_visited: cells.optional("nodes_visited")?,
            aabb_tests: cells.optional("aabb_tests")?,
            triangle_tests: cells.optional("triangle_tests")?,
            counting_seconds: cells.optional("counting_seconds")?,
            rmse: cells.optional("rmse")?,
            retraced_share: cells.optional("retraced_share")?,
            events: Event::ALL
                .iter()
                .map(|e| cells.optional(e.name()))
                .collect::<CellResult<_>>()?,
            embree_best: best(
                "embree_best_seconds",
                "embree_best_seconds_median",
                "embree_best_config",
            )?,
            embree_best_build_plus_trace: best(
                "embree_best_build_plus_trace_seconds",
                "",
                "embree_best_build_plus_trace_config",
            )?,
            // runs.csv files written before baseline best have no such columns.
            baseline_best: match cells.0.contains_key("baseline_best_seconds") {
                true => best(
                    "baseline_best_seconds",
                    "baseline_best_seconds_median",
                    "baseline_best_config",
                )?,
                false => None,
            },
        })
    }
}

/// runs.csv's rows.
pub fn write_runs(path: &Path, rows: &[RunRow]) -> Result<()> {
    write_csv(path, &runs_columns(), rows.iter().map(RunRow::cells))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row with every kind of cell: empty and set options, a Best, events, fractional seconds.
    fn row() -> RunRow {
        RunRow {
            experiment: "e".into(),
            scene: "room".into(),
            triangles: 864,
            frame: 2,
            tracer: "packet".into(),
            parameters: "packet=8;traversal=ranged".into(),
            structure: "bvh".into(),
            resolved: Some("Packet { config: PacketConfig { packet: 8 }, width: Binary }; BvhConfig { bins: 16 }".into()),
            render: Some("renderer=whitted;max_depth=2".into()),
            ray_kind: "reflection".into(),
            bounce_depth: Some(1),
            threads: 2,
            rays: 4096,
            hits: 4000,
            seconds_min: 0.1 + 0.2,
            seconds_median: 1e-7,
            generation_seconds: Some(0.125),
            build_seconds: 0.0,
            built: false,
            sah_cost: Some(61.25 + 1e-9),
            counted_rays: 4096,
            nodes_visited: Some(12345),
            aabb_tests: None,
            triangle_tests: Some(0),
            counting_seconds: None,
            rmse: Some(0.015625),
            retraced_share: None,
            events: Event::ALL
                .iter()
                .enumerate()
                .map(|(i, _)| (i % 3 != 0).then_some(i as u64 * 7))
                .collect(),
            embree_best: Some(Best {
                seconds: 0.25,
                median: 0.375,
                config: "embree3-16 (context coherent)".into(),
            }),
            embree_best_build_plus_trace: None,
            baseline_best: Some(Best {
                seconds: 0.125,
                median: 0.125,
                config: "tinybvh-8 builder=sbvh".into(),
            }),
        }
    }

    #[test]
    fn a_row_reads_back_from_its_cells_bit_for_bit() {
        let row = row();
        let fields = row.fields();
        assert_eq!(fields.len(), runs_columns().len());
        assert_eq!(fields["x_embree_best"], (0.25 / (0.1 + 0.2)).to_string());
        assert_eq!(fields["x_baseline_best"], (0.125 / (0.1 + 0.2)).to_string());
        let back = RunRow::parse(&Cells(&fields)).unwrap();
        assert_eq!(back, row);
        assert_eq!(back.seconds_min.to_bits(), (0.1f64 + 0.2).to_bits());
        let mut bad = fields.clone();
        bad.insert("build".into(), "maybe".into());
        assert!(RunRow::parse(&Cells(&bad)).unwrap_err().contains("build"));
        // A runs.csv from before baseline best reads back without it.
        let mut old = fields.clone();
        for column in [
            "baseline_best_seconds",
            "baseline_best_seconds_median",
            "baseline_best_config",
            "x_baseline_best",
        ] {
            old.remove(column);
        }
        let old = RunRow::parse(&Cells(&old)).unwrap();
        assert_eq!(
            (old.baseline_best, old.embree_best),
            (None, row.embree_best.clone())
        );
        // And from before the resolved configuration.
        let mut old = fields.clone();
        old.remove("resolved");
        assert_eq!(RunRow::parse(&Cells(&old)).unwrap().resolved, None);
        bad.remove("hits");
        assert_eq!(
            RunRow::parse(&Cells(&bad)).unwrap_err(),
            "no column \"hits\""
        );
    }
}
