//! Uniform grid with one macrocell level, rebuilt from scratch every frame (Wald, Ize, Kensler,
//! Knoll and Parker 2006, "Ray Tracing Animated Scenes using Coherent Grid Traversal": §2.4
//! macrocells, §3 rebuild).
//!
//! - Resolution (§3): about λ·N cubic cells, cell side `cbrt(V / (λN))`. An axis thinner than one
//!   cell (a flat or needle-like scene) gets a single layer and the side is recomputed over the
//!   remaining axes, so a flat scene still gets ≈ λ·N cells instead of a degenerate volume.
//!   The grid box is the scene box grown to a whole number of cubic cells, centred on the scene.
//! - Insertion (§3): each triangle goes into every cell its bounding box overlaps; with `exact`,
//!   only the cells among those that Akenine-Möller's separating-axis test cannot separate from it.
//!   Both use boxes grown by `margin`, so a triangle lying within rounding distance of a cell also
//!   lies in it: a traversal that compares hit distances with cell exit distances in f32 then never
//!   loses a triangle to rounding (see `tracers::grid_dda`).
//! - Memory (§3, "pooled memory"): no per-cell allocation — one pass counts triangles per cell, a
//!   prefix sum turns counts into offsets, a second pass fills one flat array (CSR).
//! - Macrocells (§2.4): a coarser grid of M×M×M blocks of cells, each flagged non-empty when any of
//!   its cells holds a triangle, so traversals can skip empty space M cells at a time.
//! - Local frame: the grid lives in coordinates relative to its own `origin` (the scene box's
//!   centre), so its cells follow the mesh, not the mesh's distance from the world origin: a mesh
//!   at 10⁶ gets the cells it gets at 0. Translating a point (`local`) rounds once, by at most half
//!   an ulp of the local coordinate; for triangle vertices that is 2⁻²⁴ of the local magnitude,
//!   16× below the `margin`, and traversals translate ray origins the same way and widen their
//!   own comparisons by a multiple of the local coordinates they use. Triangle tests stay in
//!   world coordinates (`triangles`), so hits are bit for bit every other tracer's.

use std::time::Instant;

use glam::{DVec3, Vec3};

use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle};
use crate::params::Params;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridConfig {
    /// Cells ≈ λ·N for N triangles (§3: most scenes are fastest around λ = 5).
    pub lambda: f32,
    /// Macrocell side M in cells (§2.4: M = 6 was consistently good).
    pub macro_size: u32,
    /// Insert by exact triangle–box overlap instead of by bounding box (§3 found it does not pay
    /// for its build time; kept to measure that claim).
    pub exact: bool,
}

impl Default for GridConfig {
    fn default() -> Self {
        GridConfig {
            lambda: 5.0,
            macro_size: 6,
            exact: false,
        }
    }
}

impl GridConfig {
    pub const PARAMS: &'static [&'static str] = &["lambda", "macro_size", "exact"];
    /// Largest accepted λ; the cell count is also capped at `Grid::MAX_TARGET_CELLS`.
    pub const MAX_LAMBDA: f32 = 1000.0;

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = GridConfig::default();
        let c = GridConfig {
            lambda: p.get_or("lambda", d.lambda)?,
            macro_size: p.get_or("macro_size", d.macro_size)?,
            exact: p.get_or("exact", d.exact)?,
        };
        // Written so that NaN fails too.
        if !(c.lambda > 0.0 && c.lambda <= Self::MAX_LAMBDA) || c.macro_size == 0 {
            return Err(Error::usage(format!(
                "grid parameters out of range: 0 < lambda ≤ {}, macro_size ≥ 1 (got {c:?})",
                Self::MAX_LAMBDA
            )));
        }
        Ok(c)
    }
}

#[derive(Clone, Debug)]
pub struct Grid {
    /// The grid's own origin, in world coordinates: every other coordinate of the grid (`bounds`,
    /// cell boundaries, insertion boxes, `margin`) is relative to it (module doc, local frame).
    pub origin: Vec3,
    /// The grid's box, relative to `origin`: the scene box padded and grown to whole cubic cells,
    /// so no triangle touches its faces.
    pub bounds: Aabb,
    /// Cells per axis.
    pub res: [u32; 3],
    /// `bounds.extent() / res` per axis (equal on all axes up to rounding: cells are cubes).
    pub cell_size: Vec3,
    pub inv_cell_size: Vec3,
    /// Cell `c` holds `cell_tris[cell_start[c] .. cell_start[c + 1]]`; `len` = cells + 1.
    pub cell_start: Vec<u32>,
    /// Scene triangle ids, ascending within each cell.
    pub cell_tris: Vec<u32>,
    /// Copy of the scene triangles, indexed by scene id.
    pub triangles: Vec<Triangle>,
    /// Macrocells per axis: `ceil(res / macro_size)`.
    pub macro_res: [u32; 3],
    /// Macrocell `(mx, my, mz)` holds a triangle; index `mx + macro_res[0] * (my + macro_res[1] * mz)`.
    pub macro_occupied: Vec<bool>,
    /// How far every insertion box (triangle bounds, and the cell box in the exact test) is grown:
    /// 1/256 of a cell plus 2⁻²⁰ of the largest local coordinate magnitude, far above f32 rounding
    /// in the traversal's distance comparisons and in the translation to the local frame.
    pub margin: f32,
    pub config: GridConfig,
    pub build_seconds: f64,
}

