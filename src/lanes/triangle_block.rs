//! Four triangles of a leaf in one structure-of-arrays block, and the test of one ray against all
//! four at once: the leaf layout of production single-ray kernels (Embree's `Triangle4`, tinybvh's
//! BVH8_CPU leaves), SIMD across a leaf's triangles rather than across rays. The wide tree stores
//! its leaves as runs of blocks (`accel::WideBvh`), and the wide single-ray walk tests a block in
//! one pass of 4-lane vector code, where the scalar leaf runs one triangle at a time.
//!
//! The ray is broadcast to every lane and each lane runs the scalar test's f32 operations in its
//! order (`watertight` with `Robust`, `moller` with `Fast`), so a lane's verdict, distance and
//! barycentrics are the scalar test's bit for bit. The block's lanes are tested against the
//! segment the ray had when it reached the block; the lanes that hit are then taken in lane order,
//! each checked again against the segment as the earlier ones shortened it (`BlockTests::finish`,
//! the scalar test's last stage), so a leaf of blocks finds exactly what the scalar leaf finds,
//! triangle by triangle. The watertight test decides before it divides: only a hitting lane
//! divides, once.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use super::moller::{LaneHits, MollerLanes};
use super::vector::{Lanes4, Vector};
use super::LaneMask;
use crate::geometry::moller::MollerRay;
use crate::geometry::triangle::{watertight_hit, ILL_CONDITIONED};
use crate::geometry::{Fast, RayTests, Robust, Triangle, WatertightRay};

/// Triangles per block.
pub const BLOCK: usize = 4;

/// Up to four triangles: their vertices `v[vertex][axis][lane]` and the primitive id each hit
/// reports. A block of fewer than four repeats its last triangle in the unused lanes, so every
/// lane holds a real triangle and no lane test meets an invented one; callers mask those lanes
/// off. 160 bytes at 32-byte alignment, so a block spans exactly three cache lines wherever it
/// lies (Embree's `Triangle4v` with its ids is 176 bytes at 16, three or four lines).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct TriangleBlock {
    pub v: [[[f32; BLOCK]; 3]; 3],
    pub prim: [u32; BLOCK],
}

const _: () = assert!(std::mem::size_of::<TriangleBlock>() == 160);

impl TriangleBlock {
    /// The block of `triangles` (1 to 4) with their primitive ids `prims`.
    pub fn new(triangles: &[Triangle], prims: &[u32]) -> Self {
        assert!(
            (1..=BLOCK).contains(&triangles.len()) && prims.len() == triangles.len(),
            "a block holds 1 to {BLOCK} triangles and their ids"
        );
        let mut block = TriangleBlock {
            v: [[[0.0; BLOCK]; 3]; 3],
            prim: [0; BLOCK],
        };
        for l in 0..BLOCK {
            let i = l.min(triangles.len() - 1);
            for (k, vertex) in triangles[i].v.iter().enumerate() {
                for a in 0..3 {
                    block.v[k][a][l] = vertex[a];
                }
            }
            block.prim[l] = prims[i];
        }
        block
    }

    /// The triangle in lane `l`.
    pub fn triangle(&self, l: usize) -> Triangle {
        let vertex = |k: usize| glam::Vec3::new(self.v[k][0][l], self.v[k][1][l], self.v[k][2][l]);
        Triangle::new(vertex(0), vertex(1), vertex(2))
    }
}

/// The lanes of `count` triangles (the first `count.min(BLOCK)`).
#[inline(always)]
pub fn used_lanes(count: u32) -> u32 {
    LaneMask::<BLOCK>::first(count.min(BLOCK as u32) as usize).bits()
}

/// A ray test of a whole block (`Robust`: watertight; `Fast`: Möller–Trumbore), split at the
/// point where lanes that hit must be taken one by one.
pub trait BlockTests: RayTests {
    /// What `finish` needs of each lane.
    type Candidates;
    /// The lanes of `used` whose triangle the ray may hit within `[tmin, tmax]`, and what
    /// finishing them needs.
    fn candidates(
        ray: &Self::TriangleRay,
        block: &TriangleBlock,
        used: u32,
        tmin: f32,
        tmax: f32,
    ) -> (u32, Self::Candidates);
    /// Lane `l` (a candidate) as the scalar test ends it with the segment `[tmin, tmax]`, where
    /// `tmax` is at most the one its candidates were found with: `(t, u, v)` or a miss.
    fn finish(
        ray: &Self::TriangleRay,
        block: &TriangleBlock,
        c: &Self::Candidates,
        l: usize,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)>;
}

/// Each lane's edge functions `U, V, W` and scaled distance, as `WatertightRay::intersect`
/// computes them; `scalar`: the lanes are finished by the scalar test itself (an edge function
/// to redo in f64 among them).
pub struct WatertightCandidates {
    u: [f32; BLOCK],
    v: [f32; BLOCK],
    w: [f32; BLOCK],
    t_scaled: [f32; BLOCK],
    scalar: bool,
}

