//! The packet frustum of coherent grid traversal (Wald et al. 2006, §2.2) in grid space, and the
//! SIMD frustum culling of triangles against it (§2.3).
//!
//! Grid space maps the grid onto `[0, Nx) × [0, Ny) × [0, Nz)` (§2.2, "canonical grid coordinate
//! system"); a point's cell is its truncated coordinates, and a ray keeps its `t`. The packet
//! marches along the major axis K, with U = K+1 and V = K+2 the other two. When the packet travels
//! towards −K we mirror K (`s = N_K − g_K`), so marching always goes to increasing `s`: slice `k`
//! is the slab `s ∈ [k, k+1]`.
//!
//! The frustum is four bounding lines per axis pair: every ray of the packet lies, at every `s`
//! past `s_ref` on its segment, within `u ∈ [u0_min + (s − s_ref)·du_min, u0_max + (s − s_ref)·du_max]`
//! and the same in v. For a common origin (camera and point-light packets) `s_ref` is the origin
//! and `u0_min = u0_max`: the paper's pyramid with apex; for general packets (different origins)
//! each ray's line is extended back to the packet's first `s`, and the interval of those points is
//! `u0` ("bounding planes/interval of origins and directions"). The slopes are the extremes of
//! `d_u / d_s` over all rays. For an n×n block of pinhole camera rays these extremes are the four
//! corner rays' (a ratio of linear functions of the screen position takes its extremes at the
//! corners of a rectangle), so bounding every ray gives the paper's corner-ray frustum without
//! trusting that the batch is laid out in screen blocks.
//!
//! General packets are bounded a second time by the same slopes anchored at the packet's last `s`:
//! every ray lies, at every `s` before `s_end_ref`, within `u ∈ [u1_min + (s − s_end_ref)·du_max,
//! u1_max + (s − s_end_ref)·du_min]`, `u1` being where the rays' lines cross `s_end_ref`. Shadow rays
//! towards a point light converge there (§4.7's light frustum, without reversing the rays), so
//! this pyramid narrows to the light while the first one widens from the surfaces; the overlap
//! box is the intersection of the two, and culling uses both sets of planes.
//!
//! Rounding: each bound is widened by `eps`, a fixed fraction (2⁻¹⁵) of the largest magnitude in
//! the computation (grid resolution, origins, slope × distance, local coordinates × cells per unit),
//! far above the few ulps by which a computed ray position or cell can differ from the grid
//! builder's, so the frustum never loses a cell a ray passes through and culling never drops a
//! triangle a ray hits.

use glam::Vec3;

use crate::lanes::min_max;

/// Relative width of the safety margin (module doc): 2⁻¹⁵, ~250× the rounding it covers.
const MARGIN: f32 = 1.0 / 32768.0;

/// The packet's axes in grid space: march axis `k` (mirrored when `flip`), then `u`, `v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchFrame {
    pub k: usize,
    pub u: usize,
    pub v: usize,
    pub flip: bool,
    /// Cells along the march axis, U and V.
    pub res: [u32; 3],
}

impl MarchFrame {
    pub fn new(k: usize, flip: bool, grid_res: [u32; 3]) -> Self {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        MarchFrame {
            k,
            u,
            v,
            flip,
            res: [grid_res[k], grid_res[u], grid_res[v]],
        }
    }

    /// A grid-space point as `(s, u, v)`.
    #[inline(always)]
    pub fn point(&self, g: Vec3) -> [f32; 3] {
        let a = g.to_array();
        let s = if self.flip {
            self.res[0] as f32 - a[self.k]
        } else {
            a[self.k]
        };
        [s, a[self.u], a[self.v]]
    }

    /// The grid slice index (along K) of march slice `slice`.
    #[inline(always)]
    pub fn grid_slice(&self, slice: u32) -> u32 {
        if self.flip {
            self.res[0] - 1 - slice
        } else {
            slice
        }
    }

