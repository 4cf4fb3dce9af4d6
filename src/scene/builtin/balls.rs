//! `balls`: Eric Haines' SPD "balls", the sphereflake, tessellated. Following SPD `balls.c`: a
//! sphere of radius ½ carries 9 spheres of a third of its radius touching it — six around its
//! equator at 60° steps and three on its upper hemisphere — each of which carries 9 more, `size`
//! levels deep; a square floor lies below; three lights. Z is up, as in the SPD.
//!
//! Size `L` is the SPD size factor (recursion depth): `(9^(L+1) − 1)/8` spheres of 144 triangles
//! (12 × 7 UV sphere) plus the 2-triangle floor: **18·(9^(L+1) − 1) + 2 triangles** (L = 1: 1,442;
//! L = 3: 118,082; L = 4, the SPD default: 1,062,866).

use std::f32::consts::PI;

use glam::{Quat, Vec3};

use super::{point_lights, static_scene, Generator, SizeKnob};
use crate::scene::tessellate::Surface;
use crate::scene::{Camera, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "balls",
    about:
        "Haines' SPD balls: the sphereflake (9 children of 1/3 radius per sphere) on a floor (Z up)",
    size: SizeKnob {
        default: 3,
        min: 1,
        max: 5,
        meaning: "recursion depth (SPD size factor); 18·(9^(L+1) − 1) + 2 triangles",
    },
    triangle_count,
    build,
};

const SLICES: u32 = 12;
const STACKS: u32 = 7;
const SPHERE_TRIANGLES: usize = (2 * SLICES * (STACKS - 1)) as usize;
const ROOT_RADIUS: f32 = 0.5;
const FLOOR: u32 = 0;
const FLAKE: u32 = 1;

pub fn sphere_count(levels: u32) -> usize {
    (9usize.pow(levels + 1) - 1) / 8
}

pub fn triangle_count(levels: u32) -> usize {
    SPHERE_TRIANGLES * sphere_count(levels) + 2
}

/// Directions of the 9 children in the parent's frame (parent direction = +z): six on the
/// equator at azimuths 15° + 60°k, three at elevation asin(√(2/3)) ≈ 54.7° and azimuths
/// 45° + 120°k — what SPD `create_objset` computes with its rotations.
fn child_directions() -> [Vec3; 9] {
    let ring = |azimuth_deg: f32, z: f32| {
        let a = azimuth_deg.to_radians();
        let horizontal = (1.0 - z * z).sqrt();
        Vec3::new(horizontal * a.cos(), horizontal * a.sin(), z)
    };
    let top = (2.0f32 / 3.0).sqrt();
    std::array::from_fn(|k| {
        if k < 6 {
            ring(15.0 + 60.0 * k as f32, 0.0)
        } else {
            ring(45.0 + 120.0 * (k - 6) as f32, top)
        }
    })
}

/// Pushes the sphere (centre, radius) and, `depth` more levels, its children: depth first, parent
/// before children, the SPD's output order.
fn flake(
    spheres: &mut Vec<(Vec3, f32)>,
    centre: Vec3,
    radius: f32,
    direction: Vec3,
    depth: u32,
    children: &[Vec3; 9],
) {
    spheres.push((centre, radius));
    if depth == 0 {
        return;
    }
    let frame = Quat::from_rotation_arc(Vec3::Z, direction);
    let child_radius = radius / 3.0;
    for &d in children {
        let child_direction = frame * d;
        let child_centre = centre + child_direction * (radius + child_radius);
        flake(
            spheres,
            child_centre,
            child_radius,
            child_direction,
            depth - 1,
            children,
        );
    }
}

pub fn spheres(levels: u32) -> Vec<(Vec3, f32)> {
    let mut out = Vec::with_capacity(sphere_count(levels));
    flake(
        &mut out,
        Vec3::ZERO,
        ROOT_RADIUS,
        Vec3::Z,
        levels,
        &child_directions(),
    );
    out
}

