//! `robust = false` on every tracer of ours (`geometry::robustness`): plain slabs and
//! Möller–Trumbore in every lane and every single-ray kernel, bit for bit the scalar tests, and
//! all culling conservative — so each tracer's closest hits are the reference tracer's with
//! `robust = false` on the same rays (or a tie at exactly the same distance) and its occlusion
//! answers equal, on camera, diffuse and point-light shadow rays of the room and balls scenes.
//! (`fast_tests_agree_with_embree_without_robust_mode` in `embree_agreement.rs` compares the fast
//! tests with Embree's non-robust build; `visibility.rs` the soft-shadow query.)

use crate::common;

use raylab::geometry::Fast;
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::{build_tracer, tracer_for_mesh, Params, TracerInfo};

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
    let reference = build_tracer(TracerInfo::find("reference").unwrap(), &fast(), &accel).unwrap();
    let want = [&primary, &diffuse].map(|b| trace_hits(reference.as_ref(), b));
    let want_shadow = trace_occlusion(reference.as_ref(), &shadow);
    assert!(want[0].iter().filter(|h| h.is_hit()).count() > primary.len() / 2);
    // The fast hits are not the robust ones bit for bit (Möller–Trumbore rounds its distances
    // and barycentrics otherwise), so a tracer still running the robust tests fails below.
    let differ = |a: &[raylab::geometry::Hit], b: &[raylab::geometry::Hit]| {
        a.iter().zip(b).filter(|(x, y)| x != y).count()
    };
    assert!(differ(&want[0], &expected_hits[0]) > primary.len() / 10);
    let packet = |traversal: &str, side: u32, lanes: u32| {
        fast()
            .with("traversal", traversal)
            .with("packet", side)
            .with("lanes", lanes)
    };
    let tracers = [
        ("grid-dda", fast()),
        ("cgt", fast()),
        (
            "cgt",
            fast()
                .with("packet", 8)
                .with("lanes", 8)
                .with("cull", false),
        ),
        ("packet", packet("masked", 8, 16)),
        ("packet", packet("ranged", 16, 8)),
        ("packet", packet("partition", 4, 4)),
        ("packet", packet("ia", 16, 16)),
        ("packet", packet("ranged", 16, 16).with("frustum", false)),
        ("packet", packet("ranged", 8, 16).with("width", 4)),
        ("packet", packet("ranged", 16, 8).with("width", 8)),
        ("stream", fast()),
        ("stream", fast().with("width", 64).with("stream", "frame")),
        ("stream", fast().with("width", 4).with("single", 8)),
        ("stream", fast().with("single", 256).with("single_tree", 8)),
        ("mft", fast()),
        ("mft", fast().with("primary", "frusta")),
        ("mft", fast().with("primary", "frusta").with("width", 4)),
    ];
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
