//! One ray broadcast to every lane of an SSE register per axis, for tests that put boxes (not
//! rays) in the lanes: the reference tracer's two-children test (`accel::child_pairs`) and
//! `wide-single`'s test of a wide node's children. SSE is the x86-64 baseline, so these run on
//! every machine the project builds for.

use std::arch::x86_64::*;

use glam::Vec3;

/// The ray's origin and reciprocal direction in all four lanes per axis, and its direction's sign
/// bits (−0.0 counts as negative, as in `RayBoxTest`).
#[derive(Clone, Copy)]
pub struct BroadcastRay {
    pub origin: [__m128; 3],
    pub inv_dir: [__m128; 3],
    pub negative: [bool; 3],
}

impl BroadcastRay {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::from_inv(origin, Vec3::ONE / dir)
    }

    /// As `new`, from the reciprocal direction `inv = 1 / dir` (its sign bits are the
    /// direction's, `1 / −0.0 = −∞`).
    #[inline(always)]
    pub fn from_inv(origin: Vec3, inv: Vec3) -> Self {
        // SAFETY: SSE is part of the x86_64 baseline.
        unsafe {
            BroadcastRay {
                origin: [
                    _mm_set1_ps(origin.x),
                    _mm_set1_ps(origin.y),
                    _mm_set1_ps(origin.z),
                ],
                inv_dir: [_mm_set1_ps(inv.x), _mm_set1_ps(inv.y), _mm_set1_ps(inv.z)],
                negative: [
                    inv.x.is_sign_negative(),
                    inv.y.is_sign_negative(),
                    inv.z.is_sign_negative(),
                ],
            }
        }
    }
}
