use std::sync::Arc;

use glam::Vec3;

use super::*;
use crate::accel::BvhConfig;
use crate::geometry::{Aabb, Triangle, WatertightRay};
use crate::random::SplitMix64;
use crate::stats::{Counters, Event};
use crate::test_util::Soup;
use crate::tracers::reference::ReferenceTracer;
use crate::tracers::visibility::{
    shadow_ray, LightSamples, QuadLight, ShadingPoint, ShadingPoints, Visibility,
};

/// A light of side `side` centred over the soup at height 3.
fn light(side: f32) -> QuadLight {
    QuadLight {
        corner: Vec3::new(-side / 2.0, 3.0, -side / 2.0),
        edge_u: Vec3::new(side, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, side),
    }
}

/// `n` points under the soup (y = −1.5), in rows as a primary-ray block order would give; every
/// seventh faces sideways (some samples behind it), one faces away, one has a NaN origin.
fn points(n: usize, sets: u32, seed: u64) -> ShadingPoints {
    let mut rng = SplitMix64::new(seed);
    let mut points = ShadingPoints::default();
    for i in 0..n {
        let position = Vec3::new(
            -1.2 + 2.4 * (i % 16) as f32 / 15.0 + rng.range(-0.05, 0.05),
            -1.5,
            -1.2 + 2.4 * (i / 16) as f32 / (n / 16).max(1) as f32,
        );
        let normal = match i % 7 {
            0 => Vec3::new(0.6, 0.2, 0.0).normalize(),
            _ if i == 5 => -Vec3::Y,
            _ => Vec3::Y,
        };
        let origin = if i == 9 {
            Vec3::NAN
        } else {
            position + normal * 1e-4
        };
        let point = ShadingPoint {
            position,
            normal,
            origin,
            time: 0.0,
            set: i as u32 % sets,
        };
        points.push(point, true);
    }
    points
}

fn samples(per_point: usize, sets: usize, seed: u64) -> LightSamples {
    let mut rng = SplitMix64::new(seed);
    let uv = (0..per_point * sets)
        .map(|_| [rng.unit(), rng.unit()])
        .collect();
    LightSamples::new(per_point, uv).unwrap()
}

fn soup(seed: u64) -> Vec<Triangle> {
    let soup = Soup {
        long: Some((11, 6.0)),
        collinear_every: Some(37),
        ..Soup::unit(0.12)
    };
    soup.triangles(400, seed)
}

/// `bvh` as the tree of `config`'s width, as a run builds it.
pub(super) fn tree_of(bvh: &Arc<Bvh>, config: MftConfig) -> BvhOfWidth {
    BvhOfWidth::of_width(bvh.clone(), config.width).unwrap()
}

fn bvh(triangles: &[Triangle]) -> Arc<Bvh> {
    Arc::new(Bvh::build(triangles, BvhConfig::default()))
}

fn answer<K: Kernel>(
    kernel: &K,
    query: VisibilityQuery<'_>,
    counters: &mut Counters,
) -> Visibility {
    let mut v = Visibility::new(query.len(), query.samples);
    kernel.light_visibility_with(query, &mut v.words, counters);
    v
}

#[test]
fn bits_equal_the_reference_tracers_on_the_same_rays() {
    let configs = [
        MftConfig::default(),
        MftConfig {
            block: 1,
            ..MftConfig::default()
        },
        MftConfig {
            block: 64,
            ..MftConfig::default()
        },
        MftConfig {
            cr: false,
            fs: false,
            leaf_rays: false,
            block: 16,
            ..MftConfig::default()
        },
        MftConfig {
            cr: true,
            fs: false,
            leaf_rays: false,
            block: 37,
            ..MftConfig::default()
        },
        MftConfig {
            fs: false,
            ..MftConfig::default()
        },
        MftConfig {
            width: 4,
            ..MftConfig::default()
        },
        MftConfig {
            width: 8,
            ..MftConfig::default()
        },
        MftConfig {
            width: 8,
            block: 37,
            cr: false,
            fs: false,
            leaf_rays: false,
            ..MftConfig::default()
        },
    ];
    for (seed, per_point, side) in [(1, 16, 1.0), (2, 100, 2.5), (3, 4, 0.0)] {
        let bvh = bvh(&soup(seed));
        let reference = ReferenceTracer::new(bvh.clone());
        let points = points(160, 4, seed);
        let samples = samples(per_point, 4, seed);
        let query = VisibilityQuery::new(&points, light(side), &samples).unwrap();
        let expected = answer(&reference, query, &mut Counters::default());
        let occluded = expected.total_occluded();
        assert!(
            occluded > query.ray_count() / 10 && occluded < 160 * per_point * 9 / 10,
            "seed {seed}: both answers occur ({occluded} occluded)"
        );
        for config in configs {
            let mft = MftTracer::new(tree_of(&bvh, config), config);
            let mut counters = Counters::default();
            let got = answer(&mft, query, &mut counters);
            assert_eq!(got, expected, "seed {seed}, {config:?}");
            assert_eq!(counters.rays as usize, query.ray_count());
        }
    }
}

