//! Single rays through the wide BVH (`wide-single`): a hand-built tree whose visiting order and
//! counters are worked out by hand, and agreement with the reference tracer — closest hits on
//! primary and diffuse rays, occlusion on shadow rays, of the built-in room, rings and balls
//! scenes, and on moving geometry — for 4 and 8 children per node, robust and not.

use crate::common;

use std::sync::Arc;

use glam::Vec3;
use raylab::accel::{Bvh, BvhConfig, WideBvh, WideTree};
use raylab::geometry::{Hit, Ray, RayBatch, RayKind, Robust, Triangle};
use raylab::scene::Mesh;
use raylab::stats::Counters;
use raylab::test_util::same_or_tie;
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::reference::ReferenceTracer;
use raylab::tracers::wide_single::WideSingleTracer;

/// `bvh` collapsed to `width` children per node, as a run builds it.
fn wide(bvh: Arc<Bvh>, width: usize) -> Arc<WideTree> {
    Arc::new(WideTree::collapse(bvh, width).unwrap())
}
use raylab::tracers::{build_tracer, tracer_for_mesh, Params, Tracer, TracerInfo};

use common::{moving_room, reference_rays, same_or_tie_moving, MovingRoom, ReferenceRays};

/// Eight walls across x at x = 0, 10, …, 70, one triangle each: even walls the lower-left half
/// of the unit square in y, z (`(0,0) (1,0) (0,1)`), odd walls the upper-right half
/// (`(1,1) (0,1) (1,0)`). One triangle per leaf: SAH splits them 4|4, 2|2, 1|1, so the 8-wide
/// tree is one node of all 8 leaves and the 4-wide one a root of 4 nodes of 2 leaves.
fn eight_walls() -> Arc<Bvh> {
    let tris: Vec<Triangle> = (0..8)
        .map(|i| {
            let x = i as f32 * 10.0;
            let p = |y: f32, z: f32| Vec3::new(x, y, z);
            if i % 2 == 0 {
                Triangle::new(p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0))
            } else {
                Triangle::new(p(1.0, 1.0), p(0.0, 1.0), p(1.0, 0.0))
            }
        })
        .collect();
    let config = BvhConfig {
        max_leaf_size: 1,
        presplit: 0.0,
        spatial: 0.0,
        ..BvhConfig::default()
    };
    Arc::new(Bvh::build(&tris, config))
}

/// Nodes visited, box tests, triangle tests of one ray.
fn counted(tracer: &dyn Tracer, ray: Ray, any: bool) -> (Hit, bool, [u64; 3]) {
    let mut batch = RayBatch::new(RayKind::Primary);
    batch.push(ray, 0);
    let mut c = Counters::default();
    let (mut hits, mut occluded) = ([Hit::MISS], [false]);
    if any {
        tracer.occluded_counted(batch.view(), &mut occluded, &mut c);
    } else {
        tracer.intersect_counted(batch.view(), &mut hits, &mut c);
    }
    (
        hits[0],
        occluded[0],
        [c.nodes_visited, c.aabb_tests, c.triangle_tests],
    )
}

/// Worked by hand. A ray along +x at (y, z) = (0.75, 0.75) from x = −1 meets every wall's box,
/// misses the even triangles and hits the odd ones.
///
/// - 8-wide: the root tests its 8 children (8 box tests), pushes 7 far to near and enters the
///   nearest, wall 0 (a leaf: its triangle misses), pops wall 1 (hits at t = 11), then skips
///   walls 2–7, whose entry (21 … 71) lies beyond the hit, untested: 3 nodes, 8 box tests, 2
///   triangle tests.
/// - 4-wide: the root tests its 4 children (4), enters the nearest (walls 0 and 1: 2 more box
///   tests), its two leaves as above, then skips the root's other 3 children: 4 nodes, 6 box
///   tests, 2 triangle tests.
/// - Along −x from x = 101 the order is reversed: wall 7 first, hit at t = 31; in the 8-wide
///   tree 2 nodes, 8 box tests, 1 triangle test.
/// - Occlusion takes the children met unsorted, in slot order, entering the last slot and
///   stopping at the first hit: wall 7, a hit. 8-wide: 2 nodes, 8 box tests, 1 triangle test
///   either way. 4-wide forward: the root's 4 box tests, its last child (walls 6 and 7: 2 box
///   tests), wall 7: 3 nodes, 6 box tests, 1 triangle test. With `tmax` = 5 along +x nothing is
///   met beyond wall 0: in the 8-wide tree 2 nodes, 8 box tests, 1 triangle test, a miss.
#[test]
fn children_are_visited_nearest_first_and_skipped_beyond_the_hit() {
    let bvh = eight_walls();
    assert_eq!(WideBvh::<8>::collapse(&bvh).nodes.len(), 1);
    assert_eq!(WideBvh::<4>::collapse(&bvh).nodes.len(), 5);
    let forward = Ray::new(Vec3::new(-1.0, 0.75, 0.75), Vec3::X, 0.0, 1000.0);
    let backward = Ray::new(Vec3::new(101.0, 0.75, 0.75), -Vec3::X, 0.0, 1000.0);
    let short = Ray::new(Vec3::new(-1.0, 0.75, 0.75), Vec3::X, 0.0, 5.0);
    let eight = WideSingleTracer::<Robust>::new(wide(bvh.clone(), 8));
    let four = WideSingleTracer::<Robust>::new(wide(bvh.clone(), 4));
    for any in [false, true] {
        let (hit, occluded, counts) = counted(&eight, forward, any);
        let expected = if any { [2, 8, 1] } else { [3, 8, 2] };
        assert_eq!(counts, expected, "8-wide forward, any {any}");
        let (hit4, occluded4, counts4) = counted(&four, forward, any);
        let expected4 = if any { [3, 6, 1] } else { [4, 6, 2] };
        assert_eq!(counts4, expected4, "4-wide forward, any {any}");
        if any {
            assert!(occluded && occluded4);
        } else {
            assert_eq!((hit.t, hit.prim), (11.0, 1));
            assert_eq!(hit, hit4);
        }
        let (hit, occluded, counts) = counted(&eight, backward, any);
        assert_eq!(counts, [2, 8, 1], "8-wide backward, any {any}");
        if any {
            assert!(occluded);
        } else {
            assert_eq!((hit.t, hit.prim), (31.0, 7));
        }
        let (hit, occluded, counts) = counted(&eight, short, any);
        assert_eq!(counts, [2, 8, 1], "8-wide short, any {any}");
        assert!(!hit.is_hit() && !occluded);
    }
}

