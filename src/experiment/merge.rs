//! `raylab merge DIR…`: joins the results directories of a sharded sweep (`raylab run --shard i/n`,
//! see `shard`) into one results directory with the rows, plots and tables an unsharded run
//! writes. Each shard keeps its measurements as rows (runs.csv, histograms.csv, verify.csv); the
//! merge checks that every shard comes from the same sweep (`shard::sweep_key`) and that each of
//! 0…n−1 is given exactly once, re-derives the plan from the experiment file recorded in
//! meta.json, reads the rows back, orders them as the unsharded runner would (scene, frame, tracer
//! instance), fills the `embree_best_*` columns again from the whole sweep's Embree rows (whichever
//! shard measured them) and writes every output from the rows. An experiment with heat maps has
//! each shard's panels in its heatmaps.bin (`heatmap_file`); the merge joins them and draws the
//! sweep's figures. Written whole or not at all, like a run.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};

use super::plan::config::Experiment;
use super::plan::overrides::RunOverrides;
use super::plan::shard::{Part, Shard, ShardMeta};
use super::plan::{Plan, SceneLoader};
use super::record::csv_file::read_typed;
use super::record::files::META_JSON;
use super::record::files::{HEATMAPS_BIN, HISTOGRAMS_CSV, RUNS_CSV, VERIFY_CSV};
use super::record::heatmap_file;
use super::record::heatmap_set::HeatmapSet;
use super::record::{results_dir, utc};
use super::record::{CheckRow, HistogramRow, Records, RunRow};
use super::results::embree_best;
use super::results::plots;
use super::run::meta::{self, MergedShard};
use super::{write_outputs, write_summary};

/// One shard's results directory, as read from its meta.json.
struct ShardDir {
    dir: PathBuf,
    meta: Value,
    shard: ShardMeta,
}

impl ShardDir {
    fn read(dir: &Path) -> Result<ShardDir> {
        let path = dir.join(META_JSON);
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let meta: Value = serde_json::from_str(&text)
            .map_err(|e| Error::input(&path, Some(e.line()), e.to_string()))?;
        let shard = meta.get("shard").cloned().ok_or_else(|| {
            Error::input(
                &path,
                None,
                "not a shard of a sweep (no \"shard\"): made by `raylab run` without --shard",
            )
        })?;
        let shard: ShardMeta = serde_json::from_value(shard)
            .map_err(|e| Error::input(&path, None, format!("\"shard\": {e}")))?;
        if shard.count == 0 || shard.index >= shard.count {
            return Err(Error::input(
                &path,
                None,
                format!("\"shard\": {}/{} is not a part", shard.index, shard.count),
            ));
        }
        Ok(ShardDir {
            dir: dir.to_path_buf(),
            meta,
            shard,
        })
    }

    fn text(&self, pointer: &str) -> String {
        self.meta
            .pointer(pointer)
            .map_or(String::new(), |v| match v {
                Value::String(s) => s.clone(),
                other => other.to_string(),
            })
    }

    fn name(&self) -> String {
        format!("shard {}/{}", self.shard.index, self.shard.count)
    }
}

/// Checks that `shards` are the n parts of one sweep, each once, and returns them in shard order.
fn complete(mut shards: Vec<ShardDir>) -> Result<Vec<ShardDir>> {
    let first = shards
        .first()
        .ok_or_else(|| Error::usage("merge: no shard directories given"))?;
    let (count, sweep) = (first.shard.count, first.shard.sweep.clone());
    let first_dir = first.dir.display().to_string();
    for s in &shards {
        if s.shard.count != count || s.shard.sweep != sweep {
            return Err(Error::usage(format!(
                "{} ({}, sweep {}) is not from the sweep of {first_dir} ({count} shards, sweep {sweep})",
                s.dir.display(),
                s.name(),
                s.shard.sweep
            )));
        }
    }
    shards.sort_by_key(|s| s.shard.index);
    for pair in shards.windows(2) {
        if pair[0].shard.index == pair[1].shard.index {
            return Err(Error::usage(format!(
                "{} given twice: {} and {}",
                pair[0].name(),
                pair[0].dir.display(),
                pair[1].dir.display()
            )));
        }
    }
    let missing: Vec<String> = (0..count)
        .filter(|i| !shards.iter().any(|s| s.shard.index == *i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::usage(format!(
            "shard{} {} missing: merge needs all {count} shards of the sweep",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        )));
    }
    Ok(shards)
}

