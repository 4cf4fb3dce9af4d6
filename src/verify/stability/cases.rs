//! The stiff and extreme cases of the stability suite, generated (no files): each is a mesh, one
//! batch of rays, and which rays must hit. Every case is swept over a magnitude (an offset from
//! the origin, a scale ratio, a bounce count). Meshes stay small (≤ 20K triangles) so the f64
//! ground truth can test every ray against every triangle.

use std::fmt;

use glam::{DVec3, Vec3};

use crate::geometry::{Ray, RayBatch, RayKind, Triangle};
use crate::random::SplitMix64;
use crate::render::offset::{coordinate_scale, offset_ray_origin};
use crate::scene::tessellate::Surface;
use crate::scene::Mesh;
use crate::verify::truth::Truth;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CaseKind {
    Watertight,
    ScaleRange,
    Slivers,
    Grazing,
    AxisParallel,
    IllFormed,
    SelfIntersection,
    NeedleFans,
}

impl CaseKind {
    pub const ALL: [CaseKind; 8] = [
        CaseKind::Watertight,
        CaseKind::ScaleRange,
        CaseKind::Slivers,
        CaseKind::Grazing,
        CaseKind::AxisParallel,
        CaseKind::IllFormed,
        CaseKind::SelfIntersection,
        CaseKind::NeedleFans,
    ];

    pub fn name(self) -> &'static str {
        match self {
            CaseKind::Watertight => "watertight",
            CaseKind::ScaleRange => "scale_range",
            CaseKind::Slivers => "slivers",
            CaseKind::Grazing => "grazing",
            CaseKind::AxisParallel => "axis_parallel",
            CaseKind::IllFormed => "ill_formed",
            CaseKind::SelfIntersection => "self_intersection",
            CaseKind::NeedleFans => "needle_fans",
        }
    }

    pub fn parse(name: &str) -> Option<CaseKind> {
        CaseKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// What the swept magnitude of this kind means.
    pub fn magnitude_name(self) -> &'static str {
        match self {
            CaseKind::ScaleRange => "enclosure / object size",
            CaseKind::SelfIntersection => "bounce",
            _ => "offset from the origin",
        }
    }
}

impl fmt::Display for CaseKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What the suite sweeps (`[stability]` in an experiment file).
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub kinds: Vec<CaseKind>,
    /// Offsets from the origin (watertight, slivers, grazing, axis-parallel, ill-formed, needle
    /// fans).
    pub offsets: Vec<f64>,
    /// Mesh scales of the watertight case.
    pub scales: Vec<f64>,
    /// Enclosure-to-object size ratios of the scale-range case.
    pub ratios: Vec<f64>,
    /// Deepest bounce of the self-intersection case (1 … this).
    pub bounces: u32,
    pub seed: u64,
}

impl Default for Sweep {
    fn default() -> Self {
        Sweep {
            kinds: CaseKind::ALL.to_vec(),
            offsets: vec![0.0, 1e3, 1e5, 1e6],
            scales: vec![1e-3, 1.0, 1e4],
            ratios: vec![1e3, 1e4, 1e5, 1e6],
            bounces: 8,
            seed: 1,
        }
    }
}

/// One generated case.
pub struct Case {
    pub kind: CaseKind,
    /// Which mesh and rays, e.g. `sphere scale=0.001`.
    pub variant: String,
    pub magnitude: f64,
    pub mesh: Mesh,
    pub rays: RayBatch,
    /// Rays that must hit something (closed meshes around their origins, vertices surrounded by
    /// triangles); only those the f64 ground truth sees meeting a triangle are kept as such.
    pub must_hit: Vec<bool>,
}

