//! Verification against Embree: identical rays (primary, shadow, diffuse bounce, mirror reflection,
//! refraction) traced by a tracer
//! under test and by Embree in robust mode, compared ray by ray. Disagreements that are ties —
//! shared edges or vertices, coplanar triangles at the same distance, rays grazing an edge, hits on
//! the boundary of the ray's interval — are classified and counted, never hidden; the rest are
//! "unexplained" by the ties, and the f64 ground truth (`truth`: every triangle tested in double
//! precision) judges each of them (`Judgement`): ours right (Embree wrong), ours wrong (Embree
//! right), both within rounding, or undecided (the truth contradicts both, or the disagreement
//! lies past `TRUTH_BUDGET`). Verification fails on "ours wrong" only; the failing and the
//! undecided rays are written to a ray file to replay with `raylab trace --rays`.

pub mod compare;
pub mod report;
pub mod stability;
pub mod truth;

use rayon::prelude::*;

use crate::error::Result;
use crate::geometry::{Hit, RayBatch, RayKind};
use crate::render::rays::{diffuse_rays, primary_rays, shadow_rays};
use crate::render::specular::specular_rays;
use crate::scene::{Frame, Mesh, Scene};
use crate::tracers::chunked::{trace_hits, trace_occlusion};
use crate::tracers::{oracle_params, tracer_for_frame, Params, Tracer, ORACLE};
use crate::verify::truth::Truth;

pub use compare::{Agreement, Judgement, Mismatch, Tie};
pub use report::{format_table, write_csv, KindReport, Tolerance};

/// The verification batches of one frame: camera rays, and the shadow, diffuse, reflection and
/// refraction rays leaving the oracle's primary hits (so the rays do not depend on the tracer
/// under test). No shadow rays when the scene has no lights, no reflection or refraction batch
/// when no primary hit spawns one.
pub fn verification_batches(
    scene: &Scene,
    frame: &Frame,
    oracle: &dyn Tracer,
    width: u32,
    height: u32,
    seed: u64,
) -> Vec<RayBatch> {
    let primary = primary_rays(&frame.camera, width, height);
    let hits = trace_hits(oracle, &primary);
    let mut batches = vec![];
    if !scene.lights.is_empty() {
        batches.push(shadow_rays(scene, &frame.mesh, &primary, &hits, seed));
    }
    batches.push(diffuse_rays(&frame.mesh, &primary, &hits, seed));
    for kind in [RayKind::Reflection, RayKind::Refraction] {
        let batch = specular_rays(kind, &frame.mesh, &scene.materials, &primary, &hits);
        if !batch.is_empty() {
            batches.push(batch);
        }
    }
    batches.insert(0, primary);
    batches
}

/// One tracer's answers on a batch: the closest hits, and for shadow rays the occlusion flags too
/// (judged on their own, with the closest hits saying why they differ).
#[derive(Clone, Debug)]
pub struct BatchAnswers {
    pub hits: Vec<Hit>,
    pub occluded: Option<Vec<bool>>,
}

impl BatchAnswers {
    pub fn of(tracer: &dyn Tracer, batch: &RayBatch) -> BatchAnswers {
        BatchAnswers {
            hits: trace_hits(tracer, batch),
            occluded: (batch.kind() == RayKind::Shadow).then(|| trace_occlusion(tracer, batch)),
        }
    }
}

/// Ray–triangle tests the f64 truth may spend judging one batch's disagreements (each costs one
/// test per triangle of the mesh): 2³⁰, seconds on two cores. Past it, disagreements stay
/// undecided, so a tracer wrong on every ray of a huge scene fails in seconds, not hours.
pub const TRUTH_BUDGET: u64 = 1 << 30;