/// Merges the shard directories `dirs` into a new results directory under `output` (default: the
/// experiment's), loading scenes with `load` to re-derive the plan. Returns the directory.
pub fn merge(dirs: &[PathBuf], output: Option<&Path>, load: SceneLoader) -> Result<PathBuf> {
    let shards = complete(
        dirs.iter()
            .map(|d| ShardDir::read(d))
            .collect::<Result<_>>()?,
    )?;
    let first = &shards[0];
    let meta_path = first.dir.join(META_JSON);
    let experiment_path = PathBuf::from(first.text("/experiment_file/path"));
    let file_text = first.text("/experiment_file/contents");
    let mut overrides: RunOverrides = first
        .meta
        .get("overrides")
        .cloned()
        .map(serde_json::from_value)
        .transpose()
        .map_err(|e| Error::input(&meta_path, None, format!("\"overrides\": {e}")))?
        .unwrap_or_default();
    overrides.shard = None;
    overrides.output = output.map(Path::to_path_buf);
    let mut exp = Experiment::parse(&experiment_path, &file_text)?;
    overrides.apply(&mut exp)?;

    plots::register_font()?;
    let started = utc::UtcTime::now();
    let plan = Plan::derive(&exp, load)?;
    let mut records = Keyed::default();
    let mut heatmaps = Vec::new();
    for s in &shards {
        let expected = Part::of(
            &plan,
            Shard {
                index: s.shard.index,
                count: s.shard.count,
            },
        )
        .units();
        if s.shard.units != expected {
            return Err(Error::usage(format!(
                "{} ({}) measured units {:?}, but this raylab splits the plan into {:?} there: \
                 merge with the raylab that ran the shards",
                s.dir.display(),
                s.name(),
                s.shard.units,
                expected
            )));
        }
        let shard_records = Records {
            runs: read_typed(&s.dir.join(RUNS_CSV), RunRow::parse)?,
            histograms: read_typed(&s.dir.join(HISTOGRAMS_CSV), HistogramRow::parse)?,
            checks: read_typed(&s.dir.join(VERIFY_CSV), CheckRow::parse)?,
        };
        let unit_of = |path: &str, scene: &str, triangles, tracer: &str, parameters: &str| {
            let unit = plan
                .scene_of(scene, triangles)
                .zip(plan.instance_of(tracer, parameters));
            unit.filter(|u| s.shard.units.contains(u)).ok_or_else(|| {
                Error::input(
                    s.dir.join(path),
                    None,
                    format!(
                        "a row outside the shard's units of the plan: scene {scene}, \
                         tracer {tracer} {parameters}"
                    ),
                )
            })
        };
        for r in shard_records.runs {
            let (scene, instance) = unit_of(
                RUNS_CSV,
                &r.scene,
                Some(r.triangles),
                &r.tracer,
                &r.parameters,
            )?;
            records.runs.push(((scene, r.frame, instance), r));
        }
        for h in shard_records.histograms {
            let (scene, instance) =
                unit_of(HISTOGRAMS_CSV, &h.scene, None, &h.tracer, &h.parameters)?;
            records.histograms.push(((scene, h.frame, instance), h));
        }
        for c in shard_records.checks {
            let (scene, instance) = unit_of(
                VERIFY_CSV,
                &c.scene,
                Some(c.triangles),
                &c.tracer,
                &c.parameters,
            )?;
            records.checks.push(((scene, c.frame, instance), c));
        }
        if !exp.heatmaps.is_empty() {
            heatmaps.push(shard_heatmaps(&plan, s)?);
        }
    }
    // The unsharded runner's order; stable, so each (scene, frame, instance) keeps its order.
    let mut records = Records {
        runs: in_order(records.runs),
        histograms: in_order(records.histograms),
        checks: in_order(records.checks),
    };
    embree_best::fill(&plan, &mut records.runs);
    let commits: Vec<String> = shards.iter().map(|s| s.text("/commit/hash")).collect();
    if commits.iter().any(|c| *c != commits[0]) {
        eprintln!(
            "raylab: the shards were measured at different commits: {}",
            commits.join(", ")
        );
    }

    let results = results_dir::PendingResults::create(&exp.output, &exp.name, &started.compact())?;
    let heatmaps = HeatmapSet::joined(heatmaps);
    write_outputs(results.dir(), &exp, &plan, (&records, &heatmaps))?;
    let mut meta = meta::gather(
        &plan.experiment,
        Some(&plan),
        &exp.threads,
        results.run_id(),
        started,
        (&exp.path, &file_text),
        &overrides,
    );
    meta.merged_from = shards
        .iter()
        .map(|s| MergedShard {
            shard: format!("{}/{}", s.shard.index, s.shard.count),
            directory: s.dir.display().to_string(),
            run_id: s.text("/run_id"),
            date: s.text("/date"),
            hostname: s.text("/hostname"),
            commit: s.text("/commit/hash"),
            cpu: s.text("/cpu/model"),
        })
        .collect();
    meta::write(results.dir(), &meta)?;
    write_summary(results.dir())?;
    results.commit()
}

