//! Triangle meshes for the NFF quadrics: spheres (`s`) and open cones or cylinders (`c`). The
//! tracers take triangles only, so a sphere becomes a latitude–longitude mesh and a cone a ring
//! of quads; all triangles face outwards (counter-clockwise seen from outside) unless the file
//! asks for the inside with negative radii.

use std::f32::consts::{PI, TAU};

use glam::Vec3;

use crate::geometry::Triangle;

/// Triangles of a sphere cut into `segments` longitudes and `segments / 2` latitude bands: the
/// two polar bands are fans, the others quads. That makes `2 · segments · (segments/2 − 1)`
/// triangles (120 for 12 segments). A negative radius shows the inside (NFF §"s").
pub fn sphere(center: Vec3, radius: f32, segments: u32) -> Vec<Triangle> {
    let bands = (segments / 2).max(2);
    let segments = segments.max(3);
    let r = radius.abs();
    let point = |band: u32, seg: u32| {
        let theta = PI * band as f32 / bands as f32;
        let phi = TAU * (seg % segments) as f32 / segments as f32;
        center
            + r * Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            )
    };
    let mut tris = Vec::with_capacity((2 * segments * (bands - 1)) as usize);
    for seg in 0..segments {
        // North cap: the pole, then two points of the first ring.
        tris.push(Triangle::new(point(0, 0), point(1, seg), point(1, seg + 1)));
        for band in 1..bands - 1 {
            let (a, b) = (point(band, seg), point(band, seg + 1));
            let (c, d) = (point(band + 1, seg), point(band + 1, seg + 1));
            tris.push(Triangle::new(a, c, d));
            tris.push(Triangle::new(a, d, b));
        }
        tris.push(Triangle::new(
            point(bands, 0),
            point(bands - 1, seg + 1),
            point(bands - 1, seg),
        ));
    }
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
    let axis = apex - base;
    if axis.length_squared() == 0.0 {
        return None;
    }
    let segments = segments.max(3);
    let inside = base_radius < 0.0;
    let (r0, r1) = if inside {
        (-base_radius, -apex_radius)
    } else {
        (base_radius, apex_radius)
    };
    // (u, v, axis) right-handed, so that increasing angle runs counter-clockwise about the axis.
    let w = axis.normalize();
    let u = w.any_orthonormal_vector();
    let v = w.cross(u);
    let ring = |centre: Vec3, r: f32, seg: u32| {
        let phi = TAU * (seg % segments) as f32 / segments as f32;
        centre + r * (phi.cos() * u + phi.sin() * v)
    };
    let mut tris = Vec::with_capacity(2 * segments as usize);
    for seg in 0..segments {
        let (b0, b1) = (ring(base, r0, seg), ring(base, r0, seg + 1));
        let (a0, a1) = (ring(apex, r1, seg), ring(apex, r1, seg + 1));
        if r0 != 0.0 {
            tris.push(Triangle::new(b0, b1, a1));
        }
        if r1 != 0.0 {
            tris.push(Triangle::new(b0, a1, a0));
        }
    }
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
