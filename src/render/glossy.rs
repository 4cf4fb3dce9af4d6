//! Glossy reflection: directions from a Phong lobe `cos^e α` about the mirror direction.
//!
//! The mapping matters for speed (Boulos et al. 2007 §4): "certain mappings transform the origin
//! in sample space to a reflected ray that is perfectly tangent to the object's surface. These
//! tangent rays generate many false positives when performing the BVH traversal." The textbook
//! inversion `cos α = u₁^(1/(e+1))` is such a mapping: `u₁ = 0` gives `α = 90°`, a direction
//! perpendicular to the mirror ray, which for any mirror ray lies on or below the surface. We use
//! `cos α = (1 − u₁)^(1/(e+1))` instead (the same density, since `1 − u₁` is uniform too): the
//! origin of sample space maps to the mirror direction itself, and `u₁ < 1` keeps `cos α > 0`.
//! A lobe direction may still fall below the surface near grazing incidence; it is reflected back
//! through the tangent plane (its normal component negated), and a direction exactly in the
//! tangent plane is replaced by the mirror direction, so no glossy ray is ever tangent or below.

use glam::Vec3;

/// A direction from the Phong lobe of `exponent` about `reflected` (unit), for the surface with
/// unit normal `n` on the side the ray leaves to, from a sample `(u1, u2)` in [0, 1)².
/// Always strictly above the surface when `reflected` is.
pub fn sample_phong_lobe(reflected: Vec3, n: Vec3, exponent: f32, u1: f32, u2: f32) -> Vec3 {
    let cos_a = (1.0 - u1).powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (tangent, bitangent) = reflected.any_orthonormal_pair();
    let d = (tangent * (sin_a * phi.cos()) + bitangent * (sin_a * phi.sin()) + reflected * cos_a)
        .normalize();
    let below = d.dot(n);
    if below > 0.0 {
        return d;
    }
    let flipped = (d - n * (2.0 * below)).normalize();
    if flipped.dot(n) > 0.0 {
        flipped
    } else {
        reflected
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampling::uniform;
    use crate::render::specular::reflect as mirror;

    #[test]
    fn origin_of_sample_space_is_the_mirror_direction() {
        let n = Vec3::Y;
        let r = mirror(Vec3::new(1.0, -0.2, 0.0).normalize(), n);
        assert!(sample_phong_lobe(r, n, 20.0, 0.0, 0.0).distance(r) < 1e-6);
        assert!(sample_phong_lobe(r, n, 20.0, 0.0, 0.7).distance(r) < 1e-6);
    }

    #[test]
    fn no_direction_is_below_or_tangent_even_at_grazing_incidence() {
        let n = Vec3::new(0.2, 1.0, -0.1).normalize();
        for incoming in [
            Vec3::new(1.0, -1e-3, 0.0),
            Vec3::new(1.0, -0.05, 0.3),
            Vec3::new(0.0, -1.0, 0.0),
        ] {
            let dir = incoming.normalize();
            // Incoming from the front: flip the direction so it points into the surface.
            let dir = if dir.dot(n) > 0.0 { -dir } else { dir };
            let r = mirror(dir, n);
            assert!(r.dot(n) > 0.0);
            for exponent in [1.0f32, 10.0, 1000.0] {
                for i in 0..20_000u64 {
                    let d = sample_phong_lobe(r, n, exponent, uniform(5, i, 0), uniform(5, i, 1));
                    assert!(
                        d.dot(n) > 0.0,
                        "{d:?} below/tangent for {incoming:?}, e={exponent}"
                    );
                    assert!((d.length() - 1.0).abs() < 1e-4);
                }
                // The extreme corners of sample space too.
                for (u1, u2) in [(0.0, 0.0), (0.999_999, 0.0), (0.999_999, 0.999_999)] {
                    assert!(sample_phong_lobe(r, n, exponent, u1, u2).dot(n) > 0.0);
                }
            }
        }
    }

    /// With normal incidence nothing falls below the surface, so the samples follow the lobe
    /// `(e+1)/2π · cos^e α` exactly: E[cos α] = (e+1)/(e+2).
    #[test]
    fn mean_cosine_matches_the_phong_lobe() {
        let n = Vec3::Z;
        let r = Vec3::Z;
        let samples = 200_000u64;
        for exponent in [1.0f32, 10.0, 100.0] {
            let mean = (0..samples)
                .map(|i| {
                    sample_phong_lobe(r, n, exponent, uniform(9, i, 0), uniform(9, i, 1)).dot(r)
                        as f64
                })
                .sum::<f64>()
                / samples as f64;
            let expected = (exponent as f64 + 1.0) / (exponent as f64 + 2.0);
            assert!(
                (mean - expected).abs() < 2e-3,
                "e={exponent}: mean cos {mean}, lobe {expected}"
            );
        }
    }
}