/// Every case of the sweep, in order.
pub fn generate(sweep: &Sweep) -> Vec<Case> {
    let mut cases = Vec::new();
    let seed = sweep.seed;
    for &kind in &sweep.kinds {
        match kind {
            CaseKind::Watertight => {
                for &offset in &sweep.offsets {
                    for &scale in &sweep.scales {
                        cases.push(watertight(Closed::Sphere, offset, scale, seed));
                        cases.push(watertight(Closed::Cube, offset, scale, seed));
                    }
                }
            }
            CaseKind::ScaleRange => {
                cases.extend(sweep.ratios.iter().map(|&r| scale_range(r, seed)));
            }
            CaseKind::Slivers => {
                for &offset in &sweep.offsets {
                    cases.push(slivers(offset, false, seed));
                    cases.push(slivers(offset, true, seed));
                }
            }
            CaseKind::Grazing => cases.extend(sweep.offsets.iter().map(|&o| grazing(o, seed))),
            CaseKind::AxisParallel => cases.extend(sweep.offsets.iter().map(|&o| axis_parallel(o))),
            CaseKind::IllFormed => cases.extend(sweep.offsets.iter().map(|&o| ill_formed(o, seed))),
            CaseKind::SelfIntersection => {
                for surface in [Bouncing::Sphere, Bouncing::Coplanar] {
                    cases.extend(self_intersection(surface, sweep.bounces, seed));
                }
            }
            CaseKind::NeedleFans => {
                cases.extend(sweep.offsets.iter().map(|&o| needle_fans(o, seed)))
            }
        }
    }
    cases
}

fn mesh_of(triangles: impl IntoIterator<Item = Triangle>) -> Mesh {
    let mut mesh = Mesh::default();
    for tri in triangles {
        mesh.push(tri, 0);
    }
    mesh
}

/// `p·scale + offset` computed in f64 and rounded once, so shared vertices stay bit-identical.
fn placed(offset: f64, scale: f64) -> impl Fn(Vec3) -> Vec3 {
    move |p| (p.as_dvec3() * scale + DVec3::splat(offset)).as_vec3()
}

/// The f32 ray from `from` towards `to`, its direction computed in f64 and rounded once.
fn towards(from: DVec3, to: DVec3) -> Ray {
    let o = from.as_vec3();
    Ray::new(o, (to - o.as_dvec3()).as_vec3(), 0.0, f32::INFINITY)
}

fn batch(rays: &[Ray]) -> RayBatch {
    let mut batch = RayBatch::with_capacity(RayKind::Diffuse, rays.len());
    for (i, ray) in rays.iter().enumerate() {
        batch.push(*ray, i as u32);
    }
    batch
}

/// A case whose rays must all hit, keeping as must-hit only the rays the f64 truth sees meeting
/// a triangle (a zero direction after rounding, say, meets none).
fn all_must_hit(
    kind: CaseKind,
    variant: String,
    magnitude: f64,
    mesh: Mesh,
    rays: Vec<Ray>,
) -> Case {
    let must_hit = rays
        .iter()
        .map(|r| !Truth::of(&mesh, r).hits.is_empty())
        .collect();
    Case {
        kind,
        variant,
        magnitude,
        mesh,
        rays: batch(&rays),
        must_hit,
    }
}

#[derive(Clone, Copy)]
enum Closed {
    Sphere,
    Cube,
}

