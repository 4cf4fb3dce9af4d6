//! The active rays of a packet in SoA lanes, and the watertight ray–triangle test (Woop et al.
//! 2013) over `L` of them at a time: the packet's SIMD triangle test (Wald et al. 2006, §2.3),
//! on the lane layer's kernel (`lanes::watertight`).
//!
//! A specialisation of the lane layer's ray stream for this tracer: the origins are stored in
//! each lane's watertight frame (`kx, ky, kz`), since a packet tests many triangles per load and
//! picking a vertex per lane then subtracting once beats `SimdRay`'s subtract-then-reorder here
//! (see `candidates`); finished rays are dropped with `lanes::stream::compact`.
//!
//! Exactness: each lane reads the triangle's coordinates along its own axes `kx, ky, kz` (rays of
//! one packet may differ in their dominant axis) and runs the scalar test's f32 stage. The lanes
//! only decide which rays *may* hit: a lane passing the edge and distance tests, or one whose edge
//! functions come out exactly zero (where the scalar test recomputes them in f64), is handed to
//! the scalar `WatertightRay::intersect`, which gives the hit. So every hit is bit for bit the
//! scalar test's, and the scalar test runs about once per hit.
//!
//! With `robust = false` the lanes hold the world origins and the directions instead and run
//! Möller–Trumbore (`lanes::moller`), whose lanes are the scalar test's bit for bit, so their
//! hits are final.

use std::marker::PhantomData;

use glam::Vec3;

use crate::geometry::triangle::axis_component;
use crate::geometry::{RayTests, Triangle, WatertightRay};
use crate::lanes::moller::MollerLanes;
use crate::lanes::stream::{compact, SoaRays};
use crate::lanes::watertight::{accept, edge_functions, needs_f64, Permuted};
use crate::lanes::LaneMask;

/// A packet's active rays, one lane slot each; the vectors' length is a multiple of `L`, and the
/// slots from `len` on are padding, masked off.
pub struct LaneRays<const L: usize, R: RayTests> {
    /// The ray's position in the packet.
    pub ray: Vec<u32>,
    /// Origin components along the ray's `kx, ky, kz` (`robust`), or along x, y, z.
    origin: [Vec<f32>; 3],
    axes: [Vec<u32>; 3],
    shear: [Vec<f32>; 3],
    /// The directions: Möller–Trumbore's (`robust = false`) only.
    dir: [Vec<f32>; 3],
    pub tmin: Vec<f32>,
    /// Shrinks to the closest hit so far.
    pub tmax: Vec<f32>,
    /// The march coordinate `s` from which the ray needs no more cells (its segment's end, then
    /// its closest hit; −∞ once an occlusion query has found a hit).
    pub s_limit: Vec<f32>,
    len: usize,
    /// The scalar test of each ray, by packet position (decides the lanes' candidates).
    tests: Vec<WatertightRay>,
    /// The triangle test: watertight (`axes`, `shear`, then `tests`) or Möller–Trumbore (`dir`).
    tests_of: PhantomData<R>,
}

impl<const L: usize, R: RayTests> Default for LaneRays<L, R> {
    fn default() -> Self {
        LaneRays {
            ray: vec![],
            origin: Default::default(),
            axes: Default::default(),
            shear: Default::default(),
            dir: Default::default(),
            tmin: vec![],
            tmax: vec![],
            s_limit: vec![],
            len: 0,
            tests: vec![],
            tests_of: PhantomData,
        }
    }
}