/// Classifies every ray of `batch`: `tested`'s answer against `reference`'s, by occlusion for
/// shadow rays and by closest hit otherwise; every disagreement the ties do not explain is judged
/// by the f64 truth (the first ones of the batch, within `TRUTH_BUDGET`).
pub fn classify(
    mesh: &Mesh,
    batch: &RayBatch,
    tested: &BatchAnswers,
    reference: &BatchAnswers,
) -> Vec<Agreement> {
    let mut agreements = compare_answers(mesh, batch, tested, reference);
    let judged = (TRUTH_BUDGET / mesh.len().max(1) as u64).max(1) as usize;
    let to_judge: Vec<usize> = (0..batch.len())
        .filter(|&i| matches!(agreements[i], Agreement::Unexplained(..)))
        .take(judged)
        .collect();
    let judgements: Vec<Judgement> = to_judge
        .par_iter()
        .map(|&i| {
            let t = Truth::of(mesh, &batch.ray(i));
            match (&tested.occluded, &reference.occluded) {
                (Some(ours), Some(theirs)) => {
                    Judgement::of(t.judge_occluded(ours[i]), t.judge_occluded(theirs[i]))
                }
                _ => Judgement::of(
                    t.judge_closest(&tested.hits[i]),
                    t.judge_closest(&reference.hits[i]),
                ),
            }
        })
        .collect();
    for (&i, judgement) in to_judge.iter().zip(judgements) {
        if let Agreement::Unexplained(m, _) = agreements[i] {
            agreements[i] = Agreement::Unexplained(m, judgement);
        }
    }
    agreements
}

/// `classify` short of the truth: agreements, ties, and disagreements left undecided.
fn compare_answers(
    mesh: &Mesh,
    batch: &RayBatch,
    tested: &BatchAnswers,
    reference: &BatchAnswers,
) -> Vec<Agreement> {
    match (&tested.occluded, &reference.occluded) {
        (Some(tested_flags), Some(reference_flags)) => (0..batch.len())
            .into_par_iter()
            .map(|i| {
                compare::occlusion(
                    mesh,
                    &batch.ray(i),
                    tested_flags[i],
                    reference_flags[i],
                    &tested.hits[i],
                    &reference.hits[i],
                )
            })
            .collect(),
        _ => (0..batch.len())
            .into_par_iter()
            .map(|i| compare::closest(mesh, &batch.ray(i), &tested.hits[i], &reference.hits[i]))
            .collect(),
    }
}

/// Compares `tracer` with `oracle` on every batch, one report per ray kind.
pub fn compare_batches(
    frame: &Frame,
    tracer: &dyn Tracer,
    oracle: &dyn Tracer,
    batches: &[RayBatch],
) -> Vec<KindReport> {
    batches
        .iter()
        .map(|batch| {
            let tested = BatchAnswers::of(tracer, batch);
            let reference = BatchAnswers::of(oracle, batch);
            let agreements = classify(&frame.mesh, batch, &tested, &reference);
            KindReport::from_agreements(
                &frame.mesh,
                batch.kind(),
                batch,
                &agreements,
                &tested.hits,
                &reference.hits,
            )
        })
        .collect()
}

/// Everything `raylab verify` does short of printing and writing files.
pub fn verify_frame(
    scene: &Scene,
    frame: &Frame,
    tracer: &str,
    params: &Params,
    width: u32,
    height: u32,
    seed: u64,
) -> Result<Vec<KindReport>> {
    let oracle = tracer_for_frame(ORACLE, &oracle_params(), frame)?;
    let tested = tracer_for_frame(tracer, params, frame)?;
    let batches = verification_batches(scene, frame, oracle.as_ref(), width, height, seed);
    Ok(compare_batches(
        frame,
        tested.as_ref(),
        oracle.as_ref(),
        &batches,
    ))
}

