//! One ray against all `W` child boxes of a wide node (`accel::WideNode`'s structure-of-arrays
//! lanes) in one SIMD slab test: the conservative slab test of `RayBoxTest::hit` (Ize 2013) with
//! the boxes in the lanes instead of the rays. Per axis the near and far planes are picked by the
//! ray's direction sign bit (so −0.0 counts as negative), once per ray as rows of the node's
//! planes, and every lane runs the scalar test's operations in its order — `(plane − origin) ·
//! inverse direction`, the far planes' by the inverse direction scaled by `FAR_SCALE` once per
//! ray, running max/min that ignore a NaN (`0·∞` for an origin on a slab plane) — so each child's
//! verdict is `RayBoxTest`'s. With `robust = false` (`Fast`) the far distances are not scaled:
//! plain slabs, each verdict `RayBoxTest::hit_with::<Fast>`'s.
//!
//! Written with explicit vectors (`lanes::vector`) on groups of children, not as lane loops over
//! `[f32; W]`: LLVM's SLP vectorizer split those loops' far-plane half into scalar loads and
//! shuffles (checked in the assembly), while these compile to straight vector code, one
//! sub/mul/max-or-min per group and plane and one movemask per group. The kernel is written once
//! over `Vector`: groups of 8 children in `Avx2` where the build has AVX2 (`target-cpu=native` on
//! the AVX2 and AVX-512 machines the project runs on), so an 8-wide node is one pass; otherwise
//! groups of 4 in `Lanes4` (the x86-64 baseline, as `child_pairs`).

use std::marker::PhantomData;

use glam::Vec3;

use crate::accel::WideNode;
use crate::geometry::RayTests;
#[cfg(target_feature = "avx2")]
use crate::lanes::vector::Avx2;
use crate::lanes::vector::{Lanes4, Vector};
use crate::lanes::BroadcastRay;

/// A ray prepared for wide-node tests with `R`'s slabs (conservative or plain): origin,
/// reciprocal direction and the far planes' scaled reciprocal broadcast per axis, in SSE lanes
/// and (AVX2 builds) AVX lanes.
#[derive(Clone, Copy)]
pub struct WideRayTest<R: RayTests> {
    sse: BroadcastRay<Lanes4>,
    /// `inv_dir · R::FAR_SCALE` per axis (`geometry::aabb::FAR_SCALE`'s doc).
    sse_far: [Lanes4; 3],
    /// Per axis, the rows of `WideNode::planes` holding the near and far planes: the low planes
    /// `a` and high `3 + a` for a direction of positive sign, the other way round for a negative
    /// one (Embree's per-ray `nearX`/`farX` offsets). Each is below 6 (`from_inv`).
    rows: [[usize; 3]; 2],
    /// Origin, reciprocal direction and its far scaling in AVX lanes; the sign bits are `sse`'s
    /// (a second copy cost every ray its stores: 0.2% more instructions on diffuse rays).
    #[cfg(target_feature = "avx2")]
    avx: [[Avx2; 3]; 3],
    tests: PhantomData<R>,
}

impl<R: RayTests> WideRayTest<R> {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::from_inv(origin, Vec3::ONE / dir)
    }

    /// As `new`, from the reciprocal direction `inv = 1 / dir`.
    #[inline(always)]
    pub fn from_inv(origin: Vec3, inv: Vec3) -> Self {
        let sse = BroadcastRay::from_inv(origin, inv);
        let far = inv * R::FAR_SCALE;
        let near = sse.negative.map(usize::from);
        let rows = [
            [3 * near[0], 1 + 3 * near[1], 2 + 3 * near[2]],
            [3 - 3 * near[0], 4 - 3 * near[1], 5 - 3 * near[2]],
        ];
        WideRayTest {
            sse,
            sse_far: far.to_array().map(Lanes4::splat),
            rows,
            #[cfg(target_feature = "avx2")]
            avx: [origin, inv, far].map(|v| v.to_array().map(Avx2::splat)),
            tests: PhantomData,
        }
    }

    /// Each child's entry distance (clipped to `tmin`) and which children the ray meets within
    /// `[tmin, tmax]` (bit `c`: child `c`; empty slots never). `W` is a multiple of 4; a multiple
    /// of 8 is tested 8 children at a time on AVX2 builds.
    #[inline(always)]
    pub fn test<const W: usize>(
        &self,
        node: &WideNode<W>,
        tmin: f32,
        tmax: f32,
    ) -> ([f32; W], u32) {
        #[cfg(target_feature = "avx2")]
        if W.is_multiple_of(8) {
            return test_in::<_, W>(&self.avx, &self.rows, node, tmin, tmax);
        }
        test_in::<_, W>(&self.sse_lanes(), &self.rows, node, tmin, tmax)
    }

    /// The ray's SSE lanes as `test_in` reads them.
    #[inline(always)]
    fn sse_lanes(&self) -> [[Lanes4; 3]; 3] {
        [self.sse.origin, self.sse.inv_dir, self.sse_far]
    }
}