/// Rays from inside a closed tessellated mesh, aimed exactly at its vertices and edge midpoints
/// and in random directions: with watertight tests every one hits.
fn watertight(shape: Closed, offset: f64, scale: f64, seed: u64) -> Case {
    let (name, surface) = match shape {
        Closed::Sphere => ("sphere", Surface::uv_sphere(32, 16)),
        Closed::Cube => ("cube", centred_cube(4)),
    };
    let map = placed(offset, scale);
    let mesh = mesh_of(surface.triangles(&map));
    // A mesh fewer than 2⁸ f32 spacings across at its offset is crushed onto a few
    // representable points: it is still traced (no crash, no hang, no false hit), but no ray
    // can be required to hit it.
    let crushed = scale < offset * f64::powi(2.0, -15);
    let centre = DVec3::splat(offset);
    let mut rng = SplitMix64::new(seed ^ 0x57a7);
    let mut origins = vec![centre];
    origins.extend((0..3).map(|_| centre + rng.vec3(-0.4, 0.4).as_dvec3() * scale));
    let mut targets: Vec<DVec3> = surface
        .vertices
        .iter()
        .map(|&v| map(v).as_dvec3())
        .collect();
    for f in &surface.faces {
        for i in 0..3 {
            let (a, b) = (f[i] as usize, f[(i + 1) % 3] as usize);
            let (a, b) = (map(surface.vertices[a]), map(surface.vertices[b]));
            targets.push((a.as_dvec3() + b.as_dvec3()) * 0.5);
        }
    }
    let mut rays: Vec<Ray> = Vec::new();
    for &o in &origins {
        rays.extend(targets.iter().map(|&t| towards(o, t)));
        rays.extend((0..256).map(|_| towards(o, o + rng.direction().as_dvec3())));
    }
    rays.retain(|r| r.dir != Vec3::ZERO);
    let mut case = all_must_hit(
        CaseKind::Watertight,
        format!("{name} scale={scale:e}"),
        offset,
        mesh,
        rays,
    );
    if crushed {
        case.variant += " (crushed: no must-hit rays)";
        case.must_hit.iter_mut().for_each(|m| *m = false);
    }
    case
}

/// The cube `[-1, 1]³`, each face cut into `n × n` cells.
fn centred_cube(n: u32) -> Surface {
    let mut cube = Surface::cube(n);
    for v in &mut cube.vertices {
        *v = *v * 2.0 - Vec3::ONE;
    }
    cube
}

/// A unit sphere inside a closed box `ratio` times larger: rays from between them towards the
/// sphere and in random directions all hit one or the other.
fn scale_range(ratio: f64, seed: u64) -> Case {
    let sphere = Surface::uv_sphere(24, 12);
    let mut tris = sphere.triangles(|p| p);
    tris.extend(centred_cube(2).triangles(placed(0.0, ratio * 0.5)));
    let mesh = mesh_of(tris);
    let mut rng = SplitMix64::new(seed ^ 0x5ca1e);
    let rays = (0..2048)
        .map(|i| {
            // Origins from just outside the sphere to a quarter of the way to the walls.
            let distance = 2.0 * (ratio / 8.0).powf(rng.unit() as f64);
            let o = rng.direction().as_dvec3() * distance;
            let target = if i % 2 == 0 {
                rng.direction().as_dvec3()
            } else {
                o + rng.direction().as_dvec3()
            };
            towards(o, target)
        })
        .collect();
    all_must_hit(
        CaseKind::ScaleRange,
        "sphere in box".into(),
        ratio,
        mesh,
        rays,
    )
}

/// Crowded needle-thin, zero-area, collinear and repeated-vertex triangles in `[-1, 1]³` (plus
/// `offset`), and either rays into the crowd or (`secondary`) rays leaving the surfaces the first
/// ones hit, from the f64 hit points pushed off by the renderer's own offset.
fn slivers(offset: f64, secondary: bool, seed: u64) -> Case {
    let mut rng = SplitMix64::new(seed ^ 0x511e);
    let at = |p: Vec3| placed(offset, 1.0)(p);
    let tris: Vec<Triangle> = (0..3000)
        .map(|i| {
            let c = rng.vec3(-1.0, 1.0);
            let d = rng.vec3(-0.3, 0.3);
            let (a, b, e) = match i % 6 {
                0 => (c, c + d, c + 2.0 * d), // collinear
                1 => (c, c, c),               // a point
                2 => (c, c, c + d),           // repeated vertex
                3 => (
                    c - d * 3.0,
                    c + d * 3.0,
                    c + d * 3.0 + rng.vec3(-1e-4, 1e-4),
                ), // needle
                _ => (c, c + rng.vec3(-0.1, 0.1), c + rng.vec3(-0.1, 0.1)),
            };
            Triangle::new(at(a), at(b), at(e))
        })
        .collect();
    let mesh = mesh_of(tris);
    let centre = DVec3::splat(offset);
    let primary: Vec<Ray> = (0..4096)
        .map(|_| {
            let o = centre + rng.direction().as_dvec3() * 3.0;
            towards(o, centre + rng.vec3(-1.0, 1.0).as_dvec3())
        })
        .collect();
    let rays = if secondary {
        primary
            .iter()
            .filter_map(|ray| leaving(&mesh, ray, &mut rng))
            .collect()
    } else {
        primary
    };
    let n = rays.len();
    Case {
        kind: CaseKind::Slivers,
        variant: if secondary { "secondary" } else { "primary" }.into(),
        magnitude: offset,
        mesh,
        rays: batch(&rays),
        must_hit: vec![false; n],
    }
}

