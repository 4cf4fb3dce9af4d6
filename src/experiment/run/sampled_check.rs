//! The sampled check of every run: a few aligned blocks of each measured ray batch, traced by the
//! tracer instance and by the verification oracle (Embree, robust, high quality), compared ray by
//! ray with the verifier's classification (`verify::classify`): disagreements that are ties
//! (shared edges, grazed edges, range ends) are counted apart from unexplained ones, which the f64
//! truth judges (ours right, ours wrong, both within rounding, undecided). Cheap enough
//! for every run (at most `SAMPLE_RAYS` rays per scene × frame × instance × ray kind), it says in
//! the summary whether the numbers came from right answers. Written to verify.csv, so the summary
//! can be recomputed from the results directory alone. The soft-shadow query is checked sample ray
//! by sample ray (`check_visibility`); render workloads are not checked here (`raylab verify`
//! checks tracers fully).

use crate::geometry::RayBatch;
use crate::scene::Mesh;
use crate::tracers::chunked::trace_hits;
use crate::tracers::{Tracer, VisibilityQuery};
use crate::verify::{classify, BatchAnswers, Judgement, KindReport};

/// Rays checked per batch at most.
pub const SAMPLE_RAYS: usize = 4 * BLOCK_RAYS;
/// Consecutive rays checked together: one 32×32 tile of camera rays (they come in Morton-ordered
/// tiles), a whole number of every packet size (n×n, n ≤ 32).
pub const BLOCK_RAYS: usize = 1024;

/// What the check of one batch found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Checked {
    pub rays: usize,
    pub ties: u64,
    pub unexplained: u64,
    /// The unexplained ones by the f64 truth's judgement, in `Judgement::ALL` order: ours right,
    /// ours wrong, both within rounding, undecided.
    pub judged: [u64; 4],
}

impl Checked {
    fn add(&mut self, other: Checked) {
        self.rays += other.rays;
        self.ties += other.ties;
        self.unexplained += other.unexplained;
        for (a, b) in self.judged.iter_mut().zip(other.judged) {
            *a += b;
        }
    }
}

/// The rays checked of `batch`: all of it when small, else `SAMPLE_RAYS / BLOCK_RAYS` blocks of
/// `BLOCK_RAYS` consecutive rays, evenly spaced and aligned to whole blocks, so a packet tracer
/// forms the very packets (screen blocks of camera rays) it forms in the timed passes.
pub fn sample(batch: &RayBatch) -> RayBatch {
    let n = batch.len();
    if n <= SAMPLE_RAYS {
        return batch.clone();
    }
    let blocks = SAMPLE_RAYS / BLOCK_RAYS;
    let stride = n / BLOCK_RAYS / blocks * BLOCK_RAYS;
    let mut out = RayBatch::with_capacity(batch.kind(), SAMPLE_RAYS);
    for b in 0..blocks {
        let range = b * stride..(b * stride + BLOCK_RAYS).min(n);
        let starts = |i: usize| i == range.start || batch.packet_start.get(i) == Some(&true);
        for i in range.clone() {
            let start = !batch.packet_start.is_empty() && starts(i);
            // Camera rays keep their grid, so multi-frusta tracing is checked as it is timed.
            if let Some(grid) = batch.camera.as_deref() {
                out.push_camera_ray(grid, batch.pixel[i], start);
                continue;
            }
            let ray = batch.ray(i);
            match start {
                true => out.push_packet_start(ray, batch.pixel[i]),
                false => out.push(ray, batch.pixel[i]),
            }
        }
    }
    out
}

/// Tallies `tested` against `reference` on `batch` (the rays both traced).
pub fn tally(
    mesh: &Mesh,
    batch: &RayBatch,
    tested: &BatchAnswers,
    reference: &BatchAnswers,
) -> Checked {
    let agreements = classify(mesh, batch, tested, reference);
    let report = KindReport::from_agreements(
        mesh,
        batch.kind(),
        batch,
        &agreements,
        &tested.hits,
        &reference.hits,
    );
    Checked {
        rays: batch.len(),
        ties: report.ties.values().sum(),
        unexplained: report.unexplained,
        judged: Judgement::ALL.map(|j| report.judged(j)),
    }
}

/// Checks `tracer` against `oracle` on a sample of `batch` over `mesh`.
pub fn check(mesh: &Mesh, tracer: &dyn Tracer, oracle: &dyn Tracer, batch: &RayBatch) -> Checked {
    let sampled = sample(batch);
    let tested = BatchAnswers::of(tracer, &sampled);
    let reference = BatchAnswers::of(oracle, &sampled);
    tally(mesh, &sampled, &tested, &reference)
}

