//! The Embree baselines — Embree 3 and, when this build has it, Embree 4 — against hand-worked
//! hits and against the reference tracer: every submission (single, packets of 4/8/16, Embree 3's
//! streams), every build quality, robust or not, both context hints; refits, ill-formed rays.

use glam::Vec3;
use raylab::accel::embree::{
    BuildQuality, Device, EmbreeConfig, EmbreeScene, EMBREE4_BUILT, EMBREE4_HINT,
};
use raylab::accel::{Accel, AccelKind};
use raylab::geometry::{Hit, Ray, RayBatch, RayKind, Triangle};
use raylab::scene::Mesh;
use raylab::stats::Counters;
use raylab::test_util::Soup;
use raylab::tracers::embree::STREAM_LENGTH;
use raylab::tracers::registry::TRACERS;
use raylab::tracers::{build_tracer, Params, Tracer, TracerInfo};
use raylab::verify::stability::cases::ill_formed_variants;

const QUALITIES: [&str; 4] = ["low", "medium", "high", "refit"];

/// Every Embree tracer of this build, by the structure it traverses: Embree 3's five, and Embree
/// 4's four when the build has it (`.ci/setup` fetches it, so CI always does; without it the
/// Embree 4 half of the test is skipped, and says so).
fn embree_tracers() -> Vec<(AccelKind, Vec<&'static str>)> {
    let mut by_kind: Vec<(AccelKind, Vec<&'static str>)> = Vec::new();
    for t in TRACERS.iter().filter(|t| t.accel.is_embree()) {
        match by_kind.iter_mut().find(|(kind, _)| *kind == t.accel) {
            Some((_, names)) => names.push(t.name),
            None => by_kind.push((t.accel, vec![t.name])),
        }
    }
    let versions = if EMBREE4_BUILT { 2 } else { 1 };
    assert_eq!(by_kind.len(), versions);
    assert_eq!(by_kind[0].1.len(), 5, "Embree 3: 1, 4, 8, 16, stream");
    if EMBREE4_BUILT {
        assert_eq!(by_kind[1].1.len(), 4, "Embree 4: 1, 4, 8, 16");
    } else {
        println!("SKIPPED the Embree 4 tracers: {EMBREE4_HINT}");
    }
    by_kind
}

fn mesh_of(triangles: Vec<Triangle>) -> Mesh {
    let material_ids = vec![0; triangles.len()];
    Mesh {
        triangles,
        material_ids,
    }
}

/// Quad a-b-c-d as triangles [a, b, c] and [a, c, d].
fn quad(tris: &mut Vec<Triangle>, [a, b, c, d]: [[f32; 3]; 4]) {
    let (a, b, c, d) = (Vec3::from(a), Vec3::from(b), Vec3::from(c), Vec3::from(d));
    tris.push(Triangle::new(a, b, c));
    tris.push(Triangle::new(a, c, d));
}

/// The unit cube (prims 0–11: faces −x, +x, −y, +y, −z, +z) above a floor at z = −1 spanning
/// [−5, 5]² (prims 12, 13).
fn box_on_floor() -> Mesh {
    let mut t = Vec::new();
    quad(
        &mut t,
        [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]],
    );
    quad(
        &mut t,
        [[1., 0., 0.], [1., 1., 0.], [1., 1., 1.], [1., 0., 1.]],
    );
    quad(
        &mut t,
        [[0., 0., 0.], [1., 0., 0.], [1., 0., 1.], [0., 0., 1.]],
    );
    quad(
        &mut t,
        [[0., 1., 0.], [1., 1., 0.], [1., 1., 1.], [0., 1., 1.]],
    );
    quad(
        &mut t,
        [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
    );
    quad(
        &mut t,
        [[0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.]],
    );
    quad(
        &mut t,
        [
            [-5., -5., -1.],
            [5., -5., -1.],
            [5., 5., -1.],
            [-5., 5., -1.],
        ],
    );
    mesh_of(t)
}

struct Expected {
    ray: Ray,
    /// (prim, t, u, v), worked out by hand from the quads above.
    hit: Option<(u32, f32, f32, f32)>,
}

fn box_rays() -> Vec<Expected> {
    let down =
        |x: f32, y: f32, tmin: f32, tmax: f32| Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z, tmin, tmax);
    let inf = f32::INFINITY;
    vec![
        // Top face, first half (x > y): (x, y) = (u + v, v).
        Expected {
            ray: down(0.75, 0.25, 0.0, inf),
            hit: Some((10, 4.0, 0.5, 0.25)),
        },
        // Top face, second half: (x, y) = (u, u + v).
        Expected {
            ray: down(0.25, 0.75, 0.0, inf),
            hit: Some((11, 4.0, 0.25, 0.5)),
        },
        // Beside the box onto the floor: (x, y) = (−5 + 10u + 10v, −5 + 10v).
        Expected {
            ray: down(3.0, 2.0, 0.0, inf),
            hit: Some((12, 6.0, 0.1, 0.7)),
        },
        // tmax cuts before the top face.
        Expected {
            ray: down(0.75, 0.25, 0.0, 3.9),
            hit: None,
        },
        // tmin skips the top face: the bottom face at t = 5.
        Expected {
            ray: down(0.75, 0.25, 4.5, inf),
            hit: Some((8, 5.0, 0.5, 0.25)),
        },
        // tmin skips the box: the floor, (x, y) = (0.75, 0.25) → u = 0.05, v = 0.525.
        Expected {
            ray: down(0.75, 0.25, 5.5, inf),
            hit: Some((12, 6.0, 0.05, 0.525)),
        },
        // Outside everything.
        Expected {
            ray: down(10.0, 10.0, 0.0, inf),
            hit: None,
        },
        Expected {
            ray: Ray::new(Vec3::new(0.5, 0.5, 5.0), Vec3::Z, 0.0, inf),
            hit: None,
        },
        // Sideways into the −x face: (y, z) = (u, u + v) on its second triangle.
        Expected {
            ray: Ray::new(Vec3::new(-5.0, 0.25, 0.75), Vec3::X, 0.0, inf),
            hit: Some((1, 5.0, 0.25, 0.5)),
        },
    ]
}