/// A random ray leaving the nearest surface `ray` meets (by the f64 truth), from the hit point
/// offset to the side the ray came from, into that hemisphere.
fn leaving(mesh: &Mesh, ray: &Ray, rng: &mut SplitMix64) -> Option<Ray> {
    let hit = Truth::of(mesh, ray).hits.first().copied()?;
    let tri = &mesh.triangles[hit.prim as usize];
    let mut n = tri.normal();
    if n == Vec3::ZERO {
        n = -ray.dir;
    }
    if n.dot(ray.dir) > 0.0 {
        n = -n;
    }
    let p = (ray.origin.as_dvec3() + ray.dir.as_dvec3() * hit.t).as_vec3();
    let origin = offset_ray_origin(p, n, coordinate_scale(tri));
    let mut dir = rng.direction();
    if dir.dot(n) < 0.0 {
        dir = -dir;
    }
    Some(Ray::new(origin, dir, 0.0, f32::INFINITY))
}

/// Fans of needles in a needle-fan case, and needles per fan: 20K triangles, as in issue 30.
pub const NEEDLE_FANS: usize = 20;
pub const NEEDLES_PER_FAN: usize = 1000;

/// Crowded needle fans (issue 30): `NEEDLE_FANS` fans of `NEEDLES_PER_FAN` needle-thin triangles,
/// each fan's needles sharing an apex and spreading little, the fans packed into `[-1, 1]³` (plus
/// `offset`); one needle in four is a sliver whose third vertex lies 10⁻⁶ off its long edge. The
/// rays are the diffuse bounce of the scene: from the f64 hit of a ray into the crowd,
/// pushed off by the renderer's own offset, into the hemisphere the ray came from — rays leaving
/// one needle among thousands a few 10⁻⁴ away.
fn needle_fans(offset: f64, seed: u64) -> Case {
    let mut rng = SplitMix64::new(seed ^ 0xfa25);
    let at = placed(offset, 1.0);
    let mut tris = Vec::with_capacity(NEEDLE_FANS * NEEDLES_PER_FAN);
    for _ in 0..NEEDLE_FANS {
        let apex = rng.vec3(-1.0, 1.0);
        let axis = rng.direction();
        for i in 0..NEEDLES_PER_FAN {
            let dir = (axis + rng.vec3(-0.05, 0.05)).normalize();
            let tip = apex + dir * rng.range(0.5, 1.0);
            let across = dir.any_orthonormal_vector();
            let width = if i % 4 == 0 { 1e-6 } else { 1e-3 };
            let side = across * width * rng.range(0.5, 1.0);
            tris.push(Triangle::new(at(apex), at(tip), at(tip + side)));
        }
    }
    let mesh = mesh_of(tris);
    let centre = DVec3::splat(offset);
    let rays: Vec<Ray> = (0..2048)
        .filter_map(|_| {
            let o = centre + rng.direction().as_dvec3() * 3.0;
            let primary = towards(o, centre + rng.vec3(-1.0, 1.0).as_dvec3());
            leaving(&mesh, &primary, &mut rng)
        })
        .collect();
    let n = rays.len();
    Case {
        kind: CaseKind::NeedleFans,
        variant: format!("{NEEDLE_FANS} fans x {NEEDLES_PER_FAN} needles, diffuse"),
        magnitude: offset,
        mesh,
        rays: batch(&rays),
        must_hit: vec![false; n],
    }
}