/// `WideRayTest::test` in groups of `V::WIDTH` children, the ray's origin, reciprocal direction
/// and its far scaling broadcast to `V`'s lanes (`[origin, inv_dir, inv_far][axis]`), its near and
/// far plane rows `[near, far][axis]` (`WideRayTest::rows`, each below 6). Per lane the operations
/// of `RayBoxTest::hit_with`: `max`/`min` are MAXPS/MINPS (`Vector`), which return their second
/// operand when either is NaN, and `le` is ordered (false on NaN).
#[inline(always)]
fn test_in<V: Vector, const W: usize>(
    [origin, inv_dir, inv_far]: &[[V; 3]; 3],
    [near_rows, far_rows]: &[[usize; 3]; 2],
    node: &WideNode<W>,
    tmin: f32,
    tmax: f32,
) -> ([f32; W], u32) {
    // Folded away: `test` picks `V` by `W` (a `const` assertion would be evaluated for the
    // branch it does not take too).
    assert!(
        W.is_multiple_of(V::WIDTH),
        "children are tested in whole groups"
    );
    let mut enter = [0.0f32; W];
    let mut hit = 0u32;
    let planes = node.planes();
    for group in (0..W).step_by(V::WIDTH) {
        let mut near_max = V::splat(tmin);
        let mut far_min = V::splat(tmax);
        for a in 0..3 {
            // SAFETY: both rows are below 6 (`WideRayTest::rows`): no bounds check per node.
            let (near, far) = unsafe {
                (
                    planes.get_unchecked(near_rows[a]),
                    planes.get_unchecked(far_rows[a]),
                )
            };
            let o = origin[a];
            let t_near = (V::load(near, group) - o) * inv_dir[a];
            let t_far = (V::load(far, group) - o) * inv_far[a];
            // The new plane first, so a NaN leaves the interval as it was.
            near_max = t_near.max(near_max);
            far_min = t_far.min(far_min);
        }
        near_max.store(&mut enter[group..]);
        hit |= (V::bits(near_max.le(far_min)) as u32) << group;
    }
    (enter, hit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::wide_bvh::spaced_leaves;
    use crate::accel::{Bvh, BvhConfig, WideBvh};
    use crate::geometry::{Aabb, Fast, RayBoxTest, Robust, Triangle};
    use crate::random::SplitMix64;
    use crate::test_util::awkward_slab_rays;

    /// One wide node whose 8 children are the given boxes (a tree of 8 one-triangle leaves, the
    /// boxes then overwritten), the unused slots of a 4-wide one kept empty.
    fn node_of(boxes: &[Aabb; 8]) -> WideNode<8> {
        let mut node = WideBvh::<8>::collapse(&spaced_leaves(8)).nodes[0];
        for (c, b) in boxes.iter().enumerate() {
            for a in 0..3 {
                node.lo[a][c] = b.min[a];
                node.hi[a][c] = b.max[a];
            }
        }
        node
    }

    /// The node tests this build has for `W = 8`, each of the ray `(o, d)`: SSE groups of 4
    /// (every build), AVX2 groups of 8 (AVX2 builds), and `test`'s pick between them; with
    /// conservative slabs (`robust` true) and plain ones.
    fn eight_wide_tests() -> Vec<(&'static str, bool, EightWideTest)> {
        vec![
            ("test", true, |o, d, n, t0, t1| {
                WideRayTest::<Robust>::new(o, d).test(n, t0, t1)
            }),
            ("sse", true, |o, d, n, t0, t1| {
                sse::<Robust>(o, d, n, t0, t1)
            }),
            #[cfg(target_feature = "avx2")]
            ("avx2", true, |o, d, n, t0, t1| {
                avx2::<Robust>(o, d, n, t0, t1)
            }),
            ("fast test", false, |o, d, n, t0, t1| {
                WideRayTest::<Fast>::new(o, d).test(n, t0, t1)
            }),
            ("fast sse", false, |o, d, n, t0, t1| {
                sse::<Fast>(o, d, n, t0, t1)
            }),
            #[cfg(target_feature = "avx2")]
            ("fast avx2", false, |o, d, n, t0, t1| {
                avx2::<Fast>(o, d, n, t0, t1)
            }),
        ]
    }

    type EightWideTest = fn(Vec3, Vec3, &WideNode<8>, f32, f32) -> ([f32; 8], u32);

    /// The ray's test in SSE groups of 4.
    fn sse<R: RayTests>(o: Vec3, d: Vec3, n: &WideNode<8>, t0: f32, t1: f32) -> ([f32; 8], u32) {
        let r = WideRayTest::<R>::new(o, d);
        test_in::<_, 8>(&r.sse_lanes(), &r.rows, n, t0, t1)
    }

    /// The ray's test in AVX2 groups of 8.
    #[cfg(target_feature = "avx2")]
    fn avx2<R: RayTests>(o: Vec3, d: Vec3, n: &WideNode<8>, t0: f32, t1: f32) -> ([f32; 8], u32) {
        let r = WideRayTest::<R>::new(o, d);
        test_in::<_, 8>(&r.avx, &r.rows, n, t0, t1)
    }

    /// `tested`'s verdict and entry distance for every child of `node` (its boxes `boxes`) are
    /// the scalar `RayBoxTest`'s (conservative if `robust`, else plain); the number of children
    /// met.
    fn agrees_with_scalar(
        (tested, robust): (([f32; 8], u32), bool),
        boxes: &[Aabb; 8],
        (o, d): (Vec3, Vec3),
        (tmin, tmax): (f32, f32),
        name: &str,
    ) -> usize {
        let (enter, mask) = tested;
        let scalar = RayBoxTest::new(o, d);
        let mut hits = 0;
        for (c, b) in boxes.iter().enumerate() {
            let want = if robust {
                scalar.hit(b, tmin, tmax)
            } else {
                scalar.hit_with::<Fast>(b, tmin, tmax)
            };
            let case = format!("{name}: box {c} o {o:?} d {d:?} [{tmin}, {tmax}]");
            assert_eq!(mask & (1 << c) != 0, want.is_some(), "{case}");
            if let Some(t) = want {
                assert_eq!(enter[c], t, "{case}");
                hits += 1;
            }
        }
        hits
    }

    /// Every child's verdict and entry distance are the scalar `RayBoxTest`'s, in the awkward
    /// cases too (zero and −0.0 components, origins on slab planes, inside, behind, short
    /// segments), and an empty slot is never hit; with SSE groups of 4 and AVX groups of 8.
    #[test]
    fn wide_test_matches_scalar_slab_test() {
        let boxes = [
            Aabb::new(Vec3::ZERO, Vec3::ONE),
            Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)),
            Aabb::new(Vec3::new(-1.0, -1.0, 5.0), Vec3::new(1.0, 1.0, 6.0)),
            Aabb::new(Vec3::splat(0.25), Vec3::splat(0.5)),
            Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0)),
            Aabb::new(Vec3::splat(-3.0), Vec3::splat(-2.0)),
            Aabb::new(Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.0, 1.0, 1.0)),
            Aabb::EMPTY,
        ];
        let node = node_of(&boxes);
        let (origins, dirs) = awkward_slab_rays();
        for (name, robust, test) in eight_wide_tests() {
            let mut hits = 0;
            for o in origins {
                for d in dirs {
                    for interval in [(0.0, f32::INFINITY), (0.0, 1.2), (2.0, 10.0)] {
                        let tested = test(o, d, &node, interval.0, interval.1);
                        hits +=
                            agrees_with_scalar((tested, robust), &boxes, (o, d), interval, name);
                    }
                }
            }
            // Not a vacuous agreement: many boxes are met, and the empty one never.
            assert!(hits > 50, "{name}: {hits}");
        }
        let four = WideBvh::<4>::collapse(&Bvh::build(
            &[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)],
            BvhConfig::default(),
        ));
        let (_, mask) = WideRayTest::<Robust>::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z).test::<4>(
            &four.nodes[0],
            0.0,
            f32::INFINITY,
        );
        assert_eq!(mask, 0b0001, "only the one leaf's slot, no empty slot");
    }

    /// Random boxes (some flat, some empty) against random rays from inside and outside, with
    /// random intervals: every lane width's verdicts and entry distances are the scalar test's.
    #[test]
    fn wide_test_matches_scalar_slab_test_on_random_boxes() {
        let mut rng = SplitMix64::new(12);
        let mut met = 0;
        for round in 0..3000 {
            let boxes: [Aabb; 8] = std::array::from_fn(|c| {
                let lo = rng.vec3(-4.0, 4.0);
                let mut size = rng.vec3(0.0, 3.0);
                size[c % 3] *= (round % 2) as f32; // flat along one axis every other round
                match (round + c) % 11 {
                    0 => Aabb::EMPTY,
                    _ => Aabb::new(lo, lo + size),
                }
            });
            let node = node_of(&boxes);
            let o = rng.vec3(-6.0, 6.0);
            // Aimed into the boxes' region, so many are met.
            let mut d = rng.vec3(-3.0, 3.0) - o;
            d[round % 3] *= ((round / 3) % 2) as f32; // axis-parallel every other triple
            let tmin = if round % 4 == 0 {
                rng.range(0.0, 2.0)
            } else {
                0.0
            };
            let tmax = if round % 5 == 0 {
                tmin + rng.range(0.0, 5.0)
            } else {
                f32::INFINITY
            };
            for (name, robust, test) in eight_wide_tests() {
                met += agrees_with_scalar(
                    (test(o, d, &node, tmin, tmax), robust),
                    &boxes,
                    (o, d),
                    (tmin, tmax),
                    name,
                );
            }
        }
        // Not vacuous: hundreds of boxes met per lane width and slab kind (563 robust with this
        // seed).
        let per_test = met / eight_wide_tests().len();
        assert!(per_test > 400, "{per_test}");
    }
}
