//! A small rigid-body integrator for equal spheres in an open-topped box: gravity, sphere–sphere
//! and sphere–wall contacts with restitution and no friction. Fixed time step, a fixed order of
//! operations and no threads, so a run is bit-for-bit repeatable.
//!
//! Each step integrates velocities and positions (semi-implicit Euler), then relaxes the contacts
//! a few times in sequence (Gauss–Seidel): overlapping spheres are pushed apart along the line of
//! centres and their approaching normal velocity is reflected with restitution `e`. Without
//! friction a contact exerts no torque, so angular velocities never change (the caller spins the
//! marbles at constant rates).

use glam::Vec3;

/// The simulated world: spheres of `radius` in the box `[0, extent.x] × [0, ∞) × [0, extent.z]`
/// (floor at y = 0; the walls act at any height; `extent.y`, the box's nominal height, only sizes
/// the contact grid).
#[derive(Clone, Copy, Debug)]
pub struct World {
    pub radius: f32,
    pub extent: Vec3,
    pub restitution: f32,
}

/// Simulation step (s). Fast enough that no sphere moves more than a fraction of its radius per
/// step at the speeds a drop of a few dozen radii reaches.
pub const STEP: f32 = 1.0 / 240.0;
/// Positions are recorded every `SAMPLE_EVERY` steps (60 Hz) and interpolated in between.
pub const SAMPLE_EVERY: usize = 4;
const ITERATIONS: usize = 8;
const GRAVITY: Vec3 = Vec3::new(0.0, -9.81, 0.0);
/// Below this approach speed a contact is treated as resting (no bounce), which stops the
/// jitter gravity would otherwise pump into resting stacks each step.
const RESTING_SPEED: f32 = 2.0 * 9.81 * STEP;

/// Recorded sphere centres: `samples[k]` holds every sphere at time `k · sample_dt`.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    pub sample_dt: f32,
    pub samples: Vec<Vec<Vec3>>,
}

impl Trajectory {
    pub fn duration(&self) -> f32 {
        (self.samples.len() - 1) as f32 * self.sample_dt
    }

    /// Centres at `time` (clamped to the recorded span), linearly interpolated between samples.
    pub fn positions_at(&self, time: f32) -> Vec<Vec3> {
        let last = self.samples.len() - 1;
        let s = (time / self.sample_dt).clamp(0.0, last as f32);
        let k = (s.floor() as usize).min(last);
        if k == last {
            return self.samples[last].clone();
        }
        let f = s - k as f32;
        self.samples[k]
            .iter()
            .zip(&self.samples[k + 1])
            .map(|(a, b)| a.lerp(*b, f))
            .collect()
    }
}

/// Runs the world from the given state for `duration` seconds.
pub fn simulate(
    world: &World,
    mut position: Vec<Vec3>,
    mut velocity: Vec<Vec3>,
    duration: f32,
) -> Trajectory {
    let steps = (duration / STEP).round() as usize;
    let mut samples = Vec::with_capacity(steps / SAMPLE_EVERY + 1);
    samples.push(position.clone());
    let mut grid = Grid::new(world);
    let mut pairs = Vec::new();
    for step in 1..=steps {
        for (p, v) in position.iter_mut().zip(velocity.iter_mut()) {
            *v += GRAVITY * STEP;
            *p += *v * STEP;
        }
        grid.close_pairs(&position, &mut pairs);
        for _ in 0..ITERATIONS {
            for &(i, j) in &pairs {
                resolve_pair(world, &mut position, &mut velocity, i as usize, j as usize);
            }
            for (p, v) in position.iter_mut().zip(velocity.iter_mut()) {
                resolve_walls(world, p, v);
            }
        }
        if step % SAMPLE_EVERY == 0 {
            samples.push(position.clone());
        }
    }
    Trajectory {
        sample_dt: STEP * SAMPLE_EVERY as f32,
        samples,
    }
}

fn bounce(approach_speed: f32, restitution: f32) -> f32 {
    if approach_speed > RESTING_SPEED {
        restitution
    } else {
        0.0
    }
}

