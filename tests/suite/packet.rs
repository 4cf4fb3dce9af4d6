//! The large-packet tracer: exact node, box-test and leaf counts of each traversal on a hand-built
//! tree, and agreement with the reference tracer — every traversal × packet size × SIMD width ×
//! frustum on/off, on primary, shadow and diffuse rays of the built-in room and balls scenes.

use crate::common;

use std::sync::Arc;

use glam::Vec3;
use raylab::accel::child_pairs::child_pairs;
use raylab::accel::{Bvh, BvhConfig, BvhNode, BvhOfWidth};
use raylab::geometry::{Aabb, Hit, Ray, RayBatch, RayKind, Triangle};
use raylab::stats::{Counters, Event};
use raylab::test_util::same_or_tie;
use raylab::tracers::chunked::{trace_hits, trace_occlusion};
use raylab::tracers::packet::{PacketConfig, PacketTracer, Traversal};
use raylab::tracers::reference::ReferenceTracer;
use raylab::tracers::{Params, Tracer, TracerInfo};

use common::{moving_room, reference_rays, same_or_tie_moving, MovingRoom, ReferenceRays};

/// Four leaves in a row along x, one triangle each (leaf `a` holds the triangle (a,0,0), (a+1,0,0),
/// (a,1,0)), under two interior nodes:
///
/// ```text
///            0: x∈[0,4]
///        /               \
///   1: x∈[0,2]         2: x∈[2,4]
///    /      \           /      \
/// 3:[0,1]  4:[1,2]   5:[2,3]  6:[3,4]
/// ```
fn four_leaf_tree() -> Bvh {
    let tri = |a: f32| {
        Triangle::new(
            Vec3::new(a, 0.0, 0.0),
            Vec3::new(a + 1.0, 0.0, 0.0),
            Vec3::new(a, 1.0, 0.0),
        )
    };
    let triangles: Vec<Triangle> = (0..4).map(|a| tri(a as f32)).collect();
    let slab = |x0: f32, x1: f32| Aabb::new(Vec3::new(x0, 0.0, 0.0), Vec3::new(x1, 1.0, 0.0));
    let interior = |bounds, first| BvhNode {
        bounds,
        first,
        count: 0,
    };
    let leaf = |a: u32| BvhNode {
        bounds: slab(a as f32, a as f32 + 1.0),
        first: a,
        count: 1,
    };
    let nodes = vec![
        interior(slab(0.0, 4.0), 1),
        interior(slab(0.0, 2.0), 3),
        interior(slab(2.0, 4.0), 5),
        leaf(0),
        leaf(1),
        leaf(2),
        leaf(3),
    ];
    Bvh {
        pairs: child_pairs(&nodes),
        nodes,
        depth: vec![0, 1, 1, 2, 2, 2, 2],
        triangles,
        prim_ids: vec![0, 1, 2, 3],
        config: BvhConfig::default(),
        build_seconds: 0.0,
        motion_end: None,
    }
}

/// One 4×4 packet = four 4-lane SIMD rays, straight down −z from z = 1. SIMD ray g's four rays
/// share x = `xs[g]` (y = 0.1 … 0.4): 0.5 hits leaf 3's triangle, 3.5 leaf 6's, 10 nothing.
fn column_packet(xs: [f32; 4]) -> RayBatch {
    let mut b = RayBatch::new(RayKind::Primary);
    for (g, x) in xs.into_iter().enumerate() {
        for l in 0..4 {
            let y = 0.1 * (l + 1) as f32;
            let ray = Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0), 0.0, 100.0);
            b.push(ray, (g * 4 + l) as u32);
        }
    }
    b
}

struct Counts {
    nodes: u64,
    box_lanes: u64,
    triangle_lanes: u64,
    leaves: u64,
    leaf_rays: u64,
}