/// `raylab verify --rays`: the rays of a ray file, compared twice — as closest-hit queries
/// (reported as `primary`) and as occlusion queries (reported as `shadow`).
pub fn verify_rays(
    frame: &Frame,
    tracer: &str,
    params: &Params,
    rays: &RayBatch,
) -> Result<Vec<KindReport>> {
    let oracle = tracer_for_frame(ORACLE, &oracle_params(), frame)?;
    let tested = tracer_for_frame(tracer, params, frame)?;
    let batches = [RayKind::Primary, RayKind::Shadow].map(|kind| RayBatch {
        kind: Some(kind),
        ..rays.clone()
    });
    Ok(compare_batches(
        frame,
        tested.as_ref(),
        oracle.as_ref(),
        &batches,
    ))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::{Ray, Triangle};

    /// A hand-made crowded-needle disagreement: a needle 2 long and 2·10⁻³ wide 10⁻⁴ above the
    /// rays' origins (prim 0) and a large triangle beyond it (prim 1). Each ray is given a pair of
    /// answers no tie explains, and the f64 truth's judgement is the one worked out by hand.
    #[test]
    fn the_truth_judges_every_disagreement_no_tie_explains() {
        let mut mesh = Mesh::default();
        let z = 1e-4;
        mesh.push(
            Triangle::new(
                Vec3::new(-1.0, -1e-3, z),
                Vec3::new(1.0, -1e-3, z),
                Vec3::new(1.0, 1e-3, z),
            ),
            0,
        );
        mesh.push(
            Triangle::new(
                Vec3::new(-5.0, -5.0, 1.0),
                Vec3::new(5.0, -5.0, 1.0),
                Vec3::new(0.0, 5.0, 1.0),
            ),
            0,
        );
        let up = |x: f32, y: f32| Ray::new(Vec3::new(x, y, 0.0), Vec3::Z, 0.0, f32::INFINITY);
        let hit = |prim: u32, t: f32| Hit {
            t,
            prim,
            u: 0.3,
            v: 0.3,
        };
        // (ray, ours, Embree's, judgement). (0.5, 0) is 5·10⁻⁴ inside the needle, far beyond
        // rounding: a certain hit. (0.5, −10⁻³) lies on its long edge: rounding decides.
        let cases = [
            (up(0.5, 0.0), Hit::MISS, hit(0, z), Judgement::OursWrong),
            (up(0.5, 0.0), hit(0, z), Hit::MISS, Judgement::OursRight),
            (up(0.5, 0.0), hit(0, z), hit(1, 1.0), Judgement::OursRight),
            (up(0.5, -1e-3), hit(0, z), hit(1, 1.0), Judgement::Rounding),
            (up(0.5, 0.0), Hit::MISS, hit(1, 1.0), Judgement::Undecided),
        ];
        let mut batch = RayBatch::new(RayKind::Diffuse);
        for (i, (ray, ..)) in cases.iter().enumerate() {
            batch.push(*ray, i as u32);
        }
        let answers = |pick: fn(&(Ray, Hit, Hit, Judgement)) -> Hit| BatchAnswers {
            hits: cases.iter().map(pick).collect(),
            occluded: None,
        };
        let (ours, embree) = (answers(|c| c.1), answers(|c| c.2));
        let agreements = classify(&mesh, &batch, &ours, &embree);
        for (i, (a, case)) in agreements.iter().zip(&cases).enumerate() {
            assert!(
                matches!(a, Agreement::Unexplained(_, j) if *j == case.3),
                "ray {i}: {a:?}, expected {:?}",
                case.3
            );
        }
        // The report counts them, and fails on ours wrong only.
        let report = KindReport::from_agreements(
            &mesh,
            RayKind::Diffuse,
            &batch,
            &agreements,
            &ours.hits,
            &embree.hits,
        );
        assert_eq!(Judgement::ALL.map(|j| report.judged(j)), [2, 1, 1, 1]);
        assert_eq!((report.unexplained, report.failing()), (5, 1));
        let tolerance = Tolerance {
            max_unexplained: 1,
            ..Tolerance::default()
        };
        assert!(report.passes(&tolerance));
        assert!(!report.passes(&Tolerance::default()));
    }
}