impl<const L: usize, R: RayTests> LaneRays<L, R> {
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Replaces the lanes' rays by the rays of a packet, all active: slot `p` holds the ray at
    /// packet position `p`, its origin and direction components `origin[axis][p]`, `dir[axis][p]`.
    #[inline]
    pub fn load(
        &mut self,
        origin: &[Vec<f32>; 3],
        dir: &[Vec<f32>; 3],
        tmin: &[f32],
        tmax: &[f32],
        s_limit: &[f32],
    ) {
        let n = tmin.len();
        self.len = n;
        self.pad();
        self.tests.clear();
        self.tmin[..n].copy_from_slice(tmin);
        self.tmax[..n].copy_from_slice(tmax);
        self.s_limit[..n].copy_from_slice(&s_limit[..n]);
        if !R::ROBUST {
            for a in 0..3 {
                self.origin[a][..n].copy_from_slice(&origin[a][..n]);
                self.dir[a][..n].copy_from_slice(&dir[a][..n]);
            }
            self.ray[..n].iter_mut().zip(0..).for_each(|(r, p)| *r = p);
            return;
        }
        for p in 0..n {
            let o = [origin[0][p], origin[1][p], origin[2][p]];
            let d = Vec3::new(dir[0][p], dir[1][p], dir[2][p]);
            let test = WatertightRay::new(Vec3::from_array(o), d);
            self.tests.push(test);
            let (_, k, shear) = test.parts();
            self.ray[p] = p as u32;
            for a in 0..3 {
                self.origin[a][p] = axis_component(o, k[a]);
                self.axes[a][p] = k[a] as u32;
                self.shear[a][p] = shear[a];
            }
        }
    }

    /// Whether some active ray's `s_limit` lies below `s` (branch-free, so it vectorizes).
    #[inline]
    pub fn any_s_limit_below(&self, s: f32) -> bool {
        self.s_limit[..self.len]
            .iter()
            .fold(false, |any, &limit| any | (limit < s))
    }

    /// Keeps the rays whose `s_limit` passes `keep`, in their order.
    pub fn retain(&mut self, keep: impl Fn(f32) -> bool) {
        self.len = compact(self, self.len, |lanes, i| keep(lanes.s_limit[i]));
    }

    /// Tests `tri` against every active ray; for each hit in the ray's `[tmin, tmax]`, sets its
    /// `tmax` to the hit distance and calls `on_hit(lanes, slot, t, u, v)`.
    #[inline]
    pub fn intersect(
        &mut self,
        tri: &Triangle,
        mut on_hit: impl FnMut(&mut Self, usize, f32, f32, f32),
    ) {
        if !R::ROBUST {
            return self.intersect_moller(tri, on_hit);
        }
        let v = tri.v.map(|p| p.to_array());
        for base in (0..self.len).step_by(L) {
            let live = LaneMask::first((self.len - base).min(L));
            for lane in (self.candidates(base, &v) & live).iter() {
                let slot = base + lane;
                let test = &self.tests[self.ray[slot] as usize];
                if let Some((t, u, w)) = test.intersect(tri, self.tmin[slot], self.tmax[slot]) {
                    self.tmax[slot] = t;
                    on_hit(self, slot, t, u, w);
                }
            }
        }
    }

    /// `intersect` by Möller–Trumbore: the lanes' verdicts are the scalar test's, so final.
    #[inline]
    fn intersect_moller(
        &mut self,
        tri: &Triangle,
        mut on_hit: impl FnMut(&mut Self, usize, f32, f32, f32),
    ) {
        let moller = MollerLanes::<L>::broadcast(tri);
        for base in (0..self.len).step_by(L) {
            let lanes = |x: &Vec<f32>| -> [f32; L] { x[base..base + L].try_into().unwrap() };
            let origin = [0, 1, 2].map(|a| lanes(&self.origin[a]));
            let dir = [0, 1, 2].map(|a| lanes(&self.dir[a]));
            let (tmin, tmax) = (lanes(&self.tmin), lanes(&self.tmax));
            let hits = moller.intersect(&origin, &dir, &tmin, &tmax);
            let live = LaneMask::first((self.len - base).min(L));
            for lane in (LaneMask::from_bools(&hits.hit) & live).iter() {
                let slot = base + lane;
                self.tmax[slot] = hits.t[lane];
                on_hit(self, slot, hits.t[lane], hits.u[lane], hits.v[lane]);
            }
        }
    }

