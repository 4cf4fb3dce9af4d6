//! NFF's quadrics as triangles: spheres (`s`) and open cones or cylinders (`c`), cut by the shared
//! tessellator (`scene::tessellate`) at the loader's segment counts. The tracers take triangles
//! only, so a sphere becomes a latitude–longitude mesh and a cone a ring of quads; all triangles
//! face outwards (counter-clockwise seen from outside) unless the file asks for the inside with
//! negative radii.

use glam::Vec3;

use crate::geometry::Triangle;
use crate::scene::tessellate::{onto_cone, Surface};

/// Triangles of a sphere cut into `segments` longitudes and `segments / 2` latitude bands: the
/// two polar bands are fans, the others quads. That makes `2 · segments · (segments/2 − 1)`
/// triangles (120 for 12 segments). A negative radius shows the inside (NFF §"s").
pub fn sphere(center: Vec3, radius: f32, segments: u32) -> Vec<Triangle> {
    let bands = (segments / 2).max(2);
    let r = radius.abs();
    let mut tris = Surface::uv_sphere(segments.max(3), bands).triangles(|p| center + p * r);
    if radius < 0.0 {
        flip_all(&mut tris);
    }
    tris
}

/// Triangles of the open side of a cone or cylinder from `base` (radius `base_radius`) to `apex`
/// (radius `apex_radius`), `segments` around: two triangles per segment, or one where a radius is
/// zero (a pointed end). `None` when base and apex coincide. Negative radii show the inside, as in
/// NFF's `c` (both are negated together, following BART's reader).
pub fn cone(
    base: Vec3,
    base_radius: f32,
    apex: Vec3,
    apex_radius: f32,
    segments: u32,
) -> Option<Vec<Triangle>> {
    if (apex - base).length_squared() == 0.0 {
        return None;
    }
    let inside = base_radius < 0.0;
    let (r0, r1) = if inside {
        (-base_radius, -apex_radius)
    } else {
        (base_radius, apex_radius)
    };
    let mut tube = Surface::tube(segments.max(3));
    // Each face has an edge along one end ring (two vertices at that z); at a pointed end that
    // edge is a point and the face has no area, so it is left out.
    let edge_radius = |f: &[u32; 3]| {
        let at_base = f
            .iter()
            .filter(|&&i| tube.vertices[i as usize].z == 0.0)
            .count();
        if at_base == 2 {
            r0
        } else {
            r1
        }
    };
    tube.faces.retain(|f| edge_radius(f) != 0.0);
    let mut tris = tube.triangles(onto_cone(base, r0, apex, r1));
    if inside {
        flip_all(&mut tris);
    }
    Some(tris)
}

fn flip_all(tris: &mut [Triangle]) {
    for t in tris {
        t.v.swap(1, 2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_has_the_documented_count_and_faces_out() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let tris = sphere(c, 2.0, 12);
        assert_eq!(tris.len(), 2 * 12 * 5);
        for t in &tris {
            for p in t.v {
                assert!(((p - c).length() - 2.0).abs() < 1e-5);
            }
            assert!(t.normal().dot(t.centroid() - c) > 0.0);
        }
        let inside = sphere(c, -2.0, 12);
        assert!(inside
            .iter()
            .all(|t| t.normal().dot(t.centroid() - c) < 0.0));
    }

    #[test]
    fn cylinder_and_cone_counts_and_orientation() {
        let cyl = cone(Vec3::ZERO, 1.0, Vec3::Z * 3.0, 1.0, 16).unwrap();
        assert_eq!(cyl.len(), 32);
        for t in &cyl {
            let radial = t.centroid() - Vec3::new(0.0, 0.0, t.centroid().z);
            assert!(t.normal().dot(radial) > 0.0);
            for p in t.v {
                assert!((p.truncate().length() - 1.0).abs() < 1e-5);
            }
        }
        let pointed = cone(Vec3::ZERO, 1.0, Vec3::Y, 0.0, 8).unwrap();
        assert_eq!(pointed.len(), 8);
        assert!(pointed.iter().all(|t| t.area() > 0.0));
        assert!(cone(Vec3::ONE, 1.0, Vec3::ONE, 1.0, 8).is_none());
    }
}
