//! Seeded, order-independent sampling: every random number is a hash of (seed, ray, dimension), so
//! a batch is the same whatever the thread count or chunking — reproducible runs.

use glam::Vec3;

use crate::random::mix64;

/// A uniform number in [0, 1) for sample `index`, dimension `dim`, under `seed`.
#[inline]
pub fn uniform(seed: u64, index: u64, dim: u32) -> f32 {
    let h = mix64(seed ^ mix64(index.wrapping_mul(0x1000_0000_01B3) ^ dim as u64));
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Cosine-weighted direction about `normal` (Malley's method: uniform disk, projected up).
pub fn cosine_hemisphere(normal: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (tangent, bitangent) = normal.any_orthonormal_pair();
    let z = (1.0 - u1).max(0.0).sqrt();
    (tangent * (r * phi.cos()) + bitangent * (r * phi.sin()) + normal * z).normalize()
}

/// A point on the unit disk, concentric mapping (Shirley & Chiu 1997): keeps strata intact.
pub fn concentric_disk(u1: f32, u2: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, phi) = if a * a > b * b {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    (r * phi.cos(), r * phi.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_range_and_decorrelated() {
        let n = 100_000;
        let mean: f64 = (0..n).map(|i| uniform(42, i, 0) as f64).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
        assert!((0..n).all(|i| (0.0..1.0).contains(&uniform(1, i, 3))));
        assert_ne!(uniform(1, 5, 0), uniform(1, 5, 1));
        assert_ne!(uniform(1, 5, 0), uniform(2, 5, 0));
        assert_eq!(uniform(1, 5, 0), uniform(1, 5, 0));
    }

    #[test]
    fn cosine_directions_lie_in_the_hemisphere_with_mean_cosine_two_thirds() {
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let samples = 50_000;
        let mut sum = 0.0;
        for i in 0..samples {
            let d = cosine_hemisphere(n, uniform(7, i, 0), uniform(7, i, 1));
            assert!((d.length() - 1.0).abs() < 1e-4);
            assert!(d.dot(n) >= -1e-6);
            sum += d.dot(n) as f64;
        }
        // E[cos θ] under a cosine density is 2/3.
        assert!((sum / samples as f64 - 2.0 / 3.0).abs() < 0.01);
    }

    #[test]
    fn concentric_disk_stays_inside() {
        for i in 0..1000 {
            let (x, y) = concentric_disk(uniform(3, i, 0), uniform(3, i, 1));
            assert!(x * x + y * y <= 1.0 + 1e-5);
        }
    }
}