    /// The lanes of slots `base .. base + L` that may hit the triangle with vertices `v` (bit
    /// `l` for slot `base + l`): the watertight test's f32 stage (`watertight_lanes`), plus the
    /// lanes with a zero or ill-conditioned edge function, which the scalar test settles in f64.
    #[inline(always)]
    fn candidates(&self, base: usize, v: &[[f32; 3]; 3]) -> LaneMask<L> {
        let lanes = |x: &Vec<f32>| -> [f32; L] { x[base..base + L].try_into().unwrap() };
        let origin = [0, 1, 2].map(|a| lanes(&self.origin[a]));
        let shear = [0, 1, 2].map(|a| lanes(&self.shear[a]));
        let axes =
            [0, 1, 2].map(|a| -> [u32; L] { self.axes[a][base..base + L].try_into().unwrap() });
        // Each vertex relative to each lane's origin, along its kx, ky, kz. The origins are stored
        // in the lanes' frames, so a vertex is picked per lane and subtracted once; the packet
        // tracer's `in_lane_frames` (subtract, then reorder, with a common-axes shortcut) was
        // 16–34% slower here (toys and conference, 16×16, 1024², 1 thread).
        let ([kx, ky, kz], [ox, oy, oz]) = (axes, origin);
        let pick = |k: u32, p: &[f32; 3]| axis_component(*p, k as usize);
        let permute = |p: &[f32; 3]| -> Permuted<L> {
            let mut out = [[0.0f32; L]; 3];
            for l in 0..L {
                out[0][l] = pick(kx[l], p) - ox[l];
                out[1][l] = pick(ky[l], p) - oy[l];
                out[2][l] = pick(kz[l], p) - oz[l];
            }
            out
        };
        let (a, b, c) = (permute(&v[0]), permute(&v[1]), permute(&v[2]));
        let (e, scale) = edge_functions(&shear, &a, &b, &c);
        let (tmin, tmax) = (lanes(&self.tmin), lanes(&self.tmax));
        let (hit, _, _) = accept(&e, &shear[2], [&a[2], &b[2], &c[2]], &tmin, &tmax);
        LaneMask::from_bools(&hit) | needs_f64(&e, &scale)
    }

    fn resize(&mut self, n: usize) {
        self.ray.resize(n, 0);
        for a in 0..3 {
            self.origin[a].resize(n, 0.0);
            self.axes[a].resize(n, a as u32);
            self.shear[a].resize(n, 0.0);
            self.dir[a].resize(n, 0.0);
        }
        self.tmin.resize(n, 0.0);
        self.tmax.resize(n, 0.0);
        self.s_limit.resize(n, 0.0);
    }

    /// Sizes the vectors to the fewest whole groups of `L` slots holding `len` (at least one), so
    /// the lane loops never run over groups of padding only.
    fn pad(&mut self) {
        let slots = self.len.div_ceil(L).max(1) * L;
        if self.ray.len() < slots {
            self.resize(slots);
        }
    }
}

impl<const L: usize, R: RayTests> SoaRays for LaneRays<L, R> {
    fn move_ray(&mut self, from: usize, to: usize) {
        self.ray[to] = self.ray[from];
        for a in 0..3 {
            self.origin[a][to] = self.origin[a][from];
            self.axes[a][to] = self.axes[a][from];
            self.shear[a][to] = self.shear[a][from];
            self.dir[a][to] = self.dir[a][from];
        }
        self.tmin[to] = self.tmin[from];
        self.tmax[to] = self.tmax[from];
        self.s_limit[to] = self.s_limit[from];
    }