#[test]
fn shrinking_culls_more_triangles_and_changes_no_answer() {
    let bvh = bvh(&soup(4));
    let points = points(256, 4, 4);
    let samples = samples(16, 4, 4);
    let query = VisibilityQuery::new(&points, light(2.0), &samples).unwrap();
    let run = |config: MftConfig| {
        let mut counters = Counters::default();
        let v = answer(
            &MftTracer::new(tree_of(&bvh, config), config),
            query,
            &mut counters,
        );
        (v, counters)
    };
    let none = MftConfig {
        cr: false,
        fs: false,
        leaf_rays: false,
        ..MftConfig::default()
    };
    let (plain, plain_counts) = run(none);
    let cr = MftConfig { cr: true, ..none };
    let (with_cr, cr_counts) = run(cr);
    let (with_fs, fs_counts) = run(MftConfig { fs: true, ..cr });
    assert_eq!(with_cr, plain);
    assert_eq!(with_fs, plain);
    // CR tightens only the corner rays: the same triangles are reached, fewer are tested.
    let tests = |c: &Counters| c.get(Event::FrustumTriangleTests);
    assert_eq!(
        cr_counts.get(Event::TrianglesAccessed),
        plain_counts.get(Event::TrianglesAccessed)
    );
    assert!(tests(&cr_counts) < tests(&plain_counts));
    // FS also tightens traversal: no more boxes than CR.
    assert!(fs_counts.get(Event::FrustumBoxTests) <= cr_counts.get(Event::FrustumBoxTests));
}

#[test]
fn on_demand_rays_are_the_querys_rays_bit_for_bit() {
    let points = points(64, 3, 5);
    let samples = samples(24, 3, 5);
    let query = VisibilityQuery::new(&points, light(1.5), &samples).unwrap();
    let mut targets = Vec::new();
    light_points(&query, &mut targets);
    let bits = |r: crate::geometry::Ray| {
        let v = [r.origin, r.dir].map(|v| v.to_array().map(f32::to_bits));
        (v, [r.tmin, r.tmax, r.time].map(f32::to_bits))
    };
    let mut rays = 0;
    for i in 0..points.len() {
        for s in 0..24 {
            let on_demand = sample_ray(&query, &targets, i, s);
            assert_eq!(on_demand.map(bits), query.ray(i, s).map(bits), "{i} {s}");
            rays += on_demand.is_some() as usize;
        }
    }
    assert_eq!(rays, query.ray_count());
    assert!(rays < 64 * 24, "some samples lie behind their surface");

    // One large triangle between every point and the light: each frustum reaches the single leaf
    // once, so exactly the query's rays are generated, and every well-formed one is occluded.
    let blocker = Triangle::new(
        Vec3::new(-20.0, 0.0, -20.0),
        Vec3::new(20.0, 0.0, -20.0),
        Vec3::new(0.0, 0.0, 30.0),
    );
    // The NaN-origin point's rays are ill-formed: answered visible, as the reference does, and
    // never generated.
    let nan_point = (0..24).filter(|&s| query.ray(9, s).is_some()).count();
    assert!(nan_point > 0);
    // The same over wide trees: their root holds the one leaf.
    for width in [2, 4, 8] {
        let config = MftConfig {
            width,
            ..MftConfig::default()
        };
        let mft = MftTracer::new(bvh(&[blocker]), config);
        let mut counters = Counters::default();
        let v = answer(&mft, query, &mut counters);
        let generated = query.ray_count() - nan_point;
        assert_eq!(counters.get(Event::RaysOnDemand) as usize, generated);
        assert_eq!(counters.triangle_tests as usize, generated);
        assert_eq!(v.total_occluded(), 64 * 24 - nan_point);
    }
}

