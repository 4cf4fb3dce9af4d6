//! The obvhs baseline: single rays through obvhs 0.4's compressed 8-wide BVH with obvhs's own
//! traversal — its `traverse!` loop (the body of `CwBvh::ray_traverse` / `ray_traverse_miss`: a
//! stack of node groups, children visited in ray-octant order) and its SIMD child-box test
//! `CwBvhNode::intersect_ray` — with our watertight triangle test (Woop et al. 2013) as the
//! primitive test, so hits compare triangle for triangle with the from-scratch tracers.
//!
//! We call the macro rather than `ray_traverse` because the macro exposes each visited node, so
//! the counters are real, and because `ray_traverse` accepts a hit only if `t < tmax`, while our
//! contract includes `t == tmax`.
//!
//! Where obvhs's box test would lose hits, we step in:
//! - **tmin.** obvhs's box test ignores `ray.tmin` and clamps the box entry to a fixed 1e-4
//!   (`cwbvh::node::EPSILON`), so a box left before t = 1e-4 is culled: a hit that close would be
//!   lost. We hand obvhs a t axis stretched by `T_SCALE` = 2⁶⁴ (reciprocal direction and tmax
//!   multiplied by it). Multiplying by a power of two is exact, so every slab distance obvhs
//!   computes is exactly 2⁶⁴ times the unscaled one and only the clamp moves, to 1e-4 · 2⁻⁶⁴ ≈
//!   5e-24 scene units. Our triangle test still applies the ray's own `[tmin, tmax]`.
//! - **Zero direction components.** obvhs computes a slab as `q·(extent/d) + (p − o)/d` from the
//!   node's min corner `p`, and picks near and far planes by `d < 0.0`. For d = ±0 no reciprocal
//!   works: obvhs's `Ray::new` uses ±1/f32::EPSILON, so −0.0 gets a negative reciprocal with the
//!   planes of a positive direction and every box the ray runs inside is culled; +∞ gives
//!   ∞ − ∞ = NaN whenever the origin lies above `p`, which obvhs's SSE `maxps`/`minps` turn into
//!   no culling at all when the zero is on z (~160× the triangle tests on a 100K-triangle soup);
//!   any finite value culls boxes whose face plane holds the origin. So rays with an
//!   exactly-zero component test obvhs's decoded child boxes with our conservative slab test
//!   (`RayBoxTest`, Ize 2013) instead; obvhs's traversal still drives them. Such rays are rare in
//!   renders (pixel centres on the central row or column of an axis-aligned camera).
//!
//! What remains different from the reference tracer: a hit at exactly t = 0 (a ray starting on a
//! triangle, tmin = 0) is lost when the ray leaves the triangle's box at t = 0, e.g. the flat box
//! of an axis-aligned triangle, because obvhs's clamp is never 0. Renderers start secondary rays
//! off the surface, so this takes a hand-made ray.
//!
//! Counters (all real): `rays`; `nodes_visited`, one per CWBVH node whose children obvhs tests;
//! `aabb_tests`, the occupied child slots of that node (obvhs's SIMD test evaluates all 8 lanes,
//! empty slots included, but empty slots are not boxes), at the children's depth; `triangle_tests`,
//! one per call of our triangle test, at the depth of the leaf holding it (a leaf is a child slot,
//! one level below its node). The root is depth 0; obvhs never tests the root's own box.

use std::sync::Arc;

use ::obvhs::cwbvh::node::{extract_byte64, CwBvhNode};
// `traverse!` names `UVec2` unqualified, so it must be in scope where the macro expands.
use glam::{UVec2, Vec3, Vec3A};

use crate::accel::ObvhsBvh;
use crate::geometry::{Aabb, Hit, Ray, RayBoxTest, WatertightRay};
use crate::stats::Stats;
use crate::tracers::kernel::SingleRayKernel;

/// 2⁶⁴: the exact stretch of obvhs's t axis that moves its fixed box-entry clamp out of the way.
const T_SCALE: f32 = 18_446_744_073_709_551_616.0;

pub struct ObvhsTracer {
    bvh: Arc<ObvhsBvh>,
}

/// The ray as obvhs's traversal sees it: exact reciprocals and the t axis stretched by `T_SCALE`
/// (module doc). Only used for rays without zero direction components.
fn traversal_ray(ray: &Ray) -> ::obvhs::ray::Ray {
    ::obvhs::ray::Ray {
        origin: Vec3A::from(ray.origin),
        direction: Vec3A::from(ray.dir),
        inv_direction: Vec3A::from(Vec3::ONE / ray.dir * T_SCALE),
        tmin: ray.tmin * T_SCALE,
        tmax: ray.tmax * T_SCALE,
    }
}