impl Grid {
    /// Cap on the λ·N target, so huge scenes at huge λ stay addressable (2²⁵ cells = 128 MiB of
    /// offsets).
    pub const MAX_TARGET_CELLS: f64 = (1u64 << 25) as f64;

    /// Most triangle references (cell-list entries) a grid of `n` triangles may hold: 64 per
    /// triangle (a well-shaped scene needs 2–5 at λ = 5), at least 2²⁴ and at most 2³¹ (8 GiB).
    pub fn max_references(n: usize) -> u64 {
        (64 * n as u64).clamp(1 << 24, 1 << 31)
    }

    pub fn build(triangles: &[Triangle], config: GridConfig) -> Grid {
        let start = Instant::now();
        let world = triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        // Halves first: the sum of two huge coordinates must not overflow.
        let origin = if world.is_empty() || !world.min.is_finite() || !world.max.is_finite() {
            Vec3::ZERO
        } else {
            world.min * 0.5 + world.max * 0.5
        };
        // Translation is monotone, so the translated box is the box of the translated vertices.
        let scene = if world.is_empty() {
            world
        } else {
            Aabb::new(world.min - origin, world.max - origin)
        };
        // Triangles much larger than a cell (slivers across the scene, a floor under a small
        // object) are inserted into every cell they span; where that would exceed
        // `max_references`, the grid gets coarser (half the cells per axis each time) instead of
        // running out of memory or overflowing the 32-bit cell offsets.
        let mut lambda = config.lambda as f64;
        let mut grid = loop {
            let grid = Grid::empty(triangles, origin, scene, lambda, config);
            let cap = Self::max_references(triangles.len());
            if grid.reference_bound() <= cap || grid.cell_count() == 1 {
                break grid;
            }
            lambda /= 8.0;
        };
        grid.insert_triangles();
        grid.mark_macrocells();
        grid.build_seconds = start.elapsed().as_secs_f64();
        grid
    }

    /// The grid's layout for `lambda` around `scene` (relative to `origin`), with no triangle
    /// inserted yet.
    fn empty(
        triangles: &[Triangle],
        origin: Vec3,
        scene: Aabb,
        lambda: f64,
        config: GridConfig,
    ) -> Grid {
        let (bounds, res) = layout(scene, triangles.len(), lambda);
        let res_v = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let extent = bounds.extent();
        let cell_size = extent / res_v;
        let magnitude = bounds.min.abs().max(bounds.max.abs()).max_element();
        let m = config.macro_size;
        let macro_res = res.map(|r| r.div_ceil(m));
        Grid {
            origin,
            bounds,
            res,
            cell_size,
            inv_cell_size: res_v / extent,
            cell_start: Vec::new(),
            cell_tris: Vec::new(),
            triangles: triangles.to_vec(),
            macro_res,
            macro_occupied: vec![false; (macro_res[0] * macro_res[1] * macro_res[2]) as usize],
            margin: cell_size.max_element() / 256.0 + magnitude * (1.0 / (1u32 << 20) as f32),
            config,
            build_seconds: 0.0,
        }
    }

    /// An upper bound on the cell-list entries insertion makes: each triangle's insertion-box
    /// cell range (exact insertion keeps a subset of it).
    fn reference_bound(&self) -> u64 {
        self.triangles
            .iter()
            .map(|tri| {
                let b = self.insertion_box(tri);
                let (lo, hi) = (self.cell_of(b.min), self.cell_of(b.max));
                (0..3).map(|a| (hi[a] - lo[a] + 1) as u64).product::<u64>()
            })
            .sum()
    }

