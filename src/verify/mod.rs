//! Verification against Embree: identical rays (primary, shadow, diffuse bounce, mirror reflection,
//! refraction) traced by a tracer
//! under test and by Embree in robust mode, compared ray by ray. Disagreements that are ties —
//! shared edges or vertices, coplanar triangles at the same distance, rays grazing an edge, hits on
//! the boundary of the ray's interval — are classified and counted, never hidden; the rest are
//! "unexplained", and any unexplained disagreement fails verification.

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

pub use compare::{Agreement, Mismatch, Tie};
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

/// Classifies every ray of `batch`: `tested`'s answer against `reference`'s, by occlusion for
/// shadow rays and by closest hit otherwise.
pub fn classify(
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
