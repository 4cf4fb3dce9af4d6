//! Coherent grid traversal (`cgt`, Wald et al. 2006): exact agreement with the single-ray
//! reference on a random soup and with Embree on built-in scenes, for every packet size and with
//! mailboxing, frustum culling and macrocells each on and off; mailboxing tests a triangle once
//! per packet; the frustum visits exactly the cells its corner rays bound.

use std::collections::BTreeSet;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use raylab::accel::{Bvh, BvhConfig, Grid, GridConfig};
use raylab::geometry::{Hit, Ray, RayBatch, RayKind, Triangle};
use raylab::render::rays::primary_rays;
use raylab::render::sampling::uniform;
use raylab::scene::library::load_scene;
use raylab::scene::Camera;
use raylab::stats::Counters;
use raylab::tracers::cgt::{CgtConfig, CgtTracer};
use raylab::tracers::reference::ReferenceTracer;
use raylab::tracers::{Kernel, Params, Tracer};
use raylab::verify::{format_table, verify_frame, Tolerance};

/// Every configuration: each packet side with each of the 8 on/off combinations.
fn configs() -> Vec<CgtConfig> {
    let mut all = vec![];
    for packet in CgtConfig::PACKET_SIDES {
        for bits in 0..8 {
            all.push(CgtConfig {
                packet,
                mailbox: bits & 1 != 0,
                cull: bits & 2 != 0,
                macrocells: bits & 4 != 0,
            });
        }
    }
    all
}

fn params_of(c: &CgtConfig) -> Params {
    Params::new()
        .with("packet", c.packet)
        .with("mailbox", c.mailbox)
        .with("cull", c.cull)
        .with("macrocells", c.macrocells)
}

