//! The numerical stability suite: stiff and extreme cases (`cases`) traced by every contender and
//! by the oracle (Embree, robust mode), each answer judged ray by ray against the oracle (the
//! verifier's tie classification) and against the f64 ground truth (`truth`), which decides who
//! is right where they disagree.
//!
//! Per case and contender, for closest hit and for occlusion: leaks (must-hit rays missed),
//! answers the f64 truth calls wrong (a certain hit missed, or a false hit), unexplained
//! disagreements with the oracle split by who the f64 truth says is right, crashes (a panic while
//! building or tracing, caught) and hangs (no answer within the time limit; the thread is left
//! behind). Ill-formed rays also get a slowdown: the time of the mixed batch over the time of its
//! good rays alone.

pub mod cases;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::geometry::{Hit, RayBatch};
use crate::tracers::{oracle_params, tracer_for_mesh, Params, ORACLE};
use crate::verify::compare::{self, Agreement, Judgement};
use crate::verify::truth::{Truth, Verdict};

pub use cases::{generate, Case, CaseKind, Sweep};

/// A tracer under test: its registry name and parameters, and how the tables name it.
#[derive(Clone, Debug)]
pub struct Contender {
    pub label: String,
    pub name: &'static str,
    pub params: Params,
}

/// Closest hit or occlusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    Closest,
    Occluded,
}

impl Query {
    pub fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Occluded => "occluded",
        }
    }
}

/// How a contender's run of one case ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Answered,
    /// The tracer refused the case with an error (e.g. a tree deeper than its stack).
    Refused(String),
    Crashed(String),
    Hung,
}

/// One row of stability.csv: a contender on one case and query.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub kind: CaseKind,
    pub variant: String,
    pub magnitude: f64,
    pub tracer: String,
    pub query: Query,
    pub status: Status,
    pub rays: usize,
    pub must_hit: usize,
    /// Must-hit rays answered with a miss.
    pub leaks: usize,
    /// Answers the f64 truth calls wrong: a certain hit missed …
    pub missed: usize,
    /// … or a hit where there is none (or not at that distance).
    pub false_hits: usize,
    /// Answers that differ from f64's only where rounding decides.
    pub rounding: usize,
    /// Disagreements with the oracle that are not ties, split by the f64 verdict: this tracer
    /// right, the oracle right, both within rounding, both wrong.
    pub unexplained: usize,
    pub unexplained_tracer_right: usize,
    pub unexplained_oracle_right: usize,
    pub unexplained_rounding: usize,
    pub unexplained_both_wrong: usize,
    /// Trace time of the batch (one thread).
    pub seconds: f64,
    /// Ill-formed case only: mixed-batch time over the good rays' time alone.
    pub slowdown: Option<f64>,
}

/// What a contender answered on a case.
struct Answers {
    hits: Vec<Hit>,
    occluded: Vec<bool>,
    seconds: f64,
    slowdown: Option<f64>,
}

/// Runs every contender on every case; `timeout` bounds each contender's build and trace of one
/// case. Calls `progress` after each (case, contender).
pub fn run(
    cases: Vec<Case>,
    contenders: &[Contender],
    timeout: Duration,
    progress: &(dyn Fn(&Case, &Contender) + Sync),
) -> Vec<Outcome> {
    let oracle = Contender {
        label: "oracle".into(),
        name: ORACLE,
        params: oracle_params(),
    };
    let mut outcomes = Vec::new();
    for case in cases {
        let case = Arc::new(case);
        let truths: Vec<Truth> = (0..case.rays.len())
            .into_par_iter()
            .map(|i| Truth::of(&case.mesh, &case.rays.ray(i)))
            .collect();
        let reference = match answer(&case, &oracle, timeout) {
            Ok(a) => a,
            Err(status) => {
                // Without the oracle nothing can be compared: every contender gets its status.
                for c in contenders {
                    for query in [Query::Closest, Query::Occluded] {
                        outcomes.push(empty(&case, c, query, status.clone()));
                    }
                }
                continue;
            }
        };
        for contender in contenders {
            match answer(&case, contender, timeout) {
                Ok(a) => {
                    for query in [Query::Closest, Query::Occluded] {
                        outcomes.push(tally(&case, contender, query, &a, &reference, &truths));
                    }
                }
                Err(status) => {
                    for query in [Query::Closest, Query::Occluded] {
                        outcomes.push(empty(&case, contender, query, status.clone()));
                    }
                }
            }
            progress(&case, contender);
        }
    }
    outcomes
}

