//! The ray stream (Gribble & Ramani 2008 §3.1): the rays of one initial stream in stream order,
//! each as one 32-byte record of what the box filter reads (`SlabRecord`: origin, reciprocal
//! direction, segment) and its slot; by slot, what only the intersection stage reads (the
//! watertight frame) and the ray's index in the chunk. Filters reorder the stream in place
//! (`lanes::stream::partition_by`); sub-streams are prefixes `0..len`.
//!
//! Moving a ray moves its record (two 32-byte moves) and its slot, not 13 separate columns
//! (swapping those was a quarter of the tracer's time, and the partition loop around them another
//! third); a box filter reads its `L` rays from `L` consecutive records. (Keeping the records in
//! slot order and moving only slots made moves cheap but turned every read into a scattered
//! one, which cost more than it saved.)
//!
//! The stream holds `L` padding rays past its end that hit nothing, so a group of `L` lanes can
//! be read from any position; readers mask lanes past its end.

// Lane loops index lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;

use crate::geometry::{Hit, RayTests, Rays, WatertightRay};
use crate::lanes::slab::SlabRays;
use crate::lanes::stream::SoaRays;
use crate::lanes::watertight::common_axes;
use crate::lanes::SimdRay;
use crate::tracers::reference::LeafRay;
use crate::tracers::wide_single::{WideRay, WideRayTest};

/// What the slab test reads of one ray: origin, `1 / dir` (its sign bit is the direction's,
/// `1 / −0.0 = −∞`, which is all the slab test needs of the direction), `tmin`, and `tmax`, the
/// segment's end shortened to the closest hit so far (−∞ once an occlusion ray has hit).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct SlabRecord {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    tmin: f32,
    tmax: f32,
}

/// The padding ray: its segment is empty, so no box and no triangle meets it.
const PADDING: SlabRecord = SlabRecord {
    origin: [0.0; 3],
    inv_dir: [0.0; 3],
    tmin: f32::INFINITY,
    tmax: f32::NEG_INFINITY,
};

/// The watertight frame of one ray (`WatertightRay::parts`): axes `kx | ky << 2 | kz << 4`, and
/// shear.
#[derive(Clone, Copy, Debug, Default)]
struct FrameRecord {
    shear: [f32; 3],
    axes: u32,
}

impl FrameRecord {
    /// The frame's axis `a` (0: kx, 1: ky, 2: kz).
    #[inline(always)]
    fn axis(&self, a: usize) -> u32 {
        self.axes >> (2 * a) & 3
    }
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

#[derive(Default)]
pub struct StreamRays<const L: usize> {
    /// In stream order: each ray's slab record and slot (`L` padding rays at the end, whose
    /// slot is the last one).
    slab: Vec<SlabRecord>,
    stream: Vec<u32>,
    /// By slot: watertight frame and index in the chunk.
    frame: Vec<FrameRecord>,
    id: Vec<u32>,
}

impl<const L: usize> StreamRays<L> {
    /// Replaces the stream by the well-formed rays among `first .. first + n` of `rays` (ids
    /// `first ..`; an ill-formed ray is a miss and never enters, so it cannot sway the
    /// stream's direction or cost its neighbours a filter), followed by `L` padding rays, and
    /// returns the stream's length.
    pub fn load(&mut self, rays: &Rays<'_>, first: usize, n: usize) -> usize {
        self.slab.clear();
        self.frame.clear();
        self.id.clear();
        for i in first..first + n {
            let ray = rays.ray(i);
            if !ray.is_well_formed() {
                continue;
            }
            let (_, k, shear) = WatertightRay::new(Vec3::ZERO, ray.dir).parts();
            self.slab.push(SlabRecord {
                origin: ray.origin.to_array(),
                inv_dir: ray.dir.to_array().map(|d| 1.0 / d),
                tmin: ray.tmin,
                tmax: ray.tmax,
            });
            self.frame.push(FrameRecord {
                shear,
                axes: (k[0] | k[1] << 2 | k[2] << 4) as u32,
            });
            self.id.push(i as u32);
        }
        let len = self.slab.len();
        self.slab.extend(std::iter::repeat_n(PADDING, L));
        self.frame.push(FrameRecord::default());
        self.id.push(0);
        self.stream.clear();
        self.stream.extend(0..len as u32);
        self.stream.extend(std::iter::repeat_n(len as u32, L));
        len
    }