#[test]
fn agrees_with_embree_on_builtin_scenes() {
    let tol = Tolerance::default();
    let mut failures = vec![];
    for (name, size, frame, frames) in [
        ("room", None, 0, 1),
        ("balls", Some(2), 0, 1),
        ("marbles", None, 1, 3),
    ] {
        let scene = load_scene(name, size).unwrap();
        let frame = scene.frame(frame, frames);
        for config in configs() {
            let reports =
                verify_frame(&scene, &frame, "cgt", &params_of(&config), 128, 128, 1).unwrap();
            assert_eq!(reports.len(), if scene.lights.is_empty() { 2 } else { 3 });
            for r in &reports {
                assert!(r.rays > 0, "{name}: no {} rays", r.kind.name());
                if !r.passes(&tol) {
                    failures.push(format!(
                        "{name} {config:?}:\n{}",
                        format_table(&reports, &tol)
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A random soup in [0, 10]³: small triangles, plus long thin ones spanning many cells.
fn soup(n: u64, seed: u64) -> Vec<Triangle> {
    let r = |i: u64, d: u32| uniform(seed, i, d);
    (0..n)
        .map(|i| {
            let c = Vec3::new(r(i, 0), r(i, 1), r(i, 2)) * 10.0;
            let size = if i % 10 == 0 { 6.0 } else { 0.8 };
            let corner = |k: u32| c + (Vec3::new(r(i, k), r(i, k + 1), r(i, k + 2)) - 0.5) * size;
            Triangle::new(corner(3), corner(6), corner(9))
        })
        .collect()
}

fn random_dir(seed: u64, i: u64) -> Vec3 {
    let z = 2.0 * uniform(seed, i, 0) - 1.0;
    let phi = std::f32::consts::TAU * uniform(seed, i, 1);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Camera rays (tiles, Morton order), rays from random points in random directions, and
/// shadow-like rays from random points to one light (common end point, finite tmax).
fn soup_batches(seed: u64) -> Vec<RayBatch> {
    let camera = Camera {
        position: Vec3::new(-4.0, 13.0, -9.0),
        target: Vec3::splat(5.0),
        fov_y_deg: 50.0,
        ..Camera::default()
    };
    let primary = primary_rays(&camera, 96, 96);
    let mut random = RayBatch::new(RayKind::Diffuse);
    let mut shadow = RayBatch::new(RayKind::Shadow);
    let light = Vec3::new(5.0, 14.0, 3.0);
    for i in 0..6000u64 {
        let o = Vec3::new(
            uniform(seed + 1, i, 0),
            uniform(seed + 1, i, 1),
            uniform(seed + 1, i, 2),
        ) * 12.0
            - 1.0;
        random.push(Ray::new(o, random_dir(seed, i), 0.0, f32::INFINITY), 0);
        let to_light = light - o;
        let d = to_light.length();
        shadow.push(Ray::new(o, to_light / d, 0.0, d * (1.0 - 1e-4)), 0);
    }
    vec![primary, random, shadow]
}

fn trace(t: &dyn Tracer, batch: &RayBatch) -> (Vec<Hit>, Vec<bool>) {
    let mut hits = vec![Hit::MISS; batch.len()];
    let mut occluded = vec![false; batch.len()];
    // Chunks of 4096 like the runner's, so partial packets at chunk ends occur.
    for start in (0..batch.len()).step_by(4096) {
        let end = (start + 4096).min(batch.len());
        let rays = batch.view().slice(start..end);
        t.intersect(rays, &mut hits[start..end]);
        t.occluded(rays, &mut occluded[start..end]);
    }
    (hits, occluded)
}

#[test]
fn agrees_with_the_reference_tracer_on_a_random_soup() {
    let tris = soup(3000, 7);
    let reference = ReferenceTracer::new(Arc::new(Bvh::build(&tris, BvhConfig::default())));
    let grid = Arc::new(Grid::build(&tris, GridConfig::default()));
    let batches = soup_batches(11);
    let expected: Vec<_> = batches.iter().map(|b| trace(&reference, b)).collect();
    for (b, (hits, _)) in batches.iter().zip(&expected) {
        let hit_count = hits.iter().filter(|h| h.is_hit()).count();
        assert!(
            hit_count > b.len() / 10 && hit_count < b.len(),
            "{:?}: {hit_count} of {} hit; the soup should catch some rays, not all",
            b.kind(),
            b.len()
        );
    }
    for config in configs() {
        let cgt = CgtTracer::new(grid.clone(), config);
        for (batch, (want_hits, want_occluded)) in batches.iter().zip(&expected) {
            let (hits, occluded) = trace(&cgt, batch);
            for i in 0..batch.len() {
                let (got, want) = (hits[i], want_hits[i]);
                let what = || format!("{config:?} {:?} ray {i}: {got:?} vs {want:?}", batch.kind());
                assert_eq!(got.is_hit(), want.is_hit(), "{}", what());
                if want.is_hit() {
                    if got.prim == want.prim {
                        assert_eq!(got.t, want.t, "{}", what());
                    } else {
                        // A tie: two triangles at the same distance (shared edges in the soup are
                        // rare, intersecting triangles are not).
                        assert!((got.t - want.t).abs() <= 1e-5 * want.t, "{}", what());
                    }
                }
                assert_eq!(occluded[i], want_occluded[i], "{} occlusion", what());
            }
        }
    }
}

/// Triangles near the corners of [0, 10]³, away from the rays of the hand-made packets; `lambda`
/// makes the grid about 1 unit per cell.
fn corner_fillers() -> Vec<Triangle> {
    let mut tris = vec![];
    for x in [0.0, 9.5] {
        for y in [0.0, 9.5] {
            for z in [0.0, 9.5] {
                let p = Vec3::new(x, y, z);
                tris.push(Triangle::new(p, p + Vec3::X * 0.5, p + Vec3::Y * 0.5));
            }
        }
    }
    tris
}

/// A 4×4 packet from `origin`, directions `(x0 + 0.1·i, y0 + 0.1·j, 1)`, row-major.
fn packet(origin: Vec3, x0: f32, y0: f32) -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Primary);
    for j in 0..4 {
        for i in 0..4 {
            let d = Vec3::new(x0 + 0.1 * i as f32, y0 + 0.1 * j as f32, 1.0);
            batch.push(Ray::new(origin, d, 0.0, f32::INFINITY), 0);
        }
    }
    batch
}

#[test]
fn mailboxing_tests_a_long_triangle_once_per_packet() {
    // A large triangle in the plane z = 6.3 covering x, y ∈ [1, 9] around the packet's footprint.
    let big = Triangle::new(
        Vec3::new(1.0, 1.0, 6.3),
        Vec3::new(17.0, 1.0, 6.3),
        Vec3::new(1.0, 17.0, 6.3),
    );
    let mut tris = corner_fillers();
    tris.push(big);
    let big_id = tris.len() as u32 - 1;
    let grid = Arc::new(Grid::build(
        &tris,
        GridConfig {
            lambda: 100.0,
            ..GridConfig::default()
        },
    ));
    let batch = packet(Vec3::new(4.0, 4.0, -10.0), -0.15, -0.15);
    for mailbox in [true, false] {
        let cgt = CgtTracer::new(
            grid.clone(),
            CgtConfig {
                mailbox,
                ..CgtConfig::default()
            },
        );
        let mut hits = vec![Hit::MISS; 16];
        let mut counters = Counters::default();
        cgt.intersect_with(batch.view(), &mut hits, &mut counters);
        for (i, h) in hits.iter().enumerate() {
            let ray = batch.ray(i);
            assert_eq!(h.prim, big_id, "ray {i}");
            assert!((ray.at(h.t).z - 6.3).abs() < 1e-5, "ray {i}: t = {}", h.t);
        }
        let visited = cgt.visited_cells(batch.view(), &mut hits);
        let holding = visited
            .iter()
            .filter(|c| grid.cell(c[0], c[1], c[2]).contains(&big_id))
            .count() as u64;
        assert!(
            holding >= 4,
            "the packet should meet the triangle in several cells"
        );
        assert_eq!(counters.rays, 16);
        assert_eq!(counters.nodes_visited, visited.len() as u64);
        if mailbox {
            assert_eq!(counters.triangle_tests, 16, "once per ray of the packet");
        } else {
            assert_eq!(
                counters.triangle_tests,
                16 * holding,
                "once per cell holding it"
            );
        }
    }
}

#[test]
fn frustum_visits_exactly_the_cells_its_corner_rays_bound() {
    let grid = Grid::build(
        &corner_fillers(),
        GridConfig {
            lambda: 100.0,
            ..GridConfig::default()
        },
    );
    let to_grid = |p: DVec3| (p - grid.bounds.min.as_dvec3()) * grid.inv_cell_size.as_dvec3();
    let res = grid.res;
    // The corner rays' (x, y) at every slice plane z = k, in f64 grid space, for a packet from
    // `origin`; None when a bound lies within 0.01 of a cell boundary (rounding may decide).
    let slabs = |origin: Vec3, x0: f32, y0: f32| -> Option<BTreeSet<[u32; 3]>> {
        let o = to_grid(origin.as_dvec3());
        let corner_dirs = [(0, 0), (3, 0), (0, 3), (3, 3)].map(|(i, j)| {
            let d = Vec3::new(x0 + 0.1 * i as f32, y0 + 0.1 * j as f32, 1.0);
            d.as_dvec3() * grid.inv_cell_size.as_dvec3()
        });
        let at = |d: DVec3, z: f64| o + d * ((z - o.z) / d.z);
        let mut cells = BTreeSet::new();
        for k in 0..res[2] {
            let pts: Vec<DVec3> = corner_dirs
                .iter()
                .flat_map(|&d| [at(d, k as f64), at(d, k as f64 + 1.0)])
                .collect();
            let lo = pts.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
            let hi = pts.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
            for v in [lo.x, lo.y, hi.x, hi.y] {
                if (v - v.round()).abs() < 0.01 || v < 0.5 || v > res[0].min(res[1]) as f64 - 0.5 {
                    return None;
                }
            }
            for y in lo.y.floor() as u32..=hi.y.floor() as u32 {
                for x in lo.x.floor() as u32..=hi.x.floor() as u32 {
                    cells.insert([x, y, k]);
                }
            }
        }
        Some(cells)
    };
    // Packets starting below the grid (z = −6), entering through its bottom and leaving
    // through its top; the first origin whose bounds keep clear of cell boundaries.
    let (origin, expected) = (0..50)
        .find_map(|n| {
            let origin = Vec3::new(4.0 + 0.037 * n as f32, 3.5 + 0.029 * n as f32, -6.0);
            slabs(origin, -0.1, -0.05).map(|cells| (origin, cells))
        })
        .expect("a packet clear of cell boundaries");
    let batch = packet(origin, -0.1, -0.05);
    let cgt = CgtTracer::new(
        Arc::new(grid.clone()),
        CgtConfig {
            macrocells: false,
            ..CgtConfig::default()
        },
    );
    let mut hits = vec![Hit::MISS; 16];
    let visited = cgt.visited_cells(batch.view(), &mut hits);
    assert!(
        hits.iter().all(|h| !h.is_hit()),
        "the packet passes between the fillers"
    );
    let unique: BTreeSet<[u32; 3]> = visited.iter().copied().collect();
    assert_eq!(unique.len(), visited.len(), "a cell visited twice");
    assert_eq!(unique, expected);
    assert!(expected.len() as u32 > res[2], "several cells per slice");
}

#[test]
fn bad_parameters_are_usage_errors() {
    for (k, v) in [
        ("packet", "3"),
        ("packet", "64"),
        ("mailbox", "yes"),
        ("cull", "1"),
    ] {
        let e = CgtConfig::from_params(&Params::new().with(k, v)).unwrap_err();
        assert!(e.to_string().contains(k), "{e}");
    }
    assert_eq!(
        CgtConfig::from_params(&Params::new()).unwrap(),
        CgtConfig::default()
    );
}
