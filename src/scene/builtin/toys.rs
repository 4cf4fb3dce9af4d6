//! `toys` (animated): wind-up toys walking about a floor, after the "toys" scene of Wald et al.
//! 2006 (§4.6 "Non-hierarchical animation", Fig. 10a: 5 toys that "walk around incoherently,
//! bump into each other, and even jump over each other", 11K triangles). Each toy is a small
//! articulated walker — an ellipsoid body, a head, two swinging legs, two swinging arms and a
//! turning wind-up key — on its own seeded elliptical track about its own centre, at its own
//! speed and direction, hopping now and then. Tracks overlap, so the toys pass through each
//! other's space: the scene's triangles move independently, with no hierarchy a structure could
//! exploit (the case the per-frame grid rebuild is for).
//!
//! Size `N` is the number of toys, 2,080 triangles each, plus the 2-triangle floor:
//! **2080·N + 2 triangles** (N = 1: 2,082; N = 5, Wald's scene: 10,402; N = 96: 199,682;
//! N = 481: 1,000,482). The floor grows with √N so the crowd's density stays alike across sizes.

use std::f32::consts::{PI, TAU};

use glam::{Quat, Vec3};

use super::{animated_scene, point_lights, Generator, SizeKnob};
use crate::random::SplitMix64;
use crate::scene::tessellate::{onto_box, Surface};
use crate::scene::{Animation, Camera, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "toys",
    about: "animated: wind-up toys walking incoherently about a floor (Wald et al. 2006, Fig. 10a)",
    size: SizeKnob {
        default: 5,
        min: 1,
        max: 500,
        meaning: "number of toys; 2080·N + 2 triangles",
    },
    triangle_count,
    build,
};

pub const DURATION: f32 = 4.0;
const SEED: u64 = 0x7045;
/// Triangles of one toy: body 2·32·15, head 2·20·11, legs 2·12·4², arms 2·12·3², key shaft
/// 2·16 and key handle 12·2².
pub const TOY_TRIANGLES: usize = 960 + 440 + 384 + 216 + 32 + 48;
/// Floor half-width per √toy: about 3.4 toy heights of floor per toy.
const SPREAD: f32 = 3.0;
/// How high a toy's hop lifts it.
const HOP: f32 = 1.2;
/// Farthest any vertex gets from its toy's vertical axis (the arms' outer corners).
const TOY_REACH: f32 = 0.62;

/// Feet hover this far above the floor at rest, so a leg swinging about its hip (0.45 up, the
/// foot's far corner √(0.43² + 0.09²) ≈ 0.44 from it) never dips through the floor.
const FOOT_CLEARANCE: f32 = 0.02;

const FLOOR: u32 = 0;
const TOY_COLOURS: [(&str, [f32; 3]); 5] = [
    ("toy_red", [0.8, 0.12, 0.1]),
    ("toy_blue", [0.1, 0.3, 0.85]),
    ("toy_green", [0.15, 0.65, 0.2]),
    ("toy_yellow", [0.9, 0.75, 0.1]),
    ("toy_tin", [0.7, 0.7, 0.72]),
];

pub fn triangle_count(toys: u32) -> usize {
    TOY_TRIANGLES * toys as usize + 2
}

/// Half-width of the square floor the toys walk on.
pub fn arena(toys: u32) -> f32 {
    SPREAD * (toys as f32).sqrt().max(1.0)
}

/// One toy's seeded motion: an elliptical track about `centre` with radii `radius`, travelled at
/// `omega` rad/s (either direction) from `phase`; a walking cadence; hops every `hop_period` s.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Track {
    centre: [f32; 2],
    radius: [f32; 2],
    omega: f32,
    phase: f32,
    cadence: f32,
    hop_period: f32,
    hop_phase: f32,
}

