//! Whitted's specular rays (Whitted 1980; Boulos et al. 2007 §3.2): perfect mirror reflection and
//! refraction by Snell's law with total internal reflection. Reflected rays leave on the side the
//! ray came from, refracted rays on the other side; both start at the offset origin of
//! `offset.rs`. A dielectric's inside is the side its triangle's normal points away from
//! (counter-clockwise winding faces out), so a ray entering by the normal side goes from air
//! (index 1) into the material, and a ray arriving from behind leaves it.

use glam::Vec3;

use crate::geometry::{Hit, Ray, RayBatch, RayKind};
use crate::render::offset::offset_ray_origin;
use crate::render::rays::SurfacePoint;
use crate::render::shading::{specular_response, SpecularResponse};
use crate::scene::{Material, Mesh};

/// Mirror image of direction `d` about the plane with unit normal `n` (either side).
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// Snell's law: the refracted direction of unit `d` through a surface whose unit normal `n` faces
/// the incoming ray (`d·n < 0`), with `eta` = index on the incoming side / index on the far side.
/// `None` on total internal reflection (sin θt > 1).
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((d * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// The relative index `eta` (incoming side over far side) of a dielectric of index `ior` for a
/// ray along `dir` meeting a triangle whose geometric (winding) normal is `geometric`.
pub fn relative_ior(geometric: Vec3, dir: Vec3, ior: f32) -> f32 {
    if geometric.dot(dir) < 0.0 {
        1.0 / ior
    } else {
        ior
    }
}

/// A ray leaving `surface` along `dir` on the side its normal faces (reflection).
pub fn reflection_ray(surface: &SurfacePoint, dir: Vec3) -> Ray {
    Ray::new(surface.ray_origin(), dir, 0.0, f32::INFINITY)
}

/// A ray leaving `surface` along `dir` through to the side its normal faces away from (refraction).
pub fn refraction_ray(surface: &SurfacePoint, dir: Vec3) -> Ray {
    let origin = offset_ray_origin(surface.p, -surface.n, surface.scale);
    Ray::new(origin, dir, 0.0, f32::INFINITY)
}

/// Where `ray` hit, and how the hit material splits it into reflection and refraction.
pub fn specular_at(
    mesh: &Mesh,
    materials: &[Material],
    ray: &Ray,
    hit: &Hit,
) -> (SurfacePoint, SpecularResponse) {
    let surface = SurfacePoint::of_hit(mesh, ray, hit);
    let material = &materials[mesh.material_ids[hit.prim as usize] as usize];
    let geometric = mesh.triangles[hit.prim as usize].normal();
    let response = specular_response(material, ray.dir, surface.n, geometric);
    (surface, response)
}

/// One secondary ray of `kind` (reflection or refraction) per hit of `parent` whose material
/// gives that kind a non-zero weight: the bounce-1 batches of the runner and of verification.
pub fn specular_rays(
    kind: RayKind,
    mesh: &Mesh,
    materials: &[Material],
    parent: &RayBatch,
    hits: &[Hit],
) -> RayBatch {
    assert!(matches!(kind, RayKind::Reflection | RayKind::Refraction));
    let mut batch = RayBatch::new(kind);
    for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
        let ray = parent.ray(i);
        let (surface, response) = specular_at(mesh, materials, &ray, hit);
        let child = match kind {
            RayKind::Reflection => (response.reflection > 0.0)
                .then(|| reflection_ray(&surface, reflect(ray.dir, surface.n))),
            _ => response
                .refraction
                .map(|(dir, _)| refraction_ray(&surface, dir)),
        };
        if let Some(child) = child {
            batch.push(child, parent.pixel[i]);
        }
    }
    batch
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        a.distance(b) < 1e-6
    }

    #[test]
    fn mirror_reflection_flips_the_normal_component() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        assert!(close(
            reflect(d, Vec3::Y),
            Vec3::new(1.0, 1.0, 0.0).normalize()
        ));
        // The normal's side does not matter.
        assert!(close(reflect(d, -Vec3::Y), reflect(d, Vec3::Y)));
        // Head-on: straight back.
        assert!(close(reflect(-Vec3::Z, Vec3::Z), Vec3::Z));
    }

    #[test]
    fn snell_refraction_by_hand() {
        // 45° from air into glass (1.5): sin θt = sin 45° / 1.5 = 0.471405, cos θt = 0.881917.
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let t = refract(d, Vec3::Y, 1.0 / 1.5).unwrap();
        assert!(close(t, Vec3::new(0.471_404_5, -0.881_917_1, 0.0)), "{t:?}");
        // Head-on: straight through.
        assert!(close(
            refract(-Vec3::Y, Vec3::Y, 1.0 / 1.5).unwrap(),
            -Vec3::Y
        ));
        // Leaving glass at 30°: sin θt = 1.5 · 0.5 = 0.75, cos θt = 0.661438.
        let d = Vec3::new(0.5, -(0.75f32).sqrt(), 0.0);
        let t = refract(d, Vec3::Y, 1.5).unwrap();
        assert!(close(t, Vec3::new(0.75, -0.661_437_8, 0.0)), "{t:?}");
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        // Glass → air: critical angle asin(1/1.5) = 41.81°. At 45° no ray leaves; at 40° one does.
        let at = |deg: f32| {
            let r = deg.to_radians();
            Vec3::new(r.sin(), -r.cos(), 0.0)
        };
        assert!(refract(at(45.0), Vec3::Y, 1.5).is_none());
        let t = refract(at(40.0), Vec3::Y, 1.5).unwrap();
        assert!((t.x - 1.5 * 40f32.to_radians().sin()).abs() < 1e-6);
        // Air → glass never reflects totally, even at grazing incidence.
        assert!(refract(at(89.9), Vec3::Y, 1.0 / 1.5).is_some());
    }

    #[test]
    fn entering_by_the_normal_side_and_leaving_through_the_back() {
        assert_eq!(relative_ior(Vec3::Y, -Vec3::Y, 1.5), 1.0 / 1.5);
        assert_eq!(relative_ior(Vec3::Y, Vec3::Y, 1.5), 1.5);
        let surface = SurfacePoint {
            p: Vec3::ZERO,
            n: Vec3::Y,
            scale: 1.0,
        };
        let reflected = reflection_ray(&surface, Vec3::Y);
        let refracted = refraction_ray(&surface, -Vec3::Y);
        assert!(reflected.origin.y > 0.0 && refracted.origin.y < 0.0);
        assert_eq!(reflected.origin.y, -refracted.origin.y);
    }
}
