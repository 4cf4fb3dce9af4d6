//! "Embree at its best": for every runs.csv row, the fastest Embree row measured on the same work
//! in the same run — same scene (and size), frame, ray kind (or render batch and bounce depth, or
//! whole frame) and thread count — whatever its Embree version (3 or 4), entry point
//! (1/4/8/16/stream), context and build quality; its configuration names the tracer, and so the
//! version (`embree3-16`, `embree4-1`, ...). Every ratio raylab publishes is against it (`x_embree_best`), never against one
//! Embree configuration that happens to be slow. Groups the run did not measure with Embree get
//! empty cells.

use std::collections::HashMap;

use crate::geometry::RayKind;
use crate::render::assembly::BatchKind;
use crate::tracers::embree::Coherence;

use super::measure::Timing;
use super::plan::{InstancePlan, Plan};
use super::runner::{Case, Traced};

/// The fastest Embree configuration of one group.
#[derive(Clone, Debug, PartialEq)]
pub struct Best {
    pub seconds: f64,
    /// `tracer parameters`, the intersect context it used spelled out (`context=auto` resolves
    /// per ray kind).
    pub config: String,
}

/// Same scene, frame, work and thread count.
type Group = (usize, usize, Traced, usize);

/// The fastest Embree row of every group, for tracing alone and for build + trace.
#[derive(Debug, Default)]
pub struct EmbreeBest {
    trace: HashMap<Group, Best>,
    build_plus_trace: HashMap<Group, Best>,
}

impl EmbreeBest {
    pub fn of(plan: &Plan, cases: &[Case]) -> EmbreeBest {
        let mut best = EmbreeBest::default();
        for case in cases {
            let instance = &plan.instances[case.instance];
            if !instance.structure.kind.is_embree() {
                continue;
            }
            let config = config(instance, case.traced);
            for timing in &case.timings {
                let group = group(case, timing);
                let build_plus_trace = case.build_seconds + timing.seconds_min;
                keep_faster(&mut best.trace, group, timing.seconds_min, &config);
                keep_faster(&mut best.build_plus_trace, group, build_plus_trace, &config);
            }
        }
        best
    }

    /// The fastest Embree tracing of the work of `case` at `timing`'s thread count.
    pub fn trace(&self, case: &Case, timing: &Timing) -> Option<&Best> {
        self.trace.get(&group(case, timing))
    }

    /// The fastest Embree build (or refit) + tracing of that work.
    pub fn build_plus_trace(&self, case: &Case, timing: &Timing) -> Option<&Best> {
        self.build_plus_trace.get(&group(case, timing))
    }
}

/// `best / seconds`: how many times faster than Embree at its best (> 1 is faster).
pub fn ratio(best: Option<&Best>, seconds: f64) -> Option<f64> {
    best.filter(|_| seconds > 0.0).map(|b| b.seconds / seconds)
}

fn group(case: &Case, timing: &Timing) -> Group {
    (case.scene, case.frame, case.traced, timing.threads)
}

fn keep_faster(map: &mut HashMap<Group, Best>, group: Group, seconds: f64, config: &str) {
    let slower = map.get(&group).is_none_or(|b| seconds < b.seconds);
    if slower {
        map.insert(
            group,
            Best {
                seconds,
                config: config.to_string(),
            },
        );
    }
}

