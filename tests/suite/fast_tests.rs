//! `robust = false` on every tracer of ours (`geometry::robustness`), in every configuration its
//! registry entry declares for tests: plain slabs and
//! Möller–Trumbore in every lane and every single-ray kernel, bit for bit the scalar tests, and
//! all culling conservative — so each tracer's closest hits are the reference tracer's with
//! `robust = false` on the same rays (or a tie at exactly the same distance) and its occlusion
//! answers equal, on camera, diffuse and point-light shadow rays of the room and balls scenes.
//! (`fast_tests_agree_with_embree_without_robust_mode` in `embree_agreement.rs` compares the fast
//! tests with Embree's non-robust build; `visibility.rs` the soft-shadow query.)

use crate::common;

use raylab::geometry::Fast;
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::{build_tracer, tracer_for_mesh, Params, Role, TracerInfo};

use common::{reference_rays, ties_against, ReferenceRays};

fn agrees_with_the_fast_reference(name: &str, size: Option<u32>) {
    let ReferenceRays {
        mesh,
        accel,
        primary,
        shadow,
        diffuse,
        expected_hits,
        ..
    } = reference_rays(name, size);
    let fast = || Params::new().with("robust", false);
    let reference = TracerInfo::of_role(Role::Reference).unwrap();
    let reference = build_tracer(reference, &fast(), &accel).unwrap();
    let want = [&primary, &diffuse].map(|b| trace_hits(reference.as_ref(), b));
    let want_shadow = trace_occlusion(reference.as_ref(), &shadow);
    assert!(want[0].iter().filter(|h| h.is_hit()).count() > primary.len() / 2);
    // The fast hits are not the robust ones bit for bit (Möller–Trumbore rounds its distances
    // and barycentrics otherwise), so a tracer still running the robust tests fails below.
    let differ = |a: &[raylab::geometry::Hit], b: &[raylab::geometry::Hit]| {
        a.iter().zip(b).filter(|(x, y)| x != y).count()
    };
    assert!(differ(&want[0], &expected_hits[0]) > primary.len() / 10);
    // Every tracer of ours but the reference itself, in every configuration its entry declares
    // for tests.
    let tracers: Vec<(&str, Params)> =
        common::test_configurations(|info| info.is_ours() && info.role != Role::Reference)
            .into_iter()
            .map(|(info, params)| (info.name, params.with("robust", false)))
            .collect();
    let mut ties = 0;
    for (tracer_name, params) in &tracers {
        let tracer = tracer_for_mesh(tracer_name, params, &mesh).unwrap();
        let what = format!("{name} {tracer_name} {params} against the fast reference:");
        for (batch, want) in [&primary, &diffuse].iter().zip(&want) {
            ties += ties_against::<Fast>(&mesh.triangles, tracer.as_ref(), batch, want, &what);
        }
        let occluded = trace_occlusion(tracer.as_ref(), &shadow);
        assert_eq!(
            occluded, want_shadow,
            "{name} {tracer_name} {params} shadow"
        );
    }
    println!("{name}: exact ties at equal distance: {ties}");
}

#[test]
fn every_tracer_of_ours_agrees_with_the_fast_reference_on_room() {
    agrees_with_the_fast_reference("room", None);
}

#[test]
fn every_tracer_of_ours_agrees_with_the_fast_reference_on_balls() {
    agrees_with_the_fast_reference("balls", Some(2));
}
