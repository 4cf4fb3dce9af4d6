//! The conservative ray–box slab test (Ize 2013, as `RayBoxTest::hit`) for `L` rays at once: near
//! and far planes chosen by the sign bit of each lane's direction, far distances scaled by
//! `FAR_SCALE`, and running max/min written `if t > acc { t } else { acc }`, which ignores a NaN
//! `t` like `f32::max` does (0·∞ when an origin lies on a slab plane). Each lane performs the
//! scalar test's operations in its order, so each lane's verdict is the scalar test's.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use super::LaneMask;
use crate::geometry::aabb::FAR_SCALE;

/// The lanes whose segment `[tmin, tmax]` meets the box `[lo, hi]`: `origin`, `inv_dir` and
/// `negative` (1 where the direction's sign bit is set) are `[axis][lane]`.
#[inline(always)]
pub fn hits<const L: usize>(
    origin: &[[f32; L]; 3],
    inv_dir: &[[f32; L]; 3],
    negative: &[[u32; L]; 3],
    tmin: &[f32; L],
    tmax: &[f32; L],
    lo: [f32; 3],
    hi: [f32; 3],
) -> LaneMask<L> {
    let mut enter = *tmin;
    let mut exit = *tmax;
    for a in 0..3 {
        let (o, inv, neg) = (&origin[a], &inv_dir[a], &negative[a]);
        for l in 0..L {
            let t_lo = (lo[a] - o[l]) * inv[l];
            let t_hi = (hi[a] - o[l]) * inv[l];
            let (near, far) = if neg[l] != 0 {
                (t_hi, t_lo)
            } else {
                (t_lo, t_hi)
            };
            let far = far * FAR_SCALE;
            enter[l] = if near > enter[l] { near } else { enter[l] };
            exit[l] = if far < exit[l] { far } else { exit[l] };
        }
    }
    let mut inside = [false; L];
    for l in 0..L {
        inside[l] = enter[l] <= exit[l];
    }
    LaneMask::from_bools(&inside)
}