    /// Grid cell coordinates `[x, y, z]` of cell `(i, j)` of march slice `slice`.
    #[inline(always)]
    pub fn cell(&self, slice: u32, i: u32, j: u32) -> [u32; 3] {
        let mut c = [0; 3];
        c[self.k] = self.grid_slice(slice);
        c[self.u] = i;
        c[self.v] = j;
        c
    }

    /// The march slices `[first, last]` of the layer of `m` grid slices (one macrocell thick,
    /// aligned to multiples of `m` in grid coordinates) that holds march slice `slice`.
    pub fn macro_layer(&self, slice: u32, m: u32) -> (u32, u32) {
        let g = self.grid_slice(slice);
        let lo = g / m * m;
        let hi = (lo + m).min(self.res[0]) - 1;
        if self.flip {
            (self.grid_slice(hi), self.grid_slice(lo))
        } else {
            (lo, hi)
        }
    }
}

/// The rays of one packet in march coordinates (SoA): origin `(o_s, o_u, o_v)`, slopes
/// `a = d_u / d_s` and `b = d_v / d_s` (`d_s > 0` for all), and the segment `[s_start, s_end]`
/// of each ray inside the grid and its `[tmin, tmax]`.
#[derive(Default)]
pub struct MarchRays {
    pub o_s: Vec<f32>,
    pub o_u: Vec<f32>,
    pub o_v: Vec<f32>,
    pub a: Vec<f32>,
    pub b: Vec<f32>,
    pub s_start: Vec<f32>,
    pub s_end: Vec<f32>,
    /// The packet's rays are the first `len` of each array (which only ever grow, so a packet
    /// after a smaller one does not refill them).
    pub len: usize,
}

impl MarchRays {
    /// Makes room for `n` rays and sets `len` (the caller then writes the values).
    pub fn set_len(&mut self, n: usize) {
        self.len = n;
        for v in [
            &mut self.o_s,
            &mut self.o_u,
            &mut self.o_v,
            &mut self.a,
            &mut self.b,
            &mut self.s_start,
            &mut self.s_end,
        ] {
            if v.len() < n {
                v.resize(n, 0.0);
            }
        }
    }
}

/// The per-ray quantity an incoherent packet is split by (at its median): a slope, or where the
/// ray's line crosses the frustum's reference `s` along u or v.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitKey {
    SlopeU,
    SlopeV,
    OriginU,
    OriginV,
}

/// The apex of a common-origin packet and its four corner-ray directions `(1, a, b)` (§2.3).
#[derive(Clone, Copy, Debug)]
struct Apex {
    origin: [f32; 3],
    corners: [[f32; 3]; 4],
    /// Largest L1 length of a corner direction (scales the culling tolerance).
    corner_len: f32,
}

/// A packet's bounding frustum (module doc).
#[derive(Clone, Copy, Debug)]
pub struct MarchFrustum {
    s_ref: f32,
    u0: [f32; 2],
    v0: [f32; 2],
    du: [f32; 2],
    dv: [f32; 2],
    /// The same lines anchored at the packet's last `s` instead (general packets; unbounded for
    /// common-origin ones): the interval where the rays' lines cross `s_end_ref`, from which they
    /// spread backwards. Converging rays (shadow rays towards a point light, §4.7) have a narrow
    /// interval there, so this bound is the tighter one near their end.
    s_end_ref: f32,
    u1: [f32; 2],
    v1: [f32; 2],
    /// The packet's extent along the march axis, `[first, last]`.
    s_range: [f32; 2],
    /// Largest magnitude in the frustum's arithmetic, and the margin derived from it.
    mag: f32,
    eps: f32,
    apex: Option<Apex>,
}

/// `[min, max]` of each of the `Q` quantities `value(i)` over `i < n`, NaNs ignored, in one pass.
/// `|x|`, or 0 when `x` is not finite.
#[inline(always)]
fn finite_abs(x: f32) -> f32 {
    if x.is_finite() {
        x.abs()
    } else {
        0.0
    }
}