    fn swap_rays(&mut self, a: usize, b: usize) {
        self.ray.swap(a, b);
        for axis in 0..3 {
            self.origin[axis].swap(a, b);
            self.axes[axis].swap(a, b);
            self.shear[axis].swap(a, b);
            self.dir[axis].swap(a, b);
        }
        self.tmin.swap(a, b);
        self.tmax.swap(a, b);
        self.s_limit.swap(a, b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Fast, Robust};
    use crate::random::SplitMix64;

    /// Every lane width finds exactly the scalar test's hits (`R`: watertight or
    /// Möller–Trumbore), including rays of mixed dominant axes in one group, edge and vertex hits
    /// (exactly zero edge functions) and partial groups.
    fn agrees_with_scalar<R: RayTests, const L: usize>() {
        let mut rng = SplitMix64::new(5);
        let tris: Vec<Triangle> = (0..200)
            .map(|i| {
                if i % 4 == 0 {
                    // Axis-aligned unit right triangles: grid-aligned rays hit edges and vertices.
                    let o = Vec3::new(
                        (rng.vec3(0.0, 4.0).x).floor(),
                        (rng.vec3(0.0, 4.0).y).floor(),
                        2.0,
                    );
                    Triangle::new(o, o + Vec3::X, o + Vec3::Y)
                } else {
                    let c = rng.vec3(0.0, 4.0);
                    Triangle::new(
                        c + rng.vec3(-1.0, 1.0),
                        c + rng.vec3(-1.0, 1.0),
                        c + rng.vec3(-1.0, 1.0),
                    )
                }
            })
            .collect();
        let mut total_hits = 0;
        for n in [1, L - 1, L, 3 * L + 2] {
            let rays: Vec<(Vec3, Vec3)> = (0..n)
                .map(|i| {
                    if i % 3 == 0 {
                        // Straight down onto a grid point or half-point.
                        let p = Vec3::new((i % 9) as f32 * 0.5, (i % 7) as f32 * 0.5, 5.0);
                        (p, -Vec3::Z)
                    } else {
                        (rng.vec3(-1.0, 5.0), rng.vec3(-1.0, 1.0))
                    }
                })
                .collect();
            let scalar: Vec<R::TriangleRay> =
                rays.iter().map(|&(o, d)| R::triangle_ray(o, d)).collect();
            let mut lanes = LaneRays::<L, R>::default();
            let columns = |f: fn(&(Vec3, Vec3)) -> Vec3| {
                [0, 1, 2].map(|a| rays.iter().map(|r| f(r)[a]).collect::<Vec<f32>>())
            };
            let (origin, dir) = (columns(|r| r.0), columns(|r| r.1));
            let (tmin, tmax) = (vec![0.0; n], vec![f32::INFINITY; n]);
            lanes.load(&origin, &dir, &tmin, &tmax, &vec![0.0; n]);
            let mut expected: Vec<Option<(u32, f32, f32, f32)>> = vec![None; n];
            let mut got = expected.clone();
            for (id, tri) in tris.iter().enumerate() {
                for (p, s) in scalar.iter().enumerate() {
                    let tmax = expected[p].map_or(f32::INFINITY, |h| h.1);
                    if let Some((t, u, v)) = R::intersect(s, tri, 0.0, tmax) {
                        expected[p] = Some((id as u32, t, u, v));
                    }
                }
                lanes.intersect(tri, |lanes, slot, t, u, v| {
                    got[lanes.ray[slot] as usize] = Some((id as u32, t, u, v));
                });
            }
            total_hits += expected.iter().flatten().count();
            assert_eq!(got, expected, "L = {L}, n = {n}");
        }
        assert!(total_hits >= 2 * L, "L = {L}: only {total_hits} hits");
    }

    #[test]
    fn lanes_find_exactly_the_scalar_hits() {
        agrees_with_scalar::<Robust, 4>();
        agrees_with_scalar::<Robust, 8>();
        agrees_with_scalar::<Robust, 16>();
        agrees_with_scalar::<Fast, 4>();
        agrees_with_scalar::<Fast, 8>();
        agrees_with_scalar::<Fast, 16>();
    }

    #[test]
    fn retain_keeps_the_matching_rays() {
        let mut lanes = LaneRays::<4, Robust>::default();
        let column = |x: f32| vec![x; 6];
        let (origin, dir) = (
            [column(0.0), column(0.0), column(0.0)],
            [column(0.0), column(0.0), column(1.0)],
        );
        let s_limit: Vec<f32> = (0..6).map(|p| p as f32).collect();
        lanes.load(&origin, &dir, &column(0.0), &column(10.0), &s_limit);
        assert_eq!((lanes.len(), lanes.ray.len()), (6, 8));
        lanes.retain(|s| s >= 3.0);
        assert_eq!(lanes.len(), 3);
        assert_eq!(&lanes.ray[..3], &[3, 4, 5]);
        assert_eq!(lanes.ray.len(), 8, "the slots stay for the next packet");
        lanes.retain(|_| false);
        assert!(lanes.is_empty());
    }
}
