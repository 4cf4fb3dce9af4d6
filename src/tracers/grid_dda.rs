//! `grid-dda`: single rays through the uniform grid by 3D-DDA (Amanatides & Woo 1987, "A Fast
//! Voxel Traversal Algorithm for Ray Tracing"), skipping empty macrocells (Wald et al. 2006,
//! §2.4): the single-ray baseline that coherent grid traversal is measured against.
//!
//! Per cell, the triangles are tested over the whole remaining `[tmin, closest]` interval and the
//! closest hit is kept even when it lies beyond the cell; the walk stops once the closest hit lies
//! within the cell just visited (t ≤ the cell's exit distance, shrunk by a relative `ACCEPT_SLACK`
//! so rounding never accepts a hit early). A triangle spanning several cells is thus found at its
//! nearest cell, and no nearer triangle in a later cell is skipped. Rounding of exit distances
//! and hit points is covered by the grid's insertion `margin`: a triangle within that distance of
//! a cell is in the cell.
//!
//! The walk runs in the grid's local frame (`Grid::local`): the ray's origin is translated once,
//! rounding by at most 2⁻²⁴ of its local coordinates, far inside the slack `cell_at` leaves
//! (2⁻²⁰ of them). Its triangle tests use the world ray, so its hits are every tracer's:
//! watertight, or with `robust = false` Möller–Trumbore (`geometry::robustness`).
//!
//! Counters: the grid has no depth, so everything is counted at depth 0 — `node(0)` once per cell
//! visited (an empty macrocell skipped at once counts as the one cell where the ray entered it),
//! `triangle_test(0)` per triangle test actually run, `ray()` per ray; the event
//! `MacrocellsSkipped` per empty macrocell jumped over, `MailboxHits` per triangle skipped by the
//! ray's mailbox.
//!
//! Mailboxing (per ray, not the packet mailboxes of CGT): the last `MAILBOX` triangles tested are
//! remembered and skipped when met again in a later cell. Skipping is exact — a retest of the same
//! triangle could only give the hit already recorded — and catches the common case of a triangle
//! spanning the consecutive cells a ray walks through.

use std::marker::PhantomData;
use std::sync::Arc;

use crate::accel::Grid;
use crate::geometry::{Hit, Ray, RayTests, Robust};
use crate::stats::{Event, Stats};
use crate::tracers::kernel::SingleRayKernel;

/// `R`: the triangle test (`robust`): watertight, or Möller–Trumbore.
pub struct GridDdaTracer<R: RayTests = Robust> {
    grid: Arc<Grid>,
    tests: PhantomData<R>,
}

/// A hit is accepted in a cell only if `t <= exit - |exit| · ACCEPT_SLACK`: 2⁻²⁰ relative is
/// several ULPs of the watertight test's and the exit distance's rounding.
const ACCEPT_SLACK: f32 = 1.0 / (1u32 << 20) as f32;

/// Triangles remembered per ray (a power of two: the slot wraps with a mask).
const MAILBOX: usize = 8;

/// The walk of one ray: its cell, and per axis the step direction and the distance at which it
/// crosses into the next cell.
struct Walk<'a> {
    grid: &'a Grid,
    /// `grid.bounds.min` and `grid.cell_size` as arrays: per-axis access by a runtime index
    /// without glam's component match (`crossing` still computes `Grid::boundary` bit for bit).
    grid_min: [f32; 3],
    cell_size: [f32; 3],
    /// The ray's origin in the grid's local frame.
    origin: [f32; 3],
    dir: [f32; 3],
    inv_dir: [f32; 3],
    cell: [u32; 3],
    next: [f32; 3],
}