/// Culling never removes a box or a triangle that a sample ray of the frustum hits, and it removes
/// a fair share of those no ray hits.
/// The wide walks reach the binary walk's leaves through wide nodes: the same bits, and the same
/// rays made on demand (a frustum's rays are made at the first leaf that keeps a triangle for it,
/// whatever the order the leaves are reached in).
#[test]
fn wide_walks_answer_as_the_binary_walk() {
    for seed in [1, 2, 5] {
        let bvh = bvh(&soup(seed));
        let points = points(160, 4, seed);
        let samples = samples(16, 4, seed);
        let query = VisibilityQuery::new(&points, light(1.5), &samples).unwrap();
        let run = |width: usize| {
            let config = MftConfig {
                width,
                ..MftConfig::default()
            };
            let mut counters = Counters::default();
            let v = answer(
                &MftTracer::new(tree_of(&bvh, config), config),
                query,
                &mut counters,
            );
            (v, counters)
        };
        let (binary, binary_counts) = run(2);
        for width in [4, 8] {
            let (wide, wide_counts) = run(width);
            assert_eq!(wide, binary, "seed {seed}, width {width}");
            assert_eq!(
                wide_counts.get(Event::RaysOnDemand),
                binary_counts.get(Event::RaysOnDemand),
                "seed {seed}, width {width}"
            );
            // Fewer nodes: each wide node stands for up to W − 1 binary ones.
            assert!(
                wide_counts.nodes_visited < binary_counts.nodes_visited,
                "seed {seed}, width {width}"
            );
        }
    }
}

/// Four small triangles, one per leaf, inside every frustum of a block of four points: the binary
/// walk tests the root's box and 3 inner nodes × 2 children (7 boxes, frusta at 3 inner nodes),
/// a 4- or 8-wide walk the root's box and the one wide node's 4 children (5 boxes, frusta at 1
/// node); both reach the 4 leaves and make every ray.
#[test]
fn a_wide_node_tests_all_its_children_at_once() {
    let small = |x: f32, z: f32| {
        Triangle::new(
            Vec3::new(x, 0.5, z),
            Vec3::new(x + 0.1, 0.5, z),
            Vec3::new(x, 0.5, z + 0.1),
        )
    };
    let triangles = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)].map(|(x, z)| small(x, z));
    let config = BvhConfig {
        max_leaf_size: 1,
        ..BvhConfig::default()
    };
    let bvh = Arc::new(Bvh::build(&triangles, config));
    let mut points = ShadingPoints::default();
    for (x, z) in [(-0.1, -0.1), (0.1, -0.1), (-0.1, 0.1), (0.1, 0.1)] {
        let position = Vec3::new(x, -1.5, z);
        let point = ShadingPoint {
            position,
            normal: Vec3::Y,
            origin: position + Vec3::Y * 1e-4,
            time: 0.0,
            set: 0,
        };
        points.push(point, true);
    }
    let samples = samples(16, 1, 7);
    let query = VisibilityQuery::new(&points, light(20.0), &samples).unwrap();
    let expected = answer(
        &ReferenceTracer::new(bvh.clone()),
        query,
        &mut Counters::default(),
    );
    for (width, boxes, inner) in [(2, 7, 3), (4, 5, 1), (8, 5, 1)] {
        // No shrinking nor leaf box test: every frustum stays as wide as made.
        let config = MftConfig {
            width,
            cr: false,
            fs: false,
            leaf_rays: false,
            ..MftConfig::default()
        };
        let mut counters = Counters::default();
        let got = answer(
            &MftTracer::new(tree_of(&bvh, config), config),
            query,
            &mut counters,
        );
        assert_eq!(got, expected, "width {width}");
        assert_eq!(counters.get(Event::FrustumBoxTests), boxes, "width {width}");
        assert_eq!(
            counters.get(Event::FrustaAtNodes),
            4 * inner,
            "width {width}"
        );
        assert_eq!(counters.aabb_tests, 4 * boxes, "width {width}");
        assert_eq!(counters.get(Event::BoxesCulled), 0, "width {width}");
        assert_eq!(counters.get(Event::LeavesVisited), 4, "width {width}");
        assert_eq!(counters.get(Event::TrianglesAccessed), 4, "width {width}");
        assert_eq!(counters.get(Event::RaysOnDemand), 4 * 16, "width {width}");
        // Inner nodes and leaves visited: the binary tree's 3 + 4, the wide tree's 1 + 4.
        assert_eq!(counters.nodes_visited, inner + 4, "width {width}");
    }
}

