//! The SIMD ray: `L` rays traced in lock step (Overbeck et al. 2008 §2.1: their 2×2 group of rays
//! in one 4-lane register; here 4, 8 or 16 lanes for SSE, AVX2 and AVX-512). Every field is a lane
//! array `[f32; L]` inside a 64-byte aligned struct, and every test is a plain loop over the lanes
//! without branches, which LLVM turns into one vector instruction per operation at the machine's
//! width (`target-cpu=native`).
//!
//! Both tests perform, lane by lane, exactly the floating-point operations of the single-ray
//! tests of the tracer's `robust` switch (`R: RayTests`: `RayBoxTest::hit_with::<R>` and
//! `R::intersect`), so every lane gets bit for bit the answer the reference tracer's ray gets:
//! - slabs: `lanes::slab` (conservative with `Robust`, plain with `Fast`);
//! - triangles, `Robust` (`lanes::watertight`): each lane carries its own watertight frame (`kx,
//!   ky, kz`, shear). When every lane of the group has the same frame (the common case for
//!   coherent rays) the vertices are permuted once per axis; otherwise per lane by selects. Edge
//!   functions that come out exactly zero are redone in f64 for those lanes, as the scalar test
//!   does;
//! - triangles, `Fast` (`lanes::moller`): Möller–Trumbore from each lane's origin and direction.
//!
//! Unused lanes (padding of a packet whose size is not a multiple of `L`) and, in occlusion
//! mode, lanes already occluded have `tmax = −∞`, so no box and no triangle can hit them.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;

use super::moller::MollerLanes;
use super::slab::SlabRays;
use super::watertight::{
    accept, any_may_hit, common_axes, edge_functions, in_lane_frames, needs_f64, redo_edges_in_f64,
    Permuted,
};
use super::{highest, LaneMask};
use crate::geometry::{Hit, Ray, RayTests, Rays, Triangle, WatertightRay};

/// `L` rays, their current closest hits, and what the box and triangle tests precompute.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct SimdRay<const L: usize> {
    pub origin: [[f32; L]; 3],
    /// The directions, which only the Möller–Trumbore test (`Fast`) reads.
    pub dir: [[f32; L]; 3],
    pub inv_dir: [[f32; L]; 3],
    /// 1 where the direction's sign bit is set (−0.0 counts as negative, as in `RayBoxTest`).
    pub negative: [[u32; L]; 3],
    pub tmin: [f32; L],
    /// The segment's end, shortened to the closest hit found so far; −∞ for unused lanes and
    /// for occluded ones.
    pub tmax: [f32; L],
    /// Watertight frame per lane: `[kx, ky, kz]` and the shear (`WatertightRay::frame`).
    pub axes: [[u32; L]; 3],
    pub shear: [[f32; L]; 3],
    /// The frame shared by all lanes, if they share one.
    pub common_axes: Option<[usize; 3]>,
    pub prim: [u32; L],
    pub u: [f32; L],
    pub v: [f32; L],
    /// Each lane's time in the shutter interval (`Ray::time`; motion blur).
    pub time: [f32; L],
    /// Lanes in use (the first `used`; the rest are padding).
    pub used: u32,
}

impl<const L: usize> Default for SimdRay<L> {
    fn default() -> Self {
        SimdRay {
            origin: [[0.0; L]; 3],
            dir: [[1.0; L]; 3],
            inv_dir: [[0.0; L]; 3],
            negative: [[0; L]; 3],
            tmin: [f32::INFINITY; L],
            tmax: [f32::NEG_INFINITY; L],
            axes: [[0; L]; 3],
            shear: [[0.0; L]; 3],
            common_axes: None,
            prim: [Hit::NO_PRIM; L],
            u: [0.0; L],
            v: [0.0; L],
            time: [0.0; L],
            used: 0,
        }
    }
}