impl BlockTests for Robust {
    type Candidates = WatertightCandidates;

    /// `WatertightRay::intersect`'s f32 operations in 4-wide vectors, in its order. A lane
    /// passing strictly outside an edge with no zero edge function is a miss, as there; if every
    /// used lane is, the block is done after the edge functions. A lane the scalar test would
    /// redo in f64 (`geometry::needs_f64`) hands every lane that may hit to the scalar test.
    /// Written on `Lanes4` rather than with `lanes::watertight`'s array stages: their `[bool; L]`
    /// verdicts came out lane by lane at L = 4, and the block test built on them ran 1670
    /// instructions per ray on conference's diffuse rays against 1232 for this one
    /// (`tools/callgrind`, issue 45's closing note).
    #[inline(always)]
    fn candidates(
        ray: &WatertightRay,
        block: &TriangleBlock,
        used: u32,
        tmin: f32,
        tmax: f32,
    ) -> (u32, WatertightCandidates) {
        type V = Lanes4;
        let (origin, [kx, ky, kz], [sx, sy, sz]) = ray.parts();
        let zero = V::splat(0.0);
        // A vertex's rows relative to the origin, in the ray's frame [kx, ky, kz].
        let rel = |k: usize, a: usize| V::load(&block.v[k][a], 0) - V::splat(origin[a]);
        let sheared = |k: usize| {
            let z = rel(k, kz);
            (
                rel(k, kx) - V::splat(sx) * z,
                rel(k, ky) - V::splat(sy) * z,
                z,
            )
        };
        let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) = (sheared(0), sheared(1), sheared(2));
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let negative = u.lt(zero) | v.lt(zero) | w.lt(zero);
        let positive = u.gt(zero) | v.gt(zero) | w.gt(zero);
        let zeros = u.eq(zero) | v.eq(zero) | w.eq(zero);
        let mut out = WatertightCandidates {
            u: [0.0; BLOCK],
            v: [0.0; BLOCK],
            w: [0.0; BLOCK],
            t_scaled: [0.0; BLOCK],
            scalar: false,
        };
        let may_hit = V::bits(!(negative & positive & !zeros)) as u32 & used;
        if may_hit == 0 {
            return (0, out);
        }
        // `geometry::needs_f64`, lane by lane.
        let scale = (cx * by).abs() + (ax * cy).abs() + (bx * ay).abs();
        let inside =
            (zero.le(u) & zero.le(v) & zero.le(w)) | (u.le(zero) & v.le(zero) & w.le(zero));
        let det = u + v + w;
        let ill = det.abs().lt(V::splat(ILL_CONDITIONED) * scale);
        if V::bits(zeros | (inside & ill)) as u32 & may_hit != 0 {
            out.scalar = true;
            return (may_hit, out);
        }
        // `accept`: inside, a non-zero determinant, a distance in range (compared scaled; the
        // signs of zeros flipped here change no comparison).
        let t_scaled = u * V::splat(sz) * az + v * V::splat(sz) * bz + w * V::splat(sz) * cz;
        let flip = det.lt(zero);
        let ts = V::select(flip, zero - t_scaled, t_scaled);
        let ad = V::select(flip, zero - det, det);
        let in_range = !ts.lt(V::splat(tmin) * ad) & !ts.gt(V::splat(tmax) * ad);
        let hit = V::bits(!(negative & positive) & !det.eq(zero) & in_range) as u32 & used;
        if hit != 0 {
            u.store(&mut out.u);
            v.store(&mut out.v);
            w.store(&mut out.w);
            t_scaled.store(&mut out.t_scaled);
        }
        (hit, out)
    }

    #[inline(always)]
    fn finish(
        ray: &WatertightRay,
        block: &TriangleBlock,
        c: &WatertightCandidates,
        l: usize,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)> {
        if c.scalar {
            return ray.intersect(&block.triangle(l), tmin, tmax);
        }
        watertight_hit(c.u[l], c.v[l], c.w[l], c.t_scaled[l], tmin, tmax)
    }
}

impl BlockTests for Fast {
    type Candidates = LaneHits<BLOCK>;

    /// `moller`'s lane test (`MollerRay::intersect` per lane, bit for bit) with the ray in
    /// every lane and a triangle per lane.
    #[inline(always)]
    fn candidates(
        ray: &MollerRay,
        block: &TriangleBlock,
        used: u32,
        tmin: f32,
        tmax: f32,
    ) -> (u32, LaneHits<BLOCK>) {
        let [v0, v1, v2] = &block.v;
        // The edges as the scalar test makes them (v1 − v0, v2 − v0).
        let edge = |to: &[[f32; BLOCK]; 3]| -> [[f32; BLOCK]; 3] {
            std::array::from_fn(|a| std::array::from_fn(|l| to[a][l] - v0[a][l]))
        };
        let triangles = MollerLanes {
            v0: *v0,
            e1: edge(v1),
            e2: edge(v2),
        };
        let broadcast = |p: glam::Vec3| [[p.x; BLOCK], [p.y; BLOCK], [p.z; BLOCK]];
        let hits = triangles.intersect(
            &broadcast(ray.origin),
            &broadcast(ray.dir),
            &[tmin; BLOCK],
            &[tmax; BLOCK],
        );
        (LaneMask::from_bools(&hits.hit).bits() & used, hits)
    }