fn resolve_pair(world: &World, position: &mut [Vec3], velocity: &mut [Vec3], i: usize, j: usize) {
    let d = position[j] - position[i];
    let distance_sq = d.length_squared();
    let contact = 2.0 * world.radius;
    if distance_sq >= contact * contact || distance_sq == 0.0 {
        return;
    }
    let distance = distance_sq.sqrt();
    let n = d / distance;
    let push = n * (0.5 * (contact - distance));
    position[i] -= push;
    position[j] += push;
    // Equal masses: the impulse splits evenly.
    let approach = (velocity[i] - velocity[j]).dot(n);
    if approach > 0.0 {
        let impulse = n * (0.5 * (1.0 + bounce(approach, world.restitution)) * approach);
        velocity[i] -= impulse;
        velocity[j] += impulse;
    }
}

fn resolve_walls(world: &World, p: &mut Vec3, v: &mut Vec3) {
    let r = world.radius;
    // (axis, lower bound, upper bound): x and z walls, and the floor (open top).
    for (axis, lo, hi) in [
        (0, r, world.extent.x - r),
        (1, r, f32::INFINITY),
        (2, r, world.extent.z - r),
    ] {
        if p[axis] < lo {
            p[axis] = lo;
            if v[axis] < 0.0 {
                v[axis] = -v[axis] * bounce(-v[axis], world.restitution);
            }
        } else if p[axis] > hi {
            p[axis] = hi;
            if v[axis] > 0.0 {
                v[axis] = -v[axis] * bounce(v[axis], world.restitution);
            }
        }
    }
}

/// Uniform grid over the box with cells one diameter (plus margin) wide: a sphere can only touch
/// spheres in its own or the 26 neighbouring cells. Heights above the grid share its top layer
/// (still correct, just coarser there).
struct Grid {
    cells: Cells,
    start: Vec<u32>,
    order: Vec<u32>,
    cell_of: Vec<u32>,
}

/// The grid's geometry: cell size and cell counts along x, y, z.
struct Cells {
    size: f32,
    dims: [usize; 3],
}

impl Cells {
    fn coords(&self, p: Vec3) -> [usize; 3] {
        let c = |x: f32, n: usize| ((x / self.size).floor().max(0.0) as usize).min(n - 1);
        [
            c(p.x, self.dims[0]),
            c(p.y, self.dims[1]),
            c(p.z, self.dims[2]),
        ]
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    fn count(&self) -> usize {
        self.dims.iter().product()
    }
}

impl Grid {
    /// Pairs closer than a diameter plus this margin become contacts for the whole step: the
    /// relaxation moves spheres far less than the margin.
    const MARGIN: f32 = 0.1;

    fn new(world: &World) -> Grid {
        let size = 2.0 * world.radius * (1.0 + Self::MARGIN);
        let along = |extent: f32| ((extent / size).ceil() as usize).max(1);
        Grid {
            cells: Cells {
                size,
                dims: [
                    along(world.extent.x),
                    along(world.extent.y),
                    along(world.extent.z),
                ],
            },
            start: Vec::new(),
            order: Vec::new(),
            cell_of: Vec::new(),
        }
    }

