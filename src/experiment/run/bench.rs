//! `raylab bench`: one tracer on one ray file, timed in seconds — the inner loop of kernel work.
//! The passes are the runner's (`passes`: warm-up, then timed passes of the counter-free kernel,
//! a baseline's rays staged untimed), so a number here is the number a run would record; the
//! counting pass is optional. `tools/ab` alternates two binaries on it, `tools/callgrind` runs it
//! with no timed pass and with one to count the instructions of one pass.

use rayon::ThreadPoolBuilder;

use crate::error::{Error, Result};
use crate::geometry::RayBatch;
use crate::render::wavefront::Work;
use crate::stats::Counters;
use crate::tracers::Tracer;

use super::passes::{count_pass, time_passes, Timing};

/// How to bench.
#[derive(Clone, Copy, Debug)]
pub struct BenchSettings {
    pub threads: usize,
    pub warmup: usize,
    /// Timed passes; 0 times nothing (what `tools/callgrind` subtracts).
    pub repeats: usize,
    /// Whether to run one counting pass too.
    pub counters: bool,
}

/// What a bench measured.
#[derive(Clone, Debug)]
pub struct Bench {
    pub rays: usize,
    pub timing: Option<Timing>,
    pub counters: Option<Counters>,
}

/// Times `tracer` on `batch` (closest hits, or occlusion for a shadow batch).
pub fn bench(tracer: &dyn Tracer, batch: &RayBatch, settings: BenchSettings) -> Result<Bench> {
    if settings.threads == 0 {
        return Err(Error::usage("--threads must be at least 1"));
    }
    let pool = ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| Error::runtime(format!("cannot start {} threads: {e}", settings.threads)))?;
    let work = Work::of_batch(batch);
    let timing = (settings.repeats > 0)
        .then(|| time_passes(&pool, tracer, work, settings.warmup, settings.repeats));
    let counters = settings
        .counters
        .then(|| count_pass(&pool, tracer, work).counters);
    Ok(Bench {
        rays: batch.len(),
        timing,
        counters,
    })
}

impl Bench {
    /// One line: rays, threads, the fastest and median pass and the rays per second of the
    /// fastest; then, with counters, nodes, box and triangle tests per ray.
    pub fn line(&self) -> String {
        let mut line = format!("{} rays", self.rays);
        if let Some(t) = &self.timing {
            let mrays = self.rays as f64 / t.seconds_min / 1e6;
            line += &format!(
                ", {} thread{}: min {:.3} ms, median {:.3} ms, {mrays:.2} Mrays/s",
                t.threads,
                if t.threads == 1 { "" } else { "s" },
                t.seconds_min * 1e3,
                t.seconds_median * 1e3
            );
        }
        if let Some(c) = &self.counters {
            let per_ray = |n: u64| n as f64 / c.rays.max(1) as f64;
            line += &format!(
                "; per ray: {:.2} nodes, {:.2} box tests, {:.2} triangle tests",
                per_ray(c.nodes_visited),
                per_ray(c.aabb_tests),
                per_ray(c.triangle_tests)
            );
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec3;

    use super::*;
    use crate::accel::{Bvh, BvhConfig};
    use crate::geometry::{Ray, RayKind, Triangle};
    use crate::tracers::reference::ReferenceTracer;

    /// Two rays at one triangle, one hitting and one missing: the counters are the reference's,
    /// worked by hand (one leaf, one triangle test per ray), and a bench with no timed pass
    /// times nothing.
    #[test]
    fn a_bench_times_and_counts_the_runners_passes() {
        let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let tracer = ReferenceTracer::new(Arc::new(Bvh::build(&[tri], BvhConfig::default())));
        let mut batch = RayBatch::new(RayKind::Primary);
        batch.push(
            Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
            0,
        );
        batch.push(
            Ray::new(Vec3::new(2.0, 2.0, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
            1,
        );
        let settings = BenchSettings {
            threads: 1,
            warmup: 1,
            repeats: 3,
            counters: true,
        };
        let b = bench(&tracer, &batch, settings).unwrap();
        let t = b.timing.as_ref().unwrap();
        assert!(t.seconds_min > 0.0 && t.seconds_min <= t.seconds_median);
        let c = b.counters.as_ref().unwrap();
        assert_eq!((c.rays, c.triangle_tests), (2, 1));
        assert!(
            b.line().starts_with("2 rays, 1 thread: min "),
            "{}",
            b.line()
        );
        let none = BenchSettings {
            repeats: 0,
            counters: false,
            ..settings
        };
        let b = bench(&tracer, &batch, none).unwrap();
        assert!(b.timing.is_none() && b.counters.is_none());
        assert_eq!(b.line(), "2 rays");
        let zero = BenchSettings {
            threads: 0,
            ..settings
        };
        assert!(bench(&tracer, &batch, zero).is_err());
    }
}