fn empty(case: &Case, contender: &Contender, query: Query, status: Status) -> Outcome {
    Outcome {
        kind: case.kind,
        variant: case.variant.clone(),
        magnitude: case.magnitude,
        tracer: contender.label.clone(),
        query,
        status,
        rays: case.rays.len(),
        must_hit: case.must_hit.iter().filter(|&&m| m).count(),
        leaks: 0,
        missed: 0,
        false_hits: 0,
        rounding: 0,
        unexplained: 0,
        unexplained_tracer_right: 0,
        unexplained_oracle_right: 0,
        unexplained_rounding: 0,
        unexplained_both_wrong: 0,
        seconds: 0.0,
        slowdown: None,
    }
}

/// Builds the contender's tracer over the case's mesh and traces its rays (closest hit, then
/// occlusion), guarded.
fn answer(case: &Arc<Case>, contender: &Contender, timeout: Duration) -> Result<Answers, Status> {
    let case = Arc::clone(case);
    let contender = contender.clone();
    guarded(&contender.label.clone(), timeout, move || {
        trace(&case, &contender)
    })
}

/// Runs `work` on a thread of its own, so a panic is caught (a crash, with its message) and a
/// hang is abandoned after `timeout` (the thread is left behind).
fn guarded<T: Send + 'static>(
    label: &str,
    timeout: Duration,
    work: impl FnOnce() -> Result<T, Status> + Send + 'static,
) -> Result<T, Status> {
    let (send, receive) = mpsc::channel();
    let worker = std::thread::Builder::new()
        .name(format!("stability {label}"))
        .spawn(move || {
            let result = catch_unwind(AssertUnwindSafe(work)).unwrap_or_else(|panic| {
                let message = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "panic".into());
                Err(Status::Crashed(message))
            });
            let _ = send.send(result);
        });
    if let Err(e) = worker {
        return Err(Status::Crashed(format!("cannot start a thread: {e}")));
    }
    receive.recv_timeout(timeout).unwrap_or(Err(Status::Hung))
}

fn trace(case: &Case, contender: &Contender) -> Result<Answers, Status> {
    let tracer = tracer_for_mesh(contender.name, &contender.params, &case.mesh)
        .map_err(|e| Status::Refused(e.to_string()))?;
    let rays = case.rays.view();
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut occluded = vec![false; rays.len()];
    let start = Instant::now();
    tracer.intersect(rays, &mut hits);
    let seconds = start.elapsed().as_secs_f64();
    tracer.occluded(rays, &mut occluded);
    let slowdown = (case.kind == CaseKind::IllFormed).then(|| {
        let good = good_rays(&case.rays);
        let mut scratch = vec![Hit::MISS; rays.len()];
        let mut time = |batch: &RayBatch| {
            let start = Instant::now();
            tracer.intersect(batch.view(), &mut scratch[..batch.len()]);
            start.elapsed().as_secs_f64()
        };
        // Alternating runs, the minimum of each: drift and other processes' load cancel.
        let (mut mixed, mut alone) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..15 {
            mixed = mixed.min(time(&case.rays));
            alone = alone.min(time(&good));
        }
        mixed / alone.max(1e-9)
    });
    Ok(Answers {
        hits,
        occluded,
        seconds,
        slowdown,
    })
}

/// The well-formed rays of a batch, in order.
fn good_rays(batch: &RayBatch) -> RayBatch {
    let mut good = RayBatch::with_capacity(batch.kind(), batch.len());
    for i in 0..batch.len() {
        let ray = batch.ray(i);
        if ray.is_well_formed() {
            good.push(ray, batch.pixel[i]);
        }
    }
    good
}