fn batch(rays: impl IntoIterator<Item = Ray>) -> RayBatch {
    let mut b = RayBatch::new(RayKind::Primary);
    for (i, r) in rays.into_iter().enumerate() {
        b.push(r, i as u32);
    }
    b
}

fn accel(kind: AccelKind, mesh: &Mesh, params: &Params) -> Accel {
    kind.build(mesh, params).unwrap()
}

fn tracer(name: &str, params: &Params, accel: &Accel) -> Box<dyn Tracer> {
    build_tracer(TracerInfo::find(name).unwrap(), params, accel).unwrap()
}

fn trace(t: &dyn Tracer, b: &RayBatch) -> (Vec<Hit>, Vec<bool>) {
    let mut hits = vec![Hit::MISS; b.len()];
    let mut occluded = vec![false; b.len()];
    t.intersect(b.view(), &mut hits);
    t.occluded(b.view(), &mut occluded);
    (hits, occluded)
}

/// Every Embree structure configuration: 4 qualities × robust or not.
fn embree_configs() -> Vec<Params> {
    QUALITIES
        .iter()
        .flat_map(|q| [false, true].map(|r| Params::new().with("quality", q).with("robust", r)))
        .collect()
}

fn contexts() -> [Params; 2] {
    [
        Params::new().with("context", "incoherent"),
        Params::new().with("context", "coherent"),
    ]
}

#[test]
fn hand_worked_hits_in_every_lane_including_partial_packets() {
    let mesh = box_on_floor();
    let expected = box_rays();
    // 2·4096 + 37 rays: three stream calls, the last packet partial for every width (16·514 + 5,
    // 8·1028 + 5, 4·2057 + 1); every lane's answer is known.
    let n = 2 * STREAM_LENGTH + 37;
    let rays = batch((0..n).map(|i| expected[i % expected.len()].ray));
    let check = |who: &str, hits: &[Hit], occluded: &[bool]| {
        for i in 0..n {
            let e = &expected[i % expected.len()];
            match e.hit {
                None => {
                    assert_eq!(hits[i], Hit::MISS, "{who}: ray {i} should miss");
                    assert!(!occluded[i], "{who}: ray {i} should be unoccluded");
                }
                Some((prim, t, u, v)) => {
                    let h = hits[i];
                    assert_eq!(h.prim, prim, "{who}: ray {i}: {h:?}");
                    assert!(
                        (h.t - t).abs() <= 1e-5 * t,
                        "{who}: ray {i}: t {} ≠ {t}",
                        h.t
                    );
                    assert!(
                        (h.u - u).abs() < 1e-5 && (h.v - v).abs() < 1e-5,
                        "{who}: ray {i}: {h:?}"
                    );
                    let p = mesh.triangles[prim as usize].point(h.u, h.v);
                    assert!(
                        p.distance(e.ray.at(t)) < 1e-4,
                        "{who}: ray {i}: (u, v) names {p}"
                    );
                    assert!(occluded[i], "{who}: ray {i} should be occluded");
                }
            }
        }
    };
    let reference = accel(AccelKind::Bvh, &mesh, &Params::new());
    let (hits, occluded) = trace(&*tracer("reference", &Params::new(), &reference), &rays);
    check("reference", &hits, &occluded);
    for config in embree_configs() {
        for (kind, names) in embree_tracers() {
            let scene = accel(kind, &mesh, &config);
            for context in contexts() {
                for name in &names {
                    let (hits, occluded) = trace(&*tracer(name, &context, &scene), &rays);
                    check(&format!("{name} {config} {context}"), &hits, &occluded);
                }
            }
        }
    }
}