/// Shard `s`'s heat-map panels, each checked to be of a (scene × tracer) unit the shard measured.
fn shard_heatmaps(plan: &Plan, s: &ShardDir) -> Result<HeatmapSet> {
    let path = s.dir.join(HEATMAPS_BIN);
    let set = heatmap_file::read(&path)?;
    let foreign = |what: String| {
        Error::input(
            &path,
            None,
            format!("{what}: not among the shard's units of the plan"),
        )
    };
    let scene_name = |scene: usize| plan.scenes.get(scene).map(|p| p.name.as_str());
    for frame in &set.shaded {
        if !s.shard.units.iter().any(|&(scene, _)| scene == frame.scene) {
            return Err(foreign(format!(
                "the shaded frame of scene {} ({})",
                frame.scene, frame.name
            )));
        }
    }
    for p in &set.panels {
        let planned = plan.instances.get(p.instance).map(|i| i.label.as_str());
        if !s.shard.units.contains(&(p.scene, p.instance)) || planned != Some(p.tracer.as_str()) {
            return Err(foreign(format!(
                "the maps of {} on scene {} ({})",
                p.tracer,
                p.scene,
                scene_name(p.scene).unwrap_or("no such scene")
            )));
        }
    }
    Ok(set)
}

/// (scene, frame, tracer instance): the unsharded runner's order.
type Key = (usize, usize, usize);

/// Every shard's rows, each with its key.
#[derive(Default)]
struct Keyed {
    runs: Vec<(Key, RunRow)>,
    histograms: Vec<(Key, HistogramRow)>,
    checks: Vec<(Key, CheckRow)>,
}

/// The rows sorted by key (stably: a case's rows keep their order).
fn in_order<T>(mut rows: Vec<(Key, T)>) -> Vec<T> {
    rows.sort_by_key(|(key, _)| *key);
    rows.into_iter().map(|(_, row)| row).collect()
}

#[cfg(test)]
mod tests {
    use std::collections::{BTreeMap, BTreeSet};
    use std::fs;

    use super::*;
    use crate::experiment::plan::tests::load_quads;
    use crate::experiment::record::files::TABLES_MD;
    use crate::experiment::run;

    const TEXT: &str = "name = \"m\"\nscenes = [\"lit\", \"dark\", \"moving\"]\n\
        tracers = [\"reference\", \"obvhs\", \"embree1\", \"embree16\"]\n\
        rays = [\"primary\", \"shadow\", \"diffuse\"]\nresolution = { width = 16, height = 16 }\n\
        frames = 2\nthreads = [1, 2]\nwarmup = 0\nrepeats = 1\n\
        [[tables]]\ntitle = \"box tests\"\nrows = \"scene\"\nmetric = \"aabb_tests\"\n\
        where = { threads = 1, ray_kind = \"primary\" }\n\
        columns = [{ label = \"reference\", where = { tracer = \"reference\" } }, { label = \"obvhs\", where = { tracer = \"obvhs\" } }]\n";