/// The hit mask of obvhs's `CwBvhNode::intersect_ray` (same bit encoding), computed with our
/// conservative slab test (Ize 2013, `RayBoxTest`) on the node's decoded child boxes. Used for
/// rays with an exactly-zero direction component, which obvhs's arithmetic cannot cull (module
/// doc). A child's box is `p + q·extent` per axis, rounded outward by one ulp so that the f32
/// decoding never shrinks it.
fn intersect_children_robust(
    node: &CwBvhNode,
    oct_inv4: u32,
    test: &RayBoxTest,
    tmin: f32,
    tmax: f32,
) -> u32 {
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let (p, extent) = (node.p, Vec3::from(node.compute_extent()));
    let corner = |qx: u8, qy: u8, qz: u8| p + Vec3::new(qx as f32, qy as f32, qz as f32) * extent;
    let mut hits = 0;
    for child in (0..8).filter(|&c| !node.is_child_empty(c)) {
        let lo = corner(
            node.child_min_x[child],
            node.child_min_y[child],
            node.child_min_z[child],
        );
        let hi = corner(
            node.child_max_x[child],
            node.child_max_y[child],
            node.child_max_z[child],
        );
        let bounds = Aabb::new(
            Vec3::new(lo.x.next_down(), lo.y.next_down(), lo.z.next_down()),
            Vec3::new(hi.x.next_up(), hi.y.next_up(), hi.z.next_up()),
        );
        if test.hit(&bounds, tmin, tmax).is_some() {
            hits |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
        }
    }
    hits
}

impl ObvhsTracer {
    pub fn new(bvh: Arc<ObvhsBvh>) -> Self {
        ObvhsTracer { bvh }
    }

    /// Depth of `node`, which the traversal hands us by reference into `cwbvh.nodes`.
    fn depth_of(&self, node: &CwBvhNode) -> usize {
        let base = self.bvh.cwbvh.nodes.as_ptr() as usize;
        let index = (node as *const CwBvhNode as usize - base) / std::mem::size_of::<CwBvhNode>();
        self.bvh.node_depth[index] as usize
    }
}

impl SingleRayKernel for ObvhsTracer {
    #[inline(always)]
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit {
        if S::ENABLED {
            stats.ray();
        }
        let bvh = &*self.bvh;
        let cwbvh = &bvh.cwbvh;
        let tris = WatertightRay::new(ray.origin, ray.dir);
        let mut obvhs_ray = traversal_ray(ray);
        let robust = ray
            .dir
            .cmpeq(Vec3::ZERO)
            .any()
            .then(|| RayBoxTest::new(ray.origin, ray.dir));
        let mut best = Hit::MISS;
        let mut tmax = ray.tmax;
        let mut leaf_depth = 0;
        let mut state = cwbvh.new_traversal(obvhs_ray.direction);
        let mut node;
        'traversal: {
            ::obvhs::traverse!(
                cwbvh,
                node,
                state,
                {
                    if S::ENABLED {
                        let depth = self.depth_of(node);
                        stats.node(depth);
                        for _ in node.child_meta.iter().filter(|&&meta| meta != 0) {
                            stats.aabb_test(depth + 1);
                        }
                        leaf_depth = depth + 1;
                    }
                    match &robust {
                        None => node.intersect_ray(&obvhs_ray, state.oct_inv4),
                        Some(test) => {
                            intersect_children_robust(node, state.oct_inv4, test, ray.tmin, tmax)
                        }
                    }
                },
                {
                    let i = state.primitive_id as usize;
                    if S::ENABLED {
                        stats.triangle_test(leaf_depth);
                    }
                    if let Some((t, u, v)) = tris.intersect(&bvh.triangles[i], ray.tmin, tmax) {
                        best = Hit {
                            t,
                            prim: cwbvh.primitive_indices[i],
                            u,
                            v,
                        };
                        if ANY {
                            break 'traversal;
                        }
                        tmax = t;
                        obvhs_ray.tmax = t * T_SCALE;
                    }
                }
            );
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Bvh, BvhConfig, ObvhsQuality};
    use crate::geometry::{RayBatch, RayKind, Triangle};
    use crate::params::Params;
    use crate::random::SplitMix64;
    use crate::stats::{Counters, NoStats};
    use crate::test_util::Soup;
    use crate::tracers::kernel::Kernel;
    use crate::tracers::reference::ReferenceTracer;