impl<const L: usize> SimdRay<L> {
    /// Loads rays `first .. first + used` of `rays` (`used ≤ L`) into the lanes; the rest become
    /// padding. Returns how many lanes hold a well-formed ray. A full group reads the batch's
    /// arrays in place; only a partial one (a batch's last) is first copied into padded lanes.
    pub fn load<R: RayTests>(&mut self, rays: &Rays<'_>, first: usize, used: usize) -> u32 {
        debug_assert!(used <= L);
        self.used = used as u32;
        if used == L {
            // Constant-length views: vector loads straight from the batch.
            let at = |src| lanes_at::<L>(src, first);
            self.time = match rays.time.is_empty() {
                true => [0.0; L],
                false => *at(rays.time),
            };
            self.load_lanes::<R>(
                [at(rays.ox), at(rays.oy), at(rays.oz)],
                [at(rays.dx), at(rays.dy), at(rays.dz)],
                [at(rays.tmin), at(rays.tmax)],
                L,
            )
        } else {
            let padded = |src: &[f32], fill: f32| -> [f32; L] {
                let mut lanes = [fill; L];
                lanes[..used].copy_from_slice(&src[first..first + used]);
                lanes
            };
            self.time = match rays.time.is_empty() {
                true => [0.0; L],
                false => padded(rays.time, 0.0),
            };
            let origin = [rays.ox, rays.oy, rays.oz].map(|s| padded(s, 0.0));
            let dir = [rays.dx, rays.dy, rays.dz].map(|s| padded(s, 1.0));
            let range = [
                padded(rays.tmin, f32::INFINITY),
                padded(rays.tmax, f32::NEG_INFINITY),
            ];
            self.load_lanes::<R>(
                [&origin[0], &origin[1], &origin[2]],
                [&dir[0], &dir[1], &dir[2]],
                [&range[0], &range[1]],
                used,
            )
        }
    }

