//! The tidy CSV files of a run. runs.csv: one row per (scene, frame, tracer, parameters, ray kind,
//! threads), and for render workloads one per (scene, frame, tracer, parameters, render, ray kind,
//! bounce depth, threads) plus a `frame` row (see `config.rs`). histograms.csv: one row per
//! (scene, frame, tracer, parameters, ray kind, BVH depth), for the ray batches.
//! Counts a tracer cannot measure (Embree's box and triangle tests) are empty cells, not zeros.
//! `build_plus_trace_seconds` is the frame's build (or refit) time of the row's structure plus
//! the row's fastest pass: "rebuild + render" for that ray kind (0 build when reused).
//! `rmse`: a distribution or path frame row's RMSE against its high-spp reference image (empty
//! elsewhere, and with `rmse = false`). `retraced_share`: an interleaved-soft-shadow frame row's
//! share of pixels retraced (`retrace` > 0; Benthin & Wald 2009 Fig. 7), empty elsewhere.
//! `embree_best_*`: the fastest Embree row on the same work in the same run (`embree_best`), its
//! configuration, and `x_embree_best` = its seconds / this row's (> 1: faster than Embree at its
//! best); the same for build + trace. Empty when the run measured no Embree row for that work.

use std::path::Path;

use crate::error::{Error, Result};
use crate::stats::Event;

use super::embree_best::{ratio, EmbreeBest};
use super::plan::Plan;
use super::runner::{Case, Traced};

pub const RUNS_CSV: &str = "runs.csv";
pub const HISTOGRAMS_CSV: &str = "histograms.csv";

pub const RUNS_COLUMNS: &[&str] = &[
    "experiment",
    "scene",
    "triangles",
    "frame",
    "tracer",
    "parameters",
    "structure",
    "render",
    "ray_kind",
    "bounce_depth",
    "threads",
    "rays",
    "hits",
    "seconds_min",
    "seconds_median",
    "mrays_per_s",
    "build_seconds",
    "build",
    "build_mtris_per_s",
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
    "embree_best_config",
    "x_embree_best",
    "embree_best_build_plus_trace_seconds",
    "embree_best_build_plus_trace_config",
    "x_embree_best_build_plus_trace",
];

/// runs.csv's columns: the fixed ones, then one per `Event`.
pub fn runs_columns() -> Vec<&'static str> {
    RUNS_COLUMNS
        .iter()
        .copied()
        .chain(Event::ALL.iter().map(|e| e.name()))
        .collect()
}

pub const HISTOGRAM_COLUMNS: &[&str] = &[
    "experiment",
    "scene",
    "frame",
    "tracer",
    "parameters",
    "ray_kind",
    "depth",
    "aabb_tests",
    "triangle_tests",
];

/// Millions of rays per second from the fastest pass; `None` for an empty batch.
pub fn mrays_per_s(rays: usize, seconds: f64) -> Option<f64> {
    (rays > 0 && seconds > 0.0).then(|| rays as f64 / seconds / 1e6)
}

/// Build (or refit) throughput in millions of triangles per second; `None` when reused.
fn build_mtris_per_s(case: &Case) -> Option<f64> {
    (case.built && case.build_seconds > 0.0)
        .then(|| case.triangles as f64 / case.build_seconds / 1e6)
}

fn cell<T: ToString>(value: Option<T>) -> String {
    value.map_or(String::new(), |v| v.to_string())
}

fn per_ray(count: u64, rays: u64) -> Option<f64> {
    (rays > 0).then(|| count as f64 / rays as f64)
}

fn csv_error(path: &Path, e: csv::Error) -> Error {
    Error::input(path, None, e.to_string())
}