/// A reproducible stream of uniform floats in [0, 1) (LCG, top 24 bits).
struct Lcg(u32);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(1664525).wrapping_add(1013904223);
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

fn triangle_soup(n: usize, seed: u64) -> Mesh {
    let soup = Soup {
        lo: 0.0,
        hi: 10.0,
        size: 0.5,
        long: None,
        collinear_every: None,
    };
    mesh_of(soup.triangles(n, seed))
}

/// Rays from around the soup's box through points inside it, with a random tmax on a third of
/// them so occlusion has both answers.
fn soup_rays(n: usize, rng: &mut Lcg) -> RayBatch {
    batch((0..n).map(|i| {
        let origin = rng.vec3() * 16.0 - 3.0;
        let target = rng.vec3() * 10.0;
        let tmax = if i % 3 == 0 {
            rng.next() * 12.0
        } else {
            f32::INFINITY
        };
        Ray::new(origin, (target - origin).normalize(), 0.0, tmax)
    }))
}

fn relative_gap(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-6)
}

#[test]
fn random_soup_matches_the_reference_tracer() {
    let mut rng = Lcg(2024);
    let mesh = triangle_soup(3000, 2024);
    // 3001 = 187·16 + 9: the last packet is partial for every width.
    let rays = soup_rays(3001, &mut rng);
    let reference = accel(AccelKind::Bvh, &mesh, &Params::new());
    let reference = tracer("reference", &Params::new(), &reference);
    let (want, want_occluded) = trace(&*reference, &rays);
    // Closest hit with no tmax: occlusion within [tmin, tmax] is a tie when it lies at tmax.
    let unbounded = {
        let mut b = rays.clone();
        b.tmax.fill(f32::INFINITY);
        trace(&*reference, &b).0
    };
    let hit_count = want.iter().filter(|h| h.is_hit()).count();
    let occluded_count = want_occluded.iter().filter(|&&o| o).count();
    assert!(
        hit_count > 1000 && hit_count < 2900,
        "the test needs hits and misses: {hit_count}"
    );
    assert!(occluded_count > 500, "{occluded_count}");

    let mut ties = 0;
    let mut compared = 0;
    for config in embree_configs() {
        for (kind, names) in embree_tracers() {
            let scene = accel(kind, &mesh, &config);
            for context in contexts() {
                for name in &names {
                    compared += rays.len();
                    let who = format!("{name} {config} {context}");
                    let (got, got_occluded) = trace(&*tracer(name, &context, &scene), &rays);
                    for i in 0..rays.len() {
                        let (g, w) = (got[i], want[i]);
                        assert_eq!(
                            g.is_hit(),
                            w.is_hit(),
                            "{who}: ray {i}: {g:?} vs reference {w:?}"
                        );
                        if w.is_hit() {
                            assert!(
                                relative_gap(g.t, w.t) <= 1e-4,
                                "{who}: ray {i}: t {} vs {}",
                                g.t,
                                w.t
                            );
                            if g.prim == w.prim {
                                assert!(
                                    (g.u - w.u).abs() < 1e-3 && (g.v - w.v).abs() < 1e-3,
                                    "{who}: ray {i}"
                                );
                            } else {
                                // A tie: two triangles at the same distance (within 1e-4); either
                                // answer is right.
                                ties += 1;
                            }
                        }
                        if got_occluded[i] != want_occluded[i] {
                            let at_tmax = relative_gap(unbounded[i].t, rays.tmax[i]) <= 1e-4;
                            assert!(
                                at_tmax,
                                "{who}: ray {i}: occluded {} vs reference {}",
                                got_occluded[i], want_occluded[i]
                            );
                            ties += 1;
                        }
                    }
                }
            }
        }
    }
    println!("{ties} ties in {compared} comparisons");
    assert!(
        ties * 10_000 <= compared,
        "{ties} ties in {compared} comparisons is not rare"
    );
}