    pub fn cell_count(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    #[inline(always)]
    pub fn cell_index(&self, x: u32, y: u32, z: u32) -> usize {
        x as usize + self.res[0] as usize * (y as usize + self.res[1] as usize * z as usize)
    }

    #[inline(always)]
    pub fn cell(&self, x: u32, y: u32, z: u32) -> &[u32] {
        let c = self.cell_index(x, y, z);
        &self.cell_tris[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// A world point in the grid's frame: `p − origin`, rounded once (module doc).
    #[inline(always)]
    pub fn local(&self, p: Vec3) -> Vec3 {
        p - self.origin
    }

    /// A world triangle in the grid's frame.
    pub fn local_triangle(&self, tri: &Triangle) -> Triangle {
        let [a, b, c] = tri.v.map(|p| self.local(p));
        Triangle::new(a, b, c)
    }

    /// Local coordinate of the plane between cells `i − 1` and `i` on `axis`. Every cell boundary used
    /// anywhere (insertion, `cell_of`, traversal) is this very f32 expression, so they agree bit
    /// for bit.
    #[inline(always)]
    pub fn boundary(&self, axis: usize, i: u32) -> f32 {
        self.bounds.min[axis] + i as f32 * self.cell_size[axis]
    }

    /// The cell `i` on `axis` with `boundary(i) <= x < boundary(i + 1)` (`x` local), clamped to
    /// the grid.
    #[inline(always)]
    pub fn axis_cell(&self, axis: usize, x: f32) -> u32 {
        let last = self.res[axis] - 1;
        // `as` saturates (NaN → 0); the estimate is then corrected against the exact boundaries.
        let mut i =
            (((x - self.bounds.min[axis]) * self.inv_cell_size[axis]).max(0.0) as u32).min(last);
        while i > 0 && x < self.boundary(axis, i) {
            i -= 1;
        }
        while i < last && x >= self.boundary(axis, i + 1) {
            i += 1;
        }
        i
    }

    /// Cell coordinates of a local point, clamped to the grid.
    pub fn cell_of(&self, p: Vec3) -> [u32; 3] {
        [
            self.axis_cell(0, p.x),
            self.axis_cell(1, p.y),
            self.axis_cell(2, p.z),
        ]
    }

    /// The local box of cell `(x, y, z)`, from `boundary`.
    pub fn cell_bounds(&self, x: u32, y: u32, z: u32) -> Aabb {
        Aabb::new(
            Vec3::new(
                self.boundary(0, x),
                self.boundary(1, y),
                self.boundary(2, z),
            ),
            Vec3::new(
                self.boundary(0, x + 1),
                self.boundary(1, y + 1),
                self.boundary(2, z + 1),
            ),
        )
    }

    /// The (world) triangle's local bounding box grown by `margin`: bounding-box insertion puts
    /// the triangle in exactly the cells from `cell_of(min)` to `cell_of(max)`.
    pub fn insertion_box(&self, tri: &Triangle) -> Aabb {
        let b = tri.bounds();
        Aabb::new(
            self.local(b.min) - self.margin,
            self.local(b.max) + self.margin,
        )
    }

    #[inline(always)]
    pub fn macro_index(&self, mx: u32, my: u32, mz: u32) -> usize {
        mx as usize
            + self.macro_res[0] as usize * (my as usize + self.macro_res[1] as usize * mz as usize)
    }

    #[inline(always)]
    pub fn macro_is_empty(&self, mx: u32, my: u32, mz: u32) -> bool {
        !self.macro_occupied[self.macro_index(mx, my, mz)]
    }

    /// Calls `f` with the index of every cell triangle `tri` is inserted into.
    fn for_each_cell(&self, tri: &Triangle, mut f: impl FnMut(usize)) {
        let b = self.insertion_box(tri);
        let (lo, hi) = (self.cell_of(b.min), self.cell_of(b.max));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    if !self.config.exact || self.overlaps_exactly(tri, x, y, z) {
                        f(self.cell_index(x, y, z));
                    }
                }
            }
        }
    }

    /// Exact insertion's test: the triangle against the cell's box grown by `margin`.
    fn overlaps_exactly(&self, tri: &Triangle, x: u32, y: u32, z: u32) -> bool {
        let c = self.cell_bounds(x, y, z);
        triangle_overlaps_box(
            &self.local_triangle(tri),
            c.min - self.margin,
            c.max + self.margin,
        )
    }

    /// Two passes over the triangles into the CSR arrays: count per cell, turn counts into end
    /// offsets, then fill backwards (decrementing each end) so each cell ends up ascending by id
    /// and `cell_start[c]` ends at the cell's first slot — no cursor array, no per-cell allocation.
    fn insert_triangles(&mut self) {
        let cells = self.cell_count();
        let mut start = vec![0u32; cells + 1];
        for tri in &self.triangles {
            self.for_each_cell(tri, |c| start[c] += 1);
        }
        let mut total = 0u32;
        for s in start.iter_mut() {
            total += *s;
            *s = total;
        }
        let mut tris = vec![0u32; total as usize];
        for (id, tri) in self.triangles.iter().enumerate().rev() {
            self.for_each_cell(tri, |c| {
                start[c] -= 1;
                tris[start[c] as usize] = id as u32;
            });
        }
        self.cell_start = start;
        self.cell_tris = tris;
    }