impl Walk<'_> {
    /// Distance at which the ray crosses the plane between cells `i − 1` and `i` on `axis`.
    #[inline(always)]
    fn crossing(&self, axis: usize, i: u32) -> f32 {
        let boundary = self.grid_min[axis] + i as f32 * self.cell_size[axis];
        (boundary - self.origin[axis]) * self.inv_dir[axis]
    }

    /// Distance at which the ray leaves the current cell on `axis` (∞ if it never moves on it).
    #[inline(always)]
    fn exit_crossing(&self, axis: usize) -> f32 {
        let d = self.dir[axis];
        if d > 0.0 {
            self.crossing(axis, self.cell[axis] + 1)
        } else if d < 0.0 {
            self.crossing(axis, self.cell[axis])
        } else {
            f32::INFINITY
        }
    }

    /// The cell on `axis` holding the ray's point at distance `t`, one cell early when the point
    /// lies within rounding distance of a boundary: starting a cell early only costs a visit,
    /// starting late could skip triangles.
    #[inline(always)]
    fn cell_at(&self, axis: usize, t: f32) -> u32 {
        let (o, d) = (self.origin[axis], self.dir[axis]);
        if d == 0.0 {
            return self.grid.axis_cell(axis, o);
        }
        let p = o + d * t;
        let slack = self.grid.margin + (o.abs() + p.abs()) * ACCEPT_SLACK;
        self.grid
            .axis_cell(axis, if d > 0.0 { p - slack } else { p + slack })
    }

    #[inline(always)]
    fn cell_index(&self) -> usize {
        self.grid
            .cell_index(self.cell[0], self.cell[1], self.cell[2])
    }

    /// The axis along which the ray leaves the current cell first.
    #[inline(always)]
    fn exit_axis(&self) -> usize {
        let n = self.next;
        if n[0] <= n[1] && n[0] <= n[2] {
            0
        } else if n[1] <= n[2] {
            1
        } else {
            2
        }
    }

    /// Moves one cell along `axis`; false when that leaves the grid.
    #[inline(always)]
    fn step(&mut self, axis: usize) -> bool {
        let i = self.cell[axis];
        if self.dir[axis] > 0.0 {
            if i + 1 >= self.grid.res[axis] {
                return false;
            }
            self.cell[axis] = i + 1;
        } else {
            if i == 0 {
                return false;
            }
            self.cell[axis] = i - 1;
        }
        self.next[axis] = self.exit_crossing(axis);
        true
    }

    /// Jumps past the current (empty) macrocell to the cell where the ray leaves it. Returns the
    /// distance of that exit, or `None` when the ray leaves the grid there.
    #[inline(always)]
    fn skip_macrocell(&mut self) -> Option<f32> {
        let g = self.grid;
        let m = g.config.macro_size;
        // Per axis: the macrocell's cell range [first, end) and the ray's exit distance.
        let mut first = [0u32; 3];
        let mut end = [0u32; 3];
        let mut exit = [f32::INFINITY; 3];
        for a in 0..3 {
            first[a] = self.cell[a] / m * m;
            end[a] = (first[a] + m).min(g.res[a]);
            if self.dir[a] > 0.0 {
                exit[a] = self.crossing(a, end[a]);
            } else if self.dir[a] < 0.0 {
                exit[a] = self.crossing(a, first[a]);
            }
        }
        let axis = if exit[0] <= exit[1] && exit[0] <= exit[2] {
            0
        } else if exit[1] <= exit[2] {
            1
        } else {
            2
        };
        let t = exit[axis];
        if t == f32::INFINITY {
            return None;
        }
        for a in 0..3 {
            if a == axis {
                if self.dir[a] > 0.0 {
                    if end[a] >= g.res[a] {
                        return None;
                    }
                    self.cell[a] = end[a];
                } else {
                    if first[a] == 0 {
                        return None;
                    }
                    self.cell[a] = first[a] - 1;
                }
            } else {
                // Still inside this macrocell's slab on the other axes (up to rounding).
                self.cell[a] = self.cell_at(a, t).clamp(first[a], end[a] - 1);
            }
        }
        for a in 0..3 {
            self.next[a] = self.exit_crossing(a);
        }
        Some(t)
    }
}