#[inline(always)]
fn sub(p: [f32; 3], q: [f32; 3]) -> [f32; 3] {
    [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
}

#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn l1(a: [f32; 3]) -> f32 {
    a[0].abs() + a[1].abs() + a[2].abs()
}

impl MarchFrustum {
    /// The frustum bounding `rays` (at least one). `apex`: the common origin in march coordinates
    /// when every ray starts there with `tmin ≥ 0` (enables corner-ray culling). `scale`: the
    /// largest of the grid's resolution and its world coordinate magnitudes × cells per unit, the
    /// scale of the rounding of the world → grid transform.
    /// Extremes are taken `L` rays at a time (`lanes::min_max`), `L` the tracer's lane width.
    pub fn new<const L: usize>(
        rays: &MarchRays,
        apex: Option<[f32; 3]>,
        scale: f32,
    ) -> MarchFrustum {
        let n = rays.len;
        let (o_s, o_u, o_v) = (&rays.o_s[..n], &rays.o_u[..n], &rays.o_v[..n]);
        let (a, b) = (&rays.a[..n], &rays.b[..n]);
        let (s_start, s_end) = (&rays.s_start[..n], &rays.s_end[..n]);
        let [starts, ends, du, dv, os, ou, ov] = min_max::<L, 7>(n, |i| {
            [s_start[i], s_end[i], a[i], b[i], o_s[i], o_u[i], o_v[i]]
        });
        let (s_first, s_last) = (starts[0], ends[1]);
        let unbounded = [f32::NEG_INFINITY, f32::INFINITY];
        let ((s_ref, u0, v0), (u1, v1)) = match apex {
            Some(o) => ((o[0], [o[1]; 2], [o[2]; 2]), (unbounded, unbounded)),
            None => {
                // Lines extended back to the first s any ray reaches (§2.2, general packets),
                // and forward to the last.
                let [u0, v0, u1, v1] = min_max::<L, 4>(n, |i| {
                    let (to_first, to_last) = (s_first - o_s[i], s_last - o_s[i]);
                    [
                        o_u[i] + to_first * a[i],
                        o_v[i] + to_first * b[i],
                        o_u[i] + to_last * a[i],
                        o_v[i] + to_last * b[i],
                    ]
                });
                ((s_first, u0, v0), (u1, v1))
            }
        };
        let slope = du[0]
            .abs()
            .max(du[1].abs())
            .max(dv[0].abs())
            .max(dv[1].abs());
        let finite_last = finite_abs(s_last);
        let origins = [os, ou, ov]
            .into_iter()
            .flatten()
            .fold(0.0f32, |m, x| m.max(x.abs()));
        let mag = [
            1.0,
            scale,
            origins,
            s_ref.abs(),
            s_first.abs(),
            finite_last,
            u0[0].abs(),
            u0[1].abs(),
            v0[0].abs(),
            v0[1].abs(),
            finite_abs(u1[0]),
            finite_abs(u1[1]),
            finite_abs(v1[0]),
            finite_abs(v1[1]),
            slope * (scale + s_ref.abs() + finite_last),
        ]
        .into_iter()
        .fold(0.0f32, f32::max);
        let eps = mag * MARGIN;
        // In the general case the reference point moves back by eps so every ray's computed
        // start, off by less than eps, still lies past it.
        let (s_ref, u0, v0) = match apex {
            Some(_) => (s_ref, u0, v0),
            None => (
                s_ref - eps,
                [u0[0] - eps * du[0].abs(), u0[1] + eps * du[1].abs()],
                [v0[0] - eps * dv[0].abs(), v0[1] + eps * dv[1].abs()],
            ),
        };
        // Moved forward by eps likewise for the end anchor (its lines spread towards lower s,
        // so its lower u bound follows the largest slope).
        let (s_end_ref, u1, v1) = (
            s_last + eps,
            [
                u1[0] - eps * du[1].abs() - eps,
                u1[1] + eps * du[0].abs() + eps,
            ],
            [
                v1[0] - eps * dv[1].abs() - eps,
                v1[1] + eps * dv[0].abs() + eps,
            ],
        );
        let apex = apex.map(|origin| {
            let corners = [
                [1.0, du[0], dv[0]],
                [1.0, du[1], dv[0]],
                [1.0, du[0], dv[1]],
                [1.0, du[1], dv[1]],
            ];
            Apex {
                origin,
                corners,
                corner_len: corners.iter().map(|c| l1(*c)).fold(0.0, f32::max),
            }
        });
        MarchFrustum {
            s_ref,
            u0: [u0[0] - eps, u0[1] + eps],
            v0: [v0[0] - eps, v0[1] + eps],
            du,
            dv,
            s_end_ref,
            u1,
            v1,
            s_range: [s_first - eps, s_last + eps],
            mag,
            eps,
            apex,
        }
    }