/// Checks `tracer`'s light-visibility answers against `oracle`'s on a sample of `query`'s points:
/// `SAMPLE_RAYS / BLOCK_RAYS` evenly spaced blocks of points casting about `BLOCK_RAYS` shadow rays
/// each. Every sample ray is one ray of the comparison: its occlusion bit from each side's
/// `light_visibility`, judged like a shadow ray (`verify::classify`, with each side's closest hit
/// on that ray saying why the bits differ).
pub fn check_visibility(
    mesh: &Mesh,
    tracer: &dyn Tracer,
    oracle: &dyn Tracer,
    query: &VisibilityQuery,
) -> Checked {
    let per_point = query.samples.per_point().max(1);
    let block = (BLOCK_RAYS / per_point).max(1);
    let blocks = SAMPLE_RAYS / BLOCK_RAYS;
    let n = query.len();
    let stride = (n / blocks).max(block);
    let mut checked = Checked::default();
    let (mut batch, mut traced) = (RayBatch::default(), Vec::new());
    for start in (0..n).step_by(stride).take(blocks) {
        let slice = query.slice(start..(start + block).min(n));
        slice.rays(&mut batch, &mut traced);
        let answers = |t: &dyn Tracer| {
            let mut bits = vec![0; slice.len() * slice.samples.words_per_point()];
            t.light_visibility(slice, &mut bits);
            let words = slice.samples.words_per_point();
            let flags = traced
                .iter()
                .map(|&(i, s)| {
                    let (i, s) = (i as usize, s as usize);
                    bits[i * words + s / 64] >> (s % 64) & 1 == 1
                })
                .collect();
            BatchAnswers {
                hits: trace_hits(t, &batch),
                occluded: Some(flags),
            }
        };
        checked.add(tally(mesh, &batch, &answers(tracer), &answers(oracle)));
    }
    checked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Hit, RayKind};
    use crate::render::rays::primary_rays;
    use crate::scene::library::load_scene;
    use crate::tracers::{oracle_params, tracer_for_frame, ORACLE};

    #[test]
    fn the_sample_is_four_aligned_blocks_spread_over_the_batch() {
        let scene = load_scene("room", Some(1)).unwrap();
        let frame = scene.frame(0, 1);
        let batch = primary_rays(&frame.camera, 256, 128);
        let s = sample(&batch);
        assert_eq!(s.len(), SAMPLE_RAYS);
        // 32,768 rays: blocks start every 8,192 rays.
        for b in 0..4 {
            for j in [0, 1, BLOCK_RAYS - 1] {
                assert_eq!(s.pixel[b * BLOCK_RAYS + j], batch.pixel[b * 8192 + j]);
            }
        }
        // The same rays, still a camera grid (multi-frusta tracing makes them on demand).
        for i in 0..s.len() {
            assert_eq!(s.ray(i), batch.ray(i / BLOCK_RAYS * 8192 + i % BLOCK_RAYS));
        }
        assert!(s.camera.is_some() && s.camera == batch.camera);
        let small = primary_rays(&frame.camera, 16, 16);
        assert_eq!(sample(&small).pixel, small.pixel);
    }

    /// The oracle agrees with itself; a copy of its answers with planted wrong answers on rays
    /// that hit well inside a triangle disagrees on exactly those rays, unexplained.
    #[test]
    fn planted_disagreements_are_counted_unexplained() {
        let scene = load_scene("room", Some(1)).unwrap();
        let frame = scene.frame(0, 1);
        let oracle = tracer_for_frame(ORACLE, &oracle_params(), &frame).unwrap();
        let batch = sample(&primary_rays(&frame.camera, 128, 128));
        let truth = BatchAnswers::of(oracle.as_ref(), &batch);
        assert_eq!(
            tally(&frame.mesh, &batch, &truth, &truth),
            Checked {
                rays: SAMPLE_RAYS,
                ties: 0,
                unexplained: 0,
                judged: [0; 4]
            }
        );
        let interior = |h: &Hit| h.is_hit() && h.u > 0.2 && h.v > 0.2 && h.u + h.v < 0.8;
        let planted: Vec<usize> = (0..batch.len())
            .filter(|&i| interior(&truth.hits[i]))
            .step_by(97)
            .take(7)
            .collect();
        assert_eq!(planted.len(), 7);
        let mut wrong = truth.clone();
        for &i in &planted {
            wrong.hits[i] = Hit::MISS;
        }
        assert!(!wrong.hits[planted[0]].is_hit());
        let checked = tally(&frame.mesh, &batch, &wrong, &truth);
        assert_eq!((checked.unexplained, checked.ties), (7, 0));
        // The f64 truth sees each planted miss as a certain hit missed: ours wrong, all 7.
        assert_eq!(checked.judged, [0, 7, 0, 0]);
        // The other way round, Embree is the one wrong.
        assert_eq!(
            tally(&frame.mesh, &batch, &truth, &wrong).judged,
            [7, 0, 0, 0]
        );

        // Shadow rays are judged by their occlusion flags.
        let mut shadow = batch.clone();
        shadow.kind = Some(RayKind::Shadow);
        let truth = BatchAnswers::of(oracle.as_ref(), &shadow);
        let mut wrong = truth.clone();
        let flags = wrong.occluded.as_mut().unwrap();
        for &i in &planted {
            flags[i] = !flags[i];
        }
        let checked = tally(&frame.mesh, &shadow, &wrong, &truth);
        assert_eq!(checked.unexplained, 7);
        assert_eq!(checked.judged, [0, 7, 0, 0]);
    }
}
