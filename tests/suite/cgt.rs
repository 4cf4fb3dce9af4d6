//! Coherent grid traversal (`cgt`, Wald et al. 2006): exact agreement with the single-ray
//! reference on a random soup and with Embree on built-in scenes, for every packet size and with
//! mailboxing, frustum culling and macrocells each on and off; mailboxing tests a triangle once
//! per packet; the frustum visits exactly the cells its corner rays bound; hand-worked counts of
//! cells, slices, skipped macrocells, mailbox hits, culled triangles and tests for a packet down
//! one column of a hand-made grid (and grid-dda's counts there).

use std::collections::BTreeSet;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use raylab::accel::{Bvh, BvhConfig, Grid, GridConfig};
use raylab::geometry::{Hit, Ray, RayBatch, RayKind, Triangle};
use raylab::lanes::WIDTHS;
use raylab::render::rays::primary_rays;
use raylab::render::sampling::uniform;
use raylab::scene::library::load_scene;
use raylab::scene::Camera;
use raylab::stats::{Counters, Event};
use raylab::test_util::Soup;
use raylab::tracers::coherent_grid::{CgtConfig, CgtTracer};
use raylab::tracers::reference::ReferenceTracer;
use raylab::tracers::{Kernel, Params, Tracer};
use raylab::verify::{format_table, verify_frame, Tolerance};

/// Every configuration: each packet side with each of the 8 on/off combinations, the lane widths
/// taking turns.
fn configs() -> Vec<CgtConfig> {
    let mut all = vec![];
    for packet in CgtConfig::PACKET_SIDES {
        for bits in 0..8 {
            all.push(CgtConfig {
                packet,
                lanes: WIDTHS[(packet as usize + bits) % WIDTHS.len()],
                mailbox: bits & 1 != 0,
                cull: bits & 2 != 0,
                macrocells: bits & 4 != 0,
                robust: true,
            });
        }
    }
    all
}

fn params_of(c: &CgtConfig) -> Params {
    Params::new()
        .with("packet", c.packet)
        .with("lanes", c.lanes)
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
            // Primary and diffuse always; shadow with lights; reflection on the room's mirror floor.
            let kinds: Vec<RayKind> = reports.iter().map(|r| r.kind).collect();
            assert!(kinds.contains(&RayKind::Primary) && kinds.contains(&RayKind::Diffuse));
            assert_eq!(kinds.contains(&RayKind::Shadow), !scene.lights.is_empty());
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
fn soup(n: usize, seed: u64) -> Vec<Triangle> {
    let soup = Soup {
        lo: 0.0,
        hi: 10.0,
        size: 0.4,
        long: Some((10, 7.5)),
        collinear_every: None,
    };
    soup.triangles(n, seed)
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
    let mut counted = vec![];
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
            // A triangle met in k cells: k − 1 mailbox hits.
            assert_eq!(counters.get(Event::MailboxHits), holding - 1);
        } else {
            assert_eq!(counters.get(Event::MailboxHits), 0);
            assert_eq!(
                counters.triangle_tests,
                16 * holding,
                "once per cell holding it"
            );
        }
        counted.push(counters);
    }
    // Every mailbox hit saves one test per active ray (all 16 until the hit's slice is left).
    let (on, off) = (&counted[0], &counted[1]);
    assert_eq!(
        off.triangle_tests,
        on.triangle_tests + 16 * on.get(Event::MailboxHits)
    );
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
    let to_grid = |p: DVec3| {
        (p - grid.origin.as_dvec3() - grid.bounds.min.as_dvec3()) * grid.inv_cell_size.as_dvec3()
    };
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