impl GridDdaTracer {
    /// The robust tracer (watertight triangles).
    pub fn new(grid: Arc<Grid>) -> Self {
        Self::with_tests(grid)
    }
}

impl<R: RayTests> GridDdaTracer<R> {
    pub fn with_tests(grid: Arc<Grid>) -> Self {
        GridDdaTracer {
            grid,
            tests: PhantomData,
        }
    }
}

impl<R: RayTests> SingleRayKernel for GridDdaTracer<R> {
    #[inline(always)]
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit {
        if S::ENABLED {
            stats.ray();
        }
        walk::<R, S, ANY>(&self.grid, ray, stats)
    }
}

/// `ray` through grid `g` with the triangle tests `R`, without counting the ray: `trace`, and
/// what tracers that hand single rays to the DDA (`cgt`'s lone rays) run, having counted them.
#[inline(always)]
pub fn walk<R: RayTests, S: Stats, const ANY: bool>(g: &Grid, ray: &Ray, stats: &mut S) -> Hit {
    let mut best = Hit::MISS;
    if g.cell_tris.is_empty() {
        return best;
    }
    let origin = g.local(ray.origin).to_array();
    let dir = ray.dir.to_array();
    let inv_dir = dir.map(|d| 1.0 / d);
    // Clip to the grid box by slabs. The near/far face is picked by the sign bit, so −0.0 acts
    // as negative; an origin on a face plane with a zero component gives 0·∞ = NaN, which
    // f32::max/min ignore (that axis does not restrict the interval).
    let (mut enter, mut leave) = (ray.tmin, ray.tmax);
    for a in 0..3 {
        let (lo, hi) = (g.bounds.min[a], g.bounds.max[a]);
        let (near, far) = if dir[a].is_sign_negative() {
            (hi, lo)
        } else {
            (lo, hi)
        };
        enter = enter.max((near - origin[a]) * inv_dir[a]);
        leave = leave.min((far - origin[a]) * inv_dir[a]);
    }
    // f32::max/min never return NaN unless both sides are NaN, so plain comparisons suffice.
    if enter > leave || enter == f32::INFINITY {
        return best;
    }
    let mut walk = Walk {
        grid: g,
        grid_min: g.bounds.min.to_array(),
        cell_size: g.cell_size.to_array(),
        origin,
        dir,
        inv_dir,
        cell: [0; 3],
        next: [0.0; 3],
    };
    for a in 0..3 {
        walk.cell[a] = walk.cell_at(a, enter);
        walk.next[a] = walk.exit_crossing(a);
    }
    let tris = R::triangle_ray(ray.origin, ray.dir);
    let (tmin, mut tmax) = (ray.tmin, ray.tmax);
    let mut mailbox = [u32::MAX; MAILBOX];
    let mut slot = 0;
    loop {
        if S::ENABLED {
            stats.node(0);
        }
        let c = walk.cell_index();
        let (first, end) = (g.cell_start[c] as usize, g.cell_start[c + 1] as usize);
        if first == end {
            // An empty cell may sit in an empty macrocell: skip all of it at once.
            let m = g.config.macro_size;
            let [x, y, z] = walk.cell;
            if g.macro_is_empty(x / m, y / m, z / m) {
                if S::ENABLED {
                    stats.event(Event::MacrocellsSkipped, 1);
                }
                match walk.skip_macrocell() {
                    Some(t) if t < tmax => continue,
                    _ => return best,
                }
            }
        }
        for &id in &g.cell_tris[first..end] {
            if mailbox.contains(&id) {
                if S::ENABLED {
                    stats.event(Event::MailboxHits, 1);
                }
                continue;
            }
            mailbox[slot] = id;
            slot = (slot + 1) & (MAILBOX - 1);
            if S::ENABLED {
                stats.triangle_test(0);
            }
            if let Some((t, u, v)) = R::intersect(&tris, &g.triangles[id as usize], tmin, tmax) {
                best = Hit { t, prim: id, u, v };
                if ANY {
                    return best;
                }
                tmax = t;
            }
        }
        let axis = walk.exit_axis();
        let exit = walk.next[axis];
        // Done when the closest hit (or the end of the ray) lies within this cell, or the ray
        // never leaves it (a zero direction).
        if tmax <= exit - exit.abs() * ACCEPT_SLACK || exit == f32::INFINITY {
            return best;
        }
        if !walk.step(axis) {
            return best;
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::{Bvh, BvhConfig, GridConfig};
    use crate::geometry::{RayBatch, RayKind, Triangle, WatertightRay};
    use crate::random::SplitMix64;
    use crate::stats::{Counters, NoStats};
    use crate::test_util::Soup;
    use crate::tracers::kernel::Kernel;
    use crate::tracers::reference::ReferenceTracer;

    /// `n` triangles in [-1, 1]³ of spread `size`, every 20th degenerate.
    fn soup(n: usize, size: f32, seed: u64) -> Vec<Triangle> {
        let soup = Soup {
            collinear_every: Some(20),
            ..Soup::unit(size)
        };
        soup.triangles(n, seed)
    }

    /// Rays of five families in turn: from outside towards the soup, from inside in a random
    /// direction, axis-parallel with +0.0 zeros, the same with −0.0 zeros, and near-axis
    /// (a component below f32::EPSILON).
    fn mixed_rays(n: usize, seed: u64) -> RayBatch {
        let mut rng = SplitMix64::new(seed);
        let mut batch = RayBatch::with_capacity(RayKind::Primary, n);
        for i in 0..n {
            let (origin, dir) = match i % 5 {
                0 => {
                    let o = rng.vec3(-1.0, 1.0).normalize_or(Vec3::X) * 3.0;
                    (o, rng.vec3(-0.8, 0.8) - o)
                }
                1 => (rng.vec3(-1.0, 1.0), rng.vec3(-1.0, 1.0)),
                family => {
                    let mut d = rng.vec3(-1.0, 1.0).to_array();
                    let axis = (rng.next_u64() % 3) as usize;
                    if family == 4 {
                        d[axis] = rng.range(-1.0, 1.0) * f32::EPSILON;
                    } else {
                        let zero = if family == 3 { -0.0 } else { 0.0 };
                        d[axis] = zero;
                        if rng.next_u64().is_multiple_of(2) {
                            d[(axis + 1) % 3] = zero;
                        }
                    }
                    (rng.vec3(-1.2, 1.2), Vec3::from_array(d))
                }
            };
            batch.push(Ray::new(origin, dir, 0.0, f32::INFINITY), i as u32);
        }
        batch
    }

    fn trace_all<S: Stats>(
        tracer: &impl Kernel,
        rays: &RayBatch,
        stats: &mut S,
    ) -> (Vec<Hit>, Vec<bool>) {
        let mut hits = vec![Hit::MISS; rays.len()];
        let mut occluded = vec![false; rays.len()];
        tracer.intersect_with(rays.view(), &mut hits, stats);
        tracer.occluded_with(rays.view(), &mut occluded, stats);
        (hits, occluded)
    }

    /// Ray by ray against the reference tracer: the same triangle at a distance within 1e-5
    /// relative (both run the same triangle test, so in practice the same bits), or a tie — a
    /// different triangle that the reference's test also hits at exactly the same distance — and
    /// the same occlusion answer. Returns (hits, ties).
    fn assert_agrees(
        triangles: &[Triangle],
        config: GridConfig,
        rays: &RayBatch,
    ) -> (usize, usize) {
        let reference = ReferenceTracer::new(Arc::new(Bvh::build(triangles, BvhConfig::default())));
        let dda = GridDdaTracer::new(Arc::new(Grid::build(triangles, config)));
        let (want, want_occluded) = trace_all(&reference, rays, &mut NoStats);
        let (got, got_occluded) = trace_all(&dda, rays, &mut NoStats);
        let (mut hits, mut ties) = (0, 0);
        for i in 0..rays.len() {
            let (w, g, ray) = (want[i], got[i], rays.ray(i));
            assert_eq!(
                got_occluded[i], want_occluded[i],
                "{config:?} ray {i} {ray:?}: occlusion"
            );
            if w.prim == g.prim {
                if w.is_hit() {
                    assert!(
                        (g.t - w.t).abs() <= 1e-5 * w.t,
                        "{config:?} ray {i}: {g:?} vs {w:?}"
                    );
                    hits += 1;
                }
            } else {
                assert!(
                    w.is_hit() && g.is_hit() && g.t == w.t,
                    "{config:?} ray {i} {ray:?}: want {w:?}, got {g:?}"
                );
                let other = WatertightRay::new(ray.origin, ray.dir).intersect(
                    &triangles[g.prim as usize],
                    ray.tmin,
                    ray.tmax,
                );
                assert_eq!(other.map(|h| h.0), Some(w.t), "ray {i}: not a tie");
                ties += 1;
            }
        }
        (hits, ties)
    }

    fn configs() -> Vec<GridConfig> {
        let mut all = vec![];
        for lambda in [0.5, 5.0, 20.0] {
            for macro_size in [1, 6] {
                for exact in [false, true] {
                    all.push(GridConfig {
                        lambda,
                        macro_size,
                        exact,
                    });
                }
            }
        }
        all
    }

    #[test]
    fn random_soup_matches_reference_ray_by_ray() {
        let triangles = soup(3000, 0.1, 1);
        let mut rays = mixed_rays(5000, 2);
        for config in configs() {
            let (hits, ties) = assert_agrees(&triangles, config, &rays);
            assert!(
                hits >= 1000 && ties <= 2,
                "{config:?}: {hits} hits, {ties} ties"
            );
        }
        // Cut tmax halfway to the closest hit on even rays (they must now miss) and raise tmin past
        // it on odd ones (the next triangle along must be found).
        let reference =
            ReferenceTracer::new(Arc::new(Bvh::build(&triangles, BvhConfig::default())));
        let (first, _) = trace_all(&reference, &rays, &mut NoStats);
        for (i, hit) in first.iter().enumerate().filter(|(_, h)| h.is_hit()) {
            if i % 2 == 0 {
                rays.tmax[i] = hit.t * 0.5;
            } else {
                rays.tmin[i] = hit.t * 1.0001;
            }
        }
        for config in configs() {
            let (hits, _) = assert_agrees(&triangles, config, &rays);
            assert!(hits >= 300, "{config:?}: {hits} hits past the first");
        }
    }

    #[test]
    fn sparse_scene_agrees_and_macrocells_save_visits_not_tests() {
        // Three small clusters at corners of the box: macrocells have space to skip.
        let mut triangles = soup(600, 0.5, 3);
        for (i, t) in triangles.iter_mut().enumerate() {
            let shift = [
                Vec3::splat(-0.8),
                Vec3::new(0.8, 0.8, 0.0),
                Vec3::new(0.0, -0.8, 0.8),
            ][i % 3];
            t.v = t.v.map(|p| p * 0.3 + shift);
        }
        let rays = mixed_rays(4000, 4);
        let mut counted = vec![];
        for macro_size in [1, 3, 6] {
            let config = GridConfig {
                macro_size,
                ..GridConfig::default()
            };
            assert_agrees(&triangles, config, &rays);
            let dda = GridDdaTracer::new(Arc::new(Grid::build(&triangles, config)));
            let mut c = Counters::default();
            let (hits, _) = trace_all(&dda, &rays, &mut c);
            counted.push((c, hits));
        }
        let (one, hits_one) = &counted[0];
        assert_eq!(one.rays, 2 * rays.len() as u64);
        let hit_count = hits_one.iter().filter(|h| h.is_hit()).count();
        println!("{hit_count} hits; M=1 {one:?}");
        assert!(hit_count >= 200);
        assert!(one.triangle_tests > 0 && one.aabb_tests == 0);
        assert_eq!(one.triangle_by_depth, vec![one.triangle_tests]);
        for (c, hits) in &counted[1..] {
            assert_eq!(hits, hits_one);
            assert!(c.nodes_visited < one.nodes_visited, "{c:?} vs {one:?}");
            let d = c.triangle_tests.abs_diff(one.triangle_tests) as f64;
            assert!(d <= 0.01 * one.triangle_tests as f64, "{c:?} vs {one:?}");
        }
    }

    #[test]
    fn hand_made_hits_and_counts() {
        // A unit square of two triangles in the plane z = 0.5 and nothing else.
        let triangles = [
            Triangle::new(
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(1.0, 0.0, 0.5),
                Vec3::new(1.0, 1.0, 0.5),
            ),
            Triangle::new(
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(1.0, 1.0, 0.5),
                Vec3::new(0.0, 1.0, 0.5),
            ),
        ];
        let dda = GridDdaTracer::new(Arc::new(Grid::build(&triangles, GridConfig::default())));
        let trace = |o: Vec3, d: Vec3, tmin: f32, tmax: f32| {
            let mut batch = RayBatch::new(RayKind::Primary);
            batch.push(Ray::new(o, d, tmin, tmax), 0);
            let mut c = Counters::default();
            let (h, occ) = trace_all(&dda, &batch, &mut c);
            (h[0], occ[0], c)
        };
        // Straight down onto (0.75, 0.25): triangle 0 at t = 4.5, from far outside the grid.
        let (h, occ, c) = trace(
            Vec3::new(0.75, 0.25, 5.0),
            Vec3::new(0.0, -0.0, -1.0),
            0.0,
            f32::INFINITY,
        );
        assert_eq!((h.prim, occ), (0, true));
        assert!((h.t - 4.5).abs() < 1e-6, "{h:?}");
        assert_eq!(c.rays, 2);
        // Upwards from below, origin inside the grid (a flat scene: one layer of cells, 0.316
        // thick, around z = 0.5): triangle 1 at t = 0.125.
        let (h, _, _) = trace(
            Vec3::new(0.25, 0.75, 0.375),
            Vec3::new(-0.0, 0.0, 1.0),
            0.0,
            f32::INFINITY,
        );
        assert_eq!(h.prim, 1);
        assert!((h.t - 0.125).abs() < 1e-6, "{h:?}");
        // The range stops short of the plane, or starts past it.
        for (tmin, tmax) in [(0.0, 0.1), (0.15, f32::INFINITY)] {
            let (h, occ, _) = trace(Vec3::new(0.25, 0.75, 0.375), Vec3::Z, tmin, tmax);
            assert!(!h.is_hit() && !occ, "[{tmin}, {tmax}]");
        }
        // Parallel to the plane (never crosses z = 0.5), and a zero direction: no hit, no hang.
        let (h, _, _) = trace(Vec3::new(-1.0, 0.5, 0.375), Vec3::X, 0.0, f32::INFINITY);
        assert!(!h.is_hit());
        let (h, _, c) = trace(Vec3::new(0.5, 0.5, 0.375), Vec3::ZERO, 0.0, f32::INFINITY);
        assert!(!h.is_hit());
        assert_eq!(
            (c.rays, c.nodes_visited),
            (2, 0),
            "ill-formed: counted, answered before any cell"
        );
        // Pointing away from the grid: no cell visited.
        let (h, _, c) = trace(Vec3::new(0.5, 0.5, 3.0), Vec3::Z, 0.0, f32::INFINITY);
        assert!(!h.is_hit());
        assert_eq!((c.rays, c.nodes_visited), (2, 0));
        // Empty grid.
        let empty = GridDdaTracer::new(Arc::new(Grid::build(&[], GridConfig::default())));
        let mut batch = RayBatch::new(RayKind::Primary);
        batch.push(Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY), 0);
        let (h, occ) = trace_all(&empty, &batch, &mut NoStats);
        assert!(!h[0].is_hit() && !occ[0]);
    }
}
