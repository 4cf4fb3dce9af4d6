//! `marbles` (animated): marbles dropped into a glass box, after the rigid-body scene of Wald et
//! al. 2006 ("Performance for Animated Scenes", Fig. 10b: 110 marbles, 8.8K triangles, a case of
//! "completely incoherent motion"). The motion is simulated once, deterministically, when the
//! scene is built (see `marble_physics`); `mesh_at` places each tessellated marble at its
//! simulated centre, spun at its own constant angular velocity (friction-free contacts exert no
//! torque). The box — floor and four glass walls — is static geometry at the start of the mesh.
//!
//! Size `N` is the number of marbles, each an 8 × 6 UV sphere of 80 triangles, plus the 10-triangle
//! box: **80·N + 10 triangles** (N = 12: 970; N = 110, Wald's scene: 8,810; N = 12,500: 1,000,010).
//! The box's footprint grows with ∛N so the pile's shape stays alike across sizes.

use glam::{Quat, Vec3};

use super::marble_physics::{simulate, Trajectory, World};
use super::{animated_scene, point_lights, Generator, SizeKnob};
use crate::random::SplitMix64;
use crate::scene::tessellate::Surface;
use crate::scene::{Animation, Camera, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "marbles",
    about: "animated: marbles dropped into a glass box, rigid-body simulation (Wald et al. 2006)",
    size: SizeKnob {
        default: 110,
        min: 1,
        max: 25_000,
        meaning: "number of marbles; 80·N + 10 triangles",
    },
    triangle_count,
    build,
};

pub const DURATION: f32 = 4.0;
pub const RADIUS: f32 = 0.5;
const SEED: u64 = 2006;
const SLICES: u32 = 8;
const STACKS: u32 = 6;
/// Centre spacing of the starting lattice: 30% gaps between marbles.
const SPACING: f32 = 2.0 * RADIUS * 1.3;
/// Height of the lowest starting layer's gap above the floor.
const DROP: f32 = 1.0;

const FLOOR: u32 = 0;
const GLASS: u32 = 1;
const MARBLE_COLOURS: [(&str, [f32; 3]); 6] = [
    ("marble_red", [0.8, 0.1, 0.1]),
    ("marble_green", [0.1, 0.7, 0.2]),
    ("marble_blue", [0.1, 0.25, 0.85]),
    ("marble_yellow", [0.9, 0.75, 0.1]),
    ("marble_white", [0.85, 0.85, 0.85]),
    ("marble_black", [0.05, 0.05, 0.05]),
];

pub fn triangle_count(marbles: u32) -> usize {
    80 * marbles as usize + 10
}

/// Marbles per side of each starting layer: ≈ 0.8·∛N, so tall piles stay about as tall as wide.
fn per_side(marbles: u32) -> u32 {
    ((0.8 * (marbles as f32).cbrt()).round() as u32).max(2)
}

/// The box interior for `marbles`: its footprint holds one starting layer, and its walls rise two
/// spacings above the highest starting marble.
pub fn box_extent(marbles: u32) -> Vec3 {
    let side = per_side(marbles);
    let layers = marbles.div_ceil(side * side);
    let width = side as f32 * SPACING;
    let height = DROP + RADIUS + (layers - 1) as f32 * SPACING + RADIUS + 2.0 * SPACING;
    Vec3::new(width, height, width)
}

fn materials() -> Vec<Material> {
    let mut materials = vec![
        Material::diffuse("floor", Vec3::splat(0.6)),
        // The "(invisible) glass box" of Wald et al.: clear walls the camera looks through.
        Material {
            dielectric: Some((1.5, 0.95)),
            ..Material::diffuse("glass", Vec3::ZERO)
        },
    ];
    materials.extend(MARBLE_COLOURS.iter().map(|&(name, colour)| Material {
        mirror: 0.25,
        ..Material::diffuse(name, colour.into())
    }));
    materials
}

/// The simulated marbles, re-tessellated at any time.
#[derive(Debug)]
pub struct MarblesAnimation {
    container: Mesh,
    marble: Surface,
    materials: Vec<u32>,
    /// Per marble: constant angular velocity (rad/s, axis × rate) and orientation at time 0.
    spin: Vec<(Vec3, Quat)>,
    trajectory: Trajectory,
}