impl Track {
    fn random(rng: &mut SplitMix64, arena: f32) -> Track {
        // Centres and radii keep every track inside ±(arena − reach): |centre| ≤ 0.45·a and
        // radius ≤ 0.5·a − reach.
        let reach = (0.5 * arena - TOY_REACH).max(0.1);
        let centre = [
            rng.range(-0.45, 0.45) * arena,
            rng.range(-0.45, 0.45) * arena,
        ];
        let radius = [rng.range(0.3, 1.0) * reach, rng.range(0.3, 1.0) * reach];
        let direction = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
        Track {
            centre,
            radius,
            omega: direction * rng.range(0.6, 1.4) * 2.5 / radius[0].max(radius[1]),
            phase: rng.range(0.0, TAU),
            cadence: rng.range(5.0, 8.0),
            hop_period: rng.range(1.5, 3.0),
            hop_phase: rng.unit(),
        }
    }

    /// Position on the floor (x, z), heading (yaw about +y, 0 = facing +z) and lift at `time`.
    fn pose(&self, time: f32) -> (Vec3, f32, f32) {
        let angle = self.omega * time + self.phase;
        let (s, c) = angle.sin_cos();
        let position = Vec3::new(
            self.centre[0] + self.radius[0] * c,
            0.0,
            self.centre[1] + self.radius[1] * s,
        );
        // Face along the velocity, d/dt of the position.
        let velocity = self.omega * Vec3::new(-self.radius[0] * s, 0.0, self.radius[1] * c);
        let heading = velocity.x.atan2(velocity.z);
        // A hop: the first quarter of each period is a parabolic jump.
        let cycle = (time / self.hop_period + self.hop_phase).fract();
        let lift = if cycle < 0.25 {
            let x = cycle * 4.0;
            HOP * 4.0 * x * (1.0 - x)
        } else {
            0.0
        };
        (position, heading, lift)
    }
}

/// A rigid part of a toy, in the toy's own frame (y up, facing +z, feet at y = 0), rotated by
/// `swing(time)` about `pivot` along `axis`.
#[derive(Debug)]
struct Part {
    surface: Surface,
    /// Maps the unit surface into the toy frame at rest.
    place: fn(Vec3) -> Vec3,
    pivot: Vec3,
    axis: Vec3,
    /// Swing angle (radians) from the walking phase.
    swing: fn(f32) -> f32,
}

fn body(p: Vec3) -> Vec3 {
    Vec3::new(0.38, 0.45, 0.3) * p + Vec3::new(0.0, 0.75, 0.0)
}
fn head(p: Vec3) -> Vec3 {
    0.22 * p + Vec3::new(0.0, 1.23, 0.0)
}
fn left_leg(p: Vec3) -> Vec3 {
    onto_box(
        Vec3::new(-0.3, FOOT_CLEARANCE, -0.09),
        Vec3::new(-0.1, 0.45, 0.09),
    )(p)
}
fn right_leg(p: Vec3) -> Vec3 {
    onto_box(
        Vec3::new(0.1, FOOT_CLEARANCE, -0.09),
        Vec3::new(0.3, 0.45, 0.09),
    )(p)
}
fn left_arm(p: Vec3) -> Vec3 {
    onto_box(Vec3::new(-0.5, 0.55, -0.06), Vec3::new(-0.38, 1.0, 0.06))(p)
}
fn right_arm(p: Vec3) -> Vec3 {
    onto_box(Vec3::new(0.38, 0.55, -0.06), Vec3::new(0.5, 1.0, 0.06))(p)
}
/// The key's shaft points backwards (−z) out of the body's back.
fn key_shaft(p: Vec3) -> Vec3 {
    Vec3::new(0.03 * p.x, 0.85 + 0.03 * p.y, -0.25 - 0.2 * p.z)
}
fn key_handle(p: Vec3) -> Vec3 {
    onto_box(Vec3::new(-0.16, 0.75, -0.5), Vec3::new(0.16, 0.95, -0.44))(p)
}

fn still(_: f32) -> f32 {
    0.0
}
fn stride(phase: f32) -> f32 {
    0.6 * phase.sin()
}
fn counter_stride(phase: f32) -> f32 {
    -stride(phase)
}
fn arm_swing(phase: f32) -> f32 {
    0.8 * phase.sin()
}
fn counter_arm_swing(phase: f32) -> f32 {
    -arm_swing(phase)
}
fn winding(phase: f32) -> f32 {
    0.5 * phase
}