pub fn write_runs(path: &Path, plan: &Plan, cases: &[Case]) -> Result<()> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    w.write_record(runs_columns())
        .map_err(|e| csv_error(path, e))?;
    let embree = EmbreeBest::of(plan, cases);
    for case in cases {
        let instance = &plan.instances[case.instance];
        let c = &case.counted.counters;
        let internal = |v: u64| case.counts_internals.then_some(v);
        let internal_per_ray = |v: u64| {
            if case.counts_internals {
                per_ray(v, c.rays)
            } else {
                None
            }
        };
        for timing in &case.timings {
            // The counting pass ran once, on the widest pool: compare it with that row's median.
            let same_threads = timing.threads == case.counted.threads;
            let best = embree.trace(case, timing);
            let build_plus_trace = case.build_seconds + timing.seconds_min;
            let best_build = embree.build_plus_trace(case, timing);
            let fixed = [
                plan.experiment.clone(),
                plan.scenes[case.scene].name.clone(),
                case.triangles.to_string(),
                case.frame.to_string(),
                instance.tracer.clone(),
                instance.params.to_string(),
                instance.structure.to_string(),
                cell(case.traced.render().map(|r| &plan.renders[r])),
                case.traced.kind_name(plan),
                cell(case.traced.depth()),
                timing.threads.to_string(),
                case.rays.to_string(),
                case.counted.hits.to_string(),
                timing.seconds_min.to_string(),
                timing.seconds_median.to_string(),
                cell(mrays_per_s(case.rays, timing.seconds_min)),
                case.build_seconds.to_string(),
                if case.built { "built" } else { "reused" }.to_string(),
                cell(build_mtris_per_s(case)),
                build_plus_trace.to_string(),
                c.rays.to_string(),
                cell(internal(c.nodes_visited)),
                cell(internal(c.aabb_tests)),
                cell(internal(c.triangle_tests)),
                cell(internal_per_ray(c.nodes_visited)),
                cell(internal_per_ray(c.aabb_tests)),
                cell(internal_per_ray(c.triangle_tests)),
                cell(same_threads.then_some(case.counted.seconds)),
                cell(same_threads.then(|| case.counted.seconds / timing.seconds_median)),
                cell(case.rmse),
                cell(case.retraced_share),
                cell(best.map(|b| b.seconds)),
                cell(best.map(|b| &b.config)),
                cell(ratio(best, timing.seconds_min)),
                cell(best_build.map(|b| b.seconds)),
                cell(best_build.map(|b| &b.config)),
                cell(ratio(best_build, build_plus_trace)),
            ];
            let events = Event::ALL.iter().map(|&e| cell(internal(c.get(e))));
            let row: Vec<String> = fixed.into_iter().chain(events).collect();
            w.write_record(&row).map_err(|e| csv_error(path, e))?;
        }
    }
    w.flush().map_err(|e| Error::io(path, e))
}

/// Tests per BVH depth, for the tracers that count them; depths past the deepest count are omitted.
pub fn write_histograms(path: &Path, plan: &Plan, cases: &[Case]) -> Result<()> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    w.write_record(HISTOGRAM_COLUMNS)
        .map_err(|e| csv_error(path, e))?;
    for case in cases
        .iter()
        .filter(|c| c.counts_internals && matches!(c.traced, Traced::Batch(_) | Traced::File(_)))
    {
        let instance = &plan.instances[case.instance];
        let c = &case.counted.counters;
        let depths = c.aabb_by_depth.len().max(c.triangle_by_depth.len());
        for depth in 0..depths {
            let row = [
                plan.experiment.clone(),
                plan.scenes[case.scene].name.clone(),
                case.frame.to_string(),
                instance.tracer.clone(),
                instance.params.to_string(),
                case.traced.kind_name(plan),
                depth.to_string(),
                c.aabb_by_depth.get(depth).copied().unwrap_or(0).to_string(),
                c.triangle_by_depth
                    .get(depth)
                    .copied()
                    .unwrap_or(0)
                    .to_string(),
            ];
            w.write_record(&row).map_err(|e| csv_error(path, e))?;
        }
    }
    w.flush().map_err(|e| Error::io(path, e))
}