/// An 8×8 tessellated square in z = 0 (plus `offset`): rays in its plane, along its shared
/// edges, along the faces of its bounding box, and from above exactly through its shared
/// interior vertices and edge midpoints (those must hit: every interior point of the square is
/// covered).
fn grazing(offset: f64, seed: u64) -> Case {
    let n = 8;
    let square = Surface::quad(Vec3::new(-1.0, -1.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0, n);
    let map = placed(offset, 1.0);
    let mesh = mesh_of(square.triangles(&map));
    let mut rng = SplitMix64::new(seed ^ 0x9a2e);
    let mut rays = Vec::new();
    let mut must_hit = Vec::new();
    let mut add = |ray: Ray, must: bool| {
        rays.push(ray);
        must_hit.push(must);
    };
    let grid_point = |i: u32, j: u32| {
        let s = |k: u32| -1.0 + 2.0 * k as f32 / n as f32;
        map(Vec3::new(s(i), s(j), 0.0)).as_dvec3()
    };
    for i in 0..=n {
        for j in 0..=n {
            let v = grid_point(i, j);
            let interior = (1..n).contains(&i) && (1..n).contains(&j);
            // Through the vertex from above, slanted and straight.
            let above = v + DVec3::new(
                rng.range(-0.5, 0.5) as f64,
                rng.range(-0.5, 0.5) as f64,
                2.0,
            );
            add(towards(above, v), interior);
            add(towards(v + DVec3::Z, v), interior);
            if i < n {
                // Through the midpoint of the edge to the next vertex (shared when interior).
                let mid = (v + grid_point(i + 1, j)) * 0.5;
                add(
                    towards(mid + DVec3::new(0.1, 0.3, 1.0), mid),
                    (1..n).contains(&j),
                );
                // Along the edge itself, in the plane.
                add(towards(v - DVec3::X, v), false);
            }
            if j < n {
                add(towards(v - DVec3::Y, v), false);
            }
            // In the plane of the square, through the vertex from a random direction.
            let dir = rng.direction();
            add(
                towards(v - DVec3::new(dir.x as f64, dir.y as f64, 0.0), v),
                false,
            );
        }
    }
    // Along the faces of the bounding box: the planes x = ±1 and y = ±1 at z = 0.
    for k in 0..=n {
        for (from, to) in [
            (grid_point(0, k) - DVec3::X, grid_point(0, k)),
            (grid_point(k, n) + DVec3::Y, grid_point(k, n)),
        ] {
            add(towards(from - DVec3::Z * 0.5, to + DVec3::Z * 0.5), false);
            add(towards(from, to), false);
        }
    }
    let must_hit = keep_meeting(&mesh, &rays, must_hit);
    Case {
        kind: CaseKind::Grazing,
        variant: "square 8x8".into(),
        magnitude: offset,
        mesh,
        rays: batch(&rays),
        must_hit,
    }
}

/// `must_hit` restricted to rays the f64 truth sees meeting a triangle.
fn keep_meeting(mesh: &Mesh, rays: &[Ray], must_hit: Vec<bool>) -> Vec<bool> {
    rays.iter()
        .zip(must_hit)
        .map(|(r, must)| must && !Truth::of(mesh, r).hits.is_empty())
        .collect()
}

/// The cube `[-1, 1]³` (plus `offset`), 4×4 cells a face, hit by rays along ±x, ±y, ±z (zero
/// components as +0 and −0), from outside through its grid's planes and from origins exactly on
/// them: a ray whose line crosses a face strictly inside must hit; one along an edge or a face
/// grazes.
fn axis_parallel(offset: f64) -> Case {
    let map = placed(offset, 1.0);
    let mesh = mesh_of(centred_cube(4).triangles(&map));
    let mut rays = Vec::new();
    let mut must_hit = Vec::new();
    let coords: Vec<f32> = (0..=8).map(|k| -1.0 + k as f32 * 0.25).collect();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            for negative_zero in [false, true] {
                let zero = if negative_zero { -0.0 } else { 0.0 };
                let mut dir = Vec3::splat(zero);
                dir[axis] = sign;
                for &a in &coords {
                    for &b in &coords {
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        // From outside, and from exactly on the cube's slab plane, on a grid
                        // plane inside (x = 0.25, …).
                        for start in [-3.0f32, -1.0, 0.25] {
                            let mut p = Vec3::ZERO;
                            p[axis] = sign * start;
                            p[u] = a;
                            p[v] = b;
                            rays.push(Ray::new(map(p), dir, 0.0, f32::INFINITY));
                            must_hit.push(a.abs() < 1.0 && b.abs() < 1.0);
                        }
                    }
                }
            }
        }
    }
    let must_hit = keep_meeting(&mesh, &rays, must_hit);
    Case {
        kind: CaseKind::AxisParallel,
        variant: "cube 4x4".into(),
        magnitude: offset,
        mesh,
        rays: batch(&rays),
        must_hit,
    }
}

