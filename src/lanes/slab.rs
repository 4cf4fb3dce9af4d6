//! The conservative ray–box slab test (Ize 2013, as `RayBoxTest::hit`) for `L` rays at once: near
//! and far planes chosen by the sign bit of each lane's direction, far distances scaled by
//! `FAR_SCALE`, and running max/min written `if t > acc { t } else { acc }`, which ignores a NaN
//! `t` like `f32::max` does (0·∞ when an origin lies on a slab plane). Each lane performs the
//! scalar test's operations in its order, so each lane's verdict is the scalar test's.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use super::LaneMask;
use crate::geometry::aabb::FAR_SCALE;

/// Each lane's entry and exit distance of the box `[lo, hi]` within its `[tmin, tmax]`: the lane's
/// segment meets the box when entry ≤ exit. `origin`, `inv_dir` and `negative` (1 where the
/// direction's sign bit is set) are `[axis][lane]`.
#[inline(always)]
fn enter_exit<const L: usize>(
    origin: &[[f32; L]; 3],
    inv_dir: &[[f32; L]; 3],
    negative: &[[u32; L]; 3],
    tmin: &[f32; L],
    tmax: &[f32; L],
    lo: [f32; 3],
    hi: [f32; 3],
) -> ([f32; L], [f32; L]) {
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
    (enter, exit)
}

/// The lanes whose segment meets the box (arguments as `enter_exit`).
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
    let (enter, exit) = enter_exit(origin, inv_dir, negative, tmin, tmax, lo, hi);
    let mut inside = [false; L];
    for l in 0..L {
        inside[l] = enter[l] <= exit[l];
    }
    LaneMask::from_bools(&inside)
}

/// Whether any lane's segment meets the box: `hits(..).any()`, reduced with an OR across the
/// lanes rather than through a mask (the packet traversal's hottest test asks only this).
#[inline(always)]
pub fn any_hit<const L: usize>(
    origin: &[[f32; L]; 3],
    inv_dir: &[[f32; L]; 3],
    negative: &[[u32; L]; 3],
    tmin: &[f32; L],
    tmax: &[f32; L],
    lo: [f32; 3],
    hi: [f32; 3],
) -> bool {
    let (enter, exit) = enter_exit(origin, inv_dir, negative, tmin, tmax, lo, hi);
    let mut any = 0u32;
    for l in 0..L {
        any |= (enter[l] <= exit[l]) as u32;
    }
    any != 0
}
