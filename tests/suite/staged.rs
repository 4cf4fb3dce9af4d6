//! A baseline is timed on rays staged beforehand in its own layout (`Kernel::stage_closest` /
//! `stage_occlusion`); counted passes and renderers take the unstaged path. Both must give the
//! same answers, bit for bit, or the timed pass would time another computation than the one
//! that is checked and counted. Every tracer that stages (Embree's entry points, tinybvh's
//! layouts and its packet call) on camera, shadow and diffuse rays, with the contexts that change
//! Embree's calls.

use raylab::geometry::{Hit, RayBatch};
use raylab::scene::library::load_scene;
use raylab::tracers::chunked::{stage_closest, stage_occlusion, trace_hits, trace_occlusion};
use raylab::tracers::registry::{not_built, TRACERS};
use raylab::tracers::{oracle_params, tracer_for_frame, Params, Tracer, ORACLE};
use raylab::verify::verification_batches;

fn staged_hits(tracer: &dyn Tracer, batch: &RayBatch) -> Option<Vec<Hit>> {
    let mut hits = vec![Hit::MISS; batch.len()];
    stage_closest(tracer, batch.view())?.trace(&mut hits);
    Some(hits)
}

fn staged_occlusion(tracer: &dyn Tracer, batch: &RayBatch) -> Option<Vec<bool>> {
    let mut occluded = vec![false; batch.len()];
    stage_occlusion(tracer, batch.view())?.trace(&mut occluded);
    Some(occluded)
}

#[test]
fn staged_baselines_answer_as_their_unstaged_path() {
    let scene = load_scene("room", None).unwrap();
    let frame = scene.frame(0, 1);
    let oracle = tracer_for_frame(ORACLE, &oracle_params(), &frame).unwrap();
    // 96×80: whole 32×32 tiles and partial ones at the edges (tinybvh-256's fallback).
    let batches = verification_batches(&scene, &frame, &*oracle, 96, 80, 7);
    let mut staging = vec![];
    for info in TRACERS.iter().filter(|info| !not_built(info.name)) {
        let contexts: &[&str] = if info.params.contains(&"context") {
            &["coherent", "incoherent"]
        } else {
            &[""]
        };
        for &context in contexts {
            let params = match context {
                "" => Params::new(),
                c => Params::new().with("context", c),
            };
            let tracer = tracer_for_frame(info.name, &params, &frame).unwrap();
            for batch in &batches {
                let label = format!("{} {context} on {:?} rays", info.name, batch.kind);
                let Some(staged) = staged_hits(&*tracer, batch) else {
                    continue;
                };
                let unstaged = trace_hits(&*tracer, batch);
                let differ = staged
                    .iter()
                    .zip(&unstaged)
                    .filter(|(a, b)| (a.t.to_bits(), a.prim) != (b.t.to_bits(), b.prim))
                    .count();
                assert_eq!(differ, 0, "{label}: {differ} staged hits differ");
                let staged = staged_occlusion(&*tracer, batch).expect("stages both queries");
                assert_eq!(
                    staged,
                    trace_occlusion(&*tracer, batch),
                    "{label}: occlusion"
                );
                assert!(
                    unstaged.iter().any(|h| h.is_hit()),
                    "{label}: hits something"
                );
                staging.push(info.name);
            }
        }
    }
    staging.dedup();
    assert!(
        ["embree3-1", "embree3-16", "embree3-stream"]
            .iter()
            .all(|name| staging.contains(name)),
        "Embree's entry points stage: {staging:?}"
    );
    println!("staged and checked: {staging:?}");
}