fn count(traversal: Traversal, width: usize) -> (Counts, Vec<Hit>) {
    let tracer = PacketTracer::new(
        BvhOfWidth::of_width(Arc::new(four_leaf_tree()), width).unwrap(),
        PacketConfig {
            packet: 4,
            lanes: 4,
            traversal,
            frustum: false,
            robust: true,
        },
    );
    let batch = column_packet([0.5, 10.0, 0.5, 3.5]);
    let mut hits = vec![Hit::MISS; batch.len()];
    let mut c = Counters::default();
    tracer.intersect_counted(batch.view(), &mut hits, &mut c);
    assert_eq!(c.rays, 16);
    assert_eq!(c.get(Event::Packets), 1);
    assert_eq!(c.get(Event::BoxesCulled), 0);
    // One triangle per leaf, read once by the packet at each leaf it reaches.
    assert_eq!(
        c.get(Event::TrianglesAccessed),
        c.get(Event::LeavesVisited),
        "{traversal:?}"
    );
    let counts = Counts {
        nodes: c.nodes_visited,
        box_lanes: c.aabb_tests,
        triangle_lanes: c.triangle_tests,
        leaves: c.get(Event::LeavesVisited),
        leaf_rays: c.get(Event::LeafActiveRays),
    };
    (counts, hits)
}

fn assert_counts(t: Traversal, want: [u64; 5]) {
    assert_counts_at_width(t, 2, want);
}

fn assert_counts_at_width(t: Traversal, width: usize, want: [u64; 5]) {
    let (c, hits) = count(t, width);
    let got = [
        c.nodes,
        c.box_lanes,
        c.triangle_lanes,
        c.leaves,
        c.leaf_rays,
    ];
    assert_eq!(
        got, want,
        "{t:?}: [nodes, box lane tests, triangle lane tests, leaves, leaf rays]"
    );
    // SIMD rays 0 and 2 hit leaf 3's triangle at t = 1, SIMD ray 3 leaf 6's, SIMD ray 1 nothing.
    for (i, h) in hits.iter().enumerate() {
        let want = match i / 4 {
            0 | 2 => Some(0),
            3 => Some(3),
            _ => None,
        };
        assert_eq!(h.is_hit().then_some(h.prim), want, "{t:?} ray {i}");
        if h.is_hit() {
            assert_eq!(h.t, 1.0);
        }
    }
}

// The packet's SIMD rays g0..g3 sit over leaves 3, none, 3, 6. Children go left first (the packet
// travels −z; x sum is +0). "k tests" below are SIMD-ray box tests (4 lane tests each).

/// Ranged (App. A.1). root: g0 hits (1). node 1: g0 (1). leaf 3: g0 hits (1), getLastHit g3 miss,
/// g2 hit → ie = 3 (2); triangles for g0..g2 (3). leaf 4: g0 misses, scan g1 g2 g3 miss (4).
/// node 2: g0 g1 g2 miss, g3 hits (4). leaf 5: g3 misses, nothing after (1). leaf 6: g3 hits
/// (1), ie = 4; triangle for g3 (1). 7 nodes, 15 box tests = 60 lanes, 4 triangle tests = 16
/// lanes, 2 leaves reached with 12 + 4 live rays.
#[test]
fn ranged_counts_on_the_hand_built_tree() {
    assert_counts(Traversal::Ranged, [7, 60, 16, 2, 16]);
}

/// The 4-wide tree (`width` = 4): one node, whose four slots the greedy collapse fills with
/// leaves 4, 3, 5, 6 (node 1 opened first, then node 2). The interval test cannot use x or y
/// (zero directions) and every box is met at t = 1 along z: all four survive, pushed far to near
/// by x (the packet's x sum is +0), so popped 3, 4, 5, 6. leaf 3: g0 hits (1), then g1 g2 g3
/// against its box (3): g0 g2 test its triangle (2). leaf 4: g0..g3 miss (4). leaf 5: (4).
/// leaf 6: g0 g1 g2 miss, g3 hits (4), triangle for g3 (1). 5 nodes (root + 4 children
/// tested), 16 box tests = 64 lanes, 3 triangle tests = 12 lanes, 2 leaves with 8 + 4 live
/// rays. The 8-wide tree is the same single node (four slots empty): the same counts.
#[test]
fn wide_counts_on_the_hand_built_tree() {
    assert_counts_at_width(Traversal::Ranged, 4, [5, 64, 12, 2, 12]);
    assert_counts_at_width(Traversal::Ranged, 8, [5, 64, 12, 2, 12]);
}

/// Partition (App. A.2), I = [0 1 2 3], ia = 4. root: all four, g1 misses → I = [0 2 3 1], ia = 3
/// (4). node 1: g0 g2 hit, g3 misses → ia = 2 (3). leaf 3: g0 g2 hit (2); triangles for both
/// (2). leaf 4: both miss (2). node 2 (ia = 3): g0 g2 miss, g3 hits → I = [3 2 0 1], ia = 1 (3).
/// leaf 5: g3 misses (1). leaf 6: g3 hits (1); triangle (1). 7 nodes, 16 box tests = 64 lanes,
/// 3 triangle tests = 12 lanes, 2 leaves with 8 + 4 rays.
#[test]
fn partition_counts_on_the_hand_built_tree() {
    assert_counts(Traversal::Partition, [7, 64, 12, 2, 12]);
}

