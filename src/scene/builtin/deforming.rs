//! `deforming` (animated): a flag waving on a pole above a floor. The flag is a finely tessellated
//! sheet whose every vertex moves: travelling waves run from the pole to the free edge with an
//! amplitude growing away from the pole, so the surface bends everywhere each frame while its
//! topology (and triangle order) stays fixed — the vertex-animated ("deforming mesh") case of the
//! dynamic-scene experiments, as opposed to `marbles`' rigid motion.
//!
//! Size `n` cuts the flag into an `n × n` grid; the pole (a 12-sided open tube) and the floor add
//! 26: **2·n² + 26 triangles** (n = 22: 994; n = 96: 18,458; n = 708: 1,002,554; n = 2237,
//! the largest, 10,008,364: Wald et al. 2006's 10M-triangle Thai Statue of Fig. 8).

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};

use super::{animated_scene, point_lights, Generator, SizeKnob};
use crate::scene::tessellate::{onto_cylinder, Surface};
use crate::scene::{Animation, Camera, Material, Mesh, Scene};

pub const GENERATOR: Generator = Generator {
    name: "deforming",
    about: "animated: a finely tessellated flag waving on a pole (every vertex moves)",
    size: SizeKnob {
        default: 96,
        min: 1,
        max: 2237,
        meaning: "flag grid cells per side; 2·n² + 26 triangles",
    },
    triangle_count,
    build,
};

pub const DURATION: f32 = 4.0;
const POLE_RADIUS: f32 = 0.06;
const POLE_HEIGHT: f32 = 6.2;
const POLE_SIDES: u32 = 12;
const FLAG_LENGTH: f32 = 4.0;
const FLAG_HEIGHT: f32 = 2.6;
const FLAG_BOTTOM: f32 = 3.4;

const FLOOR: u32 = 0;
const POLE: u32 = 1;
const CLOTH: u32 = 2;

pub fn triangle_count(n: u32) -> usize {
    2 * (n as usize).pow(2) + 2 + 2 * POLE_SIDES as usize
}

/// Where the flag point with parameters `(u, v)` ∈ [0, 1]² is at `time`: `u` runs from the pole
/// to the free edge, `v` from the bottom to the top. The sideways wave's phase travels along `u`
/// and wobbles with height; the cloth shortens as it folds and its free bottom corner sags. x is
/// monotonic in `u` and y in `v`, so the sheet never folds through itself.
pub fn flag_point(uv: Vec2, time: f32) -> Vec3 {
    let (u, v) = (uv.x, uv.y);
    let phase = TAU * (1.2 * u - 0.9 * time) + 0.8 * (TAU * (0.5 * v + 0.25 * time)).sin();
    let ripple = (TAU * (3.0 * u + 2.0 * v - 1.7 * time)).sin();
    let x = POLE_RADIUS + FLAG_LENGTH * u - 0.15 * u * u * (1.0 + phase.cos());
    let y = FLAG_BOTTOM + FLAG_HEIGHT * v - 0.25 * u * u * (1.0 - v);
    let z = u * (0.45 * phase.sin() + 0.06 * ripple);
    Vec3::new(x, y, z)
}

/// The static floor and pole, followed by the flag re-evaluated at each time.
#[derive(Debug)]
pub struct Flag {
    fixed: Mesh,
    cloth: Surface,
    /// `(u, v)` of each cloth vertex (same indexing as `cloth.vertices`).
    uv: Vec<Vec2>,
}

impl Flag {
    pub fn new(n: u32) -> Flag {
        let mut fixed = Mesh::default();
        let floor_corner = Vec3::new(-6.0, 0.0, -8.0);
        Surface::quad(floor_corner, Vec3::Z * 16.0, Vec3::X * 16.0, 1).emit(
            &mut fixed,
            FLOOR,
            |p| p,
        );
        let pole = onto_cylinder(Vec3::ZERO, Vec3::Y * POLE_HEIGHT, POLE_RADIUS);
        Surface::tube(POLE_SIDES).emit(&mut fixed, POLE, pole);
        let param = |i: u32, j: u32| Vec2::new(i as f32 / n as f32, j as f32 / n as f32);
        let uv = Surface::grid(n, n, |i, j| param(i, j).extend(0.0))
            .vertices
            .iter()
            .map(|p| p.truncate())
            .collect();
        let cloth = Surface::grid(n, n, |i, j| flag_point(param(i, j), 0.0));
        Flag { fixed, cloth, uv }
    }
}