fn parts() -> Vec<Part> {
    let hip = |x: f32| Vec3::new(x, 0.45, 0.0);
    let shoulder = |x: f32| Vec3::new(x, 0.95, 0.0);
    let key_axis = Vec3::new(0.0, 0.85, 0.0);
    let part = |surface, place, pivot, axis, swing| Part {
        surface,
        place,
        pivot,
        axis,
        swing,
    };
    vec![
        part(Surface::uv_sphere(32, 16), body, Vec3::ZERO, Vec3::X, still),
        part(Surface::uv_sphere(20, 12), head, Vec3::ZERO, Vec3::X, still),
        part(Surface::cube(4), left_leg, hip(-0.2), Vec3::X, stride),
        part(
            Surface::cube(4),
            right_leg,
            hip(0.2),
            Vec3::X,
            counter_stride,
        ),
        part(
            Surface::cube(3),
            left_arm,
            shoulder(-0.44),
            Vec3::X,
            counter_arm_swing,
        ),
        part(
            Surface::cube(3),
            right_arm,
            shoulder(0.44),
            Vec3::X,
            arm_swing,
        ),
        part(Surface::tube(16), key_shaft, key_axis, Vec3::Z, winding),
        part(Surface::cube(2), key_handle, key_axis, Vec3::Z, winding),
    ]
}

/// The floor, then every toy's parts re-posed at each time.
#[derive(Debug)]
pub struct ToysAnimation {
    floor: Mesh,
    parts: Vec<Part>,
    tracks: Vec<Track>,
}

impl ToysAnimation {
    pub fn new(toys: u32) -> ToysAnimation {
        let a = arena(toys);
        let mut floor = Mesh::default();
        Surface::quad(
            Vec3::new(-a, 0.0, -a),
            Vec3::Z * 2.0 * a,
            Vec3::X * 2.0 * a,
            1,
        )
        .emit(&mut floor, FLOOR, |p| p);
        let mut rng = SplitMix64::new(SEED);
        let tracks = (0..toys).map(|_| Track::random(&mut rng, a)).collect();
        ToysAnimation {
            floor,
            parts: parts(),
            tracks,
        }
    }

    /// Where toy `i` stands at `time` (its feet's centre; y is the hop's lift).
    pub fn toy_position(&self, i: usize, time: f32) -> Vec3 {
        let (position, _, lift) = self.tracks[i].pose(time);
        position + Vec3::Y * lift
    }
}

impl Animation for ToysAnimation {
    fn duration(&self) -> f32 {
        DURATION
    }

    fn mesh_at(&self, time: f32) -> Mesh {
        let mut mesh = self.floor.clone();
        let per_toy = self.tracks.len() * TOY_TRIANGLES;
        mesh.triangles.reserve(per_toy);
        mesh.material_ids.reserve(per_toy);
        for (i, track) in self.tracks.iter().enumerate() {
            let (position, heading, lift) = track.pose(time);
            let yaw = Quat::from_rotation_y(heading);
            let origin = position + Vec3::Y * lift;
            let walk = track.cadence * time + PI * track.hop_phase;
            let material = 1 + (i % TOY_COLOURS.len()) as u32;
            for part in &self.parts {
                let swing = Quat::from_axis_angle(part.axis, (part.swing)(walk));
                part.surface.emit(&mut mesh, material, |p| {
                    let local = part.pivot + swing * ((part.place)(p) - part.pivot);
                    origin + yaw * local
                });
            }
        }
        mesh
    }
}

fn materials() -> Vec<Material> {
    let mut materials = vec![Material::diffuse("floor", Vec3::splat(0.55))];
    materials.extend(TOY_COLOURS.iter().map(|&(name, colour)| Material {
        mirror: 0.15,
        ..Material::diffuse(name, colour.into())
    }));
    materials
}