#[test]
fn threads_trace_one_committed_scene_concurrently() {
    use rayon::prelude::*;
    let mut rng = Lcg(77);
    let mesh = triangle_soup(2000, 77);
    let rays = soup_rays(4000, &mut rng);
    for (kind, names) in embree_tracers() {
        let scene = accel(kind, &mesh, &Params::new().with("robust", true));
        for name in names {
            let t = tracer(name, &Params::new(), &scene);
            let (want, _) = trace(&*t, &rays);
            // Chunks of 100 (not a multiple of 16), each on whichever thread rayon picks.
            let mut got = vec![Hit::MISS; rays.len()];
            got.par_chunks_mut(100).enumerate().for_each(|(c, hits)| {
                let first = c * 100;
                t.intersect(rays.view().slice(first..first + hits.len()), hits);
            });
            assert_eq!(got, want, "{name}");
        }
    }
}

#[test]
fn counters_count_rays_only() {
    let mesh = box_on_floor();
    let rays = batch(box_rays().into_iter().map(|e| e.ray));
    for (kind, names) in embree_tracers() {
        let scene = accel(kind, &mesh, &Params::new());
        for name in names {
            let t = tracer(name, &Params::new(), &scene);
            assert!(!t.counts_internals(), "{name}");
            let mut counters = Counters::default();
            let mut hits = vec![Hit::MISS; rays.len()];
            let mut occluded = vec![false; rays.len()];
            t.intersect_counted(rays.view(), &mut hits, &mut counters);
            t.occluded_counted(rays.view(), &mut occluded, &mut counters);
            let expected = Counters {
                rays: 2 * rays.len() as u64,
                ..Counters::default()
            };
            assert_eq!(counters, expected, "{name}");
        }
    }
}

#[test]
fn empty_mesh_builds_and_every_ray_misses() {
    let rays = batch(box_rays().into_iter().map(|e| e.ray));
    for config in embree_configs() {
        for (kind, names) in embree_tracers() {
            let scene = accel(kind, &Mesh::default(), &config);
            for name in names {
                let (hits, occluded) = trace(&*tracer(name, &Params::new(), &scene), &rays);
                assert!(hits.iter().all(|h| *h == Hit::MISS), "{name} {config}");
                assert!(occluded.iter().all(|o| !o), "{name} {config}");
            }
        }
    }
}

/// Rays straight down through the centres of the box's top triangles.
fn top_face_rays(offset: Vec3) -> RayBatch {
    batch(
        [(0.75, 0.25), (0.25, 0.75)]
            .map(|(x, y)| Ray::new(Vec3::new(x, y, 5.0) + offset, -Vec3::Z, 0.0, f32::INFINITY)),
    )
}

