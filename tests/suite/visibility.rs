//! The light-visibility query gives every tracer the same rays, so every tracer must give the same
//! occlusion bits: every tracer of the registry in every configuration its entry declares for
//! tests (mft among them answering natively, with and without CR / FS), on the room and the
//! conference room with a quad light and on a BART scene with one added — the soft-shadow
//! workload of the runner (16 interleaved light samples per primary hit). No test here names a
//! tracer of ours or a library's: a new registry entry is checked from its entry alone.

use glam::Vec3;

use crate::common::test_configurations;
use raylab::render::area_light::{soft_shadow_points, LightSampleSets};
use raylab::render::rays::primary_rays;
use raylab::render::wavefront::{answer, Answers, Work};
use raylab::scene::library::load_scene;
use raylab::scene::{Light, Scene};
use raylab::tracers::chunked::trace_hits;
use raylab::tracers::visibility::{QuadLight, Visibility};
use raylab::tracers::{
    oracle_params, tracer_for_frame, Params, Role, TracerInfo, VisibilityQuery, ORACLE,
};

const RESOLUTION: u32 = 128;
const SAMPLES: u32 = 16;

/// A horizontal square light of side `side` centred on the scene's first light.
fn with_quad_light(mut scene: Scene, side: f32) -> Scene {
    let centre = scene.lights[0].sample_point(0.0, 0.0);
    scene.lights = vec![Light::Quad {
        corner: centre - Vec3::new(side, 0.0, side) * 0.5,
        edge_u: Vec3::new(side, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, side),
        emission: Vec3::ONE,
    }];
    scene
}

/// Real scenes come from the search path; CI always has them. Locally without them the test says so.
pub(crate) fn scenes() -> Vec<(&'static str, Scene)> {
    let mut scenes = vec![(
        "room-area-light",
        load_scene("room-area-light", None).unwrap(),
    )];
    match load_scene("conference-area-light", None) {
        Ok(conference) => {
            scenes.push(("conference-area-light", conference));
            let kitchen = load_scene("bart-kitchen", None).unwrap();
            let side = kitchen.mesh.bounds().extent().length() * 0.02;
            scenes.push(("bart-kitchen + quad light", with_quad_light(kitchen, side)));
        }
        Err(e) => {
            eprintln!("NOTE: real scenes not found ({e}); set RAYLAB_SCENES to ../shared/scenes")
        }
    }
    scenes
}

pub(crate) fn visibility(scene: &Scene, tracer: &str, params: &Params) -> (Visibility, usize) {
    let frame = scene.frame(0, 1);
    let oracle = tracer_for_frame(ORACLE, &oracle_params(), &frame).unwrap();
    let primary = primary_rays(&frame.camera, RESOLUTION, RESOLUTION);
    let hits = trace_hits(oracle.as_ref(), &primary);
    let (points, samples) = soft_shadow_points(
        &frame.mesh,
        &primary,
        &hits,
        RESOLUTION,
        SAMPLES,
        LightSampleSets::Jittered,
        7,
    )
    .unwrap();
    let light = QuadLight::of(scene.quad_light().expect("a quad light"));
    let query = VisibilityQuery::new(&points, light, &samples).unwrap();
    let work = Work::LightVisibility(query);
    let tracer = tracer_for_frame(tracer, params, &frame).unwrap();
    let mut answers = Answers::blank(&work);
    answer(tracer.as_ref(), work, &mut answers, None);
    let Answers::Visibility(v) = answers else {
        unreachable!("a visibility query answers with bits")
    };
    (v, work.rays())
}

#[test]
fn every_tracer_sees_the_same_light_samples() {
    let tracers = test_configurations(|_| true);
    let tracers: Vec<(&str, Params)> = tracers.into_iter().map(|(i, p)| (i.name, p)).collect();
    for (name, scene) in scenes() {
        let (expected, rays) = visibility(&scene, ORACLE, &oracle_params());
        let occluded = expected.total_occluded();
        let samples = expected.points() * SAMPLES as usize;
        println!(
            "{name}: {} points, {rays} rays, {occluded} of {samples} samples occluded",
            expected.points()
        );
        // Soft shadows, not all lit nor all dark: some points see part of the light.
        let partial = (0..expected.points())
            .filter(|&i| (0.0..1.0).contains(&expected.visible_fraction(i)))
            .filter(|&i| expected.visible_fraction(i) > 0.0)
            .count();
        assert!(partial > 0, "{name}: no penumbra");
        for (tracer, params) in &tracers {
            let (got, _) = visibility(&scene, tracer, params);
            let differing: Vec<usize> = (0..expected.points())
                .filter(|&i| got.occluded_count(i) != expected.occluded_count(i))
                .collect();
            assert!(
                differing.is_empty() && got == expected,
                "{name}: {tracer} {params} differs from Embree at {} points, e.g. {:?}",
                differing.len(),
                &differing[..differing.len().min(5)]
            );
        }
    }
}

/// `robust = false` like for like: every tracer of ours with plain slabs and Möller–Trumbore in
/// its lanes, in every test configuration, gives the bits the reference tracer gives with
/// `robust = false` (every lane is the scalar test bit for bit, all culling conservative); mft
/// answering natively among them.
#[test]
fn fast_tests_give_the_fast_reference_tracers_bits() {
    let fast = || Params::new().with("robust", false);
    let reference = TracerInfo::of_role(Role::Reference).unwrap().name;
    let tracers = test_configurations(TracerInfo::is_ours);
    for (name, scene) in scenes() {
        let (expected, rays) = visibility(&scene, reference, &fast());
        for (tracer, params) in &tracers {
            let params = params.clone().with("robust", false);
            let (got, _) = visibility(&scene, tracer.name, &params);
            assert_eq!(
                got, expected,
                "{name}: {} {params} ({rays} rays)",
                tracer.name
            );
        }
    }
}
