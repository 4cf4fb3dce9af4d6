//! Where a secondary ray starts: the hit point pushed off its surface by a few ULPs along the
//! normal, so the new ray cannot re-hit the surface it leaves (Wächter & Binder, "A Fast and Robust
//! Method for Avoiding Self-Intersection", Ray Tracing Gems, ch. 6). Scale-independent: no epsilon
//! to tune per scene.

use glam::Vec3;

const ORIGIN: f32 = 1.0 / 32.0;
const FLOAT_SCALE: f32 = 1.0 / 65536.0;
const INT_SCALE: f32 = 256.0;

/// `p` moved off the surface with (not necessarily unit) normal `n`, to the side `n` points to.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let n = n.normalize_or_zero();
    let nudge = |p: f32, n: f32| -> f32 {
        let of_i = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((bits + if p < 0.0 { -of_i } else { of_i }) as u32);
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            moved
        }
    };
    Vec3::new(nudge(p.x, n.x), nudge(p.y, n.y), nudge(p.z, n.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_normal_side_at_any_scale() {
        for scale in [1e-3f32, 1.0, 1e3, 1e5] {
            let p = Vec3::new(0.3, 0.7, 0.1) * scale;
            let n = Vec3::new(0.0, 0.0, 1.0);
            let q = offset_ray_origin(p, n);
            assert!(q.z > p.z, "scale {scale}: {q:?}");
            assert!(
                (q - p).length() < scale.max(1.0) * 1e-3,
                "offset too large at scale {scale}"
            );
            let q = offset_ray_origin(p, -n);
            assert!(q.z < p.z);
        }
    }
}
