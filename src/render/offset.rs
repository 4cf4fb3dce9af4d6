//! Where a secondary ray starts: the hit point pushed off its surface along the normal, far enough
//! that the new ray cannot re-hit the surface it leaves.
//!
//! The margin is proportional to the largest coordinate magnitude of the surface (its vertices
//! and the point). A ray–triangle test computes the triangle's vertices relative to the ray
//! origin, so its distance error is a few ULPs of the *largest* coordinate involved, not of the
//! point's coordinate along the normal (the per-component offset of Wächter & Binder, Ray Tracing
//! Gems ch. 6, lets a ray leaving a 2600-unit floor at y ≈ −1.57 re-hit it: the conference scene
//! showed it). Same reasoning as pbrt-v4's error-bound offset (Pharr et al., §6.8.6).

use glam::Vec3;

use crate::geometry::Triangle;

/// Margin in units of the largest coordinate magnitude: 2⁻¹⁶, i.e. 128 ULPs of f32.
const MARGIN: f32 = 1.0 / 65536.0;
/// Below this magnitude, coordinates are treated as this large (keeps the margin away from 0).
const MIN_SCALE: f32 = 1.0 / 32.0;

/// The largest coordinate magnitude of a triangle: the scale of its intersection errors.
pub fn coordinate_scale(tri: &Triangle) -> f32 {
    tri.v
        .iter()
        .map(|p| p.abs().max_element())
        .fold(MIN_SCALE, f32::max)
}

/// `p` moved off a surface of coordinate scale `scale` along `n` (not necessarily unit), to the
/// side `n` points to.
pub fn offset_ray_origin(p: Vec3, n: Vec3, scale: f32) -> Vec3 {
    let scale = scale.max(p.abs().max_element()).max(MIN_SCALE);
    p + n.normalize_or_zero() * (scale * MARGIN)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::WatertightRay;
    use crate::render::sampling::{cosine_hemisphere, uniform};

    #[test]
    fn offset_moves_to_the_normal_side_at_any_scale() {
        for scale in [1e-3f32, 1.0, 1e3, 1e5] {
            let p = Vec3::new(0.3, 0.7, 0.1) * scale;
            let q = offset_ray_origin(p, Vec3::Z, scale);
            assert!(q.z > p.z, "scale {scale}: {q:?}");
            assert!(
                (q - p).length() < scale.max(1.0) * 1e-4,
                "offset too large at scale {scale}"
            );
            assert!(offset_ray_origin(p, -Vec3::Z, scale).z < p.z);
        }
    }

    /// The case that motivated the scale: rays leaving the conference floor (a 2600-unit
    /// triangle at y = −1.57216, far from the origin) in every direction of the upper hemisphere
    /// must never hit that floor again.
    #[test]
    fn rays_leaving_a_huge_floor_do_not_rehit_it() {
        let floor = Triangle::new(
            Vec3::new(-946.888, -1.57216, -1016.1),
            Vec3::new(-946.888, -1.57216, 668.489),
            Vec3::new(1653.25, -1.57216, -1016.1),
        );
        let scale = coordinate_scale(&floor);
        for i in 0..20_000u64 {
            let (u, v) = (uniform(3, i, 0), uniform(3, i, 1));
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let p = floor.point(u, v);
            let origin = offset_ray_origin(p, Vec3::Y, scale);
            let dir = cosine_hemisphere(Vec3::Y, uniform(4, i, 0), uniform(4, i, 1));
            let hit = WatertightRay::new(origin, dir).intersect(&floor, 0.0, f32::INFINITY);
            assert!(
                hit.is_none(),
                "ray {i} from {origin:?} along {dir:?} re-hit the floor: {hit:?}"
            );
        }
    }
}
