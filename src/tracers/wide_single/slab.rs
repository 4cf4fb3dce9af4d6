//! One ray against all `W` child boxes of a wide node (`accel::WideNode`'s structure-of-arrays
//! lanes) in one SIMD slab test: the conservative slab test of `RayBoxTest::hit` (Ize 2013) with
//! the boxes in the lanes instead of the rays. Per axis the near and far planes are picked once
//! for the ray (its direction's sign bit, so −0.0 counts as negative) and every lane runs the
//! scalar test's operations in its order — `(plane − origin) · inverse direction`, far distances
//! scaled by `FAR_SCALE`, running max/min that ignore a NaN (`0·∞` for an origin on a slab plane)
//! — so each child's verdict is `RayBoxTest`'s. The lane loops over `[f32; W]` are what LLVM
//! turns into W-wide vector operations (one ymm operation per step at W = 8 on AVX2/AVX-512).

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;

use crate::accel::WideNode;
use crate::geometry::aabb::FAR_SCALE;

/// A ray prepared for wide-node tests.
#[derive(Clone, Copy, Debug)]
pub struct WideRayTest {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    negative: [bool; 3],
}

impl WideRayTest {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        WideRayTest {
            origin: origin.to_array(),
            inv_dir: (Vec3::ONE / dir).to_array(),
            negative: [
                dir.x.is_sign_negative(),
                dir.y.is_sign_negative(),
                dir.z.is_sign_negative(),
            ],
        }
    }

    /// Each child's entry distance (clipped to `tmin`) and which children the ray meets within
    /// `[tmin, tmax]` (bit `c`: child `c`; empty slots never).
    #[inline(always)]
    pub fn test<const W: usize>(
        &self,
        node: &WideNode<W>,
        tmin: f32,
        tmax: f32,
    ) -> ([f32; W], u32) {
        let mut enter = [tmin; W];
        let mut exit = [tmax; W];
        for a in 0..3 {
            let (near, far) = if self.negative[a] {
                (&node.hi[a], &node.lo[a])
            } else {
                (&node.lo[a], &node.hi[a])
            };
            let (o, inv) = (self.origin[a], self.inv_dir[a]);
            for c in 0..W {
                let t_near = (near[c] - o) * inv;
                let t_far = (far[c] - o) * inv * FAR_SCALE;
                enter[c] = if t_near > enter[c] { t_near } else { enter[c] };
                exit[c] = if t_far < exit[c] { t_far } else { exit[c] };
            }
        }
        let mut hit = 0u32;
        for c in 0..W {
            hit |= ((enter[c] <= exit[c]) as u32) << c;
        }
        (enter, hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Bvh, BvhConfig, WideBvh};
    use crate::geometry::{Aabb, RayBoxTest, Triangle};

    /// One wide node whose 8 children are the given boxes (a tree of 8 one-triangle leaves, the
    /// boxes then overwritten), the unused slots of a 4-wide one kept empty.
    fn node_of(boxes: &[Aabb; 8]) -> WideNode<8> {
        let tris: Vec<Triangle> = (0..8)
            .map(|i| {
                let p = Vec3::new(i as f32 * 10.0, 0.0, 0.0);
                Triangle::new(p, p + Vec3::X, p + Vec3::Y)
            })
            .collect();
        let config = BvhConfig {
            max_leaf_size: 1,
            presplit: 0.0,
            ..BvhConfig::default()
        };
        let mut node = WideBvh::<8>::collapse(&Bvh::build(&tris, config)).nodes[0];
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
        let origins = [
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::new(0.0, 0.5, -1.0),
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::splat(0.3),
            Vec3::new(4.0, 0.5, 0.5),
        ];
        let dirs = [
            Vec3::Z,
            Vec3::new(0.0, -0.0, 1.0),
            Vec3::new(-0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-1.0, -0.0, 0.0),
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(-0.7, 0.1, 0.0),
        ];
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
