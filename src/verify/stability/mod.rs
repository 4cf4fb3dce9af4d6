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
//!
//! Speed cliffs are failures (`speed_cliffs`): every contender's closest-hit time on a case is
//! recorded relative to `reference`'s on the same case; more than `CLIFF_RATIO` times slower than
//! `reference` there, and than its own time on the same case nearest the origin (the sweep's
//! smallest magnitude), is a cliff — a tracer that answers right but 1,000× slower than usual.
//!
//! Leaks and wrong answers are reported, never failures: so the contenders with `robust = false`
//! (ours with plain slabs and Möller–Trumbore, Embree's default build) take part like the others,
//! and their leaks are what the tables show against the robust rows.

pub mod cases;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::error;
use crate::geometry::{Hit, RayBatch};
#[cfg(test)]
use crate::scene::Mesh;
use crate::tracers::registry::{make_for_mesh, role_of};
use crate::tracers::{oracle_params, Params, Role, TracerConfig, TracerInfo, ORACLE};
use crate::verify::compare::{self, Agreement, Judgement};
use crate::verify::truth::{Truth, Verdict};

pub use cases::{generate, Case, CaseKind, Sweep};

/// A tracer under test: its registry entry, its parameters and the configuration parsed from
/// them once, and how the tables name it.
#[derive(Clone, Debug)]
pub struct Contender {
    pub label: String,
    pub info: &'static TracerInfo,
    pub params: Params,
    pub config: TracerConfig,
}

impl Contender {
    /// Tracer `info` with `params`, checked and parsed here.
    pub fn new(
        label: String,
        info: &'static TracerInfo,
        params: Params,
    ) -> error::Result<Contender> {
        let config = info.config(&params)?;
        Ok(Contender {
            label,
            info,
            params,
            config,
        })
    }

    /// Whether it runs robust tests (`TracerInfo::robust_tests`).
    fn robust(&self) -> bool {
        // The parameters were checked when the contender was made.
        self.info
            .robust_tests(&self.config, &self.params)
            .unwrap_or(true)
    }
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
    /// The contender's registry name (the tracer of `Role::Reference` is the cliffs' yardstick).
    pub tracer_name: &'static str,
    /// Whether it ran robust tests (`TracerInfo::robust_tests`): without them leaks are expected
    /// and reported (the fast tests are not watertight), and a fast reference is not the cliffs'
    /// yardstick.
    pub robust: bool,
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
    /// Closest-hit trace time of the batch (one thread; the least of up to 3 runs).
    pub seconds: f64,
    /// `seconds` over `reference`'s on the same case (`speed_cliffs`; none without a reference).
    pub relative_time: Option<f64>,
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
) -> error::Result<Vec<Outcome>> {
    let oracle = Contender::new("oracle".into(), TracerInfo::find(ORACLE)?, oracle_params())?;
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
    Ok(outcomes)
}