/// Masked (Fig. 2): interior nodes scan from g0 to the first hit, leaves test all four. root (1),
/// node 1 (1), leaf 3 (4; g0 g2 alive: 2 triangle tests), leaf 4 (4, none), node 2 (4, g3),
/// leaf 5 (4, none), leaf 6 (4; g3: 1 triangle test). 7 nodes, 22 box tests = 88 lanes,
/// 3 triangle tests = 12 lanes, 2 leaves with 8 + 4 rays.
#[test]
fn masked_counts_on_the_hand_built_tree() {
    assert_counts(Traversal::Masked, [7, 88, 12, 2, 12]);
}

/// IA (Wald et al. 2007): as Ranged down to leaf 3 (1 + 1 + 1), whose triangles every SIMD ray
/// from g0 on is tested against (4). The rays' x and y directions are 0, so interval arithmetic
/// can only use z, where every box is hit at t = 1: it culls nothing. leaf 4: g0 misses, scan
/// (4). node 2: (4). leaf 5: (1). leaf 6: (1), triangles for g3 (1). 7 nodes, 13 box tests =
/// 52 lanes, 5 triangle tests = 20 lanes, 2 leaves with 16 + 4 rays.
#[test]
fn ia_counts_on_the_hand_built_tree() {
    assert_counts(Traversal::Ia, [7, 52, 20, 2, 20]);
}

/// Occlusion: every traversal finds the same three occluded SIMD rays, and a packet whose rays all
/// hit the first leaf stops there.
#[test]
fn occlusion_stops_when_every_ray_is_occluded() {
    for traversal in Traversal::ALL {
        let config = PacketConfig {
            packet: 4,
            lanes: 4,
            traversal,
            frustum: false,
            robust: true,
        };
        let tracer = PacketTracer::new(Arc::new(four_leaf_tree()), config);
        let batch = column_packet([0.5, 10.0, 0.5, 3.5]);
        let mut flags = vec![false; 16];
        tracer.occluded(batch.view(), &mut flags);
        let want: Vec<bool> = (0..16).map(|i| i / 4 != 1).collect();
        assert_eq!(flags, want, "{traversal:?}");
        // All four SIMD rays over leaf 3: the packet ends at the first leaf it reaches.
        let all = column_packet([0.5; 4]);
        let mut c = Counters::default();
        tracer.occluded_counted(all.view(), &mut flags, &mut c);
        assert!(flags.iter().all(|&f| f), "{traversal:?}");
        assert_eq!(c.get(Event::LeavesVisited), 1, "{traversal:?}");
        assert_eq!(c.nodes_visited, 3, "{traversal:?}: root, node 1, leaf 3");
    }
    for width in [4, 8] {
        let config = PacketConfig {
            packet: 4,
            lanes: 4,
            traversal: Traversal::Ranged,
            frustum: false,
            robust: true,
        };
        let tracer = PacketTracer::new(
            BvhOfWidth::of_width(Arc::new(four_leaf_tree()), width).unwrap(),
            config,
        );
        let mut flags = vec![false; 16];
        tracer.occluded(column_packet([0.5, 10.0, 0.5, 3.5]).view(), &mut flags);
        let want: Vec<bool> = (0..16).map(|i| i / 4 != 1).collect();
        assert_eq!(flags, want, "width {width}");
        let mut c = Counters::default();
        tracer.occluded_counted(column_packet([0.5; 4]).view(), &mut flags, &mut c);
        assert!(flags.iter().all(|&f| f), "width {width}");
        assert_eq!(c.get(Event::LeavesVisited), 1, "width {width}");
        assert_eq!(c.nodes_visited, 2, "width {width}: root, leaf 3");
    }
}