/// The hand-made scene of the counting tests: the corner fillers (fixing the box to [0, 10]³ and,
/// with λ = 90 over 10 triangles, a 10³ grid of cells 1.0362 wide from −0.181: cell 4 spans
/// [3.964, 5.0], cell 6 along z [6.036, 7.072]), a sliver in the plane x = 4.05 from z = 2.2 to
/// z = 5.7 (cells (4, 4, 2..=5)), and a large triangle in the plane z = 6.3 (slice 6).
fn counting_scene(macro_size: u32) -> (Arc<Grid>, u32) {
    let mut tris = corner_fillers();
    tris.push(Triangle::new(
        Vec3::new(4.05, 4.3, 2.2),
        Vec3::new(4.05, 4.6, 2.2),
        Vec3::new(4.05, 4.45, 5.7),
    ));
    tris.push(Triangle::new(
        Vec3::new(1.0, 1.0, 6.3),
        Vec3::new(9.0, 1.0, 6.3),
        Vec3::new(1.0, 9.0, 6.3),
    ));
    let grid = Grid::build(
        &tris,
        GridConfig {
            lambda: 90.0,
            macro_size,
            ..GridConfig::default()
        },
    );
    assert_eq!(grid.res, [10, 10, 10]);
    let (sliver, big) = (8, 9);
    for z in 0..10 {
        let want: &[u32] = match z {
            2..=5 => &[sliver],
            6 => &[big],
            _ => &[],
        };
        assert_eq!(grid.cell(4, 4, z), want, "cell (4, 4, {z})");
    }
    (Arc::new(grid), big)
}

/// 16 parallel rays going +z from z = −6, origins (4.2 + 0.2·i, 4.2 + 0.2·j): a frustum one cell
/// (column (4, 4)) wide, beside the sliver (x = 4.05 < 4.2) and onto the large triangle.
fn column_packet() -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Primary);
    for j in 0..4 {
        for i in 0..4 {
            let o = Vec3::new(4.2 + 0.2 * i as f32, 4.2 + 0.2 * j as f32, -6.0);
            batch.push(Ray::new(o, Vec3::Z, 0.0, f32::INFINITY), 0);
        }
    }
    batch
}

fn count(tracer: &dyn Tracer, batch: &RayBatch, any: bool) -> (Vec<Hit>, Counters) {
    let mut hits = vec![Hit::MISS; batch.len()];
    let mut counters = Counters::default();
    if any {
        let mut occluded = vec![false; batch.len()];
        tracer.occluded_counted(batch.view(), &mut occluded, &mut counters);
        for (h, o) in hits.iter_mut().zip(occluded) {
            h.prim = if o { 0 } else { Hit::MISS.prim };
        }
    } else {
        tracer.intersect_counted(batch.view(), &mut hits, &mut counters);
    }
    (hits, counters)
}