fn materials() -> Vec<Material> {
    // SPD: floor beige kd 0.8; spheres (1, 0.9, 0.7) kd 0.5, ks 0.5 ("shiny").
    vec![
        Material::diffuse("floor", Vec3::new(1.0, 0.75, 0.33) * 0.8),
        Material {
            mirror: 0.5,
            ..Material::diffuse("flake", Vec3::new(1.0, 0.9, 0.7) * 0.5)
        },
    ]
}

pub fn build(levels: u32) -> Scene {
    let mut mesh = Mesh::default();
    mesh.triangles.reserve(triangle_count(levels));
    mesh.material_ids.reserve(triangle_count(levels));
    // Floor: 24 × 24 at z = −½ (the root sphere's radius below its centre), facing up.
    let floor_corner = Vec3::new(-12.0, -12.0, -0.5);
    Surface::quad(floor_corner, Vec3::X * 24.0, Vec3::Y * 24.0, 1).emit(&mut mesh, FLOOR, |p| p);
    let sphere = Surface::uv_sphere(SLICES, STACKS);
    for (centre, radius) in spheres(levels) {
        sphere.emit(&mut mesh, FLAKE, |p| centre + p * radius);
    }

    // SPD view from (2.1, 1.3, 1.7) at the origin; the path orbits a quarter turn about z.
    let spd_eye = Vec3::new(2.1, 1.3, 1.7);
    let camera = |position: Vec3| Camera {
        position,
        target: Vec3::ZERO,
        up: Vec3::Z,
        fov_y_deg: 45.0,
        ..Camera::default()
    };
    let keys: Vec<(f32, Camera)> = (0..=8)
        .map(|k| {
            let turn = Quat::from_rotation_z(k as f32 * (PI / 2.0) / 8.0);
            (k as f32 * 0.5, camera(turn * spd_eye))
        })
        .collect();
    // SPD light positions, together giving unit irradiance at the flake.
    let lights = point_lights(
        &[
            Vec3::new(4.0, 3.0, 2.0),
            Vec3::new(1.0, -4.0, 4.0),
            Vec3::new(-3.0, 1.0, 5.0),
        ],
        Vec3::ZERO,
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
        // SPD balls.c: 10, 91, 820, 7381 spheres for size factors 1..4.
        assert_eq!([1, 2, 3, 4].map(sphere_count), [10, 91, 820, 7381]);
        assert_eq!(triangle_count(1), 1_442);
        assert_eq!(triangle_count(4), 1_062_866);
        assert_eq!(build(1).triangle_count(), 1_442);
        // The 1M flake takes a fraction of a second: build it for real.
        assert_eq!(build(4).triangle_count(), 1_062_866);
    }

    #[test]
    fn children_touch_their_parent_and_the_flake_fits_its_unit_sphere() {
        let dirs = child_directions();
        for d in dirs {
            assert!((d.length() - 1.0).abs() < 1e-6 && d.z >= 0.0);
        }
        // Neighbouring equatorial children are 60° apart; each top child is 54.7° above them.
        assert!((dirs[0].dot(dirs[1]) - 0.5).abs() < 1e-6);
        let s = spheres(2);
        let (root, children) = (s[0], &s[1..]);
        assert_eq!(root, (Vec3::ZERO, 0.5));
        // Depth-first order: child k of the root is at 1 + 10k.
        for k in 0..9 {
            let (c, r) = children[10 * k];
            assert!((r - 0.5 / 3.0).abs() < 1e-7);
            assert!((c.length() - (0.5 + r)).abs() < 1e-6);
        }
        // SPD: "radius of sphere which would enclose entire object = 1.0"; the lowest spheres
        // just touch the floor at z = −½.
        let lowest = s.iter().map(|(c, r)| c.z - r).fold(f32::MAX, f32::min);
        assert!((lowest + 0.5).abs() < 1e-6, "{lowest}");
        let scene = build(3);
        for t in &scene.mesh.triangles[2..] {
            assert!(t.is_finite());
            for v in t.v {
                assert!(v.length() <= 1.0 + 1e-5 && v.z >= -0.5 - 1e-6);
            }
        }
    }
}
