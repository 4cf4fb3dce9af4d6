//! "Embree at its best": for every runs.csv row, the fastest Embree row measured on the same work
//! in the same run — same scene (and size), frame, ray kind (or render batch and bounce depth, or
//! whole frame) and thread count — whatever its Embree version (3 or 4), entry point
//! (1/4/8/16/stream), context and build quality; its configuration names the tracer, and so the
//! version (`embree3-16`, `embree4-1`, ...). Every ratio raylab publishes is against it
//! (`x_embree_best`), never against one Embree configuration that happens to be slow. Groups the
//! run did not measure with Embree get empty cells. Computed from rows, so a merged sweep compares
//! with the fastest Embree row of the whole sweep, whichever shard measured it.
//!
//! Beside it, "baseline best": the fastest production baseline on the same work — the Embree
//! best, or a row of another baseline library (obvhs, tinybvh: `Role::Baseline`) when faster,
//! named by its tracer and parameters (`baseline_best_*`, `x_baseline_best`).

use std::collections::HashMap;

use crate::experiment::plan::{InstancePlan, Plan};
use crate::experiment::record::{Best, RunRow};
use crate::geometry::RayKind;
use crate::tracers::embree::Coherence;
use crate::tracers::registry::role_of;
use crate::tracers::{Role, TracerConfig};

/// Same scene (and size), frame, work and thread count.
type Group = (
    String,
    usize,
    usize,
    Option<String>,
    String,
    Option<u32>,
    usize,
);

fn group(row: &RunRow) -> Group {
    (
        row.scene.clone(),
        row.triangles,
        row.frame,
        row.render.clone(),
        row.ray_kind.clone(),
        row.bounce_depth,
        row.threads,
    )
}

/// Fills every row's `embree_best` and `embree_best_build_plus_trace` from the Embree rows among
/// `rows` (those whose instance in `plan` traverses an Embree scene).
pub fn fill(plan: &Plan, rows: &mut [RunRow]) {
    let mut trace: HashMap<Group, Best> = HashMap::new();
    let mut build_plus_trace: HashMap<Group, Best> = HashMap::new();
    for row in rows.iter() {
        let Some(instance) = plan
            .instance_of(&row.tracer, &row.parameters)
            .map(|i| &plan.instances[i])
            .filter(|i| i.structure.kind.is_embree())
        else {
            continue;
        };
        let config = config(instance, &row.ray_kind);
        let pass = (row.seconds_min, row.seconds_median);
        keep_faster(&mut trace, group(row), pass, &config);
        let with_build = (row.build_seconds + pass.0, row.build_seconds + pass.1);
        keep_faster(&mut build_plus_trace, group(row), with_build, &config);
    }
    // Embree best first, so Embree stays baseline best on a tie.
    let mut baseline = trace.clone();
    for row in rows.iter() {
        if role_of(&row.tracer) == Some(Role::Baseline) && plan_is_not_embree(plan, row) {
            let config = match row.parameters.is_empty() {
                true => row.tracer.clone(),
                false => format!("{} {}", row.tracer, row.parameters),
            };
            let pass = (row.seconds_min, row.seconds_median);
            keep_faster(&mut baseline, group(row), pass, &config);
        }
    }
    for row in rows.iter_mut() {
        row.embree_best = trace.get(&group(row)).cloned();
        row.embree_best_build_plus_trace = build_plus_trace.get(&group(row)).cloned();
        row.baseline_best = baseline.get(&group(row)).cloned();
    }
}

/// Whether the row's instance traverses a structure other than an Embree scene (obvhs's,
/// tinybvh's): those baseline rows are not in the Embree best.
fn plan_is_not_embree(plan: &Plan, row: &RunRow) -> bool {
    plan.instance_of(&row.tracer, &row.parameters)
        .is_some_and(|i| !plan.instances[i].structure.kind.is_embree())
}

/// Keeps the configuration with the fastest pass; `(seconds, median)` are its fastest and
/// median passes.
fn keep_faster(
    map: &mut HashMap<Group, Best>,
    group: Group,
    (seconds, median): (f64, f64),
    config: &str,
) {
    let slower = map.get(&group).is_none_or(|b| seconds < b.seconds);
    if slower {
        map.insert(
            group,
            Best {
                seconds,
                median,
                config: config.to_string(),
            },
        );
    }
}