/// The row's Embree configuration, with the context `auto` chose for its ray kind.
fn config(instance: &InstancePlan, traced: Traced) -> String {
    let kind = match traced {
        Traced::Batch(kind)
        | Traced::Render {
            batch: BatchKind::Rays(kind),
            ..
        } => Some(kind),
        // Blind batches are traced as reflection rays; a frame mixes kinds.
        Traced::Render {
            batch: BatchKind::Blind,
            ..
        } => Some(RayKind::Reflection),
        Traced::Frame { .. } => None,
        // Ray files are traced as batches of primary rays.
        Traced::File(_) => Some(RayKind::Primary),
    };
    let coherence = Coherence::from_params(&instance.params).unwrap_or_default();
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
    use crate::experiment::measure::Counted;
    use crate::experiment::plan::tests::{experiment, load_quads};

    fn timing(threads: usize, seconds: f64) -> Timing {
        Timing {
            threads,
            seconds_min: seconds,
            seconds_median: seconds,
        }
    }

    fn case(
        instance: usize,
        scene: usize,
        kind: RayKind,
        build: f64,
        timings: Vec<Timing>,
    ) -> Case {
        Case {
            scene,
            triangles: 2,
            frame: 0,
            instance,
            traced: Traced::Batch(kind),
            rays: 100,
            counted: Counted::default(),
            counts_internals: instance == 0,
            build_seconds: build,
            built: true,
            timings,
            rmse: None,
            retraced_share: None,
            checked: None,
        }
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
        let cases = vec![
            case(0, 0, p, 0.5, vec![timing(1, 2.0), timing(2, 1.0)]),
            // embree1: faster at 1 thread, slower at 2; its build is cheaper.
            case(1, 0, p, 0.1, vec![timing(1, 1.0), timing(2, 0.8)]),
            case(2, 0, p, 0.9, vec![timing(1, 1.5), timing(2, 0.5)]),
            // Another scene: only the reference tracer, so no Embree best there.
            case(0, 1, p, 0.5, vec![timing(1, 3.0)]),
        ];
        let best = EmbreeBest::of(&plan, &cases);
        let at = |c: usize, t: usize| best.trace(&cases[c], &cases[c].timings[t]);
        assert_eq!(
            at(0, 0),
            Some(&Best {
                seconds: 1.0,
                config: "embree3-1 (context coherent)".into()
            })
        );
        assert_eq!(
            at(0, 1),
            Some(&Best {
                seconds: 0.5,
                config: "embree3-16 context=incoherent;quality=high".into()
            })
        );
        assert_eq!(at(3, 0), None);
        // Ratios: the reference at 1 thread is half as fast as the best; Embree's best row is 1.
        assert_eq!(ratio(at(0, 0), 2.0), Some(0.5));
        assert_eq!(ratio(at(1, 0), 1.0), Some(1.0));
        assert!(ratio(at(2, 0), 1.5).unwrap() < 1.0);
        assert_eq!(ratio(at(3, 0), 3.0), None);
        // Build + trace: embree1 0.1 + 1.0 against embree16 0.9 + 1.5 at 1 thread; at 2 threads
        // embree1 0.9 against embree16 1.4.
        let bt = |t: usize| {
            best.build_plus_trace(&cases[0], &cases[0].timings[t])
                .unwrap()
        };
        assert_eq!((bt(0).seconds, bt(1).seconds), (1.1, 0.9));
        // A shadow batch of the same scene is another group.
        let shadow = case(0, 0, RayKind::Shadow, 0.5, vec![timing(1, 1.0)]);
        assert_eq!(best.trace(&shadow, &shadow.timings[0]), None);
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
        let cases = vec![
            case(0, 0, p, 0.5, vec![timing(1, 2.0), timing(2, 1.0)]),
            case(1, 0, p, 0.2, vec![timing(1, 1.0), timing(2, 0.5)]),
            case(2, 0, p, 0.1, vec![timing(1, 0.8), timing(2, 0.6)]),
        ];
        let best = EmbreeBest::of(&plan, &cases);
        let at = |t: usize| best.trace(&cases[0], &cases[0].timings[t]).unwrap();
        assert_eq!(
            at(0),
            &Best {
                seconds: 0.8,
                config: "embree4-16 (context coherent)".into()
            }
        );
        assert_eq!(
            at(1),
            &Best {
                seconds: 0.5,
                config: "embree3-16 (context coherent)".into()
            }
        );
        // Build + trace at 1 thread: Embree 4, 0.1 + 0.8 against Embree 3's 0.2 + 1.0.
        let bt = best
            .build_plus_trace(&cases[0], &cases[0].timings[0])
            .unwrap();
        assert_eq!(
            (bt.seconds, bt.config.as_str()),
            (0.9, "embree4-16 (context coherent)")
        );
    }
}