    /// `load`'s work on `L` lanes of rays (`range`: tmin, tmax; padding lanes come with
    /// tmin = ∞, which no well-formed ray has), the first `used` in use (a constant for full
    /// groups). One branch-free pass over the lanes computing exactly what `RayBoxTest::new` and
    /// `WatertightRay::new` compute per ray, written with plain scalars and selects so LLVM
    /// vectorizes it (a scalar load was a third of the packet tracer's time on camera rays).
    #[inline(always)]
    fn load_lanes<R: RayTests>(
        &mut self,
        origin: [&[f32; L]; 3],
        dir: [&[f32; L]; 3],
        range: [&[f32; L]; 2],
        used: usize,
    ) -> u32 {
        let mut well_formed = 0;
        // Bitwise OR and AND of each frame axis over the lanes in use: equal exactly when every
        // lane has the same axis. Folded here from registers: reading the stored axes back
        // (`common_axes`) as one wide vector stalled on store forwarding.
        let (mut any, mut all) = ([0u32; 3], [u32::MAX; 3]);
        for l in 0..L {
            let (ox, oy, oz) = (origin[0][l], origin[1][l], origin[2][l]);
            let (dx, dy, dz) = (dir[0][l], dir[1][l], dir[2][l]);
            let (tmin, tmax) = (range[0][l], range[1][l]);
            // `Ray::is_well_formed`, lane by lane; an ill-formed ray is loaded as padding (a
            // miss): origin 0, direction (1, 1, 1), tmin = ∞, tmax = −∞.
            let ok = ox.is_finite()
                & oy.is_finite()
                & oz.is_finite()
                & dx.is_finite()
                & dy.is_finite()
                & dz.is_finite()
                & ((dx != 0.0) | (dy != 0.0) | (dz != 0.0))
                & tmin.is_finite()
                & (tmin >= 0.0)
                & (tmin < tmax);
            well_formed += ok as u32;
            let x = if ok { dx } else { 1.0 };
            let y = if ok { dy } else { 1.0 };
            let z = if ok { dz } else { 1.0 };
            self.origin[0][l] = if ok { ox } else { 0.0 };
            self.origin[1][l] = if ok { oy } else { 0.0 };
            self.origin[2][l] = if ok { oz } else { 0.0 };
            self.tmin[l] = if ok { tmin } else { f32::INFINITY };
            self.tmax[l] = if ok { tmax } else { f32::NEG_INFINITY };
            // Read by Möller–Trumbore only (stored for the watertight test they cost the
            // packet tracer's 8×8 camera rays 3%).
            if !R::ROBUST {
                self.dir[0][l] = x;
                self.dir[1][l] = y;
                self.dir[2][l] = z;
            }
            let (ix, iy, iz) = (1.0 / x, 1.0 / y, 1.0 / z);
            self.inv_dir[0][l] = ix;
            self.inv_dir[1][l] = iy;
            self.inv_dir[2][l] = iz;
            self.negative[0][l] = x.is_sign_negative() as u32;
            self.negative[1][l] = y.is_sign_negative() as u32;
            self.negative[2][l] = z.is_sign_negative() as u32;
            // The watertight frame `WatertightRay::new` picks, by the same comparisons, as
            // selects: kz the axis of largest |d| (first of equals), then kx, ky the next two
            // in cyclic order, swapped when d[kz] < 0 to keep the triangles' winding.
            let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
            let x_major = (ax >= ay) & (ax >= az);
            let y_major = !x_major & (ay >= az);
            let select = |on_x, on_y, on_z| by_major(x_major, y_major, [on_x, on_y, on_z]);
            let axis = |on_x, on_y, on_z| by_major(x_major, y_major, [on_x, on_y, on_z]);
            let d_kz = select(x, y, z);
            let swap = d_kz < 0.0;
            // The next axis after kz in cyclic order and the one after it, and their components.
            let (n1, n2) = (axis(1, 2, 0), axis(2, 0, 1));
            let (c1, c2) = (select(y, z, x), select(z, x, y));
            let k = [
                if swap { n2 } else { n1 },
                if swap { n1 } else { n2 },
                axis(0, 1, 2),
            ];
            for a in 0..3 {
                self.axes[a][l] = k[a];
                any[a] |= if l < used { k[a] } else { 0 };
                all[a] &= if l < used { k[a] } else { u32::MAX };
            }
            self.shear[0][l] = if swap { c2 } else { c1 } / d_kz;
            self.shear[1][l] = if swap { c1 } else { c2 } / d_kz;
            // 1 / d[kz], already computed: the same division, so the same bits.
            self.shear[2][l] = select(ix, iy, iz);
        }
        self.prim = [Hit::NO_PRIM; L];
        self.common_axes = (any == all).then(|| all.map(|k| k as usize));
        well_formed
    }