    #[inline(always)]
    fn finish(
        _: &MollerRay,
        _: &TriangleBlock,
        c: &LaneHits<BLOCK>,
        l: usize,
        _: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)> {
        // Found within `[tmin, tmax']` with tmax' ≥ tmax: only the far end can have moved.
        (c.t[l] <= tmax).then_some((c.t[l], c.u[l], c.v[l]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix64;
    use glam::Vec3;

    /// Random blocks of 1 to 4 triangles (needles, degenerate ones and shared edges among
    /// them) and rays aimed at their vertices and edges: taking a block's candidates in lane
    /// order and finishing each against the shortened segment gives, bit for bit, what the
    /// scalar test finds triangle by triangle.
    fn blocks_are_the_scalar_leaf<R: BlockTests>() {
        let mut rng = SplitMix64::new(41);
        let (mut hits, mut multiple) = (0, 0);
        for round in 0..4000 {
            let count = 1 + round % BLOCK;
            let p = rng.vec3(-1.0, 1.0);
            // Every other block a stack of shifted copies of one triangle, which a ray through
            // it meets several times.
            let (a, b, shift) = (
                rng.vec3(-1.0, 1.0),
                rng.vec3(-1.0, 1.0),
                rng.vec3(-0.3, 0.3),
            );
            let tris: Vec<Triangle> = (0..count)
                .map(|i| {
                    let q = p + shift * i as f32;
                    let (a, b) = match round % 2 {
                        0 => (a, b),
                        _ => (rng.vec3(-1.0, 1.0), rng.vec3(-1.0, 1.0)),
                    };
                    match (round + i) % 9 {
                        0 => Triangle::new(q, q + a, q + a * 2.0),
                        1 => Triangle::new(q, q + a, q + a + b * 1e-4),
                        _ => Triangle::new(q, q + a, q + b),
                    }
                })
                .collect();
            let prims: Vec<u32> = (0..count as u32).map(|i| 100 + i).collect();
            let block = TriangleBlock::new(&tris, &prims);
            let o = rng.vec3(-3.0, 3.0);
            let target = match round % 5 {
                0 => p,
                1 => (tris[0].v[1] + tris[count - 1].v[2]) * 0.5,
                2 => rng.vec3(-1.0, 1.0),
                _ => tris[0].point(rng.range(0.0, 0.5), rng.range(0.0, 0.5)),
            };
            let (tmin, tmax0) = (rng.range(0.0, 0.1), rng.range(0.5, 4.0));
            let ray = R::triangle_ray(o, target - o);
            let mut scalar = (tmax0, None);
            for (i, tri) in tris.iter().enumerate() {
                if let Some(h) = R::intersect(&ray, tri, tmin, scalar.0) {
                    scalar = (h.0, Some((i, h)));
                }
            }
            let (mut lanes, c) = R::candidates(&ray, &block, used_lanes(count as u32), tmin, tmax0);
            multiple += (lanes.count_ones() > 1) as usize;
            let mut blocked = (tmax0, None);
            while lanes != 0 {
                let l = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                if let Some(h) = R::finish(&ray, &block, &c, l, tmin, blocked.0) {
                    blocked = (h.0, Some((l, h)));
                }
            }
            let bits = |h: Option<(usize, (f32, f32, f32))>| {
                h.map(|(i, (t, u, v))| (i, [t, u, v].map(f32::to_bits)))
            };
            assert_eq!(bits(blocked.1), bits(scalar.1), "round {round}");
            hits += scalar.1.is_some() as usize;
        }
        assert!(
            hits > 800 && multiple > 100,
            "{hits} hits, {multiple} blocks with several"
        );
    }

    #[test]
    fn a_watertight_block_finds_the_scalar_leafs_hit() {
        blocks_are_the_scalar_leaf::<Robust>();
    }

    #[test]
    fn a_moller_block_finds_the_scalar_leafs_hit() {
        blocks_are_the_scalar_leaf::<Fast>();
    }

    #[test]
    fn a_short_block_repeats_its_last_triangle_and_its_id() {
        let tris = [
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(Vec3::Z, Vec3::X, Vec3::Y),
        ];
        let block = TriangleBlock::new(&tris, &[5, 9]);
        assert_eq!(block.prim, [5, 9, 9, 9]);
        assert_eq!(block.triangle(0), tris[0]);
        assert_eq!(block.triangle(3), tris[1]);
        assert_eq!(used_lanes(2), 0b11);
        assert_eq!(used_lanes(9), 0b1111);
    }
}
