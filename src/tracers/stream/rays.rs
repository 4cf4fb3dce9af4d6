//! The ray stream (Gribble & Ramani 2008 §3.1): the rays of one initial stream in SoA columns,
//! each carrying what the box and triangle tests precompute per ray and its index in the chunk,
//! so a filter can reorder them in place (`lanes::stream::partition_by`) and hits still land in
//! their ray's slot. Sub-streams are prefixes `0..len` of the columns.
//!
//! Every column holds `L` slots past the stream, so a group of `L` lanes can be read from any
//! ray of the stream; lanes past a stream's end are masked off by their readers.

use glam::Vec3;

use crate::geometry::{Hit, Rays, WatertightRay};
use crate::lanes::slab::SlabRays;
use crate::lanes::stream::SoaRays;
use crate::lanes::watertight::common_axes;
use crate::lanes::SimdRay;

/// `L` consecutive slots of a column from `base`.
#[inline(always)]
fn lanes<T: Copy + Default, const L: usize>(column: &[T], base: usize) -> [T; L] {
    let mut out = [T::default(); L];
    out.copy_from_slice(&column[base..base + L]);
    out
}

/// What the slab test reads for `L` rays, owned (`SlabRays` borrows it).
pub struct SlabLanes<const L: usize> {
    origin: [[f32; L]; 3],
    inv_dir: [[f32; L]; 3],
    negative: [[u32; L]; 3],
    tmin: [f32; L],
    tmax: [f32; L],
}

impl<const L: usize> SlabLanes<L> {
    pub fn slabs(&self) -> SlabRays<'_, L> {
        SlabRays {
            origin: &self.origin,
            inv_dir: &self.inv_dir,
            negative: &self.negative,
            tmin: &self.tmin,
            tmax: &self.tmax,
        }
    }

    /// Lane `l`'s direction sign bits (−0.0 counts as negative, as in `RayBoxTest`).
    pub fn negative(&self, axis: usize, lane: usize) -> bool {
        self.negative[axis][lane] != 0
    }
}

pub struct StreamRays<const L: usize> {
    origin: [Vec<f32>; 3],
    /// `1 / dir` per axis; its sign bit is the direction's (`1 / −0.0 = −∞`), which is all the
    /// slab test needs of the direction.
    inv_dir: [Vec<f32>; 3],
    /// The watertight frame (`WatertightRay::parts`): axes `kx | ky << 2 | kz << 4`, and shear.
    axes: Vec<u32>,
    shear: [Vec<f32>; 3],
    tmin: Vec<f32>,
    /// The segment's end, shortened to the closest hit found so far; −∞ once an occlusion ray
    /// has hit.
    pub tmax: Vec<f32>,
    /// The ray's index in the chunk.
    pub id: Vec<u32>,
}

impl<const L: usize> Default for StreamRays<L> {
    fn default() -> Self {
        StreamRays {
            origin: Default::default(),
            inv_dir: Default::default(),
            axes: vec![],
            shear: Default::default(),
            tmin: vec![],
            tmax: vec![],
            id: vec![],
        }
    }
}

impl<const L: usize> StreamRays<L> {
    /// Replaces the stream by the well-formed rays among `first .. first + n` of `rays` (ids
    /// `first ..`; an ill-formed ray is a miss and never enters, so it cannot sway the
    /// stream's direction or cost its neighbours a filter), pads every column with `L` rays that
    /// hit nothing, and returns the stream's length.
    pub fn load(&mut self, rays: &Rays<'_>, first: usize, n: usize) -> usize {
        let slots = n + L;
        for c in self.origin.iter_mut().chain(&mut self.inv_dir) {
            c.resize(slots, 0.0);
        }
        for c in &mut self.shear {
            c.resize(slots, 0.0);
        }
        self.axes.resize(slots, 0);
        self.tmin.resize(slots, f32::INFINITY);
        self.tmax.resize(slots, f32::NEG_INFINITY);
        self.id.resize(slots, 0);
        let mut s = 0;
        for i in first..first + n {
            if !rays.ray(i).is_well_formed() {
                continue;
            }
            let dir = Vec3::new(rays.dx[i], rays.dy[i], rays.dz[i]);
            let (_, k, shear) = WatertightRay::new(Vec3::ZERO, dir).parts();
            for a in 0..3 {
                self.inv_dir[a][s] = 1.0 / dir[a];
                self.shear[a][s] = shear[a];
            }
            self.origin[0][s] = rays.ox[i];
            self.origin[1][s] = rays.oy[i];
            self.origin[2][s] = rays.oz[i];
            self.axes[s] = (k[0] | k[1] << 2 | k[2] << 4) as u32;
            self.tmin[s] = rays.tmin[i];
            self.tmax[s] = rays.tmax[i];
            self.id[s] = i as u32;
            s += 1;
        }
        for pad in s..slots {
            self.tmin[pad] = f32::INFINITY;
            self.tmax[pad] = f32::NEG_INFINITY;
        }
        s
    }

    /// Rays `base .. base + L` as the slab test reads them.
    #[inline(always)]
    pub fn slab_lanes(&self, base: usize) -> SlabLanes<L> {
        let origin = self.origin.each_ref().map(|c| lanes(c, base));
        let inv_dir: [[f32; L]; 3] = self.inv_dir.each_ref().map(|c| lanes(c, base));
        SlabLanes {
            origin,
            negative: inv_dir.map(|lanes| lanes.map(|x| x.is_sign_negative() as u32)),
            inv_dir,
            tmin: lanes(&self.tmin, base),
            tmax: lanes(&self.tmax, base),
        }
    }

    /// Loads rays `base .. base + used` (`used ≤ L`) into `simd`'s lanes for the triangle test;
    /// the other lanes become padding that hits nothing.
    #[inline(always)]
    pub fn load_triangle_lanes(&self, base: usize, used: usize, simd: &mut SimdRay<L>) {
        let axes: [u32; L] = lanes(&self.axes, base);
        simd.origin = self.origin.each_ref().map(|c| lanes(c, base));
        simd.shear = self.shear.each_ref().map(|c| lanes(c, base));
        simd.axes = [0, 2, 4].map(|shift| axes.map(|k| k >> shift & 3));
        simd.tmin = lanes(&self.tmin, base);
        simd.tmax = lanes(&self.tmax, base);
        for l in used..L {
            simd.tmax[l] = f32::NEG_INFINITY;
        }
        simd.prim = [Hit::NO_PRIM; L];
        simd.used = used as u32;
        simd.common_axes = common_axes(&simd.axes, used);
    }
}

impl<const L: usize> SoaRays for StreamRays<L> {
    fn move_ray(&mut self, from: usize, to: usize) {
        for c in self
            .origin
            .iter_mut()
            .chain(&mut self.inv_dir)
            .chain(&mut self.shear)
        {
            c[to] = c[from];
        }
        self.axes[to] = self.axes[from];
        self.tmin[to] = self.tmin[from];
        self.tmax[to] = self.tmax[from];
        self.id[to] = self.id[from];
    }

    fn swap_rays(&mut self, a: usize, b: usize) {
        for c in self
            .origin
            .iter_mut()
            .chain(&mut self.inv_dir)
            .chain(&mut self.shear)
        {
            c.swap(a, b);
        }
        self.axes.swap(a, b);
        self.tmin.swap(a, b);
        self.tmax.swap(a, b);
        self.id.swap(a, b);
    }
}
