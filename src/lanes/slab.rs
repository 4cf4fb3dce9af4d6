//! The ray–box slab test (as `RayBoxTest::hit_with`) for `L` rays at once: near and far planes
//! chosen by the sign bit of each lane's direction, far distances taken by the reciprocal
//! direction scaled by the tests' `FAR_SCALE` (`R = Robust`: the conservative test of Ize 2013;
//! `Fast`: plain slabs), and running max/min written `if t > acc { t } else { acc }`, which
//! ignores a NaN `t` like `f32::max` does (0·∞ when an origin lies on a slab plane). Each lane
//! performs the scalar test's operations in its order, so each lane's verdict is the scalar
//! test's.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use super::LaneMask;
use crate::geometry::RayTests;

/// `L` rays as the slab test reads them, `[axis][lane]`: origins, inverse directions and
/// direction sign bits (1 where set, −0.0 included), and each lane's segment `[tmin, tmax]`.
#[derive(Clone, Copy)]
pub struct SlabRays<'a, const L: usize> {
    pub origin: &'a [[f32; L]; 3],
    pub inv_dir: &'a [[f32; L]; 3],
    pub negative: &'a [[u32; L]; 3],
    pub tmin: &'a [f32; L],
    pub tmax: &'a [f32; L],
}

impl<const L: usize> SlabRays<'_, L> {
    /// Each lane's entry and exit distance of the box `[lo, hi]` within its segment: the lane
    /// meets the box when entry ≤ exit.
    #[inline(always)]
    fn enter_exit<R: RayTests>(&self, lo: [f32; 3], hi: [f32; 3]) -> ([f32; L], [f32; L]) {
        let (mut enter, mut exit) = ([0.0f32; L], [0.0f32; L]);
        // Lanes outside, axes inside: each lane's running entry and exit are values, stored
        // once. Updated in place axis by axis, they compiled to masked stores where the arrays
        // stayed in memory (the stream's filter), which AMD's AVX2 cores run microcoded.
        for l in 0..L {
            let (mut en, mut ex) = (self.tmin[l], self.tmax[l]);
            for a in 0..3 {
                let (o, inv) = (self.origin[a][l], self.inv_dir[a][l]);
                let (near, far) = if self.negative[a][l] != 0 {
                    (hi[a], lo[a])
                } else {
                    (lo[a], hi[a])
                };
                let near = (near - o) * inv;
                let far = (far - o) * (inv * R::FAR_SCALE);
                en = if near > en { near } else { en };
                ex = if far < ex { far } else { ex };
            }
            enter[l] = en;
            exit[l] = ex;
        }
        (enter, exit)
    }

    /// The lanes whose segment meets the box `[lo, hi]`.
    #[inline(always)]
    pub fn hits<R: RayTests>(&self, lo: [f32; 3], hi: [f32; 3]) -> LaneMask<L> {
        let (enter, exit) = self.enter_exit::<R>(lo, hi);
        LaneMask::from_fn(|l| enter[l] <= exit[l])
    }

    /// Whether any lane's segment meets the box: `hits(..).any()`, reduced with an OR across the
    /// lanes rather than through a mask (the packet traversal's hottest test asks only this; the
    /// mask form cost it 25–40% at 1 thread).
    #[inline(always)]
    pub fn any_hit<R: RayTests>(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        let (enter, exit) = self.enter_exit::<R>(lo, hi);
        let mut any = 0u32;
        for l in 0..L {
            any |= (enter[l] <= exit[l]) as u32;
        }
        any != 0
    }
}
