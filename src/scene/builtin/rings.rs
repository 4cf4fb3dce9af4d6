//! `rings`: Eric Haines' SPD "rings" (Standard Procedural Databases, IEEE CG&A 1987), tessellated.
//! Overbeck et al. 2008 (§5.1) use it as the worst case for reflection rays: "the small and tangled
//! rings serve to disperse secondary rays in all directions".
//!
//! The layout follows SPD `rings.c`: each object is 6 interlocking pentagonal rings through the 30
//! edge midpoints of a dodecahedron; a ring is 5 cylinders joined by 5 spheres (radius 0.07412).
//! Objects are stacked in a square pyramid viewed from its apex — level `d` (0-based) holds
//! `(d + 1)²` objects at depth `(d + 1)/sin(π/8)` — in front of a white backdrop, with 3 lights.
//! Z is up, as in the SPD.
//!
//! Size `s` is the SPD size factor (pyramid levels): `s(s+1)(2s+1)/6` objects of 30 cylinders
//! (8 facets, 16 triangles) and 30 spheres (8 × 4 UV sphere, 48 triangles), plus the 2-triangle
//! backdrop: **1920·s(s+1)(2s+1)/6 + 2 triangles** (s = 1: 1,922; s = 7, the SPD default: 268,802;
//! s = 12: 1,248,002).

use std::f32::consts::PI;

use glam::{Mat3, Vec3};

use super::{point_lights, static_scene, Generator, SizeKnob};
use crate::scene::tessellate::{onto_cylinder, Surface};
use crate::scene::{Camera, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "rings",
    about: "Haines' SPD rings: a pyramid of interlocking pentagonal rings before a backdrop (Z up)",
    size: SizeKnob {
        default: 4,
        min: 1,
        max: 16,
        meaning: "pyramid levels (SPD size factor); 1920·s(s+1)(2s+1)/6 + 2 triangles",
    },
    triangle_count,
    build,
};

/// Radius of the ring cylinders and joint spheres ("no derivation given" in the SPD).
const TUBE_RADIUS: f32 = 0.07412;
const CYLINDER_SIDES: u32 = 8;
const SPHERE_SLICES: u32 = 8;
const SPHERE_STACKS: u32 = 4;
/// Triangles of one object: 30 cylinders and 30 spheres.
const OBJECT_TRIANGLES: usize =
    30 * (2 * CYLINDER_SIDES + 2 * SPHERE_SLICES * (SPHERE_STACKS - 1)) as usize;

pub fn object_count(levels: u32) -> usize {
    let s = levels as usize;
    s * (s + 1) * (2 * s + 1) / 6
}

pub fn triangle_count(levels: u32) -> usize {
    OBJECT_TRIANGLES * object_count(levels) + 2
}

/// Spacing of the pyramid levels along the view axis: 1/sin(π/8), so each level fills the 45° view.
fn level_spacing() -> f32 {
    1.0 / (PI / 8.0).sin()
}

/// The 30 ring vertices of one object, ring `k` being vertices `5k..5k+5` (SPD `create_dodec`):
/// a pentagon in the xy-plane, and five copies tilted about x by the angle between two
/// neighbouring five-fold axes of the icosahedron and turned about z by odd tenths of a turn.
fn ring_vertices() -> [Vec3; 30] {
    let scale = 1.0 / (1.0 + TUBE_RADIUS); // the object fits in the unit sphere
    let pentagon: [Vec3; 5] = std::array::from_fn(|k| {
        let a = k as f32 * 2.0 * PI / 5.0;
        Vec3::new(a.cos(), a.sin(), 0.0) * scale
    });
    let tilt = Mat3::from_rotation_x(2.0 * ((PI / 3.0).cos() / (PI / 5.0).sin()).acos());
    std::array::from_fn(|i| {
        let (ring, k) = (i / 5, i % 5);
        if ring == 0 {
            pentagon[k]
        } else {
            let turn = Mat3::from_rotation_z(PI * (2 * (ring - 1) + 1) as f32 / 5.0);
            turn * tilt * pentagon[k]
        }
    })
}

fn materials() -> Vec<Material> {
    // SPD: rings kd 0.5, ks 0.2 in red, green, blue and their complements; the backdrop white.
    let colours = [
        ("red", Vec3::new(1.0, 0.0, 0.0)),
        ("green", Vec3::new(0.0, 1.0, 0.0)),
        ("blue", Vec3::new(0.0, 0.0, 1.0)),
        ("cyan", Vec3::new(0.0, 1.0, 1.0)),
        ("magenta", Vec3::new(1.0, 0.0, 1.0)),
        ("yellow", Vec3::new(1.0, 1.0, 0.0)),
    ];
    let mut materials: Vec<Material> = colours
        .iter()
        .map(|&(name, colour)| Material {
            mirror: 0.2,
            ..Material::diffuse(name, colour * 0.5)
        })
        .collect();
    materials.push(Material::diffuse("backdrop", Vec3::ONE));
    materials
}
const BACKDROP: u32 = 6;