fn agrees_with_reference(name: &str, size: Option<u32>) {
    let ReferenceRays {
        mesh,
        bvh,
        primary,
        shadow,
        diffuse,
        expected_hits,
        expected_shadow,
        ..
    } = reference_rays(name, size);
    let mut ties = 0;
    // The wide trees run only ranged traversal.
    let runs = Traversal::ALL
        .into_iter()
        .map(|t| (t, 2))
        .chain([(Traversal::Ranged, 4), (Traversal::Ranged, 8)]);
    for (traversal, width) in runs {
        for packet in PacketConfig::PACKET_SIDES {
            for lanes in PacketConfig::LANES {
                for frustum in [false, true] {
                    let config = PacketConfig {
                        packet,
                        lanes,
                        traversal,
                        frustum,
                        robust: true,
                    };
                    let tracer = PacketTracer::new(
                        BvhOfWidth::of_width(bvh.clone(), width).unwrap(),
                        config,
                    );
                    for (batch, expected) in [&primary, &diffuse].iter().zip(&expected_hits) {
                        let got = trace_hits(&tracer, batch);
                        for i in 0..batch.len() {
                            if got[i] != expected[i] {
                                let ray = batch.ray(i);
                                assert!(
                                    same_or_tie(&mesh.triangles, &ray, &got[i], &expected[i]),
                                    "{name} {:?} {config:?} width {width} ray {i}: {:?} vs reference {:?}",
                                    batch.kind(),
                                    got[i],
                                    expected[i]
                                );
                                ties += 1;
                            }
                        }
                    }
                    let occluded = trace_occlusion(&tracer, &shadow);
                    let wrong = (0..shadow.len())
                        .filter(|&i| occluded[i] != expected_shadow[i])
                        .count();
                    assert_eq!(wrong, 0, "{name} shadow {config:?} width {width}");
                }
            }
        }
    }
    println!("{name}: exact ties at equal distance: {ties}");
}

#[test]
fn every_configuration_agrees_with_the_reference_on_room() {
    agrees_with_reference("room", None);
}

#[test]
fn every_configuration_agrees_with_the_reference_on_balls() {
    agrees_with_reference("balls", Some(2));
}

#[test]
fn bad_parameters_are_rejected() {
    for (k, v) in [("packet", "3"), ("lanes", "32"), ("traversal", "kd")] {
        let p = Params::new().with(k, v);
        assert!(PacketConfig::from_params(&p).is_err(), "{k} = {v}");
    }
    let p = Params::new()
        .with("packet", "32")
        .with("lanes", "8")
        .with("traversal", "partition")
        .with("frustum", "false")
        .with("robust", "false");
    assert_eq!(
        PacketConfig::from_params(&p).unwrap(),
        PacketConfig {
            packet: 32,
            lanes: 8,
            traversal: Traversal::Partition,
            frustum: false,
            robust: false,
        }
    );
    let ranged = Params::new().with("traversal", "ranged");
    for (extra, ok) in [
        (ranged.clone().with("width", 4), true),
        (ranged.clone().with("width", 8), true),
        (Params::new(), true),
        (ranged.clone().with("width", 3), false),
        (ranged.clone().with("width", 16), false),
        (
            Params::new().with("traversal", "masked").with("width", 4),
            false,
        ),
        (
            Params::new().with("traversal", "ia").with("width", 8),
            false,
        ),
    ] {
        let made = TracerInfo::find("packet").unwrap().config(&extra);
        assert_eq!(made.is_ok(), ok, "{extra}");
    }
}

/// Explicit packets (packet assembly) are kept: a 16-ray batch cut into packets of 5, 5, 5 and 1
/// rays is traced as four packets even though a packet could hold 16, with the reference
/// tracer's hits.
#[test]
fn explicit_packets_are_respected() {
    let uniform = column_packet([0.5, 10.0, 0.5, 3.5]);
    let mut explicit = RayBatch::new(RayKind::Shadow);
    for i in 0..uniform.len() {
        if i % 5 == 0 {
            explicit.push_packet_start(uniform.ray(i), i as u32);
        } else {
            explicit.push(uniform.ray(i), i as u32);
        }
    }
    let tree = Arc::new(four_leaf_tree());
    let want = trace_hits(&ReferenceTracer::new(tree.clone()), &uniform);
    assert_eq!(want.iter().filter(|h| h.is_hit()).count(), 12);
    let runs = Traversal::ALL.into_iter().map(|t| (t, 2));
    for (traversal, width) in runs.chain([(Traversal::Ranged, 4), (Traversal::Ranged, 8)]) {
        let config = PacketConfig {
            packet: 4,
            lanes: 4,
            traversal,
            frustum: true,
            robust: true,
        };
        let tracer = PacketTracer::new(BvhOfWidth::of_width(tree.clone(), width).unwrap(), config);
        let mut hits = vec![Hit::MISS; 16];
        let mut c = Counters::default();
        tracer.intersect_counted(explicit.view(), &mut hits, &mut c);
        assert_eq!(c.get(Event::Packets), 4, "{traversal:?} width {width}");
        assert_eq!(hits, want, "{traversal:?} width {width}");
    }
}