    /// Rays at stream positions `base .. base + L` as the slab test reads them.
    #[inline(always)]
    pub fn slab_lanes(&self, base: usize) -> SlabLanes<L> {
        let records: &[SlabRecord; L] = self.slab[base..base + L].try_into().unwrap();
        let mut lanes = SlabLanes {
            origin: [[0.0; L]; 3],
            inv_dir: [[0.0; L]; 3],
            negative: [[0; L]; 3],
            tmin: [0.0; L],
            tmax: [0.0; L],
        };
        for l in 0..L {
            for a in 0..3 {
                lanes.origin[a][l] = records[l].origin[a];
                lanes.inv_dir[a][l] = records[l].inv_dir[a];
                lanes.negative[a][l] = records[l].inv_dir[a].is_sign_negative() as u32;
            }
            lanes.tmin[l] = records[l].tmin;
            lanes.tmax[l] = records[l].tmax;
        }
        lanes
    }

    /// Loads the rays at stream positions `base .. base + used` (`used ≤ L`) into `simd`'s lanes
    /// for the triangle test `R`; the other lanes become padding that hits nothing. Without `robust`
    /// the lanes run Möller–Trumbore, which reads the directions: those come from the chunk
    /// `input` (the stream keeps only their reciprocals).
    #[inline(always)]
    pub fn load_triangle_lanes<R: RayTests>(
        &self,
        base: usize,
        used: usize,
        input: &Rays<'_>,
        simd: &mut SimdRay<L>,
    ) {
        let slots = &self.stream[base..base + L];
        if !R::ROBUST {
            for l in 0..used {
                let id = self.id(base + l);
                simd.dir[0][l] = input.dx[id];
                simd.dir[1][l] = input.dy[id];
                simd.dir[2][l] = input.dz[id];
            }
        }
        for l in 0..L {
            let (r, f) = (&self.slab[base + l], &self.frame[slots[l] as usize]);
            for a in 0..3 {
                simd.origin[a][l] = r.origin[a];
                simd.shear[a][l] = f.shear[a];
                simd.axes[a][l] = f.axis(a);
            }
            simd.tmin[l] = r.tmin;
            simd.tmax[l] = if l < used { r.tmax } else { f32::NEG_INFINITY };
        }
        simd.prim = [Hit::NO_PRIM; L];
        simd.used = used as u32;
        simd.common_axes = common_axes(&simd.axes, used);
    }

    /// The ray at stream position `at` as the wide single-ray traversal reads it, from its record
    /// and frame: the very tests `WideRay::new` makes of the input ray (the record's `1 / dir`
    /// and the frame are what those compute from its direction). Möller–Trumbore (`Fast`) reads
    /// the direction from the chunk `input`.
    #[inline(always)]
    pub fn wide_ray<R: RayTests>(&self, at: usize, input: &Rays<'_>) -> WideRay<R> {
        let (r, f) = (&self.slab[at], &self.frame[self.stream[at] as usize]);
        let k = [0, 1, 2].map(|a| f.axis(a) as usize);
        let dir = || input.ray(self.id(at)).dir;
        WideRay {
            boxes: WideRayTest::from_inv(Vec3::from(r.origin), Vec3::from(r.inv_dir)),
            leaf: LeafRay {
                tris: R::triangle_ray_in_frame(r.origin, (k, f.shear), dir),
                tmin: r.tmin,
                // Static geometry only (`StreamTracer::over_static` refuses a moving BVH).
                time: 0.0,
            },
            tmax: r.tmax,
        }
    }

    /// The chunk indices of the rays at stream positions `0..len` (per-ray counters).
    pub fn ids(&self, len: usize) -> Vec<u32> {
        (0..len).map(|at| self.id(at) as u32).collect()
    }

    /// The chunk index of the ray at stream position `at`.
    #[inline(always)]
    pub fn id(&self, at: usize) -> usize {
        self.id[self.stream[at] as usize] as usize
    }

    /// The current segment end of the ray at stream position `at`.
    #[inline(always)]
    pub fn tmax(&self, at: usize) -> f32 {
        self.slab[at].tmax
    }

    /// Shortens the segment of the ray at stream position `at` to `tmax`.
    #[inline(always)]
    pub fn set_tmax(&mut self, at: usize, tmax: f32) {
        self.slab[at].tmax = tmax;
    }
}

impl<const L: usize> SoaRays for StreamRays<L> {
    #[inline(always)]
    fn move_ray(&mut self, from: usize, to: usize) {
        self.stream[to] = self.stream[from];
        self.slab[to] = self.slab[from];
    }

    #[inline(always)]
    fn swap_rays(&mut self, a: usize, b: usize) {
        self.stream.swap(a, b);
        self.slab.swap(a, b);
    }
}