    fn mark_macrocells(&mut self) {
        let m = self.config.macro_size;
        for z in 0..self.res[2] {
            for y in 0..self.res[1] {
                for x in 0..self.res[0] {
                    let c = self.cell_index(x, y, z);
                    if self.cell_start[c] != self.cell_start[c + 1] {
                        let i = self.macro_index(x / m, y / m, z / m);
                        self.macro_occupied[i] = true;
                    }
                }
            }
        }
    }
}

/// The grid box and resolution for `n` triangles in `scene` (§3), both in the grid's local frame.
/// Works in f64 so the cell side of tiny or huge scenes does not round away.
fn layout(scene: Aabb, n: usize, lambda: f64) -> (Aabb, [u32; 3]) {
    if scene.is_empty() {
        return (Aabb::new(Vec3::ZERO, Vec3::ONE), [1, 1, 1]);
    }
    let magnitude = scene.min.abs().max(scene.max.abs()).max_element() as f64;
    let e = scene.extent().as_dvec3();
    // Padding keeps every vertex strictly inside, whatever rounding does to the faces; a scene
    // that is a single point at the origin gets a unit box.
    let mut pad = (e.max_element() / 4096.0).max(magnitude / (1u64 << 20) as f64);
    if pad == 0.0 {
        pad = 0.5;
    }
    let padded = e + 2.0 * pad;
    let target = (lambda * n as f64).clamp(1.0, Grid::MAX_TARGET_CELLS);
    let mut active = [true; 3];
    let side = loop {
        let k = active.iter().filter(|&&a| a).count();
        let volume: f64 = (0..3).filter(|&a| active[a]).map(|a| padded[a]).product();
        let side = (volume / target).powf(1.0 / k as f64);
        // An axis thinner than a cell gets one layer; the side is recomputed over the others.
        let thin: Vec<usize> = (0..3).filter(|&a| active[a] && padded[a] < side).collect();
        if thin.is_empty() || thin.len() == k {
            break side;
        }
        for a in thin {
            active[a] = false;
        }
    };
    // Far from the grid's origin a cell must stay well above the coordinates' f32 spacing, which
    // sets the insertion margin (2⁻²⁰ of the magnitude): with cells at 2⁻¹⁶ of it or more, the
    // margin adds at most 1/16 cell to each side of a triangle's box. In the local frame the
    // magnitude is about half the scene's extent, so this only binds for scenes of many cells
    // along one axis: a mesh far from the world origin no longer coarsens its grid (it did
    // before the local frame: a 0.15-unit mesh at 10⁵ got cells ten times its size).
    let side = side.max(magnitude * f64::powi(2.0, -16));
    let res = [0, 1, 2].map(|a| ((padded[a] / side).ceil() as u32).max(1));
    let half = DVec3::new(res[0] as f64, res[1] as f64, res[2] as f64) * side * 0.5;
    let centre = scene.center().as_dvec3();
    (
        Aabb::new((centre - half).as_vec3(), (centre + half).as_vec3()),
        res,
    )
}

