//! Material evaluation shared by the renderers: point-light Lambert shading, the exact dielectric
//! Fresnel reflectance, and how a material splits an incoming ray into mirror reflection and
//! refraction. Renderers decide which rays to trace; this file only says what they carry.

use glam::Vec3;

use crate::render::specular::{refract, relative_ior};
use crate::scene::{Light, Material};

/// Light reaching surfaces from everywhere, so shadows are dark but not black.
pub const AMBIENT: f32 = 0.08;
/// Colour of rays that leave the scene.
pub const BACKGROUND: Vec3 = Vec3::new(0.05, 0.06, 0.08);

/// Where a light shines from and how strongly, for point-light shading: point lights as they
/// are, quad lights as a point at their centre carrying their total power (renderers that do not
/// sample areas).
pub fn light_as_point(light: &Light) -> (Vec3, Vec3) {
    match *light {
        Light::Point {
            position,
            intensity,
        } => (position, intensity),
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            emission,
        } => (
            corner + (edge_u + edge_v) * 0.5,
            emission * edge_u.cross(edge_v).length(),
        ),
    }
}

/// Irradiance at `p` (unit normal `n`) from a point light of `intensity` at `position`, when
/// nothing is in between: intensity · cos θ / distance².
pub fn point_irradiance(p: Vec3, n: Vec3, position: Vec3, intensity: Vec3) -> Vec3 {
    let to_light = position - p;
    let d2 = to_light.length_squared();
    intensity * (n.dot(to_light) / d2.sqrt()).max(0.0) / d2
}

/// Exact Fresnel reflectance of unpolarised light at a dielectric interface (the mean of the s and
/// p reflectances; Pharr et al., pbrt §9.3), `cos_i` the cosine of incidence, `eta` = index on the
/// incoming side / index on the far side. 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// How a material splits a ray: the weight of its mirror reflection, and the direction and weight
/// of its refraction (none for opaque materials and on total internal reflection).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularResponse {
    pub reflection: f32,
    pub refraction: Option<(Vec3, f32)>,
}

/// The specular response of `m` to a ray along unit `dir` meeting a surface with unit normal `n`
/// facing the ray and geometric (winding) normal `geometric`. Dielectrics reflect the Fresnel
/// fraction F and refract (1 − F)·transmittance. Other materials reflect `mirror` plus their
/// glossy reflectance: a Whitted tracer follows one direction per bounce, so a glossy lobe is
/// taken at its mirror limit (the distribution renderer samples the lobe itself).
pub fn specular_response(m: &Material, dir: Vec3, n: Vec3, geometric: Vec3) -> SpecularResponse {
    match m.dielectric {
        Some((ior, transmittance)) => {
            let eta = relative_ior(geometric, dir, ior);
            match refract(dir, n, eta) {
                None => SpecularResponse {
                    reflection: 1.0,
                    refraction: None,
                },
                Some(t) => {
                    let f = fresnel_dielectric(-dir.dot(n), eta);
                    SpecularResponse {
                        reflection: f,
                        refraction: Some((t, (1.0 - f) * transmittance)),
                    }
                }
            }
        }
        None => SpecularResponse {
            reflection: (m.mirror + m.glossy.map_or(0.0, |(_, r)| r)).min(1.0),
            refraction: None,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_brewster_and_grazing_incidence() {
        // Normal incidence: ((n − 1)/(n + 1))² = 0.04 for glass, from either side.
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        // Brewster's angle atan(1.5): p-polarised light is not reflected, F = r_s²/2 with
        // r_s = (1 − n²)/(1 + n²) = −0.384615.
        let brewster = 1.5f32.atan();
        let expected = 0.5 * (1.25f32 / 3.25).powi(2);
        assert!((fresnel_dielectric(brewster.cos(), 1.0 / 1.5) - expected).abs() < 1e-6);
        // Grazing: everything is reflected.
        assert!(fresnel_dielectric(0.0, 1.0 / 1.5) > 0.9999);
        assert!(fresnel_dielectric(1e-3, 1.0 / 1.5) > 0.99);
        // Inside glass past the critical angle (41.8°): total internal reflection.
        assert_eq!(fresnel_dielectric(45f32.to_radians().cos(), 1.5), 1.0);
    }

    #[test]
    fn glass_splits_by_fresnel_and_mirrors_reflect_their_coat() {
        let glass = Material {
            dielectric: Some((1.5, 0.9)),
            diffuse: Vec3::ZERO,
            ..Material::default()
        };
        // Head-on from outside (the winding normal faces the ray).
        let r = specular_response(&glass, -Vec3::Y, Vec3::Y, Vec3::Y);
        assert!((r.reflection - 0.04).abs() < 1e-6);
        let (dir, weight) = r.refraction.unwrap();
        assert!(dir.distance(-Vec3::Y) < 1e-6 && (weight - 0.96 * 0.9).abs() < 1e-6);
        // From inside at 45°: total internal reflection.
        let d = Vec3::new(1.0, 1.0, 0.0).normalize();
        let r = specular_response(&glass, d, -Vec3::Y, Vec3::Y);
        assert_eq!((r.reflection, r.refraction), (1.0, None));

        let mirror = Material {
            mirror: 0.5,
            glossy: Some((50.0, 0.3)),
            ..Material::default()
        };
        let r = specular_response(&mirror, -Vec3::Y, Vec3::Y, Vec3::Y);
        assert_eq!((r.reflection, r.refraction), (0.8, None));
        let r = specular_response(&Material::default(), -Vec3::Y, Vec3::Y, Vec3::Y);
        assert_eq!((r.reflection, r.refraction), (0.0, None));
    }

    #[test]
    fn point_irradiance_falls_with_distance_squared_and_cosine() {
        let e = point_irradiance(Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 2.0, 0.0), Vec3::ONE);
        assert!((e - Vec3::splat(0.25)).length() < 1e-7);
        let e = point_irradiance(Vec3::ZERO, Vec3::Y, Vec3::new(2.0, 2.0, 0.0), Vec3::ONE);
        assert!((e.x - std::f32::consts::FRAC_1_SQRT_2 / 8.0).abs() < 1e-7);
        assert_eq!(
            point_irradiance(Vec3::ZERO, Vec3::Y, -Vec3::Y, Vec3::ONE),
            Vec3::ZERO
        );
    }
}