impl Animation for MarblesAnimation {
    fn duration(&self) -> f32 {
        self.trajectory.duration()
    }

    fn mesh_at(&self, time: f32) -> Mesh {
        let time = time.clamp(0.0, self.duration());
        let mut mesh = self.container.clone();
        mesh.triangles
            .reserve(self.materials.len() * self.marble.triangle_count());
        mesh.material_ids
            .reserve(self.materials.len() * self.marble.triangle_count());
        let centres = self.trajectory.positions_at(time);
        for ((centre, &(omega, start)), &material) in
            centres.iter().zip(&self.spin).zip(&self.materials)
        {
            let rotation = Quat::from_scaled_axis(omega * time) * start;
            self.marble
                .emit(&mut mesh, material, |p| *centre + rotation * (p * RADIUS));
        }
        mesh
    }
}

impl MarblesAnimation {
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }
}

/// Simulates `marbles` marbles for `DURATION` seconds.
pub fn animation(marbles: u32) -> MarblesAnimation {
    let extent = box_extent(marbles);
    let side = per_side(marbles);
    let mut rng = SplitMix64::new(SEED);

    // Start on a jittered lattice (no overlaps: the jitter is below the 30% gap) with random
    // velocities, so the marbles tumble in incoherently.
    let mut position = Vec::with_capacity(marbles as usize);
    let mut velocity = Vec::with_capacity(marbles as usize);
    let mut spin = Vec::with_capacity(marbles as usize);
    let mut material = Vec::with_capacity(marbles as usize);
    let jitter = 0.4 * (SPACING - 2.0 * RADIUS) / 2.0;
    for i in 0..marbles {
        let (layer, cell) = (i / (side * side), i % (side * side));
        let lattice = Vec3::new(
            ((cell % side) as f32 + 0.5) * SPACING,
            DROP + RADIUS + layer as f32 * SPACING,
            ((cell / side) as f32 + 0.5) * SPACING,
        );
        position
            .push(lattice + Vec3::new(rng.range(-jitter, jitter), 0.0, rng.range(-jitter, jitter)));
        velocity.push(Vec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-1.0, 1.0),
            rng.range(-2.0, 2.0),
        ));
        let axis = rng.direction();
        spin.push((
            axis * rng.range(0.0, 4.0 * std::f32::consts::PI),
            Quat::from_scaled_axis(rng.direction() * rng.range(0.0, 3.0)),
        ));
        material.push(2 + (rng.next_u64() % MARBLE_COLOURS.len() as u64) as u32);
    }
    let world = World {
        radius: RADIUS,
        extent,
        restitution: 0.5,
    };
    let trajectory = simulate(&world, position, velocity, DURATION);

    // Floor facing up, walls facing in (the box is seen from outside through the glass).
    let (x, y, z) = (Vec3::X * extent.x, Vec3::Y * extent.y, Vec3::Z * extent.z);
    let mut container = Mesh::default();
    for (corner, u, v, m) in [
        (Vec3::ZERO, z, x, FLOOR),
        (Vec3::ZERO, y, z, GLASS),
        (x, z, y, GLASS),
        (Vec3::ZERO, x, y, GLASS),
        (z, y, x, GLASS),
    ] {
        Surface::quad(corner, u, v, 1).emit(&mut container, m, |p| p);
    }

    MarblesAnimation {
        container,
        marble: Surface::uv_sphere(SLICES, STACKS),
        materials: material,
        spin,
        trajectory,
    }
}