    /// Every pair `(i, j)`, `i < j`, closer than a diameter plus the margin, in a fixed order.
    fn close_pairs(&mut self, position: &[Vec3], pairs: &mut Vec<(u32, u32)>) {
        // Counting sort of the spheres by cell: stable, so each cell lists its spheres in order.
        let cells = &self.cells;
        self.cell_of.clear();
        self.cell_of.extend(
            position
                .iter()
                .map(|&p| cells.index(cells.coords(p)) as u32),
        );
        self.start.clear();
        self.start.resize(cells.count() + 1, 0);
        for &c in &self.cell_of {
            self.start[c as usize + 1] += 1;
        }
        for c in 0..cells.count() {
            self.start[c + 1] += self.start[c];
        }
        let mut fill = self.start.clone();
        self.order.resize(position.len(), 0);
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.order[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }

        pairs.clear();
        let reach = cells.size * cells.size;
        let dims = cells.dims.map(|d| d as isize);
        for (i, &p) in position.iter().enumerate() {
            let [x, y, z] = cells.coords(p).map(|c| c as isize);
            // Each pair once: the sphere's own cell (partners after it) and the 13 neighbours
            // that come after that cell in (z, y, x) order (all partners).
            for (dx, dy, dz) in FORWARD_NEIGHBOURS {
                let (nx, ny, nz) = (x + dx, y + dy, z + dz);
                if !(0..dims[0]).contains(&nx)
                    || !(0..dims[1]).contains(&ny)
                    || !(0..dims[2]).contains(&nz)
                {
                    continue;
                }
                let c = cells.index([nx as usize, ny as usize, nz as usize]);
                let own_cell = (dx, dy, dz) == (0, 0, 0);
                for &j in &self.order[self.start[c] as usize..self.start[c + 1] as usize] {
                    if (!own_cell || j as usize > i)
                        && p.distance_squared(position[j as usize]) < reach
                    {
                        pairs.push((i.min(j as usize) as u32, i.max(j as usize) as u32));
                    }
                }
            }
        }
    }
}

/// The cell itself and the 13 of its 26 neighbours that follow it in (z, y, x) order.
const FORWARD_NEIGHBOURS: [(isize, isize, isize); 14] = [
    (0, 0, 0),
    (1, 0, 0),
    (-1, 1, 0),
    (0, 1, 0),
    (1, 1, 0),
    (-1, -1, 1),
    (0, -1, 1),
    (1, -1, 1),
    (-1, 0, 1),
    (0, 0, 1),
    (1, 0, 1),
    (-1, 1, 1),
    (0, 1, 1),
    (1, 1, 1),
];

#[cfg(test)]
mod tests {
    use super::*;

    const WORLD: World = World {
        radius: 0.5,
        extent: Vec3::new(4.0, 10.0, 4.0),
        restitution: 0.5,
    };

    #[test]
    fn a_dropped_sphere_falls_like_a_stone_and_bounces_lower() {
        let t = simulate(
            &WORLD,
            vec![Vec3::new(2.0, 5.5, 2.0)],
            vec![Vec3::ZERO],
            0.5,
        );
        // Free fall for 0.5 s: y = 5.5 − g·t²/2 to within the Euler step's error (g·t·STEP/2).
        let y = t.positions_at(0.5)[0].y;
        assert!((y - (5.5 - 0.5 * 9.81 * 0.25)).abs() < 0.02, "{y}");
        // After hitting the floor from 5 m the rebound peak is e² = 1/4 of the drop.
        let t = simulate(
            &WORLD,
            vec![Vec3::new(2.0, 5.5, 2.0)],
            vec![Vec3::ZERO],
            2.0,
        );
        let fall_time = (2.0 * 5.0 / 9.81f32).sqrt();
        let peak = t
            .samples
            .iter()
            .enumerate()
            .filter(|(k, _)| *k as f32 * t.sample_dt > fall_time + 0.05)
            .map(|(_, s)| s[0].y)
            .fold(0.0, f32::max);
        assert!((peak - (0.5 + 5.0 * 0.25)).abs() < 0.08, "{peak}");
    }

    #[test]
    fn head_on_collision_exchanges_momentum_with_restitution() {
        // Two overlapping spheres approaching at ±1 m/s: resolve their contact directly.
        let mut p = vec![Vec3::new(1.0, 1.0, 2.0), Vec3::new(1.9, 1.0, 2.0)];
        let mut v = vec![Vec3::X, -Vec3::X];
        resolve_pair(&WORLD, &mut p, &mut v, 0, 1);
        assert!((p[1].x - p[0].x - 1.0).abs() < 1e-6);
        // Relative speed 2 in, e·2 = 1 out; momentum stays zero.
        assert!((v[0].x + 0.5).abs() < 1e-6 && (v[1].x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn grid_finds_exactly_the_close_pairs() {
        let mut grid = Grid::new(&WORLD);
        let position = vec![
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(1.45, 0.5, 0.5), // 0.95 from #0: close
            Vec3::new(3.5, 0.5, 3.5),
            Vec3::new(3.5, 1.55, 3.5), // 1.05 from #2: within the margin
            Vec3::new(0.5, 30.0, 0.5), // far above the grid: clamped to its top, alone
        ];
        let mut pairs = Vec::new();
        grid.close_pairs(&position, &mut pairs);
        pairs.sort();
        assert_eq!(pairs, [(0, 1), (2, 3)]);
    }
}
