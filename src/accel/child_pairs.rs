//! The BVH's interior nodes re-laid for single-ray SIMD traversal: each interior node keeps both
//! children's boxes in structure-of-arrays form, one 4-lane vector per axis
//! `[left.min, right.min, left.max, right.max]`, so one SSE sequence tests both children
//! (the child-pair layout of Aila & Laine 2009, "Understanding the efficiency of ray traversal on
//! GPUs", used on the CPU as in tinybvh). One 64-byte cache line per interior node; the test runs
//! on the lane layer's 4-lane `Lanes4` vector.

use glam::Vec3;

use super::bvh::BvhNode;
use crate::geometry::{RayTests, Robust};
use crate::lanes::vector::{Lanes4, Vector};

#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct ChildPair {
    pub x: [f32; 4],
    pub y: [f32; 4],
    pub z: [f32; 4],
    /// `first` and `count` of the left and right child (as in `BvhNode`).
    pub first: [u32; 2],
    pub count: [u32; 2],
}

/// One entry per BVH node, indexed like `Bvh::nodes`; leaves' entries stay empty.
pub fn child_pairs(nodes: &[BvhNode]) -> Vec<ChildPair> {
    nodes
        .iter()
        .map(|n| {
            if n.is_leaf() || nodes.len() < 2 {
                return ChildPair::default();
            }
            let (l, r) = (&nodes[n.first as usize], &nodes[n.first as usize + 1]);
            let (lb, rb) = (l.bounds, r.bounds);
            ChildPair {
                x: [lb.min.x, rb.min.x, lb.max.x, rb.max.x],
                y: [lb.min.y, rb.min.y, lb.max.y, rb.max.y],
                z: [lb.min.z, rb.min.z, lb.max.z, rb.max.z],
                first: [l.first, r.first],
                count: [l.count, r.count],
            }
        })
        .collect()
}

/// A ray prepared for child-pair tests. Per axis, the plane lanes `[min_l, min_r, max_l, max_r]`
/// are multiplied by the reciprocal direction in the near lanes and by its negated far scaling
/// (`−inv·FAR_SCALE`, `RayTests::FAR_SCALE`: 1 for plain slabs) in the far ones, so that one
/// running `max` computes both the entry distance and the (negated) exit distance; a negative
/// direction (sign bit, so −0.0 counts) has its near planes in the max lanes, so its factors are
/// the other way round and its halves are swapped after the product, giving
/// `[near_l, near_r, −far_l, −far_r]` either way.
#[derive(Clone, Copy)]
pub struct PairRayTest {
    origin: [Lanes4; 3],
    negative: [bool; 3],
    factor: [Lanes4; 3],
}

impl PairRayTest {
    /// The conservative test (`with::<Robust>`), bit for bit `RayBoxTest::hit`.
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::with::<Robust>(origin, dir)
    }

    /// The test with `R`'s slabs: conservative (`Robust`) or plain (`Fast`).
    #[inline(always)]
    pub fn with<R: RayTests>(origin: Vec3, dir: Vec3) -> Self {
        let inv = Vec3::ONE / dir;
        let negative = [0, 1, 2].map(|a| inv[a].is_sign_negative());
        let factor = [0, 1, 2].map(|a| {
            let (near, far) = (inv[a], -(inv[a] * R::FAR_SCALE));
            Lanes4::new(if negative[a] {
                [far, far, near, near]
            } else {
                [near, near, far, far]
            })
        });
        PairRayTest {
            origin: origin.to_array().map(Lanes4::splat),
            negative,
            factor,
        }
    }

    /// Entry distances into the left and right child and which of them the ray hits within
    /// `[tmin, tmax]` (bit 0 left, bit 1 right).
    ///
    /// An origin on a slab plane with a zero direction component gives `0·∞ = NaN`; `max`
    /// (MAXPS) returns its second operand when either is NaN, so putting the new axis first makes
    /// NaN lanes leave the interval unrestricted — the conservative answer, as in `RayBoxTest`.
    #[inline(always)]
    pub fn test(&self, pair: &ChildPair, tmin: f32, tmax: f32) -> ([f32; 2], u32) {
        let mut acc = Lanes4::new([tmin, tmin, -tmax, -tmax]);
        for (axis, planes) in [&pair.x, &pair.y, &pair.z].into_iter().enumerate() {
            let t = (Lanes4::load(planes, 0) - self.origin[axis]) * self.factor[axis];
            let t = if self.negative[axis] {
                t.swap_halves()
            } else {
                t
            };
            acc = t.max(acc);
        }
        let exit = Lanes4::splat(0.0) - acc.swap_halves();
        let hit = (Lanes4::bits(acc.le(exit)) & 0b11) as u32;
        let mut lanes = [0.0f32; 4];
        acc.store(&mut lanes);
        ([lanes[0], lanes[1]], hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Aabb, RayBoxTest};
    use crate::test_util::awkward_slab_rays;

    fn pair(l: Aabb, r: Aabb) -> ChildPair {
        ChildPair {
            x: [l.min.x, r.min.x, l.max.x, r.max.x],
            y: [l.min.y, r.min.y, l.max.y, r.max.y],
            z: [l.min.z, r.min.z, l.max.z, r.max.z],
            ..ChildPair::default()
        }
    }

    /// The SIMD pair test must give exactly the scalar `RayBoxTest` answers, including the
    /// awkward cases (zero and −0.0 components, origins on slab planes, inside, behind), with
    /// conservative slabs (`Robust`) and plain ones (`Fast`).
    #[test]
    fn pair_test_matches_scalar_slab_test() {
        matches_scalar_slab_test::<Robust>();
        matches_scalar_slab_test::<crate::geometry::Fast>();
    }

    fn matches_scalar_slab_test<R: RayTests>() {
        let boxes = [
            Aabb::new(Vec3::ZERO, Vec3::ONE),
            Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)),
            Aabb::new(Vec3::new(-1.0, -1.0, 5.0), Vec3::new(1.0, 1.0, 6.0)),
            Aabb::new(Vec3::splat(0.25), Vec3::splat(0.5)),
        ];
        let (origins, dirs) = awkward_slab_rays();
        for l in &boxes {
            for r in &boxes {
                let p = pair(*l, *r);
                for o in origins {
                    for d in dirs {
                        for (tmin, tmax) in [(0.0, f32::INFINITY), (0.0, 1.2), (2.0, 10.0)] {
                            let scalar = RayBoxTest::new(o, d);
                            let (want_l, want_r) = (
                                scalar.hit_with::<R>(l, tmin, tmax),
                                scalar.hit_with::<R>(r, tmin, tmax),
                            );
                            let (t, mask) = PairRayTest::with::<R>(o, d).test(&p, tmin, tmax);
                            assert_eq!(
                                mask & 1 != 0,
                                want_l.is_some(),
                                "left {l:?} o {o:?} d {d:?} [{tmin},{tmax}]"
                            );
                            assert_eq!(
                                mask & 2 != 0,
                                want_r.is_some(),
                                "right {r:?} o {o:?} d {d:?} [{tmin},{tmax}]"
                            );
                            if let Some(w) = want_l {
                                assert_eq!(t[0], w);
                            }
                            if let Some(w) = want_r {
                                assert_eq!(t[1], w);
                            }
                        }
                    }
                }
            }
        }
    }
}