pub fn build(marbles: u32) -> Scene {
    let extent = box_extent(marbles);
    // Look down through the open top from just above the box, the field of view fitted to the
    // floor: ray casting treats the glass walls as opaque, so any side view sees only walls; from
    // here they are seen edge-on and the falling and piling marbles fill the frame.
    let floor_centre = Vec3::new(extent.x * 0.5, 0.0, extent.z * 0.5);
    let eye_height = extent.y * 1.1;
    let camera = Camera {
        position: floor_centre + Vec3::new(0.0, eye_height, 0.1 * extent.z),
        target: floor_centre,
        up: -Vec3::Z,
        fov_y_deg: 2.0 * (0.6 * extent.x / eye_height).atan().to_degrees(),
        ..Camera::default()
    };
    let light = Vec3::new(extent.x * 0.7, extent.y + extent.x, extent.z * 0.4);
    let lights = point_lights(&[light], floor_centre);
    animated_scene(&GENERATOR, animation(marbles), materials(), lights, camera)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    #[test]
    fn count_follows_the_formula_and_spans_1k_to_1m() {
        assert_eq!(triangle_count(12), 970);
        assert_eq!(triangle_count(110), 8_810);
        assert_eq!(triangle_count(12_500), 1_000_010);
        assert_eq!(build(12).triangle_count(), 970);
    }

    #[test]
    fn motion_keeps_count_and_order_and_is_deterministic() {
        let scene = build(110);
        assert_eq!(scene.triangle_count(), 8_810);
        let a = scene.animation.as_ref().unwrap();
        assert_eq!(a.duration(), DURATION);
        let (early, later) = (a.mesh_at(0.5), a.mesh_at(1.0));
        assert_eq!(early.len(), 8_810);
        assert_eq!(early.material_ids, later.material_ids);
        assert_eq!(early.material_ids, scene.mesh.material_ids);
        // The box (first 10 triangles) stands still; every marble moves.
        assert_eq!(early.triangles[..10], later.triangles[..10]);
        for m in 0..110 {
            let k = 10 + 80 * m;
            assert_ne!(
                early.triangles[k], later.triangles[k],
                "marble {m} did not move"
            );
        }
        // Same seed, same simulation: bit-identical geometry.
        assert_eq!(build(110).animation.unwrap().mesh_at(2.5), a.mesh_at(2.5));
    }

    #[test]
    fn marbles_stay_in_the_box_and_settle_without_interpenetrating() {
        let a = animation(110);
        let inside = Aabb::new(Vec3::ZERO, box_extent(110));
        for k in 0..=40 {
            let mesh = a.mesh_at(k as f32 * 0.1);
            assert!(mesh.triangles.iter().all(|t| t.is_finite()));
            let bounds = mesh.bounds();
            assert!(
                inside.contains(&Aabb::new(bounds.min + 1e-3, bounds.max - 1e-3)),
                "t = {}: {bounds:?} leaves {inside:?}",
                k as f32 * 0.1
            );
        }
        // Once the pile has formed (the last second) no two marbles overlap by more than 1% of a
        // diameter.
        let trajectory = a.trajectory();
        for time in [3.0, 3.5, DURATION] {
            let centres = trajectory.positions_at(time);
            let mut closest = f32::MAX;
            for i in 0..centres.len() {
                for j in 0..i {
                    closest = closest.min(centres[i].distance(centres[j]));
                }
            }
            assert!(
                closest > 2.0 * RADIUS * 0.99,
                "t = {time}: centres {closest} apart"
            );
        }
        // Settled: the restitution has taken out nearly all the energy of the fall — the mean
        // speed over the last sample interval is under 5% of what it was mid-fall. (Contacts have
        // no friction, so some marbles still slide slowly along the floor and walls.)
        let mean_speed = |time: f32| {
            let (now, before) = (
                trajectory.positions_at(time),
                trajectory.positions_at(time - trajectory.sample_dt),
            );
            now.iter()
                .zip(&before)
                .map(|(a, b)| a.distance(*b))
                .sum::<f32>()
                / (now.len() as f32 * trajectory.sample_dt)
        };
        let (falling, end) = (mean_speed(1.0), mean_speed(DURATION));
        assert!(
            falling > 2.0 && end < 0.05 * falling,
            "mean speed {falling} m/s falling, {end} m/s at the end"
        );
        let end = trajectory.positions_at(DURATION);
        // The pile is lower than the drop: the top marble ends below the starting top layer.
        let top = end.iter().map(|p| p.y).fold(0.0, f32::max);
        assert!(
            top < trajectory.samples[0]
                .iter()
                .map(|p| p.y)
                .fold(0.0, f32::max)
        );
    }
}