/// The ill-formed rays of the suite, each a variation of a good ray: raylab's answer to all of
/// them is a miss.
pub fn ill_formed_variants(good: Ray) -> Vec<(&'static str, Ray)> {
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let o = good.origin;
    let d = good.dir;
    vec![
        (
            "nan_origin",
            Ray {
                origin: Vec3::new(nan, o.y, o.z),
                ..good
            },
        ),
        (
            "inf_origin",
            Ray {
                origin: Vec3::new(o.x, -inf, o.z),
                ..good
            },
        ),
        (
            "nan_direction",
            Ray {
                dir: Vec3::new(d.x, d.y, nan),
                ..good
            },
        ),
        (
            "inf_direction",
            Ray {
                dir: Vec3::new(inf, d.y, d.z),
                ..good
            },
        ),
        (
            "zero_direction",
            Ray {
                dir: Vec3::ZERO,
                ..good
            },
        ),
        (
            "negative_zero_direction",
            Ray {
                dir: Vec3::splat(-0.0),
                ..good
            },
        ),
        (
            "tmin_equals_tmax",
            Ray {
                tmin: 1.0,
                tmax: 1.0,
                ..good
            },
        ),
        (
            "tmin_above_tmax",
            Ray {
                tmin: 2.0,
                tmax: 1.0,
                ..good
            },
        ),
        ("negative_tmax", Ray { tmax: -1.0, ..good }),
        ("nan_tmax", Ray { tmax: nan, ..good }),
        ("nan_tmin", Ray { tmin: nan, ..good }),
        ("negative_tmin", Ray { tmin: -1.0, ..good }),
        ("infinite_tmin", Ray { tmin: inf, ..good }),
    ]
}

/// Good rays at a sphere (plus `offset`) with one in eight replaced by an ill-formed ray: the
/// ill-formed must miss, the others must be answered as if alone (and not much slower: the
/// runner also times the good rays alone).
fn ill_formed(offset: f64, seed: u64) -> Case {
    let map = placed(offset, 1.0);
    let mesh = mesh_of(Surface::uv_sphere(32, 16).triangles(&map));
    let centre = DVec3::splat(offset);
    let mut rng = SplitMix64::new(seed ^ 0x111f);
    let mut rays = Vec::new();
    let mut must_hit = Vec::new();
    for i in 0..4096 {
        let from = centre + rng.direction().as_dvec3() * 4.0;
        let good = towards(from, centre + rng.vec3(-0.5, 0.5).as_dvec3());
        if i % 8 == 7 {
            let variants = ill_formed_variants(good);
            rays.push(variants[(i / 8) % variants.len()].1);
            must_hit.push(false);
        } else {
            rays.push(good);
            must_hit.push(true);
        }
    }
    let must_hit = keep_meeting(&mesh, &rays, must_hit);
    Case {
        kind: CaseKind::IllFormed,
        variant: "sphere, 1 in 8 ill-formed".into(),
        magnitude: offset,
        mesh,
        rays: batch(&rays),
        must_hit,
    }
}

