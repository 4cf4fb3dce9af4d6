//! Fixtures shared by the tracers' integration tests (`packet.rs`, `stream.rs`, `wide_single.rs`):
//! a scene's ray batches with the reference tracer's answers, the moving room, and the stability
//! sweep the stability tests run (`stability.rs`, `tinybvh.rs`), and the one results directory of
//! a run (`cli.rs`, `summary.rs`).

use std::sync::Arc;

use glam::Vec3;
use raylab::accel::{Accel, AccelKind, Bvh, BvhConfig};
use raylab::geometry::{Aabb, Hit, RayBatch, RayKind, RayTests, Triangle};
use raylab::render::rays::{diffuse_rays, primary_rays, shadow_rays};
use raylab::scene::library::load_scene;
use raylab::scene::Mesh;
use raylab::test_util::same_or_tie_with;
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::reference::ReferenceTracer;
use raylab::tracers::{Params, Tracer};
use raylab::tracers::{TracerInfo, TRACERS};
use raylab::verify::stability::Sweep;

/// A scene's SAH BVH and three batches traced by the reference tracer over it: 128² camera rays,
/// point-light shadow rays and diffuse rays from their hits (over 1000 each), with the
/// reference's closest hits (camera, diffuse) and occlusion (shadow).
pub struct ReferenceRays {
    pub mesh: Mesh,
    pub accel: Accel,
    pub bvh: Arc<Bvh>,
    pub primary: RayBatch,
    pub shadow: RayBatch,
    pub diffuse: RayBatch,
    /// The reference's closest hits on `primary` and `diffuse`.
    pub expected_hits: [Vec<Hit>; 2],
    pub expected_shadow: Vec<bool>,
}

pub fn reference_rays(name: &str, size: Option<u32>) -> ReferenceRays {
    let scene = load_scene(name, size).unwrap();
    let frame = scene.frame(0, 1);
    let mesh = frame.mesh.clone().into_owned();
    let accel = AccelKind::Bvh.build(&mesh, &Params::new()).unwrap();
    let Accel::Bvh(bvh) = &accel else {
        unreachable!("AccelKind::Bvh builds a BVH")
    };
    let bvh = bvh.clone();
    let reference = ReferenceTracer::new(bvh.clone());
    let primary = primary_rays(&frame.camera, 128, 128);
    let hits = trace_hits(&reference, &primary);
    let shadow = shadow_rays(&scene, &mesh, &primary, &hits, 3);
    let diffuse = diffuse_rays(&mesh, &primary, &hits, 3);
    assert!(shadow.len() > 1000 && diffuse.len() > 1000);
    let expected_hits = [&primary, &diffuse].map(|b| trace_hits(&reference, b));
    let expected_shadow = trace_occlusion(&reference, &shadow);
    ReferenceRays {
        mesh,
        accel,
        bvh,
        primary,
        shadow,
        diffuse,
        expected_hits,
        expected_shadow,
    }
}

/// `tracer`'s closest hits on `batch` against `want`: each equal, or a tie by the triangle test
/// `R` (`same_or_tie_with`: another triangle hit at exactly the same distance). Returns how many
/// were ties; `what` names the case in a failure.
pub fn ties_against<R: RayTests>(
    triangles: &[Triangle],
    tracer: &dyn Tracer,
    batch: &RayBatch,
    want: &[Hit],
    what: &str,
) -> usize {
    let got = trace_hits(tracer, batch);
    let mut ties = 0;
    for i in 0..batch.len() {
        if got[i] != want[i] {
            assert!(
                same_or_tie_with::<R>(triangles, &batch.ray(i), &got[i], &want[i]),
                "{what} {:?} ray {i}: {:?} vs {:?}",
                batch.kind(),
                got[i],
                want[i]
            );
            ties += 1;
        }
    }
    ties
}

/// The room moving by a translation over the shutter: the moving binary tree over its triangles
/// at shutter open and close (swept boxes), 64² camera rays at spread times, and the reference
/// tracer's closest hits on them — most rays hit, and not the static room's answers.
pub struct MovingRoom {
    pub bvh: Arc<Bvh>,
    pub timed: RayBatch,
    pub want: Vec<Hit>,
}

pub fn moving_room() -> MovingRoom {
    let scene = load_scene("room", None).unwrap();
    let frame = scene.frame(0, 1);
    let open = frame.mesh.triangles.clone();
    let size = open.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let shift = Vec3::new(0.05, 0.02, -0.03) * size.extent().max_element();
    let close: Vec<Triangle> = open
        .iter()
        .map(|t| Triangle::new(t.v[0] + shift, t.v[1] + shift, t.v[2] + shift))
        .collect();
    let bvh = Arc::new(Bvh::build_moving(&open, &close, BvhConfig::default()));
    let camera = primary_rays(&frame.camera, 64, 64);
    let mut timed = RayBatch::new(RayKind::Primary);
    for i in 0..camera.len() {
        let time = (i * 7919 % 1000) as f32 / 1000.0;
        timed.push(camera.ray(i).at_time(time), i as u32);
    }
    let want = trace_hits(&ReferenceTracer::new(bvh.clone()), &timed);
    assert!(want.iter().filter(|h| h.is_hit()).count() > timed.len() / 2);
    let still = ReferenceTracer::new(Arc::new(Bvh::build(&open, BvhConfig::default())));
    assert!(want
        .iter()
        .zip(trace_hits(&still, &timed))
        .any(|(a, b)| *a != b));
    MovingRoom { bvh, timed, want }
}

/// Equal hits, or a tie at exactly the same distance (two moving triangles meeting at an edge).
pub fn same_or_tie_moving(got: &Hit, want: &Hit) -> bool {
    got == want || (got.is_hit() && want.is_hit() && got.t == want.t)
}

/// The stability suite's sweep at fewer magnitudes: every case kind, offsets 0 and 10⁵, scales
/// 10⁻³ and 1, ratios 10³ and 10⁶, 3 bounces.
pub fn smaller_sweep() -> Sweep {
    Sweep {
        offsets: vec![0.0, 1e5],
        scales: vec![1e-3, 1.0],
        ratios: vec![1e3, 1e6],
        bounces: 3,
        ..Sweep::default()
    }
}

/// The one results directory of experiment `name` under `root`.
pub fn only_run(root: &std::path::Path, name: &str) -> std::path::PathBuf {
    let runs: Vec<std::path::PathBuf> = std::fs::read_dir(root.join(name))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    assert_eq!(runs.len(), 1, "{runs:?}");
    runs[0].clone()
}

/// The registry's tracers that `keep`, each in every configuration its entry declares for tests
/// (`TracerInfo::test_configs`): what the cross-tracer suites iterate instead of naming tracers.
pub fn test_configurations(
    keep: impl Fn(&TracerInfo) -> bool,
) -> Vec<(&'static TracerInfo, Params)> {
    TRACERS
        .iter()
        .filter(|info| keep(info))
        .flat_map(|info| info.test_params().into_iter().map(move |p| (info, p)))
        .collect()
}

/// A fresh, empty scratch directory `<suite>/<name>` under the test target's temporary directory.
pub fn scratch_in(suite: &str, name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(suite)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