fn tally(
    case: &Case,
    contender: &Contender,
    query: Query,
    answers: &Answers,
    oracle: &Answers,
    truths: &[Truth],
) -> Outcome {
    let mut o = empty(case, contender, query, Status::Answered);
    o.seconds = answers.seconds;
    o.slowdown = answers.slowdown;
    for (i, truth) in truths.iter().enumerate() {
        let ray = case.rays.ray(i);
        let (hit, reference) = (&answers.hits[i], &oracle.hits[i]);
        let (verdict, oracle_verdict, agreement) = match query {
            Query::Closest => (
                truth.judge_closest(hit),
                truth.judge_closest(reference),
                compare::closest(&case.mesh, &ray, hit, reference),
            ),
            Query::Occluded => (
                truth.judge_occluded(answers.occluded[i]),
                truth.judge_occluded(oracle.occluded[i]),
                compare::occlusion(
                    &case.mesh,
                    &ray,
                    answers.occluded[i],
                    oracle.occluded[i],
                    hit,
                    reference,
                ),
            ),
        };
        let answered_hit = match query {
            Query::Closest => hit.is_hit(),
            Query::Occluded => answers.occluded[i],
        };
        if case.must_hit[i] && !answered_hit {
            o.leaks += 1;
        }
        match verdict {
            Verdict::Right => {}
            Verdict::Rounding => o.rounding += 1,
            Verdict::Missed => o.missed += 1,
            Verdict::FalseHit => o.false_hits += 1,
        }
        if let Agreement::Unexplained(..) = agreement {
            o.unexplained += 1;
            match Judgement::of(verdict, oracle_verdict) {
                Judgement::OursRight => o.unexplained_tracer_right += 1,
                Judgement::OursWrong => o.unexplained_oracle_right += 1,
                Judgement::Rounding => o.unexplained_rounding += 1,
                Judgement::Undecided => o.unexplained_both_wrong += 1,
            }
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contender(name: &'static str, params: Params) -> Contender {
        Contender {
            label: name.into(),
            name,
            params,
        }
    }

    /// The reference tracer on the watertight and ill-formed cases at the origin: no leak, no
    /// wrong answer (every ill-formed ray a miss); Embree without robust mode gets its rows too.
    #[test]
    fn the_reference_tracer_is_watertight_and_misses_ill_formed_rays() {
        let sweep = Sweep {
            kinds: vec![CaseKind::Watertight, CaseKind::IllFormed],
            offsets: vec![0.0],
            scales: vec![1.0],
            ..Sweep::default()
        };
        let contenders = [
            contender("reference", Params::new()),
            contender("embree1", Params::new().with("robust", "false")),
        ];
        let outcomes = run(
            generate(&sweep),
            &contenders,
            Duration::from_secs(60),
            &|_, _| {},
        );
        assert_eq!(outcomes.len(), 3 * 2 * 2);
        for o in outcomes.iter().filter(|o| o.tracer == "reference") {
            assert_eq!(o.status, Status::Answered);
            assert!(o.must_hit > 1000, "{o:?}");
            assert_eq!((o.leaks, o.missed, o.false_hits), (0, 0, 0), "{o:?}");
            // Timed, so only its presence is asserted; the suite's table reports it.
            assert_eq!(o.slowdown.is_some(), o.kind == CaseKind::IllFormed, "{o:?}");
        }
    }

    /// A panic while building or tracing is caught and reported as a crash, and a hang as a
    /// hang, without taking the suite down.
    #[test]
    fn crashes_and_hangs_are_reported_not_fatal() {
        let sweep = Sweep {
            kinds: vec![CaseKind::IllFormed],
            offsets: vec![0.0],
            ..Sweep::default()
        };
        let case = Arc::new(generate(&sweep).remove(0));
        let second = Duration::from_secs(1);
        let crashed = guarded::<()>("t", second, || panic!("boom"));
        assert_eq!(crashed, Err(Status::Crashed("boom".into())));
        let hung = guarded::<()>("t", Duration::from_millis(50), || {
            std::thread::sleep(Duration::from_secs(2));
            Ok(())
        });
        assert_eq!(hung, Err(Status::Hung));
        assert_eq!(guarded("t", second, || Ok(7)), Ok(7));
        let unknown = contender("no-such-tracer", Params::new());
        assert!(matches!(
            answer(&case, &unknown, Duration::from_secs(5)).err(),
            Some(Status::Refused(_))
        ));
    }
}