pub fn build(levels: u32) -> Scene {
    let spread = level_spacing();
    let vertices = ring_vertices();
    let sphere = Surface::uv_sphere(SPHERE_SLICES, SPHERE_STACKS);
    let tube = Surface::tube(CYLINDER_SIDES);
    let mut mesh = Mesh::default();
    mesh.triangles.reserve(triangle_count(levels));
    mesh.material_ids.reserve(triangle_count(levels));
    for depth in 0..levels {
        let y = spread * (depth + 1) as f32;
        for iz in 0..=depth {
            for ix in 0..=depth {
                let offset = Vec3::new(
                    (2 * ix) as f32 - depth as f32,
                    y,
                    (2 * iz) as f32 - depth as f32,
                );
                for (i, &v) in vertices.iter().enumerate() {
                    let previous = if i % 5 == 0 { i + 4 } else { i - 1 };
                    let (base, apex) = (v + offset, vertices[previous] + offset);
                    let ring = (i / 5) as u32;
                    tube.emit(&mut mesh, ring, onto_cylinder(base, apex, TUBE_RADIUS));
                    sphere.emit(&mut mesh, ring, |p| base + p * TUBE_RADIUS);
                }
            }
        }
    }

    // The SPD camera sits at the apex end looking down the pyramid axis (+y). Our path circles
    // it around the axis (radius 1) with the same view direction.
    let eye_centre = Vec3::new(0.0, -spread, 0.5);
    let spd_eye = Vec3::new(-1.0, -spread, 0.5);
    let camera = |position: Vec3| Camera {
        position,
        target: position + Vec3::Y,
        up: Vec3::Z,
        fov_y_deg: 45.0,
        ..Camera::default()
    };
    let keys: Vec<(f32, Camera)> = (0..=8)
        .map(|k| {
            let a = PI + k as f32 * PI / 4.0; // start at the SPD eye, −x of the centre
            (
                k as f32 * 0.5,
                camera(eye_centre + Vec3::new(a.cos(), 0.0, a.sin())),
            )
        })
        .collect();

    // The backdrop just spans the 45° view (+1%) as in the SPD, widened by the path radius so it
    // fills the view along the whole path; it faces the camera.
    let wall_y = spread * (levels + 1) as f32;
    let half = 1.01 * (wall_y - eye_centre.y) * (PI / 8.0).tan() + 1.0;
    let corner = Vec3::new(eye_centre.x - half, wall_y, eye_centre.z - half);
    Surface::quad(corner, Vec3::X * 2.0 * half, Vec3::Z * 2.0 * half, 1).emit(
        &mut mesh,
        BACKDROP,
        |p| p,
    );

    // SPD light positions; NFF lights do not fall off, ours do (1/d²), so together they are
    // scaled to give unit irradiance at the middle of the pyramid.
    let middle = Vec3::new(0.0, wall_y * 0.5, 0.0);
    let lights = point_lights(
        &[
            Vec3::new(3.0, -spread, 3.0),
            Vec3::new(-4.0, -spread, 1.0),
            Vec3::new(2.0, -spread, -4.0),
        ],
        middle,
    );
    static_scene(
        &GENERATOR,
        mesh,
        materials(),
        lights,
        camera(spd_eye),
        &keys,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_follows_the_formula_and_spans_1k_to_1m() {
        assert_eq!(object_count(1), 1);
        assert_eq!(object_count(7), 140); // SPD: 4200 spheres = 140 objects × 30
        assert_eq!(triangle_count(1), 1_922);
        assert_eq!(triangle_count(7), 268_802);
        assert_eq!(triangle_count(12), 1_248_002);
        for levels in [1, 2] {
            assert_eq!(build(levels).triangle_count(), triangle_count(levels));
        }
    }

    #[test]
    fn ring_vertices_are_the_thirty_edge_midpoints_of_a_dodecahedron() {
        let v = ring_vertices();
        let scale = 1.0 / (1.0 + TUBE_RADIUS);
        // All on one sphere, all distinct, and each ring a regular planar pentagon through the
        // centre whose normal is a five-fold axis: the 6 normals are pairwise 63.43° apart.
        for p in v {
            assert!((p.length() - scale).abs() < 1e-5);
        }
        let min_gap = (0..30)
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| v[i].distance(v[j]))
            .fold(f32::MAX, f32::min);
        // Icosidodecahedron edge = circumradius / φ.
        let golden = (1.0 + 5f32.sqrt()) / 2.0;
        assert!((min_gap - scale / golden).abs() < 1e-4, "{min_gap}");
        let normals: Vec<Vec3> = (0..6)
            .map(|r| v[5 * r].cross(v[5 * r + 1]).normalize())
            .collect();
        for a in 0..6 {
            for b in 0..a {
                let angle = normals[a].dot(normals[b]).abs().acos().to_degrees();
                assert!((angle - 63.435).abs() < 0.01, "{angle}");
            }
        }
    }

    #[test]
    fn pyramid_and_backdrop_bounds_and_finite_vertices() {
        let scene = build(3);
        let spread = level_spacing();
        let bounds = scene.mesh.bounds();
        assert!(scene.mesh.triangles.iter().all(|t| t.is_finite()));
        // The deepest level (y = 3·spread, objects up to ±2 in x and z, radius 1) sits in front of
        // the backdrop at y = 4·spread, which is the farthest geometry.
        assert!((bounds.max.y - 4.0 * spread).abs() < 1e-4);
        let objects = scene.mesh.triangles[..scene.triangle_count() - 2]
            .iter()
            .fold(crate::geometry::Aabb::EMPTY, |b, t| b.union(t.bounds()));
        // An object reaches its ring radius plus the tube radius from its centre: SPD scales the
        // rings by 1/(1 + r) but not the tube, so just over 1.
        let reach = 1.0 / (1.0 + TUBE_RADIUS) + TUBE_RADIUS + 1e-5;
        assert!(objects.min.y > spread - reach && objects.max.y < 3.0 * spread + reach);
        assert!(objects.min.x >= -2.0 - reach && objects.max.x <= 2.0 + reach);
        assert!(objects.max.x > 2.0 + reach - 0.01);
        assert_eq!(scene.camera.position, Vec3::new(-1.0, -spread, 0.5));
        assert_eq!(scene.camera_path.as_ref().unwrap().duration(), 4.0);
    }
}
