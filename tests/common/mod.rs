//! Fixtures shared by the integration tests of the tracers that take motion blur over wide trees
//! (`packet.rs`, `wide_single.rs`).

use std::sync::Arc;

use glam::Vec3;
use raylab::accel::{Bvh, BvhConfig};
use raylab::geometry::{Aabb, Hit, RayBatch, RayKind, Triangle};
use raylab::render::rays::primary_rays;
use raylab::scene::library::load_scene;
use raylab::tracers::batch::trace_hits;
use raylab::tracers::reference::ReferenceTracer;

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
