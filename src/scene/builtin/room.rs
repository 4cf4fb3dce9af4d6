//! `room`: a closed room with a table and two boxes, a reflective floor and a point light under
//! the ceiling, seen from inside — the setting of the ERW6 scene of the papers (804 triangles:
//! Wald et al. 2006, static-scene comparison; Overbeck et al. 2008 §5.1, "extremely simple ...
//! all flat surfaces"), rebuilt here because ERW6 itself is not distributed.
//!
//! Size `n` cuts every face of the room and of its seven blocks (table top, four legs, two boxes)
//! into an `n × n` grid: 8 boxes × 6 faces × 2n² = **96·n² triangles** (n = 3: 864, close to
//! ERW6's 804; n = 103: 1,018,464). Subdividing keeps the scene's look and grows only the count
//! and the triangle density, which is what the size sweeps measure.

use glam::{Quat, Vec3};

use super::{static_scene, Generator, SizeKnob};
use crate::scene::tessellate::Surface;
use crate::scene::{Camera, Light, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "room",
    about:
        "closed room with a table and boxes, reflective floor, light under the ceiling (ERW6-like)",
    size: SizeKnob {
        default: 3,
        min: 1,
        max: 200,
        meaning: "subdivisions per face edge; 96·n² triangles",
    },
    triangle_count,
    build,
};

/// Interior extent: x ∈ [0, 10], y ∈ [0, 6] (up), z ∈ [0, 10].
pub const EXTENT: Vec3 = Vec3::new(10.0, 6.0, 10.0);

pub fn triangle_count(n: u32) -> usize {
    96 * (n as usize).pow(2)
}

const WALL: u32 = 0;
const ACCENT_WALL: u32 = 1;
const FLOOR: u32 = 2;
const CEILING: u32 = 3;
const WOOD: u32 = 4;
const RED: u32 = 5;
const BLUE: u32 = 6;

fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("wall", Vec3::new(0.75, 0.73, 0.68)),
        Material::diffuse("accent_wall", Vec3::new(0.55, 0.65, 0.8)),
        Material {
            mirror: 0.5,
            ..Material::diffuse("floor", Vec3::new(0.35, 0.35, 0.38))
        },
        Material::diffuse("ceiling", Vec3::splat(0.85)),
        Material::diffuse("wood", Vec3::new(0.55, 0.35, 0.18)),
        Material::diffuse("red", Vec3::new(0.75, 0.15, 0.12)),
        Material::diffuse("blue", Vec3::new(0.15, 0.25, 0.7)),
    ]
}

/// A box standing in the room: centre, half extents, rotation about the vertical axis (radians).
struct Block {
    center: Vec3,
    half: Vec3,
    yaw: f32,
    material: u32,
}

fn blocks() -> Vec<Block> {
    let upright = |center: Vec3, half: Vec3, material| Block {
        center,
        half,
        yaw: 0.0,
        material,
    };
    let leg = |x: f32, z: f32| upright(Vec3::new(x, 1.1, z), Vec3::new(0.1, 1.1, 0.1), WOOD);
    vec![
        upright(Vec3::new(5.0, 2.3, 5.0), Vec3::new(1.6, 0.1, 1.1), WOOD),
        leg(3.6, 4.1),
        leg(6.4, 4.1),
        leg(3.6, 5.9),
        leg(6.4, 5.9),
        Block {
            center: Vec3::new(1.8, 2.0, 7.6),
            half: Vec3::new(0.8, 2.0, 0.8),
            yaw: -20f32.to_radians(),
            material: BLUE,
        },
        Block {
            center: Vec3::new(7.9, 0.75, 7.4),
            half: Vec3::splat(0.75),
            yaw: 30f32.to_radians(),
            material: RED,
        },
    ]
}

pub fn build(n: u32) -> Scene {
    let (x, y, z) = (Vec3::X * EXTENT.x, Vec3::Y * EXTENT.y, Vec3::Z * EXTENT.z);
    let mut mesh = Mesh::default();
    // The room's six faces, each facing inwards (edge_u × edge_v points into the room).
    let faces = [
        (Vec3::ZERO, z, x, FLOOR),
        (y, x, z, CEILING),
        (Vec3::ZERO, y, z, WALL),
        (x, z, y, WALL),
        (Vec3::ZERO, x, y, WALL),
        (z, y, x, ACCENT_WALL),
    ];
    for (corner, u, v, material) in faces {
        Surface::quad(corner, u, v, n).emit(&mut mesh, material, |p| p);
    }
    let cube = Surface::cube(n);
    for block in blocks() {
        let rotation = Quat::from_rotation_y(block.yaw);
        cube.emit(&mut mesh, block.material, |p| {
            block.center + rotation * ((p * 2.0 - Vec3::ONE) * block.half)
        });
    }

    let camera = |position: [f32; 3], target: [f32; 3]| Camera {
        position: position.into(),
        target: target.into(),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        ..Camera::default()
    };
    let start = camera([9.2, 3.4, 0.8], [4.5, 1.2, 6.0]);
    // A walk along the front wall to the left corner, keeping the table in view.
    let keys = [
        (0.0, start),
        (1.0, camera([7.0, 3.0, 0.6], [4.0, 1.5, 6.5])),
        (2.0, camera([4.5, 2.6, 0.6], [5.0, 1.4, 6.0])),
        (3.0, camera([1.5, 3.0, 1.0], [5.5, 1.2, 5.5])),
        (4.0, camera([0.8, 3.6, 3.5], [6.0, 1.0, 5.0])),
    ];
    // ~1 W/m²-equivalent on the floor below it: intensity / 5.6².
    let light = Light::Point {
        position: Vec3::new(5.0, 5.6, 5.0),
        intensity: Vec3::new(32.0, 30.0, 27.0),
    };
    static_scene(&GENERATOR, mesh, materials(), vec![light], start, &keys)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    #[test]
    fn count_follows_the_formula_and_spans_1k_to_1m() {
        assert_eq!(triangle_count(3), 864);
        assert_eq!(triangle_count(103), 1_018_464);
        for n in [1, 3] {
            assert_eq!(build(n).triangle_count(), triangle_count(n));
        }
        // 1M triangles build in well under the 2 s budget: check the real thing once.
        assert_eq!(build(103).triangle_count(), 1_018_464);
    }

    #[test]
    fn everything_lies_inside_the_room_and_the_camera_path_too() {
        let scene = build(2);
        let room = Aabb::new(Vec3::ZERO, EXTENT);
        assert_eq!(scene.mesh.bounds(), room);
        assert!(scene
            .mesh
            .triangles
            .iter()
            .all(|t| t.is_finite() && t.area() > 0.0));
        let path = scene.camera_path.as_ref().unwrap();
        assert_eq!(path.duration(), 4.0);
        for key in &path.keys {
            assert!(room.contains_point(key.camera.position));
        }
        let Light::Point { position, .. } = scene.lights[0] else {
            panic!()
        };
        assert!(position.y < EXTENT.y && room.contains_point(position));
    }

    #[test]
    fn room_faces_point_inwards_and_the_floor_is_the_reflective_material() {
        let scene = build(1);
        let centre = EXTENT * 0.5;
        // The first 6 faces × 2 triangles are the room itself.
        for t in &scene.mesh.triangles[..12] {
            assert!(t.normal().dot(centre - t.centroid()) > 0.0);
        }
        let floor = scene.material_of(0);
        assert_eq!(floor.name, "floor");
        assert!(floor.is_reflective());
        assert_eq!(
            scene.materials.iter().filter(|m| m.is_reflective()).count(),
            1
        );
    }
}