fn batch_of(ray: Ray) -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Primary);
    batch.push(ray, 0);
    batch
}

fn agrees_with_reference(name: &str, size: Option<u32>) {
    let ReferenceRays {
        mesh,
        accel,
        bvh,
        primary,
        shadow,
        diffuse,
        ..
    } = reference_rays(name, size);
    let mut ties = 0;
    // With `robust = false` both run plain slabs and Möller–Trumbore: the same hits again.
    for (robust, width) in [(true, 4), (true, 8), (false, 4), (false, 8)] {
        let reference = if robust {
            Box::new(ReferenceTracer::new(bvh.clone())) as Box<dyn Tracer>
        } else {
            let fast = Params::new().with("robust", false);
            build_tracer(TracerInfo::find("reference").unwrap(), &fast, &accel).unwrap()
        };
        let reference = reference.as_ref();
        let params = Params::new().with("width", width).with("robust", robust);
        // Its own structure: the wide tree of this width over the same BVH.
        let tracer = tracer_for_mesh("wide-single", &params, &mesh).unwrap();
        for batch in [&primary, &diffuse, &shadow] {
            let want = trace_hits(reference, batch);
            assert!(want.iter().any(Hit::is_hit));
            let got = trace_hits(tracer.as_ref(), batch);
            for i in 0..batch.len() {
                if got[i] != want[i] {
                    assert!(
                        same_or_tie(&mesh.triangles, &batch.ray(i), &got[i], &want[i]),
                        "{name} {:?} width {width} robust {robust} ray {i}: {:?} vs reference {:?}",
                        batch.kind(),
                        got[i],
                        want[i]
                    );
                    ties += 1;
                }
            }
            assert_eq!(
                trace_occlusion(tracer.as_ref(), batch),
                trace_occlusion(reference, batch),
                "{name} {:?} width {width} robust {robust}",
                batch.kind()
            );
        }
    }
    println!("{name}: exact ties at equal distance: {ties}");
}

#[test]
fn agrees_with_the_reference_on_room() {
    agrees_with_reference("room", None);
}

#[test]
fn agrees_with_the_reference_on_rings() {
    agrees_with_reference("rings", Some(2));
}

#[test]
fn agrees_with_the_reference_on_balls() {
    agrees_with_reference("balls", Some(2));
}

/// Motion blur: a mesh moving by a translation over the shutter, camera rays at spread times;
/// the wide trees' swept boxes and the shared leaf stage give the reference's hits and
/// occlusion exactly.
#[test]
fn moving_geometry_gives_the_references_hits() {
    let MovingRoom { bvh, timed, want } = moving_room();
    let reference = ReferenceTracer::new(bvh.clone());
    for tracer in [
        Box::new(WideSingleTracer::<Robust>::new(wide(bvh.clone(), 4))) as Box<dyn Tracer>,
        Box::new(WideSingleTracer::<Robust>::new(wide(bvh.clone(), 8))),
    ] {
        let got = trace_hits(tracer.as_ref(), &timed);
        for i in 0..timed.len() {
            assert!(
                same_or_tie_moving(&got[i], &want[i]),
                "ray {i}: {:?} vs reference {:?}",
                got[i],
                want[i]
            );
        }
        assert_eq!(
            trace_occlusion(tracer.as_ref(), &timed),
            trace_occlusion(&reference, &timed)
        );
    }
}

#[test]
fn bad_width_and_empty_trees() {
    let mesh = Mesh {
        triangles: vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)],
        material_ids: vec![0],
    };
    for width in ["2", "16", "x", "-8"] {
        let err = tracer_for_mesh("wide-single", &Params::new().with("width", width), &mesh);
        assert!(err.is_err(), "width {width}");
    }
    let err = tracer_for_mesh("wide-single", &Params::new().with("robust", "yes"), &mesh);
    let message = err.err().unwrap().to_string();
    assert!(message.contains("robust = \"yes\""), "{message}");
    // An empty tree: every ray misses, nothing is occluded.
    let empty =
        WideSingleTracer::<Robust>::new(wide(Arc::new(Bvh::build(&[], BvhConfig::default())), 8));
    let batch = batch_of(Ray::new(Vec3::ZERO, Vec3::X, 0.0, 10.0));
    assert_eq!(trace_hits(&empty, &batch), vec![Hit::MISS]);
    assert_eq!(trace_occlusion(&empty, &batch), vec![false]);
}