#[test]
fn culling_never_removes_what_a_sample_ray_hits() {
    let mut rng = SplitMix64::new(6);
    let triangles = Soup {
        long: Some((5, 8.0)),
        collinear_every: Some(29),
        ..Soup::unit(0.2)
    }
    .triangles(600, 6);
    let (mut pairs, mut culled_tris, mut culled_boxes, mut hit_pairs) = (0, 0, 0, 0);
    for round in 0..40 {
        let side = [0.0, 0.3, 1.0, 4.0][round % 4];
        let light = light(side);
        let mut frusta = Frusta {
            len: MAX_FRUSTA,
            ..Frusta::default()
        };
        let margins = Margins::new(4.0);
        let mut rays = Vec::new();
        for f in 0..MAX_FRUSTA {
            // Origins below, inside and above the soup; some on a triangle's corner.
            let tri = &triangles[rng.next_u64() as usize % triangles.len()];
            let origin = if f % 9 == 0 {
                tri.v[0]
            } else if f % 9 == 1 {
                // A shading point's origin: just off a surface, either side.
                let side = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
                tri.centroid() + tri.normal().normalize_or_zero() * (side * 1.5e-5)
            } else {
                rng.vec3(-1.5, 1.5)
            };
            let (s0, t0) = (rng.range(0.0, 0.9), rng.range(0.0, 0.9));
            let rect = [s0, rng.range(s0, 1.0), t0, rng.range(t0, 1.0)];
            frusta.set(f, origin, &light, rect);
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            let uv = corners
                .into_iter()
                .chain((0..28).map(|_| (rng.unit(), rng.unit())))
                .map(|(a, b)| {
                    (
                        rect[0] + a * (rect[1] - rect[0]),
                        rect[2] + b * (rect[3] - rect[2]),
                    )
                });
            let towards = light.point(0.5, 0.5) - origin;
            rays.push(
                uv.filter_map(|(s, t)| shadow_ray(origin, towards, origin, light.point(s, t)))
                    .collect::<Vec<_>>(),
            );
        }
        frusta.derive(u64::MAX, Some(&margins));
        for tri in &triangles {
            let keep = keep_mask(&frusta, tri, u64::MAX, false);
            let bounds = Aabb::from_points(&tri.v);
            let [reach] = frusta.box_masks([&bounds], u64::MAX, &margins);
            for (f, frustum_rays) in rays.iter().enumerate() {
                pairs += 1;
                let hit = frustum_rays.iter().any(|r| {
                    WatertightRay::new(r.origin, r.dir)
                        .intersect(tri, r.tmin, r.tmax)
                        .is_some()
                });
                hit_pairs += hit as usize;
                let kept = keep >> f & 1 == 1;
                let reached = reach >> f & 1 == 1;
                assert!(
                    kept || !hit,
                    "round {round}: culled {tri:?} for frustum {f}"
                );
                assert!(
                    reached || !hit,
                    "round {round}: culled box of {tri:?} for {f}"
                );
                culled_tris += !kept as usize;
                culled_boxes += !reached as usize;
            }
        }
    }
    assert!(hit_pairs > 1000, "rays do hit triangles ({hit_pairs})");
    let share = |n: usize| n as f64 / (pairs - hit_pairs) as f64;
    assert!(
        share(culled_tris) > 0.9,
        "triangles culled {}",
        share(culled_tris)
    );
    assert!(
        share(culled_boxes) > 0.85,
        "boxes culled {}",
        share(culled_boxes)
    );
}