    /// The margin all comparisons leave (module doc).
    pub fn eps(&self) -> f32 {
        self.eps
    }

    /// The `s` where the frustum's lines start (the apex, or the packet's first `s`).
    pub fn s_ref(&self) -> f32 {
        self.s_ref
    }

    /// How incoherent the packet is: widths `[du, dv]` of its slope intervals (how many cells its
    /// overlap box grows per slice) and `[u, v]` of its origin interval at `s_ref` (in cells,
    /// margins left out).
    fn extents(&self) -> [f32; 4] {
        [
            self.du[1] - self.du[0],
            self.dv[1] - self.dv[0],
            self.u0[1] - self.u0[0] - 2.0 * self.eps,
            self.v0[1] - self.v0[0] - 2.0 * self.eps,
        ]
    }

    /// How many halvings of its extents the packet needs before its slopes spread at most
    /// `max_slope` and its origins at most `max_origin` (u + v, in cells): each extent halved
    /// until it is at most half its limit. A median split halves about one extent (an estimate:
    /// it assumes the rays spread evenly).
    pub fn halvings(&self, max_slope: f32, max_origin: f32) -> u32 {
        let [slope_u, slope_v, origin_u, origin_v] = self.extents();
        let halvings = |extent: f32, limit: f32| {
            let ratio = extent / (0.5 * limit);
            if ratio > 1.0 {
                // `as` saturates: an infinite or huge ratio is many halvings.
                ratio.log2().ceil() as u32
            } else {
                0
            }
        };
        // Splitting rays apart by origin separates their slopes too when they share an end
        // point (shadow rays), so the two needs overlap: the larger one counts.
        (halvings(slope_u, max_slope) + halvings(slope_v, max_slope))
            .max(halvings(origin_u, max_origin) + halvings(origin_v, max_origin))
    }

    /// What to split the packet by when its slopes spread more than `max_slope` or its origins
    /// more than `max_origin` (u + v, in cells; module doc of `cgt`): the wider of its slope
    /// extents, else the wider of its origin extents. `None`: coherent enough.
    pub fn split_key(&self, max_slope: f32, max_origin: f32) -> Option<SplitKey> {
        let [slope_u, slope_v, origin_u, origin_v] = self.extents();
        if slope_u + slope_v > max_slope {
            Some(if slope_u >= slope_v {
                SplitKey::SlopeU
            } else {
                SplitKey::SlopeV
            })
        } else if origin_u + origin_v > max_origin {
            Some(if origin_u >= origin_v {
                SplitKey::OriginU
            } else {
                SplitKey::OriginV
            })
        } else {
            None
        }
    }

    /// The march slices `[first, last]` the packet spans inside a grid `slices` thick, or `None`.
    pub fn slice_range(&self, slices: u32) -> Option<(u32, u32)> {
        let [lo, hi] = self.s_range;
        if hi < 0.0 || lo >= slices as f32 || lo > hi {
            return None;
        }
        // `as` saturates: an infinite end becomes the last slice after the clamp.
        let first = lo.max(0.0).floor() as u32;
        let last = (hi.floor() as i64).min(slices as i64 - 1) as u32;
        Some((first, last))
    }