/// The row's Embree configuration, with the context `auto` chose for its ray kind.
fn config(instance: &InstancePlan, ray_kind: &str) -> String {
    let kind = match ray_kind {
        // Blind batches are traced as reflection rays; a frame mixes kinds.
        "blind" => Some(RayKind::Reflection),
        "frame" => None,
        // Ray files are traced as batches of primary rays.
        file if file.starts_with("file:") => Some(RayKind::Primary),
        kind => RayKind::parse(kind),
    };
    let coherence = match instance.config {
        TracerConfig::Embree(coherence) => coherence,
        _ => Coherence::default(),
    };
    let mut parts = vec![instance.tracer.clone()];
    if !instance.params.0.is_empty() {
        parts.push(instance.params.to_string());
    }
    if let (Coherence::Auto, Some(kind)) = (coherence, kind) {
        parts.push(format!("(context {})", coherence.for_kind(kind)));
    }
    parts.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::plan::tests::{experiment, load_quads};

    /// A row of `instance` of `plan` on `kind` of `scene` at 1 and 2 threads with these fastest
    /// passes (seconds), built in `build` seconds.
    fn rows(
        plan: &Plan,
        instance: usize,
        scene: &str,
        kind: RayKind,
        build: f64,
        timings: &[(usize, f64)],
    ) -> Vec<RunRow> {
        let i = &plan.instances[instance];
        timings
            .iter()
            .map(|&(threads, seconds)| RunRow {
                experiment: plan.experiment.clone(),
                scene: scene.to_string(),
                triangles: 2,
                frame: 0,
                tracer: i.tracer.clone(),
                parameters: i.params.to_string(),
                structure: i.structure.to_string(),
                resolved: Some(i.resolved()),
                render: None,
                ray_kind: kind.name().to_string(),
                bounce_depth: Some(0),
                threads,
                rays: 100,
                hits: 0,
                seconds_min: seconds,
                seconds_median: seconds,
                generation_seconds: None,
                build_seconds: build,
                built: true,
                sah_cost: None,
                counted_rays: 100,
                nodes_visited: None,
                aabb_tests: None,
                triangle_tests: None,
                counting_seconds: None,
                rmse: None,
                retraced_share: None,
                events: Vec::new(),
                embree_best: None,
                embree_best_build_plus_trace: None,
                baseline_best: None,
            })
            .collect()
    }

    #[test]
    fn the_fastest_embree_row_of_each_group_with_its_configuration() {
        let exp = experiment(
            "scenes = [\"lit\", \"dark\"]\nrays = [\"primary\", \"shadow\"]\n\
             tracers = [\"reference\", \"embree1\", { name = \"embree16\", params = { context = [\"incoherent\"], quality = [\"high\"] } }]\n\
             threads = [1, 2]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let p = RayKind::Primary;
        let mut all = [
            rows(&plan, 0, "lit", p, 0.5, &[(1, 2.0), (2, 1.0)]),
            // embree1: faster at 1 thread, slower at 2; its build is cheaper.
            rows(&plan, 1, "lit", p, 0.1, &[(1, 1.0), (2, 0.8)]),
            rows(&plan, 2, "lit", p, 0.9, &[(1, 1.5), (2, 0.5)]),
            // Another scene: only the reference tracer, so no Embree best there.
            rows(&plan, 0, "dark", p, 0.5, &[(1, 3.0)]),
            // A shadow batch of the same scene is another group.
            rows(&plan, 0, "lit", RayKind::Shadow, 0.5, &[(1, 1.0)]),
        ]
        .concat();
        fill(&plan, &mut all);
        let best = |r: usize| all[r].embree_best.clone();
        assert_eq!(
            best(0),
            Some(Best {
                seconds: 1.0,
                median: 1.0,
                config: "embree3-1 (context coherent)".into()
            })
        );
        assert_eq!(
            best(1),
            Some(Best {
                seconds: 0.5,
                median: 0.5,
                config: "embree3-16 context=incoherent;quality=high".into()
            })
        );
        assert_eq!(best(6), None);
        assert_eq!(best(7), None);
        // Ratios: the reference at 1 thread is half as fast as the best; Embree's best row is 1.
        let ratio = |r: usize| Best::ratio(all[r].embree_best.as_ref(), all[r].seconds_min);
        assert_eq!(ratio(0), Some(0.5));
        assert_eq!(ratio(2), Some(1.0));
        assert!(ratio(4).unwrap() < 1.0);
        assert_eq!(ratio(6), None);
        // Build + trace: embree1 0.1 + 1.0 against embree16 0.9 + 1.5 at 1 thread; at 2 threads
        // embree1 0.9 against embree16 1.4.
        let bt = |r: usize| all[r].embree_best_build_plus_trace.clone().unwrap().seconds;
        assert_eq!((bt(0), bt(1)), (1.1, 0.9));
    }

    /// Baseline best: obvhs beats Embree at 2 threads and is named there; Embree stays baseline
    /// best where it is faster; the reference tracer, no baseline, is never it.
    #[test]
    fn baseline_best_is_the_fastest_production_baseline() {
        let exp = experiment(
            "scenes = [\"lit\"]\nrays = [\"primary\"]\n\
             tracers = [\"reference\", \"embree1\", \"obvhs\"]\nthreads = [1, 2]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let p = RayKind::Primary;
        let mut all = [
            rows(&plan, 0, "lit", p, 0.5, &[(1, 0.1), (2, 0.05)]),
            rows(&plan, 1, "lit", p, 0.1, &[(1, 1.0), (2, 0.8)]),
            rows(&plan, 2, "lit", p, 0.2, &[(1, 1.5), (2, 0.4)]),
        ]
        .concat();
        fill(&plan, &mut all);
        let best = |r: usize| all[r].baseline_best.clone().unwrap();
        assert_eq!(best(0).config, "embree3-1 (context coherent)");
        assert_eq!((best(1).seconds, best(1).config.as_str()), (0.4, "obvhs"));
        assert_eq!(all[1].embree_best.as_ref().unwrap().seconds, 0.8);
        assert_eq!(Best::ratio(all[1].baseline_best.as_ref(), 0.05), Some(8.0));
    }

    /// Embree 3 and Embree 4 on the same work: the best is whichever is faster at each thread
    /// count, its configuration naming the tracer and so the version.
    #[cfg(embree4)]
    #[test]
    fn the_best_is_picked_across_embree_3_and_4_and_names_which() {
        let exp = experiment(
            "scenes = [\"lit\"]\nrays = [\"primary\"]\n\
             tracers = [\"reference\", \"embree3-16\", \"embree4-16\"]\nthreads = [1, 2]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        use crate::accel::AccelKind;
        assert_eq!(plan.instances[2].structure.kind, AccelKind::Embree4);
        let p = RayKind::Primary;
        let mut all = [
            rows(&plan, 0, "lit", p, 0.5, &[(1, 2.0), (2, 1.0)]),
            rows(&plan, 1, "lit", p, 0.2, &[(1, 1.0), (2, 0.5)]),
            rows(&plan, 2, "lit", p, 0.1, &[(1, 0.8), (2, 0.6)]),
        ]
        .concat();
        fill(&plan, &mut all);
        let at = |r: usize| all[r].embree_best.clone().unwrap();
        assert_eq!(
            at(0),
            Best {
                seconds: 0.8,
                median: 0.8,
                config: "embree4-16 (context coherent)".into()
            }
        );
        assert_eq!(
            at(1),
            Best {
                seconds: 0.5,
                median: 0.5,
                config: "embree3-16 (context coherent)".into()
            }
        );
        // Build + trace at 1 thread: Embree 4, 0.1 + 0.8 against Embree 3's 0.2 + 1.0.
        let bt = all[0].embree_best_build_plus_trace.clone().unwrap();
        assert_eq!(
            (bt.seconds, bt.config.as_str()),
            (0.9, "embree4-16 (context coherent)")
        );
    }
}
