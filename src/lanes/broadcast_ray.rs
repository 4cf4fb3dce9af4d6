//! One ray broadcast to every lane of a vector per axis, for tests that put boxes (not rays) in
//! the lanes: the reference tracer's two-children test (`accel::child_pairs`, `Lanes4`) and
//! `wide-single`'s test of a wide node's children (`Lanes4` or `Avx2`, by the node's width).

use glam::Vec3;

use super::vector::{Lanes4, Vector};

/// The ray's origin and reciprocal direction in all lanes of `V` per axis, and its direction's
/// sign bits (−0.0 counts as negative, as in `RayBoxTest`).
#[derive(Clone, Copy)]
pub struct BroadcastRay<V: Vector = Lanes4> {
    pub origin: [V; 3],
    pub inv_dir: [V; 3],
    pub negative: [bool; 3],
}

impl<V: Vector> BroadcastRay<V> {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::from_inv(origin, Vec3::ONE / dir)
    }

    /// As `new`, from the reciprocal direction `inv = 1 / dir` (its sign bits are the
    /// direction's, `1 / −0.0 = −∞`).
    #[inline(always)]
    pub fn from_inv(origin: Vec3, inv: Vec3) -> Self {
        // Component by component: through arrays (`to_array().map`) it cost 4 instructions more
        // per ray (callgrind, `wide-single` 4 wide).
        BroadcastRay {
            origin: [V::splat(origin.x), V::splat(origin.y), V::splat(origin.z)],
            inv_dir: [V::splat(inv.x), V::splat(inv.y), V::splat(inv.z)],
            negative: [
                inv.x.is_sign_negative(),
                inv.y.is_sign_negative(),
                inv.z.is_sign_negative(),
            ],
        }
    }
}