#[test]
fn blocks_out_of_range_are_refused() {
    for block in [0, 65] {
        let params = Params::new().with("block", block);
        assert!(MftConfig::from_params(&params).is_err());
    }
    let params = Params::new()
        .with("block", 64)
        .with("fs", false)
        .with("backface", true);
    assert_eq!(
        MftConfig::from_params(&params).unwrap(),
        MftConfig {
            block: 64,
            cr: true,
            fs: false,
            leaf_rays: true,
            primary: PrimaryRays::Packets,
            backface: true,
            width: 2,
            robust: true,
        }
    );
    assert!(MftConfig::from_params(&Params::new().with("cr", "maybe")).is_err());
    for width in [0, 1, 3, 16] {
        let params = Params::new().with("width", width);
        assert!(MftConfig::from_params(&params).is_err(), "width {width}");
    }
    let width = |w: usize| MftConfig::from_params(&Params::new().with("width", w));
    assert_eq!(width(8).unwrap().width, 8);
}

/// A value for a frustum lane, box or vertex coordinate: mostly ordinary, sometimes a signed
/// zero, an infinity, NaN or a subnormal.
fn edgy(rng: &mut SplitMix64, lo: f32, hi: f32) -> f32 {
    const SPECIALS: [f32; 6] = [0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e-40];
    if rng.unit() < 0.06 {
        SPECIALS[rng.next_u64() as usize % SPECIALS.len()]
    } else {
        rng.range(lo, hi)
    }
}

/// The box and triangle masks of every vector type the build has equal the portable lanes' (one
/// and sixteen wide), on real frusta and on frusta, boxes and triangles with NaN, infinite, zero
/// and subnormal values poked in.
#[test]
fn vector_kernels_give_the_portable_lanes_masks() {
    use crate::lanes::vector::{Native, Portable, Vector};
    fn masks<V: Vector>(
        frusta: &Frusta,
        b: [&Aabb; 2],
        tri: &Triangle,
        c: u64,
        m: &Margins,
    ) -> [u64; 4] {
        let [first, second] = frusta.box_masks_with::<V, 2>(b, c, m);
        // Two boxes at once are each box alone.
        assert_eq!(frusta.box_masks_with::<V, 1>([b[1]], c, m), [second]);
        [
            first,
            second,
            cull::keep_mask_with::<V>(frusta, tri, c, false),
            cull::keep_mask_with::<V>(frusta, tri, c, true),
        ]
    }
    let mut rng = SplitMix64::new(13);
    let light = light(1.5);
    let margins = Margins::new(4.0);
    let (mut compared, mut kept) = (0, [0u32; 4]);
    for round in 0..300 {
        let mut frusta = Frusta {
            len: MAX_FRUSTA,
            ..Frusta::default()
        };
        for f in 0..MAX_FRUSTA {
            let origin = rng.vec3(-1.5, 1.5);
            let (s0, t0) = (rng.range(0.0, 0.9), rng.range(0.0, 0.9));
            let rect = [s0, rng.range(s0, 1.0), t0, rng.range(t0, 1.0)];
            frusta.set(f, origin, &light, rect);
        }
        frusta.derive(u64::MAX, Some(&margins));
        if round % 2 == 1 {
            // Every field of some lanes overwritten with edge values.
            let mut fields: Vec<&mut [f32; MAX_FRUSTA]> = frusta
                .origin
                .iter_mut()
                .chain(frusta.corner.iter_mut().flatten())
                .chain(frusta.corner_len_sq.iter_mut())
                .chain(std::iter::once(&mut frusta.reach))
                .chain(frusta.rcp.iter_mut().flatten())
                .chain(frusta.free_inf.iter_mut())
                .chain(frusta.side.iter_mut().flatten())
                .chain(frusta.side_slack.iter_mut())
                .collect();
            for field in fields.iter_mut() {
                for x in field.iter_mut() {
                    *x = edgy(&mut rng, -2.0, 2.0);
                }
            }
        }
        let edgy_point = |rng: &mut SplitMix64| {
            Vec3::new(
                edgy(rng, -1.5, 1.5),
                edgy(rng, -1.5, 1.5),
                edgy(rng, -1.5, 1.5),
            )
        };
        for _ in 0..20 {
            let edgy_box = |rng: &mut SplitMix64| {
                let (a, b) = (edgy_point(rng), rng.vec3(-0.3, 0.3));
                Aabb::new(a, a + b.abs())
            };
            let (b0, b1) = (edgy_box(&mut rng), edgy_box(&mut rng));
            let bounds = [&b0, &b1];
            let tri = Triangle::new(
                edgy_point(&mut rng),
                edgy_point(&mut rng),
                edgy_point(&mut rng),
            );
            let candidates = if rng.unit() < 0.5 {
                u64::MAX
            } else {
                rng.next_u64()
            };
            let want = masks::<Portable<1>>(&frusta, bounds, &tri, candidates, &margins);
            assert_eq!(
                masks::<Portable<16>>(&frusta, bounds, &tri, candidates, &margins),
                want
            );
            assert_eq!(
                masks::<Native>(&frusta, bounds, &tri, candidates, &margins),
                want
            );
            #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
            assert_eq!(
                masks::<crate::lanes::vector::Avx2>(&frusta, bounds, &tri, candidates, &margins),
                want
            );
            compared += 1;
            for (k, m) in kept.iter_mut().zip(want) {
                *k += m.count_ones();
            }
        }
    }
    // Both answers occur in every mask (random boxes are small: few are reached), and back-face
    // culling drops more.
    let pairs = compared * 64;
    assert!(
        kept.iter()
            .all(|&k| k > pairs / 1000 && k < pairs * 99 / 100),
        "{kept:?} of {pairs}"
    );
    assert!(kept[3] < kept[2]);
}