#[test]
fn refit_moves_the_hits_with_the_vertices() {
    let mesh = box_on_floor();
    let lift = Vec3::new(20.0, 0.0, 2.0);
    // The box moves 20 to +x and 2 up; the floor stays.
    let moved = mesh_of(
        mesh.triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                if i < 12 {
                    Triangle {
                        v: t.v.map(|p| p + lift),
                    }
                } else {
                    *t
                }
            })
            .collect(),
    );
    // As the runner does per frame: `rebuild` refits a scene of quality refit in place and
    // builds any other anew.
    for (kind, names) in embree_tracers() {
        for quality in [BuildQuality::Refit, BuildQuality::Medium] {
            for robust in [false, true] {
                let params = Params::new()
                    .with("quality", quality)
                    .with("robust", robust);
                let first = accel(kind, &mesh, &params);
                let accel = kind.rebuild(Some(first), &moved, &params).unwrap();
                assert!(accel.build_seconds() > 0.0);
                for name in &names {
                    let t = tracer(name, &Params::new(), &accel);
                    // At the new place: the top face now at z = 3, so t = 2.
                    let (hits, _) = trace(&*t, &top_face_rays(lift - Vec3::Z * 2.0));
                    assert_eq!(
                        hits.iter().map(|h| h.prim).collect::<Vec<_>>(),
                        [10, 11],
                        "{name} {quality}"
                    );
                    assert!(
                        hits.iter().all(|h| (h.t - 2.0).abs() < 1e-5),
                        "{name} {quality}: {hits:?}"
                    );
                    // Where the box was, only the floor remains (x > y: prim 12, x < y: prim 13) at
                    // z = −1, t = 6.
                    let (hits, _) = trace(&*t, &top_face_rays(Vec3::ZERO));
                    assert_eq!(
                        hits.iter().map(|h| h.prim).collect::<Vec<_>>(),
                        [12, 13],
                        "{name} {quality}"
                    );
                    assert!(
                        hits.iter().all(|h| (h.t - 6.0).abs() < 1e-5),
                        "{name} {quality}: {hits:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn refit_rejects_a_different_triangle_count() {
    let mesh = box_on_floor();
    let config = EmbreeConfig {
        quality: BuildQuality::Refit,
        robust: false,
    };
    let mut scene: EmbreeScene =
        EmbreeScene::build(Device::shared().unwrap(), &mesh, config).unwrap();
    let fewer = mesh_of(mesh.triangles[..12].to_vec());
    let err = scene.refit(&fewer).unwrap_err();
    assert!(err.to_string().contains("14 triangles, got 12"), "{err}");
}

#[test]
fn registry_lists_the_embree_tracers_and_checks_their_parameters() {
    for (kind, names) in embree_tracers() {
        for name in names {
            let info = TracerInfo::find(name).unwrap();
            assert_eq!(info.accel, kind);
            assert_eq!(info.accepts(), ["context", "quality", "robust"]);
            let version = if kind == AccelKind::Embree { "3" } else { "4" };
            assert!(name.starts_with(&format!("embree{version}-")), "{name}");
            assert!(
                info.about
                    .starts_with(&format!("Embree {version} baseline")),
                "{name}"
            );
        }
    }
    // The old names of Embree 3's tracers are aliases of the new ones.
    for (alias, name) in [
        ("embree1", "embree3-1"),
        ("embree4", "embree3-4"),
        ("embree8", "embree3-8"),
        ("embree16", "embree3-16"),
        ("embree-stream", "embree3-stream"),
    ] {
        assert!(std::ptr::eq(
            TracerInfo::find(alias).unwrap(),
            TracerInfo::find(name).unwrap()
        ));
    }
    let mesh = box_on_floor();
    let scene = accel(AccelKind::Embree, &mesh, &Params::new());
    let info = TracerInfo::find("embree8").unwrap();
    assert!(build_tracer(info, &Params::new().with("context", "sideways"), &scene).is_err());
    assert!(build_tracer(info, &Params::new().with("leaf_size", 2), &scene).is_err());
    assert!(AccelKind::Embree
        .build(&mesh, &Params::new().with("quality", "ultra"))
        .is_err());
    // An Embree tracer needs an Embree scene.
    let bvh = accel(AccelKind::Bvh, &mesh, &Params::new());
    assert!(build_tracer(info, &Params::new(), &bvh).is_err());
    assert!(scene.build_seconds() > 0.0);
}

/// Every ill-formed ray of the stability suite (NaN, infinite, zero direction, empty or negative
/// intervals) is a miss and unoccluded for every Embree tracer, in every lane of a packet, beside
/// good rays answered as if alone: Embree itself would abort the process on some of them.
#[test]
fn ill_formed_rays_miss_and_never_abort() {
    let mesh = box_on_floor();
    let good = box_rays()[0].ray;
    let variants = ill_formed_variants(good);
    // Good and ill-formed rays alternating, 3 times over: every lane position of a 16-packet sees
    // both.
    let mut rays = Vec::new();
    for _ in 0..3 {
        for (_, bad) in &variants {
            rays.extend([good, *bad]);
        }
    }
    let b = batch(rays.iter().copied());
    for (kind, names) in embree_tracers() {
        let scene = accel(kind, &mesh, &Params::new());
        for name in names {
            let (hits, occluded) = trace(&*tracer(name, &Params::new(), &scene), &b);
            for i in 0..rays.len() {
                let variant = variants[(i / 2) % variants.len()].0;
                if i % 2 == 0 {
                    // Within a few ulps: Embree's AVX2 kernels divide by a refined reciprocal
                    // estimate (3.9999998 on an AVX2-only EPYC), its AVX-512 ones exactly.
                    let t_near = (hits[i].t - 4.0).abs() <= 16.0 * f32::EPSILON;
                    assert!(
                        hits[i].prim == 10 && t_near,
                        "{name}: good ray {i}: {:?}",
                        hits[i]
                    );
                    assert!(occluded[i], "{name}: good ray {i}");
                } else {
                    assert_eq!(hits[i], Hit::MISS, "{name}: {variant}");
                    assert!(!occluded[i], "{name}: {variant}");
                }
            }
        }
    }
}