/// Motion blur on the wide trees: a mesh moving by a translation over the shutter, camera rays at
/// random times, closest hits and occlusion equal to the reference tracer's over the same moving
/// binary tree (which the wide trees are collapsed from, swept boxes and all).
#[test]
fn wide_trees_trace_moving_geometry_like_the_reference() {
    let MovingRoom { bvh, timed, want } = moving_room();
    let want_occluded = trace_occlusion(&ReferenceTracer::new(bvh.clone()), &timed);
    for width in [4, 8] {
        for frustum in [false, true] {
            let config = PacketConfig {
                packet: 8,
                lanes: 16,
                traversal: Traversal::Ranged,
                frustum,
                robust: true,
            };
            let tracer =
                PacketTracer::new(BvhOfWidth::of_width(bvh.clone(), width).unwrap(), config);
            let got = trace_hits(&tracer, &timed);
            for i in 0..timed.len() {
                assert!(
                    same_or_tie_moving(&got[i], &want[i]),
                    "width {width} frustum {frustum} ray {i}: {:?} vs reference {:?}",
                    got[i],
                    want[i]
                );
            }
            assert_eq!(
                trace_occlusion(&tracer, &timed),
                want_occluded,
                "width {width}"
            );
        }
    }
}

/// Every ray's result is written by its packet, straight into the caller's buffer (nothing is
/// cleared first): buffers full of stale results come out as the reference's hits and occlusion
/// flags — for packets that end in a partial SIMD ray, with ill-formed rays (misses) among them,
/// at every SIMD width, traversal and tree width.
#[test]
fn every_ray_overwrites_a_stale_result() {
    let bvh = Arc::new(four_leaf_tree());
    let mut batch = column_packet([0.5, 10.0, 0.5, 3.5]);
    let down = Vec3::new(0.0, 0.0, -1.0);
    let extra = [
        Ray::new(Vec3::new(2.5, 0.2, 1.0), down, 0.0, 100.0),
        Ray::new(Vec3::new(f32::NAN, 0.2, 1.0), down, 0.0, 100.0),
        Ray::new(Vec3::new(1.5, 0.2, 1.0), Vec3::ZERO, 0.0, 100.0),
        Ray::new(Vec3::new(1.5, 0.3, 1.0), down, 0.0, 100.0),
        Ray::new(Vec3::new(3.5, 0.3, 1.0), down, 5.0, 2.0),
    ];
    for (i, ray) in extra.iter().enumerate() {
        batch.push(*ray, 16 + i as u32);
    }
    let reference = trace_hits(&ReferenceTracer::new(bvh.clone()), &batch);
    let want: Vec<Hit> = (0..batch.len())
        .map(|i| match batch.ray(i).is_well_formed() {
            true => reference[i],
            false => Hit::MISS,
        })
        .collect();
    assert_eq!(want.iter().filter(|h| h.is_hit()).count(), 12 + 2);
    let stale = Hit {
        t: 0.25,
        prim: 2,
        u: 0.5,
        v: 0.25,
    };
    let runs = Traversal::ALL
        .into_iter()
        .map(|t| (t, 2))
        .chain([(Traversal::Ranged, 4), (Traversal::Ranged, 8)]);
    for (traversal, width) in runs {
        for packet in [2, 4, 8] {
            for lanes in PacketConfig::LANES {
                let config = PacketConfig {
                    packet,
                    lanes,
                    traversal,
                    frustum: false,
                    robust: true,
                };
                let tracer =
                    PacketTracer::new(BvhOfWidth::of_width(bvh.clone(), width).unwrap(), config);
                let mut hits = vec![stale; batch.len()];
                tracer.intersect(batch.view(), &mut hits);
                assert_eq!(hits, want, "{config:?} width {width}");
                let mut occluded = vec![true; batch.len()];
                tracer.occluded(batch.view(), &mut occluded);
                let hit: Vec<bool> = want.iter().map(Hit::is_hit).collect();
                assert_eq!(occluded, hit, "{config:?} width {width}");
            }
        }
    }
}