    /// Lane `l` becomes `ray`, exactly as `load` makes a lane (an ill-formed ray or `None`
    /// becomes padding, which nothing hits). For rays made one at a time (multi-frusta tracing
    /// generates them on demand); `set_common_axes` must follow once all lanes are set.
    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, ray: Option<&Ray>) {
        let (origin, dir, tmin, tmax, time) = match ray {
            Some(r) if r.is_well_formed() => (r.origin, r.dir, r.tmin, r.tmax, r.time),
            _ => (Vec3::ZERO, Vec3::ONE, f32::INFINITY, f32::NEG_INFINITY, 0.0),
        };
        let (_, k, shear) = WatertightRay::new(Vec3::ZERO, dir).parts();
        for a in 0..3 {
            self.origin[a][l] = origin[a];
            self.dir[a][l] = dir[a];
            self.inv_dir[a][l] = 1.0 / dir[a];
            self.negative[a][l] = dir[a].is_sign_negative() as u32;
            self.axes[a][l] = k[a] as u32;
            self.shear[a][l] = shear[a];
        }
        (self.tmin[l], self.tmax[l], self.time[l]) = (tmin, tmax, time);
        self.prim[l] = Hit::NO_PRIM;
    }

    /// After `set_lane`: all `L` lanes are in use (padding lanes have `tmax = −∞`); the frame
    /// shared by the live lanes, if any. Padding lanes take a live lane's frame so they do not
    /// prevent sharing.
    pub fn set_common_axes(&mut self) {
        self.used = L as u32;
        let live = (0..L).find(|&l| self.tmax[l] != f32::NEG_INFINITY);
        if let Some(live) = live {
            for l in 0..L {
                if self.tmax[l] == f32::NEG_INFINITY {
                    for a in 0..3 {
                        self.axes[a][l] = self.axes[a][live];
                        self.shear[a][l] = self.shear[a][live];
                    }
                }
            }
        }
        self.common_axes = common_axes(&self.axes, L);
    }

    /// The lanes not ended (`tmax > −∞`): in occlusion mode, the live lanes not yet occluded.
    #[inline(always)]
    pub fn live_mask(&self) -> u64 {
        let mut mask = 0u64;
        for l in 0..L {
            mask |= ((self.tmax[l] != f32::NEG_INFINITY) as u64) << l;
        }
        mask
    }

    /// Whether any lane's segment `[tmin, tmax]` meets the box `[lo, hi]`
    /// (`RayBoxTest::hit_with::<R>` per lane).
    #[inline(always)]
    pub fn hits_box<R: RayTests>(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        self.slabs().any_hit::<R>(lo, hi)
    }

    /// The lanes whose segment meets the box `[lo, hi]`.
    #[inline(always)]
    pub fn box_lanes<R: RayTests>(&self, lo: [f32; 3], hi: [f32; 3]) -> LaneMask<L> {
        self.slabs().hits::<R>(lo, hi)
    }

    /// The lanes as the slab test reads them.
    #[inline(always)]
    fn slabs(&self) -> SlabRays<'_, L> {
        SlabRays {
            origin: &self.origin,
            inv_dir: &self.inv_dir,
            negative: &self.negative,
            tmin: &self.tmin,
            tmax: &self.tmax,
        }
    }

    /// A vertex relative to every lane's origin, in every lane's watertight frame. With a frame
    /// shared by all lanes each output row is read straight from the origin row it comes from
    /// (the same subtractions): building the relative vertex first and then picking its rows by
    /// a run-time index went through the stack and was the costliest step of the packet
    /// tracer's triangle test.
    #[inline(always)]
    fn permute(&self, p: [f32; 3]) -> Permuted<L> {
        match self.common_axes {
            Some([kx, ky, kz]) => [
                self.relative(p[kx], kx),
                self.relative(p[ky], ky),
                self.relative(p[kz], kz),
            ],
            None => self.permute_lanes(&p.map(|x| [x; L])),
        }
    }

    /// Coordinate `x` on axis `axis` relative to every lane's origin (a plain loop: `array::map`
    /// here was left as an out-of-line call).
    #[inline(always)]
    fn relative(&self, x: f32, axis: usize) -> [f32; L] {
        let origin = &self.origin[axis];
        let mut out = [0.0f32; L];
        for l in 0..L {
            out[l] = x - origin[l];
        }
        out
    }

    /// As `permute` for a vertex that differs per lane (`p[axis][lane]`).
    #[inline(always)]
    fn permute_lanes(&self, p: &[[f32; L]; 3]) -> Permuted<L> {
        let mut rel = [[0.0f32; L]; 3];
        for a in 0..3 {
            for l in 0..L {
                rel[a][l] = p[a][l] - self.origin[a][l];
            }
        }
        in_lane_frames(rel, &self.axes, self.common_axes)
    }

    /// The triangle test `R` of every lane against `tri` (scene id `prim`); lanes that hit
    /// within their `[tmin, tmax]` record it and shorten `tmax` to it (or, with `ANY`, are
    /// marked occluded and end). Returns how many lanes hit.
    #[inline(always)]
    pub fn intersect<R: RayTests, const ANY: bool>(&mut self, tri: &Triangle, prim: u32) -> u32 {
        if !R::ROBUST {
            return self.intersect_moller::<ANY>(&MollerLanes::broadcast(tri), prim);
        }
        let a = self.permute(tri.v[0].to_array());
        let b = self.permute(tri.v[1].to_array());
        let c = self.permute(tri.v[2].to_array());
        self.intersect_permuted::<ANY>(&a, &b, &c, prim)
    }

    /// As `intersect::<Robust>`, with the triangle's vertices already relative to the origin
    /// along the axes that every lane shares (`SharedFrame::relative`): the same numbers
    /// `intersect` computes in each lane, so the same verdicts, without the per-lane
    /// subtractions.
    #[inline(always)]
    pub fn intersect_relative<const ANY: bool>(&mut self, rel: &[[f32; 3]; 3], prim: u32) -> u32 {
        // Broadcast by hand: `array::map` here was left as an out-of-line call.
        let lanes = |v: [f32; 3]| -> Permuted<L> { [[v[0]; L], [v[1]; L], [v[2]; L]] };
        let (a, b, c) = (lanes(rel[0]), lanes(rel[1]), lanes(rel[2]));
        self.intersect_permuted::<ANY>(&a, &b, &c, prim)
    }

    /// As `intersect` for a triangle moving linearly from `open` to `close` over the shutter
    /// interval (motion blur): each lane meets the triangle where it is at that lane's time,
    /// interpolated exactly as the reference tracer does (`Triangle::lerp`), so hits agree bit
    /// for bit. The cost over a static triangle: three vertex interpolations and a per-lane
    /// gather of the vertices into each lane's frame, for every lane in use.
    #[inline(always)]
    pub fn intersect_moving<R: RayTests, const ANY: bool>(
        &mut self,
        open: &Triangle,
        close: &Triangle,
        prim: u32,
    ) -> u32 {
        if !R::ROBUST {
            let at_time = |l| open.lerp(close, self.time[l]);
            let tri = MollerLanes::per_lane(self.used as usize, at_time);
            return self.intersect_moller::<ANY>(&tri, prim);
        }
        let mut at_time = [[[0.0f32; L]; 3]; 3];
        for l in 0..self.used as usize {
            let tri = open.lerp(close, self.time[l]);
            for (k, vertex) in tri.v.iter().enumerate() {
                for a in 0..3 {
                    at_time[k][a][l] = vertex[a];
                }
            }
        }
        let a = self.permute_lanes(&at_time[0]);
        let b = self.permute_lanes(&at_time[1]);
        let c = self.permute_lanes(&at_time[2]);
        self.intersect_permuted::<ANY>(&a, &b, &c, prim)
    }

    /// The watertight test on a triangle already in every lane's frame (`lanes::watertight`),
    /// zero or ill-conditioned edge functions redone in f64 as the scalar test does. A SIMD ray
    /// whose lanes all pass strictly outside an edge stops after the edge functions
    /// (`any_may_hit`).
    #[inline(always)]
    fn intersect_permuted<const ANY: bool>(
        &mut self,
        a: &Permuted<L>,
        b: &Permuted<L>,
        c: &Permuted<L>,
        prim: u32,
    ) -> u32 {
        let (mut e, scale) = edge_functions(&self.shear, a, b, c);
        if !any_may_hit(&e) {
            return 0;
        }
        let redo = needs_f64(&e, &scale);
        if redo.any() {
            redo_edges_in_f64(&self.shear, a, b, c, &mut e, redo);
        }
        let (hit, t_scaled, abs_det) = accept(
            &e,
            &self.shear[2],
            [&a[2], &b[2], &c[2]],
            &self.tmin,
            &self.tmax,
        );
        if !hit.contains(&true) {
            return 0;
        }
        self.take::<ANY>(prim, |l| {
            let t = t_scaled[l] / abs_det[l];
            let inv = 1.0 / (e[0][l] + e[1][l] + e[2][l]);
            (hit[l] & t.is_finite(), t, e[1][l] * inv, e[2][l] * inv)
        })
    }

    /// The Möller–Trumbore test (`Fast`) of every lane against its triangle `tri`.
    #[inline(always)]
    fn intersect_moller<const ANY: bool>(&mut self, tri: &MollerLanes<L>, prim: u32) -> u32 {
        let hits = tri.intersect(&self.origin, &self.dir, &self.tmin, &self.tmax);
        if !hits.hit.contains(&true) {
            return 0;
        }
        self.take::<ANY>(prim, |l| (hits.hit[l], hits.t[l], hits.u[l], hits.v[l]))
    }

    /// Records `prim` in the lanes that hit: `lane(l)` is lane `l`'s verdict, distance and
    /// barycentrics `(hit, t, u, v)`, computed inside the store loop (as arrays first, the
    /// watertight test's camera rays were 6–18% slower). Returns how many lanes hit.
    #[inline(always)]
    fn take<const ANY: bool>(
        &mut self,
        prim: u32,
        lane: impl Fn(usize) -> (bool, f32, f32, f32),
    ) -> u32 {
        // Every lane is written: the new value where it hits, else the old one, read by a
        // volatile load. A store under the hit mask, or of a select with an ordinary load of the
        // same slot, compiles to a masked store (`vmaskmovps`), microcoded and slow on AMD's
        // AVX2 cores; a volatile load cannot be folded into one.
        // SAFETY: plain reads of the struct's own arrays.
        let (old_prim, old_u, old_v, old_tmax) = unsafe {
            (
                std::ptr::read_volatile(&self.prim),
                std::ptr::read_volatile(&self.u),
                std::ptr::read_volatile(&self.v),
                std::ptr::read_volatile(&self.tmax),
            )
        };
        let mut count = 0;
        for l in 0..L {
            let (take, t, u, v) = lane(l);
            let tmax = if ANY { f32::NEG_INFINITY } else { t };
            self.prim[l] = if take { prim } else { old_prim[l] };
            self.u[l] = if take { u } else { old_u[l] };
            self.v[l] = if take { v } else { old_v[l] };
            self.tmax[l] = if take { tmax } else { old_tmax[l] };
            count += take as u32;
        }
        count
    }

    /// Lanes still looking for a hit (used and, in occlusion mode, not yet occluded).
    #[inline(always)]
    pub fn live_lanes(&self) -> u32 {
        let mut n = 0;
        for l in 0..L {
            n += (self.tmax[l] != f32::NEG_INFINITY) as u32;
        }
        n
    }

    /// The largest `tmax` over the lanes (−∞ when none is live).
    #[inline(always)]
    pub fn max_tmax(&self) -> f32 {
        highest(self.tmax)
    }

    /// The first `out.len()` lanes' results (`hit`), written to `out`. A zipped loop of
    /// run-time length on purpose: LLVM vectorizes it into interleaving stores, where a loop of
    /// constant length `L` is unrolled into 4·L scalar stores.
    #[inline(always)]
    pub fn store_hits(&self, out: &mut [Hit]) {
        let lanes = self.tmax.iter().zip(&self.prim).zip(&self.u).zip(&self.v);
        for (slot, (((&t, &prim), &u), &v)) in out.iter_mut().zip(lanes) {
            let miss = prim == Hit::NO_PRIM;
            *slot = Hit {
                t: if miss { Hit::MISS.t } else { t },
                prim,
                u: if miss { Hit::MISS.u } else { u },
                v: if miss { Hit::MISS.v } else { v },
            };
        }
    }

    /// Lane `l`'s result.
    pub fn hit(&self, l: usize) -> Hit {
        if self.prim[l] == Hit::NO_PRIM {
            Hit::MISS
        } else {
            Hit {
                t: self.tmax[l],
                prim: self.prim[l],
                u: self.u[l],
                v: self.v[l],
            }
        }
    }
}