#[derive(Clone, Copy)]
enum Bouncing {
    /// Inside a closed, finely tessellated sphere.
    Sphere,
    /// Inside a closed box whose floor is two overlapping coplanar tessellations.
    Coplanar,
}

/// Chains of diffuse bounces inside a closed mesh: bounce k's rays leave bounce k−1's f64 hits
/// (offset by the renderer's rule). One case per bounce; every ray must hit (the mesh is closed),
/// and no ray may hit the surface it leaves.
fn self_intersection(surface: Bouncing, bounces: u32, seed: u64) -> Vec<Case> {
    let (name, tris) = match surface {
        Bouncing::Sphere => ("sphere", Surface::uv_sphere(64, 32).triangles(|p| p * 3.0)),
        Bouncing::Coplanar => {
            let mut tris = centred_cube(2).triangles(|p| p * 2.0);
            for n in [5, 7] {
                let floor =
                    Surface::quad(Vec3::new(-1.5, -1.5, -1.0), Vec3::X * 3.0, Vec3::Y * 3.0, n);
                tris.extend(floor.triangles(|p| p));
            }
            ("coplanar floors", tris)
        }
    };
    let mesh = mesh_of(tris);
    let mut rng = SplitMix64::new(seed ^ 0x5e1f);
    let mut rays: Vec<Ray> = (0..2048)
        .map(|_| Ray::new(Vec3::ZERO, rng.direction(), 0.0, f32::INFINITY))
        .collect();
    let mut cases = Vec::new();
    for bounce in 1..=bounces {
        rays = rays
            .iter()
            .filter_map(|r| leaving(&mesh, r, &mut rng))
            .collect();
        cases.push(all_must_hit(
            CaseKind::SelfIntersection,
            name.into(),
            bounce as f64,
            mesh.clone(),
            rays.clone(),
        ));
    }
    cases
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_generates_cases_with_must_hit_rays_where_promised() {
        let sweep = Sweep {
            offsets: vec![0.0, 1e5],
            scales: vec![1.0],
            ratios: vec![1e4],
            bounces: 2,
            ..Sweep::default()
        };
        let cases = generate(&sweep);
        for kind in CaseKind::ALL {
            let of_kind: Vec<&Case> = cases.iter().filter(|c| c.kind == kind).collect();
            assert!(!of_kind.is_empty(), "{kind}");
            for case in of_kind {
                assert_eq!(case.must_hit.len(), case.rays.len());
                let musts = case.must_hit.iter().filter(|&&m| m).count();
                let expect_musts = !matches!(kind, CaseKind::Slivers | CaseKind::NeedleFans)
                    && !case.variant.contains("crushed");
                assert_eq!(musts > 0, expect_musts, "{kind} {}", case.variant);
            }
        }
    }

    #[test]
    fn watertight_targets_are_the_vertices_and_edge_midpoints() {
        let case = watertight(Closed::Cube, 0.0, 1.0, 1);
        let cube = centred_cube(4);
        // 4 origins × (vertices + 3 midpoints per face + 256 random directions).
        let per_origin = cube.vertices.len() + 3 * cube.faces.len() + 256;
        assert_eq!(case.rays.len(), 4 * per_origin);
        // From the centre, a ray aimed at a corner of the cube reaches it at t = 1.
        let corner = case.rays.ray(0);
        assert_eq!(corner.origin, Vec3::ZERO);
        assert_eq!(corner.origin + corner.dir, cube.vertices[0]);
        assert!(case.must_hit.iter().all(|&m| m));
    }

    #[test]
    fn ill_formed_rays_cycle_through_every_variant_and_may_miss() {
        let case = ill_formed(0.0, 1);
        let bad: Vec<usize> = (0..case.rays.len()).filter(|i| i % 8 == 7).collect();
        assert_eq!(bad.len(), 512);
        for &i in &bad {
            assert!(!case.must_hit[i]);
            assert!(!case.rays.ray(i).is_well_formed());
        }
    }
}
