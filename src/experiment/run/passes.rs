//! Timing and counting one tracer on one wavefront (`render::wavefront::answer`: a batch or a
//! light-visibility query, split into chunks over a rayon pool); timed passes run the
//! counter-free kernel, one extra pass runs the counting kernel and merges the per-chunk counters.

use std::hint::black_box;
use std::time::Instant;

use rayon::ThreadPool;

use crate::experiment::record::selection::median_of_sorted;
use crate::render::wavefront::{answer, Answers, Work};
use crate::stats::Counters;
use crate::tracers::chunked::{stage_closest, stage_occlusion};
use crate::tracers::Tracer;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    pub threads: usize,
    pub seconds_min: f64,
    pub seconds_median: f64,
}

/// What one counting pass found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Counted {
    pub counters: Counters,
    /// Rays that hit something (closest hit) or were occluded (shadow rays).
    pub hits: usize,
    /// Wall time of the counting pass and its thread count: against a timed pass at the same
    /// thread count it gives the cost of counting.
    pub seconds: f64,
    pub threads: usize,
}

/// `warmup` untimed passes, then `repeats` timed ones, all in `pool`. The answers land in a
/// buffer passed to `black_box` after every pass, so no pass can be optimised away.
pub fn time_passes(
    pool: &ThreadPool,
    tracer: &dyn Tracer,
    work: Work<'_>,
    warmup: usize,
    repeats: usize,
) -> Timing {
    let mut answers = Answers::blank(&work);
    let seconds = pool.install(|| {
        for _ in 0..warmup {
            timed_pass(tracer, work, &mut answers);
        }
        (0..repeats)
            .map(|_| timed_pass(tracer, work, &mut answers))
            .collect()
    });
    timing_of(pool.current_num_threads(), seconds)
}

/// The seconds of one pass of `tracer` over `work`, in the current pool. A tracer with a layout
/// of its own (a baseline library's) gets the rays staged in it first, untimed
/// (`chunked::stage_*`): it is timed on rays as its user would hold them.
fn timed_pass(tracer: &dyn Tracer, work: Work<'_>, answers: &mut Answers) -> f64 {
    // Each staged batch is freed after its clock stops.
    let seconds = match (work, &mut *answers) {
        (Work::Closest(batch), Answers::Hits(hits)) => {
            stage_closest(tracer, batch.view()).map(|mut staged| seconds_of(|| staged.trace(hits)))
        }
        (Work::Occlusion(batch), Answers::Occluded(occluded)) => {
            stage_occlusion(tracer, batch.view())
                .map(|mut staged| seconds_of(|| staged.trace(occluded)))
        }
        _ => None,
    };
    let seconds = seconds.unwrap_or_else(|| seconds_of(|| answer(tracer, work, answers, None)));
    black_box(answers);
    seconds
}

/// Wall seconds of `f`.
fn seconds_of(f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64()
}

/// The fastest and the median of `seconds` (one per timed pass, at least one).
pub fn timing_of(threads: usize, mut seconds: Vec<f64>) -> Timing {
    seconds.sort_by(f64::total_cmp);
    Timing {
        threads,
        seconds_min: seconds[0],
        seconds_median: median_of_sorted(&seconds),
    }
}

/// One pass with the counting kernel, in `pool`.
pub fn count_pass(pool: &ThreadPool, tracer: &dyn Tracer, work: Work<'_>) -> Counted {
    let start = Instant::now();
    let mut answers = Answers::blank(&work);
    let mut counters = Counters::default();
    pool.install(|| answer(tracer, work, &mut answers, Some(&mut counters)));
    Counted {
        counters,
        hits: answers.blocked_count(&work),
        seconds: start.elapsed().as_secs_f64(),
        threads: pool.current_num_threads(),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec3;

    use super::*;
    use crate::accel::{Bvh, BvhConfig};
    use crate::geometry::{Ray, RayBatch, RayKind, Triangle};
    use crate::tracers::reference::ReferenceTracer;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median_of_sorted(&[1.0, 2.0, 9.0]), 2.0);
        assert_eq!(median_of_sorted(&[1.0, 2.0, 4.0, 9.0]), 3.0);
        assert_eq!(median_of_sorted(&[5.0]), 5.0);
    }

    #[test]
    fn counting_pass_merges_every_chunk() {
        // One triangle in the plane z = 0; 10000 rays (three chunks, the last partial) straight
        // down, every other one aimed beside it. A one-leaf BVH: each ray tests the root box; the
        // hitting half then visits the leaf and tests its one triangle.
        let tri = Triangle {
            v: [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
        };
        let tracer = ReferenceTracer::new(Arc::new(Bvh::build(&[tri], BvhConfig::default())));
        let mut batch = RayBatch::new(RayKind::Primary);
        for i in 0..10_000u32 {
            let x = if i % 2 == 0 { 0.25 } else { 5.0 };
            batch.push(
                Ray::new(Vec3::new(x, 0.25, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
                i,
            );
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let counted = count_pass(&pool, &tracer, Work::of_batch(&batch));
        assert_eq!(counted.hits, 5_000);
        assert_eq!(counted.counters.rays, 10_000);
        assert_eq!(counted.counters.aabb_tests, 10_000);
        assert_eq!(counted.counters.nodes_visited, 5_000);
        assert_eq!(counted.counters.triangle_tests, 5_000);

        batch.kind = Some(RayKind::Shadow);
        let counted = count_pass(&pool, &tracer, Work::of_batch(&batch));
        assert_eq!(counted.hits, 5_000);

        let timing = time_passes(&pool, &tracer, Work::of_batch(&batch), 1, 3);
        assert_eq!(timing.threads, 2);
        assert!(timing.seconds_min > 0.0 && timing.seconds_min <= timing.seconds_median);
    }
}