impl Animation for Flag {
    fn duration(&self) -> f32 {
        DURATION
    }

    fn mesh_at(&self, time: f32) -> Mesh {
        let mut mesh = self.fixed.clone();
        let moved: Vec<Vec3> = self.uv.iter().map(|&uv| flag_point(uv, time)).collect();
        self.cloth.emit_vertices(&mut mesh, CLOTH, &moved);
        mesh
    }
}

fn materials() -> Vec<Material> {
    vec![
        Material {
            mirror: 0.3,
            ..Material::diffuse("floor", Vec3::splat(0.5))
        },
        Material {
            mirror: 0.6,
            ..Material::diffuse("pole", Vec3::splat(0.7))
        },
        Material::diffuse("cloth", Vec3::new(0.75, 0.08, 0.08)),
    ]
}

pub fn build(n: u32) -> Scene {
    let flag_centre = Vec3::new(FLAG_LENGTH * 0.5, FLAG_BOTTOM + FLAG_HEIGHT * 0.5, 0.0);
    let lights = point_lights(&[Vec3::new(-3.0, 9.0, 6.0)], flag_centre);
    let camera = Camera {
        position: Vec3::new(2.0, 3.6, 9.0),
        target: Vec3::new(2.0, 4.3, 0.0),
        up: Vec3::Y,
        fov_y_deg: 45.0,
        ..Camera::default()
    };
    animated_scene(&GENERATOR, Flag::new(n), materials(), lights, camera)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_follows_the_formula_and_spans_1k_to_1m() {
        assert_eq!(triangle_count(22), 994);
        assert_eq!(triangle_count(708), 1_002_554);
        assert_eq!(build(22).triangle_count(), 994);
        assert_eq!(build(96).triangle_count(), 18_458);
        // A million-triangle frame is cheap to evaluate: do it once for real.
        assert_eq!(Flag::new(708).mesh_at(1.3).len(), 1_002_554);
    }

    #[test]
    fn every_flag_vertex_moves_but_the_pole_edge_and_topology_stay() {
        let flag = Flag::new(16);
        let (a, b) = (flag.mesh_at(0.0), flag.mesh_at(0.7));
        assert_eq!(a.len(), b.len());
        assert_eq!(a.material_ids, b.material_ids);
        let fixed = flag.fixed.len();
        assert_eq!(a.triangles[..fixed], b.triangles[..fixed]);
        // Cloth vertices away from the pole (u > 0) all move; the edge at the pole (u = 0) is
        // pinned to x = pole radius, z = 0.
        for (&uv, i) in flag.uv.iter().zip(0..) {
            let (p, q) = (flag_point(uv, 0.0), flag_point(uv, 0.7));
            assert_eq!(p, flag.cloth.vertices[i]);
            if uv.x == 0.0 {
                assert_eq!(p, q);
                assert_eq!((p.x, p.z), (POLE_RADIUS, 0.0));
            } else {
                assert!(p.distance(q) > 1e-4, "vertex {i} at {uv} did not move");
            }
        }
    }

    #[test]
    fn flag_stays_beside_the_pole_above_the_floor_and_finite() {
        let flag = Flag::new(32);
        for k in 0..=40 {
            let mesh = flag.mesh_at(k as f32 * 0.1);
            let bounds = mesh.bounds();
            assert!(mesh.triangles.iter().all(|t| t.is_finite()));
            // Floor −6..10 × −8..8 at y = 0; pole up to 6.2; flag within ±0.51 of z = 0.
            assert_eq!((bounds.min.y, bounds.max.y), (0.0, POLE_HEIGHT));
            let cloth = mesh.triangles[flag.fixed.len()..]
                .iter()
                .fold(crate::geometry::Aabb::EMPTY, |b, t| b.union(t.bounds()));
            assert!(
                cloth.min.x >= POLE_RADIUS - 1e-6
                    && cloth.max.x <= POLE_RADIUS + FLAG_LENGTH + 1e-5
            );
            assert!(
                cloth.min.y >= FLAG_BOTTOM - 0.25
                    && cloth.max.y <= FLAG_BOTTOM + FLAG_HEIGHT + 1e-5
            );
            assert!(cloth.min.z >= -0.51 && cloth.max.z <= 0.51);
        }
    }
}
