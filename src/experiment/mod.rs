//! Experiments: a TOML file of scenes × tracers × parameter grid × ray kinds × frames × threads,
//! turned into a plan, run, and written to `results/<experiment>/<run-id>/` as runs.csv,
//! histograms.csv, PNG plots and meta.json — all at once or not at all — plus the experiment's own
//! paper-vs-ours tables (tables.md, see `tables`) and line figures (see `figures`).

pub mod merge;
pub mod plan;
pub mod record;
pub mod reproduce;
pub mod results;
pub mod run;

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::scene::library::load_scene;

pub use plan::config::{check_threads, Experiment, SceneSpec, StructureKey, TracerInstance};
pub use plan::overrides::{Chatter, RunOverrides};
pub use plan::{Plan, SceneLoader};
pub use record::files::RAYS_DIR;

use plan::figure_spec::DataFile;
use plan::shard;
use record::files::{HEATMAPS_BIN, HISTOGRAMS_CSV, RUNS_CSV, SUMMARY_MD, TABLES_MD, VERIFY_CSV};
use record::heatmap_set::HeatmapSet;
use record::selection::Row;
use record::{check_row, heatmap_file, histogram_row, results_dir, run_row, utc};
use record::{HistogramRow, Records, RunRow};
use results::{error_plot, plots, summary, tables};
use run::{meta, runner};

/// Runs the experiment in `path` with the built-in and library scenes; returns the results
/// directory.
pub fn run_experiment(path: &Path, overrides: &RunOverrides) -> Result<PathBuf> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut exp = Experiment::parse(path, &text)?;
    overrides.apply(&mut exp)?;
    run(&exp, &text, overrides, &|spec: &SceneSpec| {
        load_scene(&spec.name, spec.size)
    })
}

/// Runs a parsed experiment (`file_text`: its file as written, for meta.json) with scenes from
/// `load`: plans, prints the plan, measures, and writes every output into a temporary directory
/// that becomes the results directory only when all is written.
pub fn run(
    exp: &Experiment,
    file_text: &str,
    overrides: &RunOverrides,
    load: SceneLoader,
) -> Result<PathBuf> {
    crate::memory::check(
        &format!(
            "experiment {} ({} rays per batch)",
            exp.path.display(),
            exp.largest_batch()
        ),
        crate::memory::for_rays(exp.largest_batch()),
    )?;
    if let Some(settings) = &exp.stability {
        if let Some(shard) = overrides.shard {
            return Err(Error::usage(format!(
                "--shard {shard}: the stability suite of {} is not sharded (run it whole)",
                exp.path.display()
            )));
        }
        return run::stability_suite::run(exp, settings, file_text, overrides);
    }
    // A missing font would otherwise only show after the whole run.
    plots::register_font()?;
    let started = utc::UtcTime::now();
    let clock = std::time::Instant::now();
    let plan = Plan::derive(exp, load)?;
    overrides.chatter.say(&plan.to_string());
    let part = match overrides.shard {
        Some(shard) => {
            let part = shard::Part::of(&plan, shard);
            let units: Vec<String> = part
                .units()
                .iter()
                .map(|&(s, i)| format!("{} × {}", plan.scenes[s].name, plan.instances[i].label))
                .collect();
            overrides.chatter.say(&format!(
                "shard {shard}: {} of {} (scene × tracer) units: {}",
                units.len(),
                plan.scenes.len() * plan.instances.len(),
                if units.is_empty() {
                    "none".to_string()
                } else {
                    units.join(", ")
                }
            ));
            part
        }
        None => shard::Part::whole(&plan),
    };
    let run_id = match overrides.shard {
        Some(s) => format!("{}-shard{}of{}", started.compact(), s.index, s.count),
        None => started.compact(),
    };
    let results = results_dir::PendingResults::create(&exp.output, &exp.name, &run_id)?;

    let progress = runner::progress_bar(
        part.measurements(&plan),
        overrides.chatter != Chatter::Quiet,
    );
    let dump = overrides.dump_rays.then(|| results.dir().join(RAYS_DIR));
    let measured = runner::run_plan(exp, &plan, &part, load, &progress, dump.as_deref());
    progress.finish_and_clear();
    let (cases, heatmaps) = measured?;
    let mut records = run::case::records(&plan, &cases);
    results::embree_best::fill(&plan, &mut records.runs);

    let dir = results.dir();
    let mut meta = meta::gather(
        &plan.experiment,
        Some(&plan),
        &exp.threads,
        results.run_id(),
        started,
        (&exp.path, file_text),
        overrides,
    );
    match overrides.shard {
        // A part's plots and tables would show a part: `raylab merge` draws them for the whole.
        Some(shard) => {
            write_records(dir, &records)?;
            if !exp.heatmaps.is_empty() {
                heatmap_file::write(&dir.join(HEATMAPS_BIN), &heatmaps)?;
            }
            meta.shard = Some(shard::ShardMeta {
                index: shard.index,
                count: shard.count,
                sweep: shard::sweep_key(file_text, overrides),
                units: part.units(),
            });
        }
        None => write_outputs(dir, exp, &plan, (&records, &heatmaps))?,
    }
    meta.wall_seconds = Some(clock.elapsed().as_secs_f64());
    meta::write(dir, &meta)?;
    if overrides.shard.is_none() {
        write_summary(dir)?;
    }
    results.commit()
}

/// summary.md, from the files just written (runs.csv, verify.csv, meta.json), as `raylab summary`
/// recomputes it. A run and a merged sweep write it last.
fn write_summary(dir: &Path) -> Result<()> {
    let summary = summary::Summary::read(dir)?;
    let path = dir.join(SUMMARY_MD);
    std::fs::write(&path, summary.markdown()).map_err(|e| Error::io(&path, e))
}

/// The rows themselves: runs.csv, histograms.csv and verify.csv. A shard of a sweep writes only
/// these (its plots and tables would show a part); `raylab merge` reads them back.
fn write_records(dir: &Path, records: &Records) -> Result<()> {
    run_row::write_runs(&dir.join(RUNS_CSV), &records.runs)?;
    histogram_row::write_histograms(&dir.join(HISTOGRAMS_CSV), &records.histograms)?;
    check_row::write_checks(&dir.join(VERIFY_CSV), &records.checks)
}

/// Everything a run writes from its rows and heat-map panels except meta.json: the rows, the heat
/// maps, the plots, the error plots, and the experiment's tables and figures. A merged sweep
/// writes the same.
fn write_outputs(
    dir: &Path,
    exp: &Experiment,
    plan: &Plan,
    (records, heatmaps): (&Records, &HeatmapSet),
) -> Result<()> {
    write_records(dir, records)?;
    results::heatmap::write_figures(dir, &exp.heatmaps, heatmaps)?;
    plots::write_plots(dir, plan, &records.runs, &records.histograms)?;
    error_plot::write_error_plots(dir, exp, plan, &records.runs)?;
    let rows: Vec<Row> = records.runs.iter().map(RunRow::fields).collect();
    tables::write_tables(&dir.join(TABLES_MD), &exp.name, &exp.tables, &rows)?;
    let histograms: Vec<Row> = records
        .histograms
        .iter()
        .map(HistogramRow::fields)
        .collect();
    for figure in &exp.figures {
        match figure.data {
            DataFile::Runs => figure.draw(dir, &rows)?,
            DataFile::Histograms => figure.draw(dir, &histograms)?,
        }
    }
    Ok(())
}