/// Akenine-Möller's separating-axis test (JGT 2001, "Fast 3D Triangle-Box Overlap Testing"): the
/// triangle and the box `[lo, hi]` are disjoint iff one of 13 axes separates them — the 3 box
/// normals, the triangle normal, and the 9 cross products of box axes with triangle edges. In f64
/// so rounding stays far below the `margin` the caller grows the box by. Degenerate triangles give
/// zero axes, which separate nothing: conservative.
pub fn triangle_overlaps_box(tri: &Triangle, lo: Vec3, hi: Vec3) -> bool {
    let c = (lo.as_dvec3() + hi.as_dvec3()) * 0.5;
    let h = (hi.as_dvec3() - lo.as_dvec3()) * 0.5;
    let v = tri.v.map(|p| p.as_dvec3() - c);
    let separated = |axis: DVec3| {
        let p = v.map(|q| axis.dot(q));
        let r = h.dot(axis.abs());
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    for e in edges {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            if separated(axis.cross(e)) {
                return false;
            }
        }
    }
    if [DVec3::X, DVec3::Y, DVec3::Z].into_iter().any(separated) {
        return false;
    }
    !separated(edges[0].cross(edges[1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix64;

    /// `n` triangles with centres in [-1, 1]³: mostly small, some long and skinny across the box,
    /// and every tenth degenerate (collinear or a point).
    fn soup(n: usize, seed: u64) -> Vec<Triangle> {
        let mut rng = SplitMix64::new(seed);
        (0..n)
            .map(|i| {
                let c = rng.vec3(-1.0, 1.0);
                match i % 10 {
                    0 => {
                        let d = rng.vec3(-0.3, 0.3);
                        Triangle::new(c, c + d, c + 2.0 * d)
                    }
                    1 => Triangle::new(c, c, c),
                    2 | 3 => {
                        let d = rng.vec3(-1.0, 1.0);
                        Triangle::new(c - d, c + d, c + d + rng.vec3(-0.02, 0.02))
                    }
                    _ => Triangle::new(
                        c + rng.vec3(-0.1, 0.1),
                        c + rng.vec3(-0.1, 0.1),
                        c + rng.vec3(-0.1, 0.1),
                    ),
                }
            })
            .collect()
    }

    fn config(lambda: f32, macro_size: u32, exact: bool) -> GridConfig {
        GridConfig {
            lambda,
            macro_size,
            exact,
        }
    }

    fn cells(g: &Grid) -> impl Iterator<Item = [u32; 3]> + '_ {
        (0..g.res[2]).flat_map(move |z| {
            (0..g.res[1]).flat_map(move |y| (0..g.res[0]).map(move |x| [x, y, z]))
        })
    }

    fn assert_csr(g: &Grid, n: usize) {
        assert_eq!(g.cell_start.len(), g.cell_count() + 1);
        assert_eq!(g.cell_start[0], 0);
        assert_eq!(*g.cell_start.last().unwrap() as usize, g.cell_tris.len());
        assert!(g.cell_start.windows(2).all(|w| w[0] <= w[1]));
        for [x, y, z] in cells(g) {
            let c = g.cell(x, y, z);
            assert!(c.windows(2).all(|w| w[0] < w[1]), "cell {x},{y},{z}: {c:?}");
            assert!(c.iter().all(|&id| (id as usize) < n));
        }
    }

    /// Half-open cells `[boundary(i), boundary(i + 1))`, the outermost ones reaching to infinity:
    /// a box overlaps cell `i` on an axis iff it starts before the cell's end and ends at or after
    /// its start.
    fn box_overlaps_cell(g: &Grid, b: &Aabb, cell: [u32; 3]) -> bool {
        (0..3).all(|a| {
            let i = cell[a];
            let starts_before_end = i + 1 == g.res[a] || b.min[a] < g.boundary(a, i + 1);
            let ends_after_start = i == 0 || b.max[a] >= g.boundary(a, i);
            starts_before_end && ends_after_start
        })
    }

    #[test]
    fn bbox_insertion_is_exactly_the_overlapped_cells() {
        let tris = soup(300, 1);
        for lambda in [0.5, 2.0, 5.0, 20.0] {
            let g = Grid::build(&tris, config(lambda, 6, false));
            assert_csr(&g, tris.len());
            let boxes: Vec<Aabb> = tris.iter().map(|t| g.insertion_box(t)).collect();
            for cell in cells(&g) {
                let want: Vec<u32> = (0..tris.len() as u32)
                    .filter(|&i| box_overlaps_cell(&g, &boxes[i as usize], cell))
                    .collect();
                assert_eq!(
                    g.cell(cell[0], cell[1], cell[2]),
                    want,
                    "λ {lambda}, cell {cell:?}"
                );
            }
        }
    }

    #[test]
    fn exact_insertion_covers_the_triangle_and_nothing_outside_its_box() {
        let tris = soup(300, 2);
        for lambda in [1.0, 5.0, 20.0] {
            let bbox = Grid::build(&tris, config(lambda, 6, false));
            let exact = Grid::build(&tris, config(lambda, 6, true));
            assert_csr(&exact, tris.len());
            assert_eq!((exact.res, exact.bounds), (bbox.res, bbox.bounds));
            let cells_of = |g: &Grid, id: u32| -> Vec<[u32; 3]> {
                cells(g)
                    .filter(|c| g.cell(c[0], c[1], c[2]).contains(&id))
                    .collect()
            };
            for (id, t) in tris.iter().enumerate() {
                let (e, b) = (cells_of(&exact, id as u32), cells_of(&bbox, id as u32));
                assert!(e.iter().all(|c| b.contains(c)), "λ {lambda} tri {id}");
                // Dense barycentric samples of the triangle land only in its cells.
                for i in 0..=40 {
                    for j in 0..=40 - i {
                        let p = t.point(i as f32 / 40.0, j as f32 / 40.0);
                        let c = exact.cell_of(exact.local(p));
                        assert!(e.contains(&c), "λ {lambda} tri {id}: {p:?} in {c:?}");
                    }
                }
            }
            // The long diagonal triangles make box insertion clearly wasteful.
            assert!(
                (exact.cell_tris.len() as f64) < 0.9 * bbox.cell_tris.len() as f64,
                "λ {lambda}: exact {} vs bbox {}",
                exact.cell_tris.len(),
                bbox.cell_tris.len()
            );
        }
    }

    #[test]
    fn separating_axis_test_on_hand_made_cases() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        // In the plane z = 0.5, the region x + y ≥ 2.5: its bounding box [0.5, 2]² overlaps the
        // unit box, but the edge (2, 0.5)–(0.5, 2) separates it (a cross-product axis).
        let corner = Triangle::new(
            Vec3::new(2.0, 0.5, 0.5),
            Vec3::new(0.5, 2.0, 0.5),
            Vec3::new(2.0, 2.0, 0.5),
        );
        assert!(!triangle_overlaps_box(&corner, lo, hi));
        // The same triangle reaching x + y ≥ 1.5 does overlap.
        let reaching = Triangle::new(
            Vec3::new(1.5, 0.0, 0.5),
            Vec3::new(0.0, 1.5, 0.5),
            Vec3::new(2.0, 2.0, 0.5),
        );
        assert!(triangle_overlaps_box(&reaching, lo, hi));
        // A large triangle whose plane x + y + z = 3.5 misses the box (max of x + y + z is 3).
        let plane = Triangle::new(
            Vec3::new(3.5, 0.0, 0.0),
            Vec3::new(0.0, 3.5, 0.0),
            Vec3::new(0.0, 0.0, 3.5),
        );
        assert!(!triangle_overlaps_box(&plane, lo, hi));
        // x + y + z = 2.5 cuts it.
        let cut = Triangle::new(
            Vec3::new(2.5, 0.0, 0.0),
            Vec3::new(0.0, 2.5, 0.0),
            Vec3::new(0.0, 0.0, 2.5),
        );
        assert!(triangle_overlaps_box(&cut, lo, hi));
        // Degenerate: a point inside overlaps, a point outside does not.
        let p = Vec3::splat(0.5);
        assert!(triangle_overlaps_box(&Triangle::new(p, p, p), lo, hi));
        let q = Vec3::new(0.5, 0.5, 1.5);
        assert!(!triangle_overlaps_box(&Triangle::new(q, q, q), lo, hi));
    }

    #[test]
    fn hand_worked_two_triangle_grid() {
        // Scene box [0,2]×[0,1]×[0,1], padded by 2/4096 per side; λ·N = 8 cells:
        // side = cbrt(2.000977 · 1.000977² / 8) = 0.63048 → res = ceil(3.17, 1.59, 1.59) = [4, 2, 2].
        // Local origin: the box centre (1, 0.5, 0.5). x boundaries: -0.261, 0.370, 1.001, 1.631,
        // 2.262; y and z: -0.130, 0.5, 1.130 (world; local ones are these minus the origin).
        let a = Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::new(0.0, 0.3, 0.2),
        );
        let b = Triangle::new(
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(2.0, 0.8, 0.9),
        );
        let g = Grid::build(&[a, b], config(4.0, 2, false));
        assert_eq!(g.res, [4, 2, 2]);
        assert!((g.cell_size.x - 0.63048).abs() < 1e-4);
        assert_eq!(g.origin, Vec3::new(1.0, 0.5, 0.5));
        assert!((g.boundary(0, 0) + 1.26096).abs() < 1e-4);
        assert!(g.boundary(1, 1).abs() < 1e-4);
        assert_eq!(g.cell(0, 0, 0), &[0]);
        for x in 0..4 {
            assert_eq!(g.cell(x, 1, 1), &[1], "cell {x},1,1");
        }
        assert_eq!(g.cell_tris.len(), 5);
        assert_eq!(g.macro_res, [2, 1, 1]);
        assert_eq!(g.macro_occupied, vec![true, true]);
        assert_eq!(g.cell_of(g.local(Vec3::new(1.2, 0.9, 0.1))), [2, 1, 0]);
        assert_eq!(g.cell_of(Vec3::splat(-100.0)), [0, 0, 0]);
        assert_eq!(g.cell_of(Vec3::splat(100.0)), [3, 1, 1]);
    }

    #[test]
    fn resolution_follows_lambda_n_with_cubic_cells() {
        let n = 300;
        let tris = soup(n, 3);
        let scene = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        for lambda in [0.5, 1.0, 5.0, 20.0] {
            let g = Grid::build(&tris, config(lambda, 6, false));
            let target = lambda as f64 * n as f64;
            let cells = g.cell_count() as f64;
            // res = ceil(padded extent / side) per axis, with side³ · λN = padded volume.
            let below: f64 = g.res.iter().map(|&r| (r - 1) as f64).product();
            assert!(cells >= target && below < target, "λ {lambda}: {:?}", g.res);
            let s = g.cell_size.x;
            assert!(
                (g.cell_size - Vec3::splat(s)).abs().max_element() <= 1e-5 * s,
                "not cubic: {:?}",
                g.cell_size
            );
            let (lo, hi) = (g.local(scene.min), g.local(scene.max));
            assert!(g.bounds.min.cmplt(lo).all() && g.bounds.max.cmpgt(hi).all());
        }
    }

    #[test]
    fn flat_and_needle_scenes_get_lambda_n_cells_in_their_dimensions() {
        let mut rng = SplitMix64::new(4);
        // 200 triangles in the plane z = 3.
        let flat: Vec<Triangle> = (0..200)
            .map(|_| {
                let mut p = [0.0; 3].map(|_| rng.vec3(-1.0, 1.0));
                for q in &mut p {
                    q.z = 3.0;
                }
                Triangle { v: p }
            })
            .collect();
        let g = Grid::build(&flat, config(5.0, 6, false));
        assert_eq!(g.res[2], 1);
        let (x, y) = (g.res[0] as f64, g.res[1] as f64);
        assert!(
            x * y >= 1000.0 && (x - 1.0) * (y - 1.0) < 1000.0,
            "{:?}",
            g.res
        );
        let s = g.cell_size.x;
        assert!((g.cell_size - Vec3::splat(s)).abs().max_element() <= 1e-5 * s);
        assert_csr(&g, flat.len());
        assert!(g.cell_tris.len() >= flat.len());

        // 50 degenerate triangles along the x axis: one row of λ·N cells.
        let needle: Vec<Triangle> = (0..50)
            .map(|i| {
                let x = i as f32 * 0.1;
                Triangle::new(Vec3::X * x, Vec3::X * (x + 0.05), Vec3::X * (x + 0.1))
            })
            .collect();
        let g = Grid::build(&needle, config(5.0, 6, false));
        assert_eq!((g.res[1], g.res[2]), (1, 1));
        // ceil(250 · (1 ± rounding)) may give 251.
        assert!((250..=251).contains(&g.res[0]), "{:?}", g.res);
        assert_csr(&g, needle.len());

        // Every vertex at one point.
        let p = Vec3::new(7.0, -2.0, 1.0);
        let point = vec![Triangle::new(p, p, p); 3];
        let g = Grid::build(&point, config(5.0, 6, false));
        assert_eq!(g.origin, p);
        let [x, y, z] = g.cell_of(g.local(p));
        assert_eq!(g.cell(x, y, z), &[0, 1, 2]);
        assert!(g.bounds.min.cmplt(Vec3::ZERO).all() && g.bounds.max.cmpgt(Vec3::ZERO).all());
    }

    #[test]
    fn empty_mesh_gives_a_valid_empty_grid() {
        let g = Grid::build(&[], GridConfig::default());
        assert_eq!(g.res, [1, 1, 1]);
        assert_eq!(g.cell_start, vec![0, 0]);
        assert!(g.cell_tris.is_empty() && g.triangles.is_empty());
        assert_eq!(g.macro_res, [1, 1, 1]);
        assert!(g.macro_is_empty(0, 0, 0));
        assert_eq!(g.cell(0, 0, 0), &[] as &[u32]);
    }

    #[test]
    fn macrocells_are_occupied_exactly_when_a_cell_inside_is() {
        // Small triangles in two clusters at opposite corners: most macrocells are empty.
        let tris: Vec<Triangle> = soup(200, 5)
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % 10 >= 4)
            .map(|(i, t)| {
                let corner = if i % 2 == 0 { -0.7 } else { 0.7 };
                Triangle {
                    v: t.v.map(|p| p * 0.25 + Vec3::splat(corner)),
                }
            })
            .collect();
        for m in [1, 2, 5, 6, 7] {
            let g = Grid::build(&tris, config(20.0, m, false));
            assert_eq!(g.macro_res, g.res.map(|r| r.div_ceil(m)));
            assert_eq!(
                g.macro_occupied.len(),
                g.macro_res.iter().product::<u32>() as usize
            );
            let mut empty = 0;
            for mz in 0..g.macro_res[2] {
                for my in 0..g.macro_res[1] {
                    for mx in 0..g.macro_res[0] {
                        let any = cells(&g).any(|[x, y, z]| {
                            [x / m, y / m, z / m] == [mx, my, mz] && !g.cell(x, y, z).is_empty()
                        });
                        assert_eq!(!g.macro_is_empty(mx, my, mz), any, "M {m} ({mx},{my},{mz})");
                        empty += usize::from(!any);
                    }
                }
            }
            assert!(
                empty > 0,
                "M {m}: a sparse soup at λ 20 has empty macrocells"
            );
        }
    }

    #[test]
    fn config_from_params() {
        assert_eq!(
            GridConfig::from_params(&Params::new()).unwrap(),
            GridConfig::default()
        );
        let p = Params::new()
            .with("lambda", 2.5)
            .with("macro_size", 4)
            .with("exact", true);
        assert_eq!(GridConfig::from_params(&p).unwrap(), config(2.5, 4, true));
        for (k, v) in [
            ("lambda", "0"),
            ("lambda", "-1"),
            ("lambda", "NaN"),
            ("lambda", "inf"),
            ("macro_size", "0"),
            ("macro_size", "-2"),
            ("exact", "maybe"),
        ] {
            assert!(
                GridConfig::from_params(&Params::new().with(k, v)).is_err(),
                "{k}={v}"
            );
        }
    }

    /// Regression (issues 14 and 30): the 69K-triangle, 0.15-unit bunny moved 10⁵ from the origin
    /// first overflowed the reference count (cells below the insertion margin), then got cells ten
    /// times its size (at least 2⁻¹⁶ of the world magnitude), so every ray tested every triangle.
    /// In the local frame the grid of a mesh moved by 10⁵ or 10⁶ is the grid at the origin, cell
    /// for cell: the sphere's vertices are multiples of 1/16, which every offset keeps exact.
    #[test]
    fn a_mesh_far_from_the_origin_gets_the_cells_it_gets_at_the_origin() {
        use crate::scene::tessellate::Surface;
        let snap = |p: Vec3| (p * 8.0 * 16.0).round() / 16.0;
        let at = |offset: f32| {
            let tris = Surface::uv_sphere(256, 136)
                .triangles(|p| snap(p) + Vec3::new(offset, -offset, offset));
            (Grid::build(&tris, GridConfig::default()), tris)
        };
        let (home, tris) = at(0.0);
        assert!(tris.len() > 69_000);
        // About λ·N cells, each holding a handful of triangles.
        assert!(home.cell_count() >= 5 * tris.len(), "{:?}", home.res);
        assert!(home.margin < home.cell_size.min_element() / 8.0);
        for offset in [1e5, 1e6] {
            let (far, far_tris) = at(offset);
            assert_eq!(far.origin - home.origin, Vec3::new(offset, -offset, offset));
            assert_eq!(far.res, home.res, "offset {offset}");
            assert_eq!(far.cell_size, home.cell_size, "offset {offset}");
            assert_eq!(far.margin, home.margin, "offset {offset}");
            assert_eq!(far.cell_start, home.cell_start, "offset {offset}");
            assert_eq!(far.cell_tris, home.cell_tris, "offset {offset}");
            assert_every_triangle_is_in_its_cells(&far, &far_tris);
        }
        // An unsnapped mesh at 10⁵ (rounded by the offset) still gets fine cells.
        let tris =
            Surface::uv_sphere(256, 136).triangles(|p| p * 0.075 + Vec3::new(1e5, -1e5, 1e5));
        let g = Grid::build(&tris, GridConfig::default());
        assert!(g.cell_count() >= 5 * tris.len(), "{:?}", g.res);
        let per_triangle = g.cell_tris.len() as f64 / tris.len() as f64;
        assert!(
            per_triangle <= 8.0,
            "{per_triangle} references per triangle"
        );
        assert_every_triangle_is_in_its_cells(&g, &tris);
    }

    /// Slivers spanning the whole scene would put every triangle in every cell: the grid
    /// coarsens until the references fit `max_references` instead of exhausting memory.
    #[test]
    fn slivers_across_the_scene_coarsen_the_grid_within_the_reference_cap() {
        let mut rng = SplitMix64::new(7);
        let tris: Vec<Triangle> = (0..20_000)
            .map(|_| {
                let a = rng.vec3(-1.0, 1.0);
                Triangle::new(a, -a, -a + rng.vec3(-1e-3, 1e-3))
            })
            .collect();
        let g = Grid::build(&tris, GridConfig::default());
        assert!(g.cell_tris.len() as u64 <= Grid::max_references(tris.len()));
        assert!(g.cell_count() < 20_000 * 5, "coarsened: {:?}", g.res);
        assert_every_triangle_is_in_its_cells(&g, &tris);
    }

    fn assert_every_triangle_is_in_its_cells(g: &Grid, tris: &[Triangle]) {
        for (id, tri) in tris.iter().enumerate() {
            for p in tri.v {
                let [x, y, z] = g.cell_of(g.local(p));
                assert!(
                    g.cell(x, y, z).contains(&(id as u32)),
                    "triangle {id} at {p}"
                );
            }
        }
    }
}