#[test]
fn hand_worked_counts_of_a_packet_down_one_column() {
    let batch = column_packet();
    for macro_size in [2, 6] {
        let (grid, big) = counting_scene(macro_size);
        for (bits, lanes) in (0..8).flat_map(|b| WIDTHS.map(|l| (b, l))) {
            let config = CgtConfig {
                packet: 4,
                lanes,
                mailbox: bits & 1 != 0,
                cull: bits & 2 != 0,
                macrocells: bits & 4 != 0,
                robust: true,
            };
            let what = format!("M = {macro_size}, {config:?}");
            let cgt = CgtTracer::new(grid.clone(), config);
            let (hits, c) = count(&cgt, &batch, false);
            for (i, h) in hits.iter().enumerate() {
                // The ray reaches z = 6.3 after 12.3.
                assert_eq!(h.prim, big, "{what}: ray {i}");
                assert!((h.t - 12.3).abs() < 1e-5, "{what}: ray {i}: {h:?}");
            }
            assert_eq!(c.rays, 16);
            assert_eq!(c.get(Event::Packets), 1, "{what}");
            // Column (4, 4) up to the hit's slice 6. Macrocells of side 2: the layer of slices
            // 0..=1 is empty in macro column (2, 2) and skipped (one macrocell), slices 2..=6 are
            // stepped. Side 6: macrocell (0, 0, 0) holds the sliver (and a filler), nothing skips.
            let skip = config.macrocells && macro_size == 2;
            let (slices, skipped) = if skip { (5, 1) } else { (7, 0) };
            assert_eq!(c.get(Event::SlicesStepped), slices, "{what}");
            assert_eq!(c.get(Event::MacrocellsSkipped), skipped, "{what}");
            assert_eq!(c.nodes_visited, slices, "{what}: one cell per slice");
            // Cells (4, 4, 2..=6) hold triangles, all 16 rays alive in each.
            assert_eq!(c.get(Event::LeavesVisited), 5, "{what}");
            assert_eq!(c.get(Event::LeafActiveRays), 5 * 16, "{what}");
            // The sliver spans 4 cells of the walk: 3 mailbox hits. With culling it is culled
            // (the frustum's u_min = 4.2 plane has it beyond) at each of its untested meetings.
            let mailbox_hits = if config.mailbox { 3 } else { 0 };
            let sliver_meetings = 4 - mailbox_hits;
            assert_eq!(c.get(Event::MailboxHits), mailbox_hits, "{what}");
            let culled = if config.cull { sliver_meetings } else { 0 };
            assert_eq!(c.get(Event::TrianglesCulled), culled, "{what}");
            assert_eq!(
                c.triangle_tests,
                16 * (1 + sliver_meetings - culled),
                "{what}: the large triangle once, the sliver unless culled"
            );
            // Occlusion: the same walk and counts (the hit ends every ray in slice 6).
            let (occluded, o) = count(&cgt, &batch, true);
            assert!(occluded.iter().all(|h| h.prim == 0), "{what}");
            assert_eq!(o, c, "{what}: occlusion counts");
        }
        // grid-dda down the same column: per ray, macrocell (2, 2, 0) skipped at once (side 2)
        // and counted as one cell, then cells 2..=6; the sliver tested at z = 2, mailboxed at
        // 3..=5, the large triangle hit at 6.
        let dda = raylab::tracers::grid_dda::GridDdaTracer::new(grid.clone());
        let (hits, c) = count(&dda, &batch, false);
        assert!(hits
            .iter()
            .all(|h| h.prim == big && (h.t - 12.3).abs() < 1e-5));
        let (nodes, skipped) = if macro_size == 2 { (6, 1) } else { (7, 0) };
        assert_eq!(c.nodes_visited, 16 * nodes, "M = {macro_size}");
        assert_eq!(
            c.get(Event::MacrocellsSkipped),
            16 * skipped,
            "M = {macro_size}"
        );
        assert_eq!(c.get(Event::MailboxHits), 16 * 3);
        assert_eq!(c.triangle_tests, 16 * 2);
    }
}

#[test]
fn a_packet_split_by_direction_counts_one_packet_per_part() {
    let (grid, big) = counting_scene(2);
    // Rays 8..16 of the column packet reversed, starting above the grid at z = 16: they meet
    // the large triangle first, at 16 − 6.3 = 9.7.
    let mut batch = RayBatch::new(RayKind::Primary);
    let column = column_packet();
    for i in 0..16 {
        let r = column.ray(i);
        if i < 8 {
            batch.push(r, 0);
        } else {
            let o = Vec3::new(r.origin.x, r.origin.y, 16.0);
            batch.push(Ray::new(o, -Vec3::Z, 0.0, f32::INFINITY), 0);
        }
    }
    let cgt = CgtTracer::new(grid, CgtConfig::default());
    let (hits, c) = count(&cgt, &batch, false);
    for (i, h) in hits.iter().enumerate() {
        let t = if i < 8 { 12.3 } else { 9.7 };
        assert_eq!(h.prim, big, "ray {i}");
        assert!((h.t - t).abs() < 1e-5, "ray {i}: {h:?}");
    }
    assert_eq!(c.get(Event::Packets), 2);
    // Up: slices 2..=6 as above; down: layer 8..=9 empty in column (2, 2) (skipped), slices
    // 7 and 6 stepped (layer 6..=7 holds the large triangle).
    assert_eq!(c.get(Event::SlicesStepped), 5 + 2);
    assert_eq!(c.get(Event::MacrocellsSkipped), 1 + 1);
    assert_eq!(
        c.triangle_tests,
        8 + 8,
        "the sliver culled, the large triangle once per ray"
    );
}