    /// Columns that hold or derive from times: they differ between any two runs.
    const TIMED: &[&str] = &[
        "seconds_min",
        "seconds_median",
        "mrays_per_s",
        "generation_seconds",
        "build_seconds",
        "build_mtris_per_s",
        "build_plus_trace_seconds",
        "counting_seconds",
        "counting_overhead",
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

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("raylab-merge-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    fn run_into(out: &Path, shard: Option<Shard>) -> PathBuf {
        run_text_into(TEXT, out, shard)
    }

    fn run_text_into(text: &str, out: &Path, shard: Option<Shard>) -> PathBuf {
        let mut exp = Experiment::parse(Path::new("m.toml"), text).unwrap();
        exp.output = out.to_path_buf();
        let overrides = RunOverrides {
            shard,
            ..RunOverrides::default()
        };
        run(&exp, text, &overrides, &load_quads).unwrap()
    }

    fn rows(path: &Path) -> Vec<BTreeMap<String, String>> {
        crate::experiment::record::selection::read_rows(path).unwrap()
    }

    fn files(dir: &Path) -> BTreeSet<String> {
        fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect()
    }

    #[test]
    fn three_merged_shards_equal_the_unsharded_run_but_for_timings() {
        let out = scratch("equal");
        let whole = run_into(&out.join("whole"), None);
        let shards: Vec<PathBuf> = [2, 0, 1]
            .map(|index| {
                run_into(
                    &out.join(format!("s{index}")),
                    Some(Shard { index, count: 3 }),
                )
            })
            .to_vec();
        // A shard writes its rows, not plots or tables of a part.
        for file in [RUNS_CSV, HISTOGRAMS_CSV, VERIFY_CSV] {
            assert!(files(&shards[0]).contains(file));
        }
        assert!(!files(&shards[0]).contains(TABLES_MD));
        let merged = merge(&shards, Some(&out.join("merged")), &load_quads).unwrap();

        let (a, b) = (rows(&whole.join(RUNS_CSV)), rows(&merged.join(RUNS_CSV)));
        // 3 scenes × 2 frames × 4 tracers × 2 threads × (3, 2, 3 ray kinds).
        assert_eq!(a.len(), 2 * 4 * 2 * 8);
        assert_eq!(a.len(), b.len());
        let untimed = |r: &BTreeMap<String, String>| {
            let mut r = r.clone();
            r.retain(|k, _| !TIMED.contains(&k.as_str()));
            r
        };
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(untimed(x), untimed(y));
        }
        assert_eq!(
            fs::read(whole.join(HISTOGRAMS_CSV)).unwrap(),
            fs::read(merged.join(HISTOGRAMS_CSV)).unwrap()
        );
        assert_eq!(
            fs::read_to_string(whole.join(TABLES_MD)).unwrap(),
            fs::read_to_string(merged.join(TABLES_MD)).unwrap()
        );
        let mut expected = files(&whole);
        expected.insert(META_JSON.into());
        assert_eq!(files(&merged), expected);

        // Embree at its best is the fastest Embree row of the whole sweep, whichever shard ran it:
        // the shards put embree1 and embree16 of some scene in different parts.
        let meta: Vec<ShardMeta> = shards
            .iter()
            .map(|d| ShardDir::read(d).unwrap().shard)
            .collect();
        let owner = |s: usize, i: usize| meta.iter().position(|m| m.units.contains(&(s, i)));
        assert!((0..3).any(|s| owner(s, 2) != owner(s, 3)));
        let group = |r: &BTreeMap<String, String>| {
            ["scene", "frame", "ray_kind", "threads"].map(|k| r[k].clone())
        };
        for r in &b {
            let fastest = b
                .iter()
                .filter(|e| e["tracer"].starts_with("embree") && group(e) == group(r))
                .map(|e| e["seconds_min"].parse::<f64>().unwrap())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(
                r["embree_best_seconds"].parse::<f64>().unwrap(),
                fastest,
                "{r:?}"
            );
        }
        let merged_meta: Value =
            serde_json::from_str(&fs::read_to_string(merged.join(META_JSON)).unwrap()).unwrap();
        assert_eq!(merged_meta["merged_from"].as_array().unwrap().len(), 3);
        assert_eq!(merged_meta["merged_from"][1]["shard"], "1/3");
        // Reports show where each part was measured.
        let facts = crate::experiment::results::report::Results::read(&merged)
            .unwrap()
            .facts();
        let (_, parts) = facts
            .iter()
            .find(|(l, _)| *l == "merged from shards")
            .unwrap();
        assert_eq!(parts.matches(" on ").count(), 3, "{parts}");
        assert!(parts.starts_with("0/3 on "), "{parts}");
        let _ = fs::remove_dir_all(&out);
    }

    /// The heat-map figures in `dir`, by name.
    fn heat_maps(dir: &Path) -> BTreeMap<String, Vec<u8>> {
        files(dir)
            .into_iter()
            .filter(|f| f.starts_with("heatmap-"))
            .map(|f| (f.clone(), fs::read(dir.join(&f)).unwrap()))
            .collect()
    }

