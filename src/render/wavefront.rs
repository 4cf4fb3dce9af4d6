//! Breadth-first tracing: a renderer hands the tracer one whole batch at a time (a wavefront) —
//! camera rays, then the shadow, reflection or refraction rays they spawn, or a light-visibility
//! query — and gets every answer back before it shades. Whitted, distribution and the runner's
//! ray batches all trace through `answer`, so a timed pass, a counted pass and a rendered frame
//! split the work the same way (`tracers::chunked`).

use std::time::Instant;

use crate::geometry::{Hit, RayBatch};
use crate::render::assembly::BatchKind;
use crate::stats::Counters;
use crate::tracers::chunked::{counted_pass, pass, visibility_pass};
use crate::tracers::visibility::Visibility;
use crate::tracers::{Tracer, VisibilityQuery};

/// Whether the tracer's plain (timed) or counting calls are used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tracing {
    Timed,
    Counted,
}

/// What a tracer is asked about a whole wavefront.
#[derive(Clone, Copy, Debug)]
pub enum Work<'a> {
    /// The closest hit of every ray.
    Closest(&'a RayBatch),
    /// Whether anything lies on each ray (shadow rays).
    Occlusion(&'a RayBatch),
    /// Which light samples each shading point sees.
    LightVisibility(VisibilityQuery<'a>),
}

impl<'a> Work<'a> {
    /// What a batch of this kind asks: occlusion for shadow rays, closest hits otherwise.
    pub fn of_batch(batch: &'a RayBatch) -> Self {
        match batch.kind().is_occlusion() {
            true => Work::Occlusion(batch),
            false => Work::Closest(batch),
        }
    }

    /// Rays this work traces (a visibility query: the samples in front of their surface).
    pub fn rays(&self) -> usize {
        match self {
            Work::Closest(batch) | Work::Occlusion(batch) => batch.len(),
            Work::LightVisibility(query) => query.ray_count(),
        }
    }
}

/// The tracer's answers for one wavefront.
#[derive(Clone, Debug, PartialEq)]
pub enum Answers {
    Hits(Vec<Hit>),
    Occluded(Vec<bool>),
    Visibility(Visibility),
}

impl Answers {
    /// Answers for `work`, before tracing.
    pub fn blank(work: &Work<'_>) -> Answers {
        match work {
            Work::Closest(batch) => Answers::Hits(vec![Hit::MISS; batch.len()]),
            Work::Occlusion(batch) => Answers::Occluded(vec![false; batch.len()]),
            Work::LightVisibility(query) => {
                Answers::Visibility(Visibility::new(query.len(), query.samples))
            }
        }
    }

    /// Whether ray `i` met anything: what a shadow ray asks.
    pub fn blocked(&self, i: usize) -> bool {
        match self {
            Answers::Hits(h) => h[i].is_hit(),
            Answers::Occluded(o) => o[i],
            Answers::Visibility(v) => v.occluded(i / v.per_point, i % v.per_point),
        }
    }

    /// Rays of `work` that met anything: closest-hit rays that hit, shadow rays that were
    /// occluded (a visibility query's samples behind their surface cast no ray: not counted).
    pub fn blocked_count(&self, work: &Work<'_>) -> usize {
        match self {
            Answers::Hits(h) => h.iter().filter(|h| h.is_hit()).count(),
            Answers::Occluded(o) => o.iter().filter(|&&o| o).count(),
            Answers::Visibility(v) => {
                let samples = v.points() * v.per_point;
                v.total_occluded() - (samples - work.rays())
            }
        }
    }
}

/// One pass of `tracer` over `work` into `answers` (from `Answers::blank(work)`), in the current
/// pool: the plain calls, or with `counters` the counting ones, merged into them.
pub fn answer(
    tracer: &dyn Tracer,
    work: Work<'_>,
    answers: &mut Answers,
    counters: Option<&mut Counters>,
) {
    let chunk = tracer.chunk_rays();
    // Whether the counters charge each count to its ray too (`Counters::attributing`).
    let per_ray = counters.as_ref().is_some_and(|c| c.per_ray.is_some());
    match (work, answers, counters) {
        (Work::Closest(batch), Answers::Hits(out), None) => {
            pass(batch.view(), out, chunk, &|r, h| tracer.intersect(r, h))
        }
        (Work::Closest(batch), Answers::Hits(out), Some(c)) => c.merge(&counted_pass(
            batch.view(),
            out,
            chunk,
            per_ray,
            &|r, h, c| tracer.intersect_counted(r, h, c),
        )),
        (Work::Occlusion(batch), Answers::Occluded(out), None) => {
            pass(batch.view(), out, chunk, &|r, o| tracer.occluded(r, o))
        }
        (Work::Occlusion(batch), Answers::Occluded(out), Some(c)) => c.merge(&counted_pass(
            batch.view(),
            out,
            chunk,
            per_ray,
            &|r, o, c| tracer.occluded_counted(r, o, c),
        )),
        (Work::LightVisibility(query), Answers::Visibility(v), counters) => {
            visibility_pass(tracer, query, &mut v.words, counters)
        }
        (work, answers, _) => unreachable!(
            "answers from Answers::blank(work): {work:?} with {}",
            match answers {
                Answers::Hits(_) => "hits",
                Answers::Occluded(_) => "occlusion flags",
                Answers::Visibility(_) => "visibility bits",
            }
        ),
    }
}

/// One traced wavefront of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchRecord {
    pub kind: BatchKind,
    pub depth: u32,
    pub rays: usize,
    /// Closest-hit rays that hit something, shadow rays that were occluded (blind batches: rays
    /// that hit something within their interval).
    pub hits: usize,
    /// Wall time of the tracer's pass over the batch.
    pub seconds: f64,
    /// The tracer's counters (`Tracing::Counted` only; zero otherwise).
    pub counters: Counters,
}

impl BatchRecord {
    /// Adds `other`'s rays, hits, time and counters: another wave of the same kind and depth.
    pub fn add(&mut self, other: &BatchRecord) {
        self.rays += other.rays;
        self.hits += other.hits;
        self.seconds += other.seconds;
        self.counters.merge(&other.counters);
    }
}

/// Traces `work` (a wavefront of `kind` at bounce `depth`), timing the pass or counting it;
/// returns the answers and the wavefront's record.
pub fn trace(
    tracer: &dyn Tracer,
    work: Work<'_>,
    kind: BatchKind,
    depth: u32,
    tracing: Tracing,
) -> (Answers, BatchRecord) {
    let mut answers = Answers::blank(&work);
    let mut counters = Counters::default();
    let start = Instant::now();
    let counting = (tracing == Tracing::Counted).then_some(&mut counters);
    answer(tracer, work, &mut answers, counting);
    let seconds = start.elapsed().as_secs_f64();
    let record = BatchRecord {
        kind,
        depth,
        rays: work.rays(),
        hits: answers.blocked_count(&work),
        seconds,
        counters,
    };
    (answers, record)
}