#[test]
fn interleaved_clusters_split_at_the_median_into_two_walked_packets() {
    let (grid, big) = counting_scene(2);
    // Two clusters of 8 parallel rays going +z, 5 units (4.8 cells) apart in x, interleaved in
    // the batch: halves in batch order would each hold both clusters; median halves by where the
    // rays start along u (x) hold one cluster each, which is coherent.
    let mut batch = RayBatch::new(RayKind::Primary);
    for i in 0..16 {
        let (cluster, k) = (i % 2, i / 2);
        let x = 4.2 + 0.2 * (k % 4) as f32 + 5.0 * cluster as f32;
        let y = 4.2 + 0.2 * (k / 4) as f32;
        batch.push(
            Ray::new(Vec3::new(x, y, -6.0), Vec3::Z, 0.0, f32::INFINITY),
            0,
        );
    }
    let cgt = CgtTracer::new(grid, CgtConfig::default());
    let (hits, c) = count(&cgt, &batch, false);
    for (i, h) in hits.iter().enumerate() {
        if i % 2 == 0 {
            assert_eq!(h.prim, big, "ray {i}");
            assert!((h.t - 12.3).abs() < 1e-5, "ray {i}: {h:?}");
        } else {
            // x + y > 10: beside the large triangle's hypotenuse.
            assert!(!h.is_hit(), "ray {i}: {h:?}");
        }
    }
    assert_eq!(c.get(Event::Packets), 2);
    // Cluster 0 as in the column test with M = 2 (5 slices, one cell each, the sliver culled);
    // cluster 1 walks column (9, 4): layers 0..=1, 2..=3, 4..=5 and 8..=9 are empty in macro
    // column (4, 2) (one macrocell each); layer 6..=7 is not (the large triangle's bounding box
    // reaches cells x = 8), so slices 6 and 7 are stepped, through empty cells.
    assert_eq!(c.get(Event::SlicesStepped), 5 + 2);
    assert_eq!(c.get(Event::MacrocellsSkipped), 1 + 4);
    assert_eq!(c.nodes_visited, 5 + 2);
    assert_eq!(
        c.triangle_tests, 8,
        "the large triangle, once per ray of cluster 0"
    );
}

#[test]
fn hopelessly_incoherent_packets_take_the_dda_ray_by_ray() {
    let (grid, _) = counting_scene(2);
    // 16 rays from one point down in directions (cos φ, sin φ, −1): slopes spread over [−1, 1]
    // on both axes, 2 + 2 halvings needed, 2⁴ > 16 / 2 (the halves would be single rays first).
    let mut batch = RayBatch::new(RayKind::Diffuse);
    for i in 0..16 {
        let phi = std::f32::consts::TAU * i as f32 / 16.0;
        let d = Vec3::new(phi.cos(), phi.sin(), -1.0);
        batch.push(Ray::new(Vec3::new(4.5, 4.5, 9.0), d, 0.0, f32::INFINITY), 0);
    }
    let cgt = CgtTracer::new(grid.clone(), CgtConfig::default());
    let dda = raylab::tracers::grid_dda::GridDdaTracer::new(grid);
    for any in [false, true] {
        let (hits, c) = count(&cgt, &batch, any);
        let (want_hits, mut want) = count(&dda, &batch, any);
        assert_eq!(hits, want_hits);
        assert!(hits.iter().filter(|h| h.is_hit()).count() >= 6);
        assert_eq!(c.get(Event::Packets), 16, "one per lone ray");
        want.events[Event::Packets as usize] = 16;
        assert_eq!(c, want, "exactly the DDA's work");
    }
}