/// Back-face culling (option `backface`) on a hand-worked triangle: in the plane y = 1 with
/// normal +y (winding (0,0,1) × (1,0,0)), seen from below by a frustum towards a light above it,
/// every ray meets its back: culled with the option, kept without; wound the other way, kept.
#[test]
fn backface_culling_drops_a_triangle_seen_from_behind() {
    let light = QuadLight {
        corner: Vec3::new(0.4, 3.0, 0.4),
        edge_u: Vec3::new(0.2, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 0.2),
    };
    let margins = Margins::new(3.0);
    let mut frusta = Frusta {
        len: 1,
        ..Frusta::default()
    };
    frusta.set(0, Vec3::new(0.5, 0.0, 0.5), &light, [0.0, 1.0, 0.0, 1.0]);
    frusta.derive(1, Some(&margins));
    let (a, b, c) = (
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 2.0),
        Vec3::new(2.0, 1.0, 0.0),
    );
    let facing_up = Triangle::new(a, b, c);
    assert_eq!(facing_up.normal().normalize(), Vec3::Y);
    let facing_down = Triangle::new(a, c, b);
    assert_eq!(keep_mask(&frusta, &facing_up, 1, false), 1);
    assert_eq!(keep_mask(&frusta, &facing_up, 1, true), 0);
    assert_eq!(keep_mask(&frusta, &facing_down, 1, true), 1);
    assert_eq!(keep_mask(&frusta, &facing_down, 1, false), 1);
}

/// On closed, outward-wound meshes (UV spheres) with every shading point outside them,
/// back-face culling changes no answer, and it culls more (frustum, triangle) pairs.
#[test]
fn backface_culling_changes_no_answer_on_closed_meshes() {
    use crate::scene::tessellate::Surface;
    let sphere = Surface::uv_sphere(24, 12);
    let triangles: Vec<Triangle> = [
        (-0.8, 0.3, -0.6),
        (0.5, 1.2, 0.2),
        (0.0, 0.0, 0.9),
        (0.9, -0.2, -0.9),
    ]
    .into_iter()
    .flat_map(|(x, y, z)| sphere.triangles(|p| p * 0.45 + Vec3::new(x, y, z)))
    .collect();
    let bvh = bvh(&triangles);
    let points = points(256, 4, 9);
    let samples = samples(16, 4, 9);
    let query = VisibilityQuery::new(&points, light(2.0), &samples).unwrap();
    let expected = answer(
        &ReferenceTracer::new(bvh.clone()),
        query,
        &mut Counters::default(),
    );
    let occluded = expected.total_occluded();
    assert!(occluded > query.ray_count() / 20 && occluded < query.ray_count() * 9 / 10);
    let run = |backface: bool| {
        let config = MftConfig {
            backface,
            ..MftConfig::default()
        };
        let mut counters = Counters::default();
        let v = answer(
            &MftTracer::new(tree_of(&bvh, config), config),
            query,
            &mut counters,
        );
        (v, counters.get(Event::TrianglesCulled))
    };
    let ((plain, plain_culled), (culled, backface_culled)) = (run(false), run(true));
    assert_eq!(plain, expected);
    assert_eq!(culled, expected);
    assert!(
        backface_culled > plain_culled,
        "{backface_culled} vs {plain_culled}"
    );
}