fn empty(case: &Case, contender: &Contender, query: Query, status: Status) -> Outcome {
    Outcome {
        kind: case.kind,
        variant: case.variant.clone(),
        magnitude: case.magnitude,
        tracer: contender.label.clone(),
        tracer_name: contender.info.name,
        robust: contender.robust(),
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
        relative_time: None,
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
    let tracer = make_for_mesh(
        contender.info,
        &contender.config,
        &contender.params,
        &case.mesh,
    )
    .map_err(|e| Status::Refused(e.to_string()))?;
    let rays = case.rays.view();
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut occluded = vec![false; rays.len()];
    // The least of up to 3 runs (fewer once a second is spent): a cliff is judged on it.
    let (mut seconds, mut spent) = (f64::INFINITY, 0.0);
    for _ in 0..3 {
        let start = Instant::now();
        tracer.intersect(rays, &mut hits);
        let t = start.elapsed().as_secs_f64();
        seconds = seconds.min(t);
        spent += t;
        if spent > 1.0 {
            break;
        }
    }
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

/// A contender more than this many times slower than `reference` on a case (and than itself near
/// the origin) has a speed cliff.
pub const CLIFF_RATIO: f64 = 10.0;
/// Trace times under this are never cliffs: timer resolution and scheduling noise.
pub const CLIFF_MIN_SECONDS: f64 = 0.01;

/// Whether `o` is the yardstick's: the tracer of `Role::Reference`.
fn is_reference(o: &Outcome) -> bool {
    role_of(o.tracer_name) == Some(Role::Reference)
}

/// A speed cliff: a contender on a case, its time, and the two ratios that make it one.
#[derive(Clone, Debug, PartialEq)]
pub struct Cliff {
    pub kind: CaseKind,
    pub variant: String,
    pub magnitude: f64,
    pub tracer: String,
    pub seconds: f64,
    /// Over `reference`'s time on the same case.
    pub vs_reference: f64,
    /// Over its own time on the same case kind and variant at the sweep's smallest magnitude.
    pub vs_origin: f64,
}

/// Sets every answered closest-hit outcome's `relative_time` (over the `reference` contender's on
/// the same case) and returns the speed cliffs: more than `CLIFF_RATIO`× `reference` and more
/// than `CLIFF_RATIO`× the contender's own time on the same kind and variant at the sweep's
/// smallest magnitude (the origin, for offsets), and at least `CLIFF_MIN_SECONDS`. Without a
/// `reference` contender nothing is relative and nothing is a cliff.
pub fn speed_cliffs(outcomes: &mut [Outcome]) -> Vec<Cliff> {
    let timed = |o: &Outcome| o.query == Query::Closest && o.status == Status::Answered;
    let same_case = |a: &Outcome, b: &Outcome| {
        a.kind == b.kind && a.variant == b.variant && a.magnitude == b.magnitude
    };
    // The yardstick's rows, looked up in the registry once, not once per pair.
    let yardsticks: Vec<&Outcome> = outcomes
        .iter()
        .filter(|r| timed(r) && r.robust && is_reference(r))
        .collect();
    let reference: Vec<Option<f64>> = outcomes
        .iter()
        .map(|o| {
            yardsticks
                .iter()
                .find(|r| same_case(r, o))
                .map(|r| r.seconds)
        })
        .collect();
    // Own time at the smallest magnitude of the same kind and variant.
    let origin: Vec<Option<f64>> = outcomes
        .iter()
        .map(|o| {
            outcomes
                .iter()
                .filter(|h| {
                    timed(h) && h.tracer == o.tracer && h.kind == o.kind && h.variant == o.variant
                })
                .min_by(|a, b| a.magnitude.total_cmp(&b.magnitude))
                .map(|h| h.seconds)
        })
        .collect();
    let mut cliffs = Vec::new();
    for (i, o) in outcomes.iter_mut().enumerate() {
        let (Some(r), Some(home)) = (reference[i], origin[i]) else {
            continue;
        };
        if !timed(o) {
            continue;
        }
        let floor = |t: f64| t.max(f64::MIN_POSITIVE);
        o.relative_time = Some(o.seconds / floor(r));
        let (vs_reference, vs_origin) = (o.seconds / floor(r), o.seconds / floor(home));
        if o.seconds >= CLIFF_MIN_SECONDS && vs_reference > CLIFF_RATIO && vs_origin > CLIFF_RATIO {
            cliffs.push(Cliff {
                kind: o.kind,
                variant: o.variant.clone(),
                magnitude: o.magnitude,
                tracer: o.tracer.clone(),
                seconds: o.seconds,
                vs_reference,
                vs_origin,
            });
        }
    }
    cliffs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic sweep: `reference` 20 ms everywhere; `cliff` as fast at the origin and 50×
    /// slower at 10⁵ (a cliff); `slow` 50× slower everywhere (slow, not a cliff); `quick` 80×
    /// slower than itself at the origin but faster than `reference`; on a second variant where
    /// `reference` takes 0.1 ms, `noisy` is 50× slower than both at 5 ms (under the noise floor,
    /// not a cliff); `refused` never answered. A `reference` with `robust = false`, listed first
    /// and 5 s everywhere, is not the yardstick.
    #[test]
    fn a_tracer_ten_times_slower_than_reference_and_than_itself_at_the_origin_is_a_cliff() {
        let case = Case {
            kind: CaseKind::Grazing,
            variant: "square".into(),
            magnitude: 0.0,
            mesh: Mesh::default(),
            rays: RayBatch::default(),
            must_hit: vec![],
        };
        // Rows labelled `tracer`, of the reference tracer for "reference", else of another one.
        let row = |tracer: &'static str, magnitude: f64, seconds: f64, query: Query| {
            let name = if tracer == "reference" {
                tracer
            } else {
                "packet"
            };
            let c = Contender {
                label: tracer.into(),
                ..contender(name, Params::new())
            };
            let mut o = empty(&case, &c, query, Status::Answered);
            o.magnitude = magnitude;
            o.seconds = seconds;
            o
        };
        let tiny = |tracer: &'static str, magnitude: f64, seconds: f64| Outcome {
            variant: "tiny".into(),
            ..row(tracer, magnitude, seconds, Query::Closest)
        };
        let mut outcomes = vec![];
        for magnitude in [0.0, 1e5] {
            let far = magnitude > 0.0;
            outcomes.extend([
                Outcome {
                    tracer: "reference[robust=false]".into(),
                    robust: false,
                    ..row("reference", magnitude, 5.0, Query::Closest)
                },
                row("reference", magnitude, 0.02, Query::Closest),
                row("reference", magnitude, 0.02, Query::Occluded),
                row(
                    "cliff",
                    magnitude,
                    if far { 1.0 } else { 0.02 },
                    Query::Closest,
                ),
                row(
                    "cliff",
                    magnitude,
                    if far { 1.0 } else { 0.02 },
                    Query::Occluded,
                ),
                row("slow", magnitude, 1.0, Query::Closest),
                row(
                    "quick",
                    magnitude,
                    if far { 0.008 } else { 1e-4 },
                    Query::Closest,
                ),
                tiny("reference", magnitude, 1e-4),
                tiny("noisy", magnitude, if far { 5e-3 } else { 1e-4 }),
            ]);
        }
        outcomes.push(Outcome {
            status: Status::Refused("no".into()),
            ..row("refused", 1e5, 0.0, Query::Closest)
        });
        let cliffs = speed_cliffs(&mut outcomes);
        assert_eq!(cliffs.len(), 1, "{cliffs:?}");
        let c = &cliffs[0];
        assert_eq!((c.tracer.as_str(), c.magnitude), ("cliff", 1e5));
        assert_eq!(c.kind, CaseKind::Grazing);
        let near = |x: Option<f64>, y: f64| x.is_some_and(|x| (x - y).abs() < 1e-9 * y);
        assert!(
            near(Some(c.vs_reference), 50.0) && near(Some(c.vs_origin), 50.0),
            "{c:?}"
        );
        let relative = |tracer: &str, magnitude: f64, query: Query| {
            outcomes
                .iter()
                .find(|o| o.tracer == tracer && o.magnitude == magnitude && o.query == query)
                .unwrap()
                .relative_time
        };
        assert!(near(relative("cliff", 0.0, Query::Closest), 1.0));
        assert!(near(relative("cliff", 1e5, Query::Closest), 50.0));
        assert!(near(relative("slow", 1e5, Query::Closest), 50.0));
        assert!(near(relative("quick", 1e5, Query::Closest), 0.4));
        assert!(near(relative("reference", 0.0, Query::Closest), 1.0));
        assert!(near(
            relative("reference[robust=false]", 1e5, Query::Closest),
            250.0
        ));
        let noisy = outcomes
            .iter()
            .find(|o| o.tracer == "noisy" && o.magnitude == 1e5);
        assert!(near(noisy.unwrap().relative_time, 50.0));
        // Only closest-hit answers are timed.
        assert_eq!(relative("cliff", 1e5, Query::Occluded), None);
        assert_eq!(relative("refused", 1e5, Query::Closest), None);
    }

    fn contender(name: &'static str, params: Params) -> Contender {
        Contender::new(name.into(), TracerInfo::find(name).unwrap(), params).unwrap()
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
        let fast = || Params::new().with("robust", "false");
        let contenders = [
            contender("reference", Params::new()),
            contender("embree3-1", fast()),
            Contender {
                label: "reference[robust=false]".into(),
                ..contender("reference", fast())
            },
            contender("wide-single", fast()),
        ];
        let outcomes = run(
            generate(&sweep),
            &contenders,
            Duration::from_secs(60),
            &|_, _| {},
        )
        .unwrap();
        assert_eq!(outcomes.len(), 3 * 4 * 2);
        for o in outcomes.iter().filter(|o| o.tracer == "reference") {
            assert!(o.robust);
            assert_eq!(o.status, Status::Answered);
            assert!(o.must_hit > 1000, "{o:?}");
            assert_eq!((o.leaks, o.missed, o.false_hits), (0, 0, 0), "{o:?}");
            // Timed, so only its presence is asserted; the suite's table reports it.
            assert_eq!(o.slowdown.is_some(), o.kind == CaseKind::IllFormed, "{o:?}");
        }
        // Our fast tests answer every case and miss every ill-formed ray. On the watertight cases
        // (rays aimed at shared edges and vertices) they leak — 1,315 of the sphere's and 112 of
        // the cube's must-hit rays here — counted for the tables, not failed; wide-single's
        // verdicts are the fast reference's, so its leaks too.
        let fast: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.tracer != "reference" && o.tracer_name != "embree3-1")
            .collect();
        assert_eq!(fast.len(), 3 * 2 * 2);
        for o in &fast {
            assert!(!o.robust);
            assert_eq!(o.status, Status::Answered, "{o:?}");
            let leaks_like_the_reference = fast.iter().any(|r| {
                r.tracer_name == "reference"
                    && (&r.variant, r.query) == (&o.variant, o.query)
                    && r.leaks == o.leaks
            });
            assert!(leaks_like_the_reference, "{o:?}");
            match o.kind {
                CaseKind::IllFormed => {
                    assert_eq!((o.leaks, o.missed, o.false_hits), (0, 0, 0), "{o:?}")
                }
                _ => assert!(o.leaks > 0, "{o:?}"),
            }
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
        assert!(Contender::new(
            "x".into(),
            TracerInfo::find("reference").unwrap(),
            Params::new().with("lanes", 4)
        )
        .is_err());
        // A tracer that cannot be made (here: handed another family's configuration) is refused.
        let unmakeable = Contender {
            config: TracerConfig::Plain,
            ..contender("reference", Params::new())
        };
        assert!(matches!(
            answer(&case, &unmakeable, Duration::from_secs(5)).err(),
            Some(Status::Refused(_))
        ));
    }
}
