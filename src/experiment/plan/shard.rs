//! Sweeps split across machines: `raylab run EXP --shard i/n` measures the i-th of n disjoint parts
//! of the plan, and `raylab merge` (see `merge`) joins the n results into one.
//!
//! The unit of work is one tracer instance on one scene, over every frame, ray kind, ray file,
//! render workload and thread count: a structure's frames stay together (reuse and refit chains
//! are unchanged) and a part builds only the structures of its own units, plus the reference BVH
//! that generates secondary rays. Units go to parts by longest-first greedy balancing of an
//! estimated cost (`unit_cost`), a deterministic function of the plan, so every shard computes the
//! same split without talking to the others. Ray seeds depend on the experiment, frame and ray kind
//! only, so a shard traces exactly the rays an unsharded run traces.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use crate::experiment::plan::overrides::RunOverrides;
use crate::experiment::plan::Plan;
use crate::experiment::record::digest::digest;

/// Part `index` of `count` (`index/count` on the command line, counted from 0 like
/// `$SLURM_ARRAY_TASK_ID`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Parses `i/n` with 0 ≤ i < n.
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || {
            Error::usage(format!(
                "--shard {text:?}: expected i/n with 0 ≤ i < n (e.g. 3/16)"
            ))
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        match index < count {
            true => Ok(Shard { index, count }),
            false => Err(bad()),
        }
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// What a shard's meta.json records so that `raylab merge` can check its inputs belong together.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardMeta {
    pub index: usize,
    pub count: usize,
    /// `sweep_key` of the run.
    pub sweep: String,
    /// The (scene, instance) units this part measured, as plan indices.
    pub units: Vec<(usize, usize)>,
}

/// The digest of what decides a sweep's measurements: the experiment file as written and the
/// overrides that change numbers (not where results go, nor which shard this is). Shards of one
/// sweep share it; merging shards of different sweeps is refused.
pub fn sweep_key(file_text: &str, overrides: &RunOverrides) -> String {
    let numbers_only = RunOverrides {
        output: None,
        shard: None,
        dump_rays: false,
        ..overrides.clone()
    };
    let overrides = serde_json::to_string(&numbers_only).unwrap_or_default();
    digest([file_text.as_bytes(), overrides.as_bytes()])
}

/// Which (scene, instance) units of a plan one run measures.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// `[scene][instance]`.
    measured: Vec<Vec<bool>>,
}

impl Part {
    /// Every unit: an unsharded run.
    pub fn whole(plan: &Plan) -> Part {
        Part {
            measured: vec![vec![true; plan.instances.len()]; plan.scenes.len()],
        }
    }

    /// The units of `shard`: longest estimated cost first, each to the part with the least
    /// estimated work so far (the lowest index on ties).
    pub fn of(plan: &Plan, shard: Shard) -> Part {
        let mut units: Vec<((usize, usize), f64)> = (0..plan.scenes.len())
            .flat_map(|s| (0..plan.instances.len()).map(move |i| (s, i)))
            .map(|unit| (unit, unit_cost(plan, unit.0)))
            .collect();
        // Stable: equal costs keep plan order, so the split is the same on every machine.
        units.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut load = vec![0.0f64; shard.count];
        let mut part = Part {
            measured: vec![vec![false; plan.instances.len()]; plan.scenes.len()],
        };
        for ((scene, instance), cost) in units {
            let lightest = (0..shard.count)
                .min_by(|&a, &b| load[a].total_cmp(&load[b]))
                .expect("a shard count is at least 1");
            load[lightest] += cost;
            part.measured[scene][instance] = lightest == shard.index;
        }
        part
    }

    pub fn measures(&self, scene: usize, instance: usize) -> bool {
        self.measured[scene][instance]
    }

    pub fn measures_scene(&self, scene: usize) -> bool {
        self.measured[scene].iter().any(|&m| m)
    }

    /// The units measured, in plan order.
    pub fn units(&self) -> Vec<(usize, usize)> {
        self.measured
            .iter()
            .enumerate()
            .flat_map(|(s, row)| {
                row.iter()
                    .enumerate()
                    .filter(|(_, &m)| m)
                    .map(move |(i, _)| (s, i))
            })
            .collect()
    }