    #[test]
    fn merged_shards_draw_the_heat_maps_of_the_unsharded_run() {
        let text = "name = \"m\"\nscenes = [\"lit\", \"dark\"]\n\
            tracers = [\"reference\", { name = \"packet\", params = { packet = [4, 8] } }, \"embree1\"]\n\
            rays = [\"primary\", \"shadow\"]\nresolution = { width = 16, height = 16 }\n\
            frames = 1\nthreads = [1]\nwarmup = 0\nrepeats = 1\nheatmaps = [\"box\", \"lanes\"]\n";
        let out = scratch("maps");
        let whole = run_text_into(text, &out.join("whole"), None);
        let shards: Vec<PathBuf> = (0..3)
            .map(|index| {
                let dir = out.join(format!("s{index}"));
                run_text_into(text, &dir, Some(Shard { index, count: 3 }))
            })
            .collect();
        // A shard writes its panels, not figures of a part.
        for shard in &shards {
            assert!(heat_maps(shard).is_empty());
            assert!(shard.join(HEATMAPS_BIN).is_file());
        }
        let merged = merge(&shards, Some(&out.join("merged")), &load_quads).unwrap();
        let drawn = heat_maps(&whole);
        // lit: primary and shadow rays, dark (no light): primary; box and lanes each.
        assert_eq!(drawn.len(), 6, "{:?}", drawn.keys());
        // Counts do not depend on timing: the merged figures are the whole run's, byte for byte.
        assert!(
            heat_maps(&merged) == drawn,
            "{:?}",
            heat_maps(&merged).keys()
        );

        // A shard's panels in another shard's directory, or a damaged file: an error naming it.
        let into = out.join("bad");
        let swapped = out.join("swapped");
        let _ = fs::remove_dir_all(&swapped);
        fs::create_dir_all(&swapped).unwrap();
        for f in fs::read_dir(&shards[0]).unwrap() {
            let f = f.unwrap();
            fs::copy(f.path(), swapped.join(f.file_name())).unwrap();
        }
        fs::copy(shards[1].join(HEATMAPS_BIN), swapped.join(HEATMAPS_BIN)).unwrap();
        let dirs = [swapped.clone(), shards[1].clone(), shards[2].clone()];
        let e = merge(&dirs, Some(&into), &load_quads).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let e = e.to_string();
        assert!(
            e.contains(&swapped.join(HEATMAPS_BIN).display().to_string()),
            "{e}"
        );
        assert!(e.contains("not among the shard's units"), "{e}");
        let bytes = fs::read(shards[0].join(HEATMAPS_BIN)).unwrap();
        fs::write(swapped.join(HEATMAPS_BIN), &bytes[..bytes.len() - 3]).unwrap();
        let e = merge(&dirs, Some(&into), &load_quads)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the file ends in"), "{e}");
        assert!(!into.exists());
        let _ = fs::remove_dir_all(&out);
    }

    #[test]
    fn a_missing_duplicated_or_foreign_shard_is_an_error_naming_it() {
        let out = scratch("errors");
        let s: Vec<PathBuf> = (0..3)
            .map(|index| {
                run_into(
                    &out.join(format!("s{index}")),
                    Some(Shard { index, count: 3 }),
                )
            })
            .collect();
        let into = out.join("merged");
        let fails = |dirs: &[PathBuf]| {
            let e = merge(dirs, Some(&into), &load_quads).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            e.to_string()
        };
        let e = fails(&[s[0].clone(), s[2].clone()]);
        assert!(e.contains("shard 1/3 missing"), "{e}");
        let e = fails(&[s[0].clone(), s[1].clone(), s[1].clone(), s[2].clone()]);
        assert!(e.contains("shard 1/3 given twice"), "{e}");
        let whole = run_into(&out.join("whole"), None);
        let e = fails(&[s[0].clone(), whole.clone()]);
        assert!(
            e.contains(&whole.display().to_string()) && e.contains("not a shard"),
            "{e}"
        );
        // A shard of another sweep (one frame instead of two).
        let other = {
            let text = TEXT.replace("frames = 2", "frames = 1");
            let mut exp = Experiment::parse(Path::new("m.toml"), &text).unwrap();
            exp.output = out.join("other");
            let overrides = RunOverrides {
                shard: Some(Shard { index: 1, count: 3 }),
                ..RunOverrides::default()
            };
            run(&exp, &text, &overrides, &load_quads).unwrap()
        };
        let e = fails(&[s[0].clone(), other.clone(), s[2].clone()]);
        assert!(
            e.contains(&other.display().to_string()) && e.contains("not from the sweep"),
            "{e}"
        );
        // Nothing was left behind by the failed merges.
        assert!(!into.exists());
        let _ = fs::remove_dir_all(&out);
    }
}