    /// The overlap box `[u_min, u_max, v_min, v_max]` of the frustum with the slab
    /// `s ∈ [s0, s1]` (§2.2, B), or `None` when the packet does not reach it. For successive unit
    /// slabs this is the paper's incremental `B(i+1) = B(i) + ΔB` with `ΔB = (du_min, du_max,
    /// dv_min, dv_max)`, evaluated as `B(0) + i·ΔB` so rounding does not build up over hundreds of
    /// slices.
    #[inline(always)]
    pub fn overlap(&self, s0: f32, s1: f32) -> Option<[f32; 4]> {
        let lo = s0.max(self.s_range[0]) - self.s_ref;
        let hi = s1.min(self.s_range[1]) - self.s_ref;
        if lo > hi {
            return None;
        }
        // The same slab seen from the end anchor (both ends ≤ 0 there).
        let (lo_e, hi_e) = (
            lo + self.s_ref - self.s_end_ref,
            hi + self.s_ref - self.s_end_ref,
        );
        Some([
            (self.u0[0] + (lo * self.du[0]).min(hi * self.du[0]))
                .max(self.u1[0] + (lo_e * self.du[1]).min(hi_e * self.du[1])),
            (self.u0[1] + (lo * self.du[1]).max(hi * self.du[1]))
                .min(self.u1[1] + (lo_e * self.du[0]).max(hi_e * self.du[0])),
            (self.v0[0] + (lo * self.dv[0]).min(hi * self.dv[0]))
                .max(self.v1[0] + (lo_e * self.dv[1]).min(hi_e * self.dv[1])),
            (self.v0[1] + (lo * self.dv[1]).max(hi * self.dv[1]))
                .min(self.v1[1] + (lo_e * self.dv[0]).max(hi_e * self.dv[0])),
        ])
    }

    /// Whether no ray of the packet can hit the triangle with march-space vertices `p`
    /// (§2.3, SIMD frustum culling). Two sufficient tests:
    /// - the frustum's own planes: all three vertices beyond one side plane, or before the
    ///   packet's first / after its last `s` (the only test for general packets, whose rays have
    ///   no common origin);
    /// - for common-origin packets, Dmitriev et al.'s shaft culling with the four corner rays:
    ///   every ray's direction is a positive combination of the corner directions, so when all
    ///   four corners pass outside the same edge of the triangle (as seen from the apex), so does
    ///   every ray.
    #[inline]
    pub fn culls(&self, p: &[[f32; 3]; 3]) -> bool {
        let tol = self.eps;
        // One bit per plane a vertex lies beyond; a plane all three lie beyond culls.
        let mut beyond_all = 0b11_1111u8;
        for q in p {
            let ds = q[0] - self.s_ref;
            let beyond = (q[0] < self.s_range[0] - tol) as u8
                | ((q[0] > self.s_range[1] + tol) as u8) << 1
                | ((q[1] < self.u0[0] + ds * self.du[0] - tol) as u8) << 2
                | ((q[1] > self.u0[1] + ds * self.du[1] + tol) as u8) << 3
                | ((q[2] < self.v0[0] + ds * self.dv[0] - tol) as u8) << 4
                | ((q[2] > self.v0[1] + ds * self.dv[1] + tol) as u8) << 5;
            beyond_all &= beyond;
        }
        if beyond_all != 0 {
            return true;
        }
        let Some(apex) = &self.apex else {
            // General packets: the lines from the end anchor (their lower bound follows the
            // largest slope, as they spread towards lower s).
            let mut beyond_all = 0b1111u8;
            for q in p {
                let ds = q[0] - self.s_end_ref;
                let beyond = (q[1] < self.u1[0] + ds * self.du[1] - tol) as u8
                    | ((q[1] > self.u1[1] + ds * self.du[0] + tol) as u8) << 1
                    | ((q[2] < self.v1[0] + ds * self.dv[1] - tol) as u8) << 2
                    | ((q[2] > self.v1[1] + ds * self.dv[0] + tol) as u8) << 3;
                beyond_all &= beyond;
            }
            return beyond_all != 0;
        };
        // A ray from the apex with direction d meets the triangle (at t > 0) iff d = αA + βB + γC
        // with α, β, γ ≥ 0, A, B, C the vertices seen from the apex; γ = d·(A×B)/V with
        // V = A·(B×C), and likewise for α, β. Tolerances scale with the operands' magnitudes
        // (plus the coordinate scale `mag`, the size of their rounding errors).
        let [a, b, c] = p.map(|q| sub(q, apex.origin));
        let [la, lb, lc] = [l1(a) + self.mag, l1(b) + self.mag, l1(c) + self.mag];
        let volume = dot(a, cross(b, c));
        if volume.abs() <= MARGIN * la * lb * lc {
            return false; // apex (nearly) in the triangle's plane: which side is inside is unclear
        }
        let sign = volume.signum();
        // SIMD over the corner rays (§2.3): lane 4·e + c tests corner c against edge e.
        let edges = [(a, b, la, lb), (b, c, lb, lc), (c, a, lc, la)].map(|(x, y, lx, ly)| {
            (
                cross(x, y).map(|n| sign * n),
                MARGIN * apex.corner_len * lx * ly,
            )
        });
        let mut outside = [false; 12];
        for (l, out) in outside.iter_mut().enumerate() {
            let (n, tol) = edges[l / 4];
            let d = apex.corners[l % 4];
            *out = dot(d, n) < -tol;
        }
        outside.chunks(4).any(|corners| corners.iter().all(|&o| o))
    }
}