    /// Timed measurements of this part: the progress bar's length (see `Plan::measurements`).
    pub fn measurements(&self, plan: &Plan) -> usize {
        let per_kind = plan.frames * plan.threads.len();
        self.units()
            .iter()
            .map(|&(s, _)| {
                let scene = &plan.scenes[s];
                (scene.ray_kinds.len() + plan.ray_files.len() + plan.renders.len()) * per_kind
            })
            .sum()
    }
}

/// An estimate of one tracer instance's work on scene `s`, in arbitrary units: every timed,
/// warm-up and counting pass over every frame traces each ray kind's pixels at a cost growing
/// with log(triangles); a render workload counts as four ray kinds (it traces several bounces);
/// builds cost triangles × log(triangles) each. Only the ratios between units matter.
fn unit_cost(plan: &Plan, s: usize) -> f64 {
    let scene = &plan.scenes[s];
    let triangles = scene.triangles as f64;
    let log = (triangles + 2.0).log2();
    let pixels = plan.width as f64 * plan.height as f64;
    let kinds = scene.ray_kinds.len() + plan.ray_files.len() + 4 * plan.renders.len();
    let passes = (plan.warmup + plan.repeats) * plan.threads.len() + 1;
    let builds = if scene.rebuild_per_frame {
        plan.frames
    } else {
        1
    };
    plan.frames as f64 * kinds as f64 * pixels * log * passes as f64
        + builds as f64 * triangles * log
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::plan::tests::{experiment, load_quads};

    #[test]
    fn shard_arguments_are_checked() {
        assert_eq!(
            Shard::parse("3/16").unwrap(),
            Shard {
                index: 3,
                count: 16
            }
        );
        for bad in ["16/16", "1", "a/2", "-1/2", "0/0", "1/2/3"] {
            let e = Shard::parse(bad).unwrap_err();
            assert!(e.to_string().contains(bad), "{e}");
            assert_eq!(e.exit_code(), 2);
        }
    }

    #[test]
    fn parts_are_disjoint_cover_the_plan_and_balance_by_cost() {
        let exp = experiment(
            "scenes = [\"lit\", \"dark\", \"moving\"]\ntracers = [\"reference\", \"obvhs\", \"embree1\"]\nrays = [\"primary\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let parts: Vec<Part> = (0..3)
            .map(|index| Part::of(&plan, Shard { index, count: 3 }))
            .collect();
        for s in 0..3 {
            for i in 0..3 {
                let owners = parts.iter().filter(|p| p.measures(s, i)).count();
                assert_eq!(owners, 1, "scene {s} instance {i}");
            }
        }
        // The same split every time.
        assert_eq!(parts[1], Part::of(&plan, Shard { index: 1, count: 3 }));
        // Nine units over three parts: every part gets some, and the estimated work of the
        // heaviest part is within one unit's cost of the lightest.
        let load = |p: &Part| -> f64 { p.units().iter().map(|&(s, _)| unit_cost(&plan, s)).sum() };
        let heaviest_unit = (0..3).map(|s| unit_cost(&plan, s)).fold(0.0, f64::max);
        let loads: Vec<f64> = parts.iter().map(load).collect();
        let (lo, hi) = (
            loads.iter().copied().fold(f64::MAX, f64::min),
            loads.iter().copied().fold(0.0, f64::max),
        );
        assert!(lo > 0.0 && hi - lo <= heaviest_unit, "{loads:?}");
        let whole = Part::whole(&plan);
        assert_eq!(whole.units().len(), 9);
        assert_eq!(
            parts.iter().map(|p| p.measurements(&plan)).sum::<usize>(),
            plan.measurements()
        );
        // More parts than units: the extra parts are empty.
        let empty = Part::of(
            &plan,
            Shard {
                index: 9,
                count: 10,
            },
        );
        assert!(empty.units().is_empty());
    }

    #[test]
    fn the_sweep_key_ignores_where_results_go_and_which_shard() {
        let base = RunOverrides::default();
        let elsewhere = RunOverrides {
            output: Some("/scratch".into()),
            shard: Some(Shard { index: 1, count: 4 }),
            ..RunOverrides::default()
        };
        let fewer_frames = RunOverrides {
            frames: Some(1),
            ..RunOverrides::default()
        };
        assert_eq!(sweep_key("x", &base), sweep_key("x", &elsewhere));
        assert_ne!(sweep_key("x", &base), sweep_key("x", &fewer_frames));
        assert_ne!(sweep_key("x", &base), sweep_key("y", &base));
    }
}