    fn soup(n: usize, size: f32, seed: u64) -> Vec<Triangle> {
        Soup::unit(size).triangles(n, seed)
    }

    /// How a ray of the mixed test batch was made, so each family can be checked to be exercised.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Family {
        /// From outside the soup's bounds towards a point inside.
        Outside,
        /// Origin inside the bounds, random direction.
        Inside,
        /// One or two direction components exactly zero (+0.0 or −0.0).
        AxisParallel,
        /// Only a sign differs from `AxisParallel`: every zero is −0.0.
        NegativeZero,
        /// Random direction whose components have magnitude below f32::EPSILON (obvhs's own
        /// `Ray::new` would clamp their reciprocals).
        NearAxis,
    }

    const FAMILIES: [Family; 5] = [
        Family::Outside,
        Family::Inside,
        Family::AxisParallel,
        Family::NegativeZero,
        Family::NearAxis,
    ];

    fn mixed_rays(n: usize, seed: u64) -> (RayBatch, Vec<Family>) {
        let mut rng = SplitMix64::new(seed);
        let mut batch = RayBatch::with_capacity(RayKind::Primary, n);
        let mut families = Vec::with_capacity(n);
        for i in 0..n {
            let family = FAMILIES[i % FAMILIES.len()];
            let (origin, dir) = match family {
                Family::Outside => {
                    let o = rng.vec3(-1.0, 1.0).normalize_or(Vec3::X) * 3.0;
                    (o, rng.vec3(-0.8, 0.8) - o)
                }
                Family::Inside => (rng.vec3(-1.0, 1.0), rng.vec3(-1.0, 1.0)),
                Family::AxisParallel | Family::NegativeZero => {
                    let zero = if family == Family::NegativeZero {
                        -0.0
                    } else {
                        0.0
                    };
                    let mut d = rng.vec3(-1.0, 1.0).to_array();
                    // Zero one or two axes (never all three).
                    let first = (rng.next_u64() % 3) as usize;
                    d[first] = zero;
                    if rng.next_u64().is_multiple_of(2) {
                        d[(first + 1) % 3] = zero;
                    }
                    (rng.vec3(-1.0, 1.0), Vec3::from_array(d))
                }
                Family::NearAxis => {
                    let mut d = rng.vec3(-1.0, 1.0).to_array();
                    let axis = (rng.next_u64() % 3) as usize;
                    d[axis] = rng.range(-1.0, 1.0) * f32::EPSILON;
                    (rng.vec3(-1.0, 1.0), Vec3::from_array(d))
                }
            };
            batch.push(Ray::new(origin, dir, 0.0, f32::INFINITY), i as u32);
            families.push(family);
        }
        (batch, families)
    }

    fn trace_all(tracer: &impl Kernel, rays: &RayBatch) -> (Vec<Hit>, Vec<bool>) {
        let mut hits = vec![Hit::MISS; rays.len()];
        let mut occluded = vec![false; rays.len()];
        tracer.intersect_with(rays.view(), &mut hits, &mut NoStats);
        tracer.occluded_with(rays.view(), &mut occluded, &mut NoStats);
        (hits, occluded)
    }

    #[derive(Debug, Default, PartialEq)]
    struct Agreement {
        hits: usize,
        misses: usize,
        /// Both hit at exactly the same t, on different triangles.
        ties: usize,
    }

    /// Asserts that obvhs finds what the reference tracer finds, ray by ray: the same triangle with
    /// the very same (t, u, v) — both run the same triangle test — or a tie at exactly the same t,
    /// and the same occlusion answer.
    fn assert_agree(triangles: &[Triangle], quality: ObvhsQuality, rays: &RayBatch) -> Agreement {
        let reference = ReferenceTracer::new(Arc::new(Bvh::build(triangles, BvhConfig::default())));
        let obvhs = ObvhsTracer::new(Arc::new(ObvhsBvh::build(triangles, quality).unwrap()));
        let (want, want_occluded) = trace_all(&reference, rays);
        let (got, got_occluded) = trace_all(&obvhs, rays);
        let mut agreement = Agreement::default();
        for i in 0..rays.len() {
            let (w, g) = (want[i], got[i]);
            let ray = rays.ray(i);
            assert_eq!(
                got_occluded[i], want_occluded[i],
                "{quality:?} ray {i} {ray:?}: occlusion"
            );
            assert_eq!(
                got_occluded[i],
                w.is_hit(),
                "{quality:?} ray {i}: occlusion vs closest hit"
            );
            if w.prim == g.prim {
                assert_eq!(g, w, "{quality:?} ray {i} {ray:?}");
                if w.is_hit() {
                    agreement.hits += 1;
                } else {
                    agreement.misses += 1;
                }
            } else {
                assert!(
                    w.is_hit() && g.is_hit() && g.t == w.t,
                    "{quality:?} ray {i} {ray:?}: want {w:?}, got {g:?}"
                );
                // A tie is real only if the reference also hits obvhs's triangle at that t.
                let other = WatertightRay::new(ray.origin, ray.dir).intersect(
                    &triangles[g.prim as usize],
                    ray.tmin,
                    ray.tmax,
                );
                assert_eq!(
                    other.map(|h| h.0),
                    Some(w.t),
                    "ray {i}: obvhs's triangle is not at the tied distance"
                );
                agreement.ties += 1;
            }
        }
        agreement
    }

    #[test]
    fn random_soup_matches_reference_ray_by_ray() {
        let triangles = soup(4000, 0.08, 1);
        let (mut rays, families) = mixed_rays(5000, 2);
        let a = assert_agree(&triangles, ObvhsQuality::default(), &rays);
        println!("default: {a:?}");
        assert_eq!(a.hits + a.misses + a.ties, rays.len());
        assert!(a.ties <= 2, "ties should be rare in a random soup: {a:?}");

        // Every family of rays both hits and misses, so each corner case is really exercised.
        let reference =
            ReferenceTracer::new(Arc::new(Bvh::build(&triangles, BvhConfig::default())));
        let (hits, _) = trace_all(&reference, &rays);
        for family in FAMILIES {
            let of = |hit: bool| {
                (0..rays.len())
                    .filter(|&i| families[i] == family && hits[i].is_hit() == hit)
                    .count()
            };
            assert!(
                of(true) >= 100 && of(false) >= 20,
                "{family:?}: {} hits, {} misses",
                of(true),
                of(false)
            );
        }

        // Cut tmax halfway to the closest hit: nothing lies nearer, so every such ray must miss.
        // Raise tmin past the closest hit on the others: the next triangle along (if any) is found.
        let mut cut = 0;
        for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
            if i % 2 == 0 {
                rays.tmax[i] = hit.t * 0.5;
                cut += 1;
            } else {
                rays.tmin[i] = hit.t * 1.0001;
            }
        }
        let obvhs = ObvhsTracer::new(Arc::new(
            ObvhsBvh::build(&triangles, ObvhsQuality::default()).unwrap(),
        ));
        let (got, occluded) = trace_all(&obvhs, &rays);
        let cut_missed = (0..rays.len())
            .filter(|&i| i % 2 == 0 && hits[i].is_hit() && !got[i].is_hit() && !occluded[i]);
        assert_eq!(cut_missed.count(), cut);
        let a = assert_agree(&triangles, ObvhsQuality::default(), &rays);
        println!("tmin/tmax moved: {a:?}");
        assert!(
            a.hits >= 500,
            "raised tmin should still find farther triangles: {a:?}"
        );
    }

    #[test]
    fn every_quality_preset_builds_and_agrees() {
        let triangles = soup(3000, 0.1, 3);
        let (rays, _) = mixed_rays(3000, 4);
        let mut agreements = Vec::new();
        for quality in ObvhsQuality::ALL {
            let bvh = ObvhsBvh::build(&triangles, quality).unwrap();
            // Every scene triangle is reachable: each appears among the primitives (pre-splits
            // may list a triangle more than once).
            let mut seen = vec![false; triangles.len()];
            for &p in &bvh.cwbvh.primitive_indices {
                seen[p as usize] = true;
            }
            assert!(seen.iter().all(|&s| s), "{quality:?} lost triangles");
            assert_eq!(bvh.triangles.len(), bvh.cwbvh.primitive_indices.len());
            agreements.push(assert_agree(&triangles, quality, &rays));
        }
        // Hits and misses are the same whatever the tree.
        for a in &agreements {
            assert_eq!(
                a.hits + a.ties,
                agreements[0].hits + agreements[0].ties,
                "{agreements:?}"
            );
        }
    }

    #[test]
    fn empty_mesh_misses_everything() {
        let bvh = Arc::new(ObvhsBvh::build(&[], ObvhsQuality::default()).unwrap());
        assert!(bvh.is_empty());
        let tracer = ObvhsTracer::new(bvh);
        let (rays, _) = mixed_rays(50, 5);
        let mut hits = vec![
            Hit {
                t: 1.0,
                prim: 7,
                u: 0.0,
                v: 0.0
            };
            rays.len()
        ];
        let mut occluded = vec![true; rays.len()];
        let mut counters = Counters::default();
        tracer.intersect_with(rays.view(), &mut hits, &mut counters);
        tracer.occluded_with(rays.view(), &mut occluded, &mut counters);
        assert!(hits.iter().all(|h| *h == Hit::MISS));
        assert!(occluded.iter().all(|&o| !o));
        assert_eq!(
            counters,
            Counters {
                rays: 100,
                ..Counters::default()
            },
            "an empty tree visits no node"
        );
    }

    fn unit_triangle() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    /// Closest hit of one ray through obvhs's own `ray_traverse` and its own `Ray::new`.
    fn obvhs_as_shipped(bvh: &ObvhsBvh, origin: Vec3, dir: Vec3) -> bool {
        let ray = ::obvhs::ray::Ray::new(origin.into(), dir.into(), 0.0, f32::INFINITY);
        let tris = WatertightRay::new(origin, dir);
        let mut hit = ::obvhs::ray::RayHit::none();
        bvh.cwbvh.ray_traverse(ray, &mut hit, |_, i| {
            tris.intersect(&bvh.triangles[i], 0.0, f32::INFINITY)
                .map_or(f32::INFINITY, |h| h.0)
        })
    }

    #[test]
    fn negative_zero_and_near_hits_need_the_adaptations() {
        let bvh = Arc::new(ObvhsBvh::build(&[unit_triangle()], ObvhsQuality::default()).unwrap());
        let tracer = ObvhsTracer::new(bvh.clone());
        let cases = [
            // −0.0 in x: obvhs's own ray culls the box it runs inside.
            (Vec3::new(0.25, 0.25, 1.0), Vec3::new(-0.0, 0.0, -1.0)),
            // A hit at t ≈ 5e-5, closer than obvhs's fixed box-entry clamp of 1e-4 (no zero
            // component, so it goes through obvhs's own box test with the stretched t axis).
            (Vec3::new(0.25, 0.25, 5e-5), Vec3::new(0.125, 0.25, -1.0)),
        ];
        for (origin, dir) in cases {
            assert!(
                !obvhs_as_shipped(&bvh, origin, dir),
                "obvhs as shipped now hits {origin} {dir}"
            );
            let mut rays = RayBatch::new(RayKind::Primary);
            rays.push(Ray::new(origin, dir, 0.0, f32::INFINITY), 0);
            let (hits, occluded) = trace_all(&tracer, &rays);
            let expected = origin.z / -dir.z;
            assert_eq!((hits[0].prim, occluded[0]), (0, true), "{origin} {dir}");
            assert!(
                (hits[0].t - expected).abs() <= 1e-6 * expected,
                "{:?}",
                hits[0]
            );
        }
    }

    #[test]
    fn known_deviation_hit_at_exactly_zero_distance_in_a_flat_box() {
        // A ray starting exactly on a triangle, tmin = 0: the reference reports t = 0, but the
        // triangle's box is flat, the ray leaves it at t = 0, and obvhs's box-entry clamp (1e-4,
        // moved to ≈ 5e-24 by T_SCALE but never to 0) culls it. The next surface is still found.
        // (With a zero direction component the robust child test would find t = 0.)
        let far = Triangle::new(
            Vec3::new(-1.0, -1.0, -2.0),
            Vec3::new(3.0, -1.0, -2.0),
            Vec3::new(-1.0, 3.0, -2.0),
        );
        let triangles = [unit_triangle(), far];
        let tracer = ObvhsTracer::new(Arc::new(
            ObvhsBvh::build(&triangles, ObvhsQuality::default()).unwrap(),
        ));
        let reference =
            ReferenceTracer::new(Arc::new(Bvh::build(&triangles, BvhConfig::default())));
        let mut rays = RayBatch::new(RayKind::Primary);
        let dir = Vec3::new(0.125, 0.25, -1.0);
        rays.push(Ray::new(Vec3::new(0.25, 0.25, 0.0), dir, 0.0, 9.0), 0);
        let (want, _) = trace_all(&reference, &rays);
        let (got, _) = trace_all(&tracer, &rays);
        assert_eq!((want[0].prim, want[0].t), (0, 0.0));
        assert_eq!((got[0].prim, got[0].t), (1, 2.0));
    }

    #[test]
    fn axis_aligned_geometry_with_rays_along_edges_and_face_planes() {
        // Unit squares on the integer lattice in the planes x, y, z ∈ {0, 2}: obvhs's quantised
        // child boxes fall exactly on lattice values, so rays whose origin coordinates are
        // lattice values run inside box face planes and along triangle edges (ties abound).
        let mut triangles = Vec::new();
        for axis in 0..3 {
            for level in [0.0, 2.0] {
                for i in 0..4 {
                    for j in 0..4 {
                        let p = |a: f32, b: f32| {
                            let mut v = [0.0; 3];
                            v[axis] = level;
                            v[(axis + 1) % 3] = a;
                            v[(axis + 2) % 3] = b;
                            Vec3::from_array(v)
                        };
                        let (a, b) = (i as f32, j as f32);
                        triangles.push(Triangle::new(p(a, b), p(a + 1.0, b), p(a + 1.0, b + 1.0)));
                        triangles.push(Triangle::new(p(a, b), p(a + 1.0, b + 1.0), p(a, b + 1.0)));
                    }
                }
            }
        }
        // Never 0 or 2, so no origin lies on a square (that would be a t = 0 hit, see above).
        let coords = [-0.5, 0.5, 1.0, 1.5, 3.0, 4.5];
        let mut dirs = Vec::new();
        for axis in 0..3 {
            for sign in [1.0, -1.0] {
                for zeros in [[0.0, 0.0], [-0.0, 0.0], [0.0, -0.0], [-0.0, -0.0]] {
                    let mut d = [zeros[0]; 3];
                    d[axis] = sign;
                    d[(axis + 1) % 3] = zeros[0];
                    d[(axis + 2) % 3] = zeros[1];
                    dirs.push(Vec3::from_array(d));
                }
            }
        }
        dirs.extend([
            Vec3::new(1.0, 1.0, -0.0),
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(0.0, -1.0, -1.0),
            Vec3::new(1.0, -2.0, 0.0),
            // No zero component: these go through obvhs's own box test, along lattice diagonals.
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(-2.0, 1.0, -1.0),
            Vec3::new(0.5, 1.0, -1.0),
        ]);
        let mut rays = RayBatch::new(RayKind::Primary);
        for &x in &coords {
            for &y in &coords {
                for &z in &coords {
                    for &d in &dirs {
                        rays.push(Ray::new(Vec3::new(x, y, z), d, 0.0, f32::INFINITY), 0);
                    }
                }
            }
        }
        let a = assert_agree(&triangles, ObvhsQuality::default(), &rays);
        println!("{a:?}");
        assert!(
            a.hits + a.ties > rays.len() / 5 && a.misses > rays.len() / 5,
            "{a:?}"
        );
        assert!(a.ties > 0, "rays along shared edges should tie: {a:?}");
    }

    #[test]
    fn hit_exactly_at_tmax_and_tmin_counts() {
        let tracer = ObvhsTracer::new(Arc::new(
            ObvhsBvh::build(&[unit_triangle()], ObvhsQuality::default()).unwrap(),
        ));
        let mut rays = RayBatch::new(RayKind::Shadow);
        let (o, d) = (Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        rays.push(Ray::new(o, d, 0.0, 2.0), 0); // hit exactly at tmax
        rays.push(Ray::new(o, d, 2.0, 9.0), 1); // hit exactly at tmin
        rays.push(Ray::new(o, d, 0.0, 1.999), 2); // just short
        rays.push(Ray::new(o, d, 2.001, 9.0), 3); // just past
        let (hits, occluded) = trace_all(&tracer, &rays);
        assert_eq!(occluded, vec![true, true, false, false]);
        let expected = Hit {
            t: 2.0,
            prim: 0,
            u: 0.25,
            v: 0.5,
        };
        assert_eq!(&hits[..2], &[expected, expected]);
        assert_eq!(&hits[2..], &[Hit::MISS, Hit::MISS]);
    }

    #[test]
    fn counters_on_a_single_triangle() {
        // obvhs makes one root node whose only child slot is a leaf holding the triangle.
        let bvh = Arc::new(ObvhsBvh::build(&[unit_triangle()], ObvhsQuality::default()).unwrap());
        assert_eq!((bvh.cwbvh.nodes.len(), bvh.max_depth()), (1, 0));
        let tracer = ObvhsTracer::new(bvh);
        let mut rays = RayBatch::new(RayKind::Primary);
        rays.push(
            Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
            0,
        ); // hits
           // Misses the box; x and y cull it.
        rays.push(
            Ray::new(
                Vec3::new(5.0, 5.0, 1.0),
                Vec3::new(0.1, 0.1, -1.0),
                0.0,
                f32::INFINITY,
            ),
            1,
        );
        // Misses the box too, with zero x and y components: the robust child test culls it.
        rays.push(
            Ray::new(Vec3::new(5.0, 5.0, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
            2,
        );
        let mut hits = vec![Hit::MISS; 3];
        let mut counters = Counters::default();
        tracer.intersect_with(rays.view(), &mut hits, &mut counters);
        assert_eq!(
            hits.iter().map(Hit::is_hit).collect::<Vec<_>>(),
            vec![true, false, false]
        );
        assert_eq!(
            counters,
            Counters {
                rays: 3,
                nodes_visited: 3,
                aabb_tests: 3,
                triangle_tests: 1,
                aabb_by_depth: vec![0, 3],
                triangle_by_depth: vec![0, 1],
                ..Counters::default()
            }
        );
        const { assert!(ObvhsTracer::COUNTS_INTERNALS) };
    }

    #[test]
    fn counters_add_up_on_a_soup() {
        let triangles = soup(2000, 0.08, 6);
        let bvh = Arc::new(ObvhsBvh::build(&triangles, ObvhsQuality::default()).unwrap());
        let nodes = bvh.cwbvh.nodes.len() as u64;
        let tracer = ObvhsTracer::new(bvh);
        let (all, families) = mixed_rays(4000, 7);
        // Each family separately: rays with zero components must cull as well as the others.
        for family in FAMILIES {
            let mut rays = RayBatch::new(RayKind::Primary);
            for i in (0..all.len()).filter(|&i| families[i] == family) {
                rays.push(all.ray(i), i as u32);
            }
            let n = rays.len() as u64;
            let mut hits = vec![Hit::MISS; rays.len()];
            let mut counters = Counters::default();
            tracer.intersect_with(rays.view(), &mut hits, &mut counters);
            assert_eq!(counters.rays, n);
            let by_depth = |v: &[u64]| v.iter().sum::<u64>();
            assert_eq!(counters.aabb_tests, by_depth(&counters.aabb_by_depth));
            assert_eq!(
                counters.triangle_tests,
                by_depth(&counters.triangle_by_depth)
            );
            // The root's own box is never tested; the root node is visited once per ray.
            assert_eq!(counters.aabb_by_depth[0], 0);
            assert!(counters.nodes_visited >= n && counters.nodes_visited < n * nodes / 5);
            // Every hit needed a triangle test, and the cull did its work (a handful per ray).
            let hit_count = hits.iter().filter(|h| h.is_hit()).count() as u64;
            assert!(hit_count > n / 4 && counters.triangle_tests >= hit_count);
            assert!(counters.triangle_tests < 20 * n, "{family:?}: {counters:?}");
            println!(
                "{family:?}: {:.1} nodes of {nodes}, {:.1} triangles per ray",
                counters.nodes_visited as f64 / n as f64,
                counters.triangle_tests as f64 / n as f64
            );
            // Counting does not change the answers.
            let mut plain = vec![Hit::MISS; rays.len()];
            tracer.intersect_with(rays.view(), &mut plain, &mut NoStats);
            assert_eq!(plain, hits);
        }
    }

    #[test]
    fn quality_parameter_names_the_presets() {
        assert_eq!(
            ObvhsQuality::from_params(&Params::new()).unwrap(),
            ObvhsQuality::MediumBuild
        );
        for q in ObvhsQuality::ALL {
            assert_eq!(
                ObvhsQuality::from_params(&Params::new().with("quality", q.name())).unwrap(),
                q
            );
        }
        let err = ObvhsQuality::from_params(&Params::new().with("quality", "best")).unwrap_err();
        assert!(err.to_string().contains("very_slow_build"), "{err}");
    }

    /// Seconds this thread has spent on a CPU (Linux `schedstat`): on a machine shared with other
    /// work, the time spent waiting for a core is not the tracer's.
    fn thread_cpu_seconds() -> Option<f64> {
        let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        Some(stat.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
    }

    /// Not an assertion: prints build times and single-thread Mrays/s against the reference
    /// tracer. Run in release: `cargo test --release --lib tracers::obvhs -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn throughput_vs_reference_on_a_100k_soup() {
        use std::time::Instant;
        let triangles = soup(100_000, 0.02, 11);
        let (all, families) = mixed_rays(250_000, 12);
        let general = |i: &usize| matches!(families[*i], Family::Outside | Family::Inside);
        let mut rays = RayBatch::new(RayKind::Primary);
        for i in (0..all.len()).filter(general) {
            rays.push(all.ray(i), i as u32);
        }
        let reference_bvh = Bvh::build(&triangles, BvhConfig::default());
        println!(
            "{} triangles, {} rays (outside + inside), 1 thread",
            triangles.len(),
            rays.len()
        );
        println!("reference BVH build {:.3} s", reference_bvh.build_seconds);
        let mut tracers: Vec<(String, Box<dyn crate::tracers::kernel::Tracer>)> = vec![(
            "reference".into(),
            Box::new(ReferenceTracer::new(Arc::new(reference_bvh))),
        )];
        for quality in ObvhsQuality::ALL {
            let bvh = ObvhsBvh::build(&triangles, quality).unwrap();
            println!(
                "obvhs {} build {:.3} s, {} nodes, depth {}",
                quality.name(),
                bvh.build_seconds,
                bvh.cwbvh.nodes.len(),
                bvh.max_depth()
            );
            let name = format!("obvhs {}", quality.name());
            tracers.push((name, Box::new(ObvhsTracer::new(Arc::new(bvh)))));
        }

        // The cost of exactly-zero direction components, as counts.
        let mut zeros = RayBatch::new(RayKind::Primary);
        for i in (0..all.len() / 10).filter(|&i| families[i] == Family::AxisParallel) {
            zeros.push(all.ray(i), i as u32);
        }
        let mut zero_hits = vec![Hit::MISS; zeros.len()];
        let compared = ["reference", "obvhs medium_build"];
        for (name, tracer) in tracers
            .iter()
            .filter(|(n, _)| compared.contains(&n.as_str()))
        {
            let mut counters = Counters::default();
            tracer.intersect_counted(zeros.view(), &mut zero_hits, &mut counters);
            let per_ray = counters.triangle_tests as f64 / zeros.len() as f64;
            println!("{name}: {per_ray:.1} triangle tests per axis-parallel ray");
        }

        let mut hits = vec![Hit::MISS; rays.len()];
        let mut occluded = vec![false; rays.len()];
        // Minimum wall and CPU seconds of 5 runs after a warm-up.
        let best_of = |f: &mut dyn FnMut()| {
            f();
            (0..5).fold((f64::INFINITY, f64::INFINITY), |(wall, cpu), _| {
                let (t, c) = (Instant::now(), thread_cpu_seconds());
                f();
                let c = thread_cpu_seconds()
                    .zip(c)
                    .map_or(f64::INFINITY, |(b, a)| b - a);
                (wall.min(t.elapsed().as_secs_f64()), cpu.min(c))
            })
        };
        let n = rays.len() as f64;
        let mrays = |seconds: f64| n / seconds / 1e6;
        for (name, tracer) in &tracers {
            let (closest_wall, closest_cpu) =
                best_of(&mut || tracer.intersect(rays.view(), &mut hits));
            let (any_wall, any_cpu) = best_of(&mut || tracer.occluded(rays.view(), &mut occluded));
            let mut counters = Counters::default();
            tracer.intersect_counted(rays.view(), &mut hits, &mut counters);
            println!(
                "{name:>24}: Mrays/s by CPU time: closest {:5.2}, occluded {:5.2} \
                 (by wall time {:5.2}, {:5.2}) | per ray {:5.1} nodes {:5.1} boxes {:4.1} triangles",
                mrays(closest_cpu),
                mrays(any_cpu),
                mrays(closest_wall),
                mrays(any_wall),
                counters.nodes_visited as f64 / n,
                counters.aabb_tests as f64 / n,
                counters.triangle_tests as f64 / n
            );
        }
    }
}