/// The value for the major axis (x, else y, else z) of a direction: a select per lane.
#[inline(always)]
fn by_major<T>(x_major: bool, y_major: bool, [on_x, on_y, on_z]: [T; 3]) -> T {
    if x_major {
        on_x
    } else if y_major {
        on_y
    } else {
        on_z
    }
}

/// Lanes `first .. first + L` of a batch's array.
#[inline(always)]
fn lanes_at<const L: usize>(src: &[f32], first: usize) -> &[f32; L] {
    <&[f32; L]>::try_from(&src[first..first + L]).expect("L lanes")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Aabb, Fast, Ray, RayBatch, RayBoxTest, RayKind, Robust, WatertightRay};
    use crate::random::SplitMix64;
    use glam::Vec3;

    fn batch(rays: &[Ray]) -> RayBatch {
        let mut b = RayBatch::new(RayKind::Diffuse);
        rays.iter().for_each(|r| b.push(*r, 0));
        b
    }

    fn random_rays(rng: &mut SplitMix64, n: usize) -> Vec<Ray> {
        let mut v = |s: f32| (rng.unit() * 2.0 - 1.0) * s;
        (0..n)
            .map(|i| {
                let mut d = Vec3::new(v(1.0), v(1.0), v(1.0));
                // Exercise zero and −0.0 components and axis-parallel rays.
                match i % 7 {
                    0 => d.x = 0.0,
                    1 => d.y = -0.0,
                    _ => {}
                }
                Ray::new(
                    Vec3::new(v(2.0), v(2.0), v(2.0)),
                    d,
                    0.0,
                    1.0 + v(3.0).abs(),
                )
            })
            .collect()
    }

    /// Every lane's box and triangle verdicts are the scalar tests' of `R`
    /// (`RayBoxTest::hit_with::<R>`, `R::intersect`), bit for bit, at width `L`, full and partial
    /// groups.
    fn lanes_agree_with_the_scalar_tests<R: RayTests, const L: usize>() {
        let mut rng = SplitMix64::new(11);
        let rays = random_rays(&mut rng, L * 400);
        let mut simd = SimdRay::<L>::default();
        for (chunk_i, chunk) in rays.chunks(L).enumerate() {
            // Some groups partial, to exercise padding.
            let used = if chunk_i % 5 == 0 { L - 3 } else { L };
            simd.load::<R>(&batch(&chunk[..used]).view(), 0, used);
            let mut v = |s: f32| (rng.unit() * 2.0 - 1.0) * s;
            let p = Vec3::new(v(1.0), v(1.0), v(1.0));
            let tri = Triangle::new(p, p + Vec3::new(v(1.0), v(1.0), v(1.0)), p + Vec3::Z);
            let lo = Vec3::new(v(1.0), v(1.0), v(1.0));
            let b = Aabb::new(lo, lo + Vec3::new(v(1.0).abs(), v(1.0).abs(), 0.5));
            let box_lanes = simd.box_lanes::<R>(b.min.to_array(), b.max.to_array());
            for (l, r) in chunk[..used].iter().enumerate() {
                let want = RayBoxTest::new(r.origin, r.dir).hit_with::<R>(&b, r.tmin, r.tmax);
                assert_eq!(box_lanes.contains(l), want.is_some(), "L = {L}, lane {l}");
            }
            assert!(
                (used..L).all(|l| !box_lanes.contains(l)),
                "padding never hits"
            );
            assert_eq!(
                simd.hits_box::<R>(b.min.to_array(), b.max.to_array()),
                box_lanes.any()
            );
            let n = simd.intersect::<R, false>(&tri, 7);
            let mut expected = 0;
            for (l, r) in chunk[..used].iter().enumerate() {
                let want = R::intersect(&R::triangle_ray(r.origin, r.dir), &tri, r.tmin, r.tmax);
                match want {
                    Some((t, u, v)) => {
                        expected += 1;
                        let got = simd.hit(l);
                        assert_eq!((got.t, got.prim, got.u, got.v), (t, 7, u, v));
                    }
                    None => assert!(!simd.hit(l).is_hit()),
                }
            }
            assert_eq!(n, expected);
            assert!((used..L).all(|l| !simd.hit(l).is_hit()));
        }
    }

    #[test]
    fn lanes_agree_bit_for_bit_with_the_scalar_tests() {
        lanes_agree_with_the_scalar_tests::<Robust, 4>();
        lanes_agree_with_the_scalar_tests::<Robust, 8>();
        lanes_agree_with_the_scalar_tests::<Robust, 16>();
        lanes_agree_with_the_scalar_tests::<Fast, 4>();
        lanes_agree_with_the_scalar_tests::<Fast, 8>();
        lanes_agree_with_the_scalar_tests::<Fast, 16>();
    }

    #[test]
    fn max_tmax_is_the_largest_lane_wherever_it_is() {
        fn check<const L: usize>() {
            for at in 0..L {
                let mut tmax: [f32; L] = std::array::from_fn(|l| l as f32 - 100.0);
                tmax[at] = 7.5;
                let simd = SimdRay::<L> {
                    tmax,
                    ..Default::default()
                };
                assert_eq!(simd.max_tmax(), 7.5, "L = {L}, largest in lane {at}");
            }
            assert_eq!(SimdRay::<L>::default().max_tmax(), f32::NEG_INFINITY);
        }
        check::<1>();
        check::<3>();
        check::<4>();
        check::<8>();
        check::<12>();
        check::<16>();
    }

    #[test]
    fn lanes_set_one_by_one_equal_loaded_lanes() {
        let mut rng = SplitMix64::new(11);
        let mut rays: Vec<Ray> = (0..16)
            .map(|_| {
                Ray::new(
                    rng.vec3(-2.0, 2.0),
                    rng.direction(),
                    0.0,
                    rng.range(1.0, 9.0),
                )
            })
            .collect();
        // Ill-formed: becomes padding either way.
        rays[5].dir = Vec3::ZERO;
        let mut loaded = SimdRay::<16>::default();
        loaded.load::<Fast>(&batch(&rays).view(), 0, 16);
        let mut set = SimdRay::<16>::default();
        for (l, ray) in rays.iter().enumerate() {
            set.set_lane(l, Some(ray));
        }
        set.set_common_axes();
        let bits = |x: &[[f32; 16]; 3]| x.map(|a| a.map(f32::to_bits));
        // A padding lane's frame is free (`set_common_axes` gives it a live lane's).
        let live_frames = |x: [[u32; 16]; 3]| {
            x.map(|mut a| {
                a[5] = 0;
                a
            })
        };
        assert_eq!(bits(&set.origin), bits(&loaded.origin));
        assert_eq!(bits(&set.dir), bits(&loaded.dir));
        assert_eq!(bits(&set.inv_dir), bits(&loaded.inv_dir));
        assert_eq!(
            live_frames(bits(&set.shear)),
            live_frames(bits(&loaded.shear))
        );
        assert_eq!(set.negative, loaded.negative);
        assert_eq!(live_frames(set.axes), live_frames(loaded.axes));
        assert_eq!(set.tmin.map(f32::to_bits), loaded.tmin.map(f32::to_bits));
        assert_eq!(set.tmax.map(f32::to_bits), loaded.tmax.map(f32::to_bits));
        assert_eq!(set.live_mask(), 0xffff & !(1 << 5));
    }

    #[test]
    fn zero_edge_functions_take_the_f64_path_like_the_scalar_test() {
        // Rays through the shared vertex and along the edge of a triangle: exact zeros.
        let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let rays: Vec<Ray> = [
            Vec3::ZERO,
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.25, 0.0),
        ]
        .iter()
        .map(|&p| Ray::new(p + Vec3::Z, -Vec3::Z, 0.0, 10.0))
        .collect();
        let mut simd = SimdRay::<4>::default();
        simd.load::<Robust>(&batch(&rays).view(), 0, rays.len());
        assert_eq!(simd.intersect::<Robust, false>(&tri, 3), 3);
        for (l, r) in rays.iter().enumerate() {
            let (t, u, v) = WatertightRay::new(r.origin, r.dir)
                .intersect(&tri, 0.0, 10.0)
                .unwrap();
            assert_eq!(simd.hit(l), Hit { t, prim: 3, u, v });
        }
    }
}