pub fn build(toys: u32) -> Scene {
    let a = arena(toys);
    let lights = point_lights(&[Vec3::new(-0.6 * a, 2.0 * a + 4.0, 0.8 * a)], Vec3::ZERO);
    // From the front and above, the whole floor in view.
    let camera = Camera {
        position: Vec3::new(0.0, 1.3 * a + 2.0, 2.1 * a + 2.0),
        target: Vec3::new(0.0, 0.4, 0.0),
        up: Vec3::Y,
        fov_y_deg: 45.0,
        ..Camera::default()
    };
    animated_scene(
        &GENERATOR,
        ToysAnimation::new(toys),
        materials(),
        lights,
        camera,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    /// Highest point of a toy standing on the floor (head top, 1.23 + 0.22), before hopping.
    const TOY_HEIGHT: f32 = 1.45;

    #[test]
    fn count_follows_the_formula_at_every_time() {
        assert_eq!(
            parts()
                .iter()
                .map(|p| p.surface.triangle_count())
                .sum::<usize>(),
            2080
        );
        assert_eq!(triangle_count(5), 10_402);
        assert_eq!(triangle_count(96), 199_682);
        assert_eq!(triangle_count(481), 1_000_482);
        let toys = ToysAnimation::new(5);
        for time in [0.0, 1.3, 4.0] {
            let mesh = toys.mesh_at(time);
            assert_eq!(mesh.len(), 10_402);
            assert_eq!(mesh.material_ids.len(), 10_402);
        }
        assert_eq!(build(5).triangle_count(), 10_402);
    }

    #[test]
    fn deterministic_across_builds() {
        let (a, b) = (ToysAnimation::new(7), ToysAnimation::new(7));
        assert_eq!(a.tracks, b.tracks);
        assert_eq!(a.mesh_at(2.25).triangles, b.mesh_at(2.25).triangles);
        // Triangle order and materials never change with time.
        assert_eq!(a.mesh_at(0.0).material_ids, a.mesh_at(3.0).material_ids);
    }

    #[test]
    fn toys_move_relative_to_each_other() {
        let toys = ToysAnimation::new(5);
        let (t0, t1) = (0.0, 0.5);
        let moves: Vec<Vec3> = (0..5)
            .map(|i| toys.toy_position(i, t1) - toys.toy_position(i, t0))
            .collect();
        // Every toy walks at least 0.3 units in half a second (speed ≥ 0.6·2.5·min/max radius)…
        for (i, m) in moves.iter().enumerate() {
            let floor_move = Vec3::new(m.x, 0.0, m.z).length();
            assert!(floor_move > 0.3, "toy {i} moved {floor_move}");
        }
        // …and no two toys move alike: over the animation every pair's distance changes by more
        // than half a toy body's width, 0.38 (no rigid motion of the whole crowd).
        for i in 0..5 {
            for j in i + 1..5 {
                let apart = |t: f32| toys.toy_position(i, t).distance(toys.toy_position(j, t));
                let change = (1..=40)
                    .map(|k| (apart(k as f32 * 0.1) - apart(0.0)).abs())
                    .fold(0.0, f32::max);
                assert!(
                    change > 0.38,
                    "toys {i} and {j}: distance changes by {change}"
                );
            }
        }
        // The first toy's mesh (after the floor) moves; the floor does not.
        let (a, b) = (toys.mesh_at(t0), toys.mesh_at(t1));
        assert_eq!(a.triangles[..2], b.triangles[..2]);
        let moved = a.triangles[2..2 + TOY_TRIANGLES]
            .iter()
            .zip(&b.triangles[2..2 + TOY_TRIANGLES])
            .filter(|(p, q)| p != q)
            .count();
        assert_eq!(moved, TOY_TRIANGLES);
    }

    #[test]
    fn toys_stay_on_the_floor_inside_the_scene_box() {
        for n in [1, 5, 40] {
            let toys = ToysAnimation::new(n);
            let a = arena(n);
            for k in 0..=40 {
                let mesh = toys.mesh_at(k as f32 * 0.1);
                assert!(mesh.triangles.iter().all(|t| t.is_finite()));
                let crowd = mesh.triangles[2..]
                    .iter()
                    .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
                assert!(
                    crowd.min.x >= -a && crowd.max.x <= a && crowd.min.z >= -a && crowd.max.z <= a,
                    "{n} toys at {k}: {crowd:?} outside ±{a}"
                );
                // Swinging legs lift the feet, never push them through the floor.
                assert!(crowd.min.y >= -1e-4, "{crowd:?}");
                assert!(crowd.max.y <= TOY_HEIGHT + HOP + 0.05, "{crowd:?}");
            }
        }
    }
}