/// The cells `[i0, i1] × [j0, j1]` of a `res_u × res_v` slice that an overlap box covers
/// (§2.2: truncating B's corners), or `None` when the box lies outside the slice.
#[inline(always)]
pub fn cell_range(b: [f32; 4], res_u: u32, res_v: u32) -> Option<[u32; 4]> {
    let [u0, u1, v0, v1] = b;
    if u1 < 0.0 || v1 < 0.0 || u0 >= res_u as f32 || v0 >= res_v as f32 {
        return None;
    }
    let lo = |x: f32| x.max(0.0) as u32;
    let hi = |x: f32, n: u32| (x as u32).min(n - 1);
    Some([lo(u0), hi(u1, res_u), lo(v0), hi(v1, res_v)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_frame_maps_slices_and_macro_layers_back() {
        let f = MarchFrame::new(1, true, [4, 10, 6]);
        assert_eq!((f.u, f.v, f.res), (2, 0, [10, 6, 4]));
        assert_eq!(f.point(Vec3::new(1.0, 2.5, 3.0)), [7.5, 3.0, 1.0]);
        assert_eq!(f.cell(0, 5, 3), [3, 9, 5]);
        // Macro size 4 over 10 grid slices: layers 0..=3, 4..=7 and 8..=9; marching down, grid
        // slice 9 is march slice 0.
        assert_eq!(f.macro_layer(0, 4), (0, 1)); // grid slices 8..=9
        assert_eq!(f.macro_layer(2, 4), (2, 5)); // grid slices 4..=7
        assert_eq!(f.macro_layer(9, 4), (6, 9)); // grid slices 0..=3
        let g = MarchFrame::new(2, false, [4, 10, 6]);
        assert_eq!(g.macro_layer(5, 4), (4, 5));
    }

    fn one_ray_packet(o: [f32; 3], d: [f32; 3], s_end: f32) -> MarchRays {
        MarchRays {
            o_s: vec![o[0]],
            o_u: vec![o[1]],
            o_v: vec![o[2]],
            a: vec![d[1] / d[0]],
            b: vec![d[2] / d[0]],
            s_start: vec![o[0]],
            s_end: vec![s_end],
            len: 1,
        }
    }

    #[test]
    fn overlap_of_a_single_ray_follows_its_line() {
        let rays = one_ray_packet([0.5, 1.25, 2.5], [1.0, 0.5, -0.25], 8.0);
        let f = MarchFrustum::new::<16>(&rays, None, 10.0);
        let e = f.eps();
        let b = f.overlap(2.0, 3.0).unwrap();
        // At s = 2 the ray is at u = 1.25 + 1.5·0.5 = 2.0, at s = 3: 2.5; v from 2.125 to 1.875.
        for (got, want) in b.iter().zip([2.0, 2.5, 1.875, 2.125]) {
            assert!((got - want).abs() <= 4.0 * e, "{b:?}");
        }
        assert_eq!(cell_range(b, 4, 4), Some([1, 2, 1, 2]));
        assert_eq!(f.slice_range(5), Some((0, 4)));
        assert_eq!(f.slice_range(20), Some((0, 8)));
    }

    #[test]
    fn converging_rays_are_bounded_by_their_shared_end_too() {
        // Two rays from (s, u) = (0, 0) and (0, 8) to the end point (8, 4), v = 0: slopes ±0.5.
        let rays = MarchRays {
            o_s: vec![0.0; 2],
            o_u: vec![0.0, 8.0],
            o_v: vec![0.0; 2],
            a: vec![0.5, -0.5],
            b: vec![0.0; 2],
            s_start: vec![0.0; 2],
            s_end: vec![8.0; 2],
            len: 2,
        };
        let f = MarchFrustum::new::<16>(&rays, None, 16.0);
        let e = 8.0 * f.eps();
        // The last slab: the rays are within u ∈ [3.5, 4.5]; the start-anchored lines alone
        // give [−3.5, 11.5].
        let b = f.overlap(7.0, 8.0).unwrap();
        for (got, want) in b.iter().zip([3.5, 4.5, 0.0, 0.0]) {
            assert!((got - want).abs() <= e, "{b:?}");
        }
        // The first slab: [0, 8] where the start anchor alone gives [−0.5, 8.5].
        let b = f.overlap(0.0, 1.0).unwrap();
        assert!(b[0].abs() <= e && (b[1] - 8.0).abs() <= e, "{b:?}");
        // Near the end, beside the rays: only the end-anchored planes cull it.
        let beside = [[7.0, 6.0, -1.0], [7.5, 6.5, 1.0], [7.0, 7.0, 0.0]];
        assert!(f.culls(&beside));
        let across = [[7.0, 3.0, -1.0], [7.5, 5.0, 1.0], [7.0, 4.0, 0.0]];
        assert!(!f.culls(&across));
    }

    #[test]
    fn corner_rays_cull_a_triangle_beside_the_frustum_and_keep_one_inside() {
        // Apex at the origin, slopes in [−0.1, 0.1] on both axes.
        let rays = MarchRays {
            o_s: vec![0.0; 2],
            o_u: vec![0.0; 2],
            o_v: vec![0.0; 2],
            a: vec![-0.1, 0.1],
            b: vec![-0.1, 0.1],
            s_start: vec![0.0; 2],
            s_end: vec![100.0; 2],
            len: 2,
        };
        let f = MarchFrustum::new::<16>(&rays, Some([0.0; 3]), 1.0);
        // Inside: spans the axis at s = 10.
        let inside = [[10.0, -1.0, -1.0], [10.0, 1.0, -1.0], [10.0, 0.0, 1.0]];
        assert!(!f.culls(&inside));
        // Beside the corner (u, v) = (1, 1) of the frustum's section [−1, 1]² at s = 10: its edge
        // u + v = 3.5 separates it, but no single side plane has all three vertices beyond it.
        let beside = [[10.0, 0.5, 3.0], [10.0, 3.0, 0.5], [10.0, 3.0, 3.0]];
        assert!(f.culls(&beside));
        let general = MarchFrustum::new::<16>(&rays, None, 1.0);
        assert!(!general.culls(&beside), "no plane separates it");
        // Wholly beyond the u_max plane: both frustum kinds cull it.
        let far = [[10.0, 3.0, 0.0], [12.0, 4.0, 0.0], [11.0, 3.5, 1.0]];
        assert!(f.culls(&far) && general.culls(&far));
    }
}
