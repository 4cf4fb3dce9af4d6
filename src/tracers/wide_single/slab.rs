//! One ray against all `W` child boxes of a wide node (`accel::WideNode`'s structure-of-arrays
//! lanes) in one SIMD slab test: the conservative slab test of `RayBoxTest::hit` (Ize 2013) with
//! the boxes in the lanes instead of the rays. Per axis the near and far planes are picked by the
//! ray's direction sign bit (so −0.0 counts as negative) and every lane runs the scalar test's
//! operations in its order — `(plane − origin) · inverse direction`, far distances scaled by
//! `FAR_SCALE`, running max/min that ignore a NaN (`0·∞` for an origin on a slab plane) — so each
//! child's verdict is `RayBoxTest`'s.
//!
//! Written with SSE intrinsics on groups of 4 children (baseline x86-64, as `child_pairs`), not
//! as lane loops over `[f32; W]`: LLVM's SLP vectorizer split those loops' far-plane half into
//! scalar loads and shuffles (checked in the assembly), while these compile to straight vector
//! code, one sub/mul/max-or-min per group and plane and one movemask per group.

use std::arch::x86_64::*;

use glam::Vec3;

use crate::accel::WideNode;
use crate::geometry::aabb::FAR_SCALE;
use crate::lanes::BroadcastRay;

/// A ray prepared for wide-node tests: origin and reciprocal direction broadcast per axis.
#[derive(Clone, Copy)]
pub struct WideRayTest(BroadcastRay);

impl WideRayTest {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        WideRayTest(BroadcastRay::new(origin, dir))
    }

    /// Each child's entry distance (clipped to `tmin`) and which children the ray meets within
    /// `[tmin, tmax]` (bit `c`: child `c`; empty slots never). `W` is a multiple of 4.
    #[inline(always)]
    pub fn test<const W: usize>(
        &self,
        node: &WideNode<W>,
        tmin: f32,
        tmax: f32,
    ) -> ([f32; W], u32) {
        const { assert!(W.is_multiple_of(4), "children are tested in groups of 4") };
        let mut enter = [0.0f32; W];
        let mut hit = 0u32;
        // SAFETY: SSE is part of the x86_64 baseline; every load and store is of 4 lanes at
        // `group < W`, `W` a multiple of 4, inside arrays of `W` lanes.
        unsafe {
            let far_scale = _mm_set1_ps(FAR_SCALE);
            for group in (0..W).step_by(4) {
                let mut near_max = _mm_set1_ps(tmin);
                let mut far_min = _mm_set1_ps(tmax);
                for a in 0..3 {
                    let (near, far) = if self.0.negative[a] {
                        (&node.hi[a], &node.lo[a])
                    } else {
                        (&node.lo[a], &node.hi[a])
                    };
                    let (o, inv) = (self.0.origin[a], self.0.inv_dir[a]);
                    let t_near =
                        _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(near[group..].as_ptr()), o), inv);
                    let t_far = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(far[group..].as_ptr()), o), inv);
                    // `_mm_max_ps(a, b)` / `_mm_min_ps(a, b)` return `b` when either is NaN: the
                    // new plane first, so a NaN leaves the interval as it was.
                    near_max = _mm_max_ps(t_near, near_max);
                    far_min = _mm_min_ps(_mm_mul_ps(t_far, far_scale), far_min);
                }
                _mm_storeu_ps(enter[group..].as_mut_ptr(), near_max);
                hit |= (_mm_movemask_ps(_mm_cmple_ps(near_max, far_min)) as u32) << group;
            }
        }
        (enter, hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::wide_bvh::spaced_leaves;
    use crate::accel::{Bvh, BvhConfig, WideBvh};
    use crate::geometry::{Aabb, RayBoxTest, Triangle};
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

    /// Every child's verdict and entry distance are the scalar `RayBoxTest`'s, in the awkward
    /// cases too (zero and −0.0 components, origins on slab planes, inside, behind, short
    /// segments), and an empty slot is never hit.
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
        let mut hits = 0;
        for o in origins {
            for d in dirs {
                for (tmin, tmax) in [(0.0, f32::INFINITY), (0.0, 1.2), (2.0, 10.0)] {
                    let (enter, mask) = WideRayTest::new(o, d).test(&node, tmin, tmax);
                    let scalar = RayBoxTest::new(o, d);
                    for (c, b) in boxes.iter().enumerate() {
                        let want = scalar.hit(b, tmin, tmax);
                        let case = format!("box {c} o {o:?} d {d:?} [{tmin}, {tmax}]");
                        assert_eq!(mask & (1 << c) != 0, want.is_some(), "{case}");
                        if let Some(t) = want {
                            assert_eq!(enter[c], t, "{case}");
                            hits += 1;
                        }
                    }
                }
            }
        }
        // Not a vacuous agreement: many boxes are met, and the empty one never.
        assert!(hits > 50, "{hits}");
        let four = WideBvh::<4>::collapse(&Bvh::build(
            &[Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)],
            BvhConfig::default(),
        ));
        let (_, mask) = WideRayTest::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z).test(
            &four.nodes[0],
            0.0,
            f32::INFINITY,
        );
        assert_eq!(mask, 0b0001, "only the one leaf's slot, no empty slot");
    }
}
