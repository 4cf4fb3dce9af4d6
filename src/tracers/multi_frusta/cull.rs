//! Triangle culling for a block of frusta (Benthin & Wald 2009 §4, §5.1: "back-face and corner
//! ray culling"), one loop over the frusta per triangle, before any ray is generated.
//!
//! - **Plane culling** (our exact form of the paper's back-face culling): when the frustum's
//!   origin and its four corner targets lie strictly on one side of the triangle's plane, no
//!   segment from the origin to a point of the rectangle crosses it. The paper culls triangles
//!   facing away from the origin, which changes answers on open meshes (a shadow ray is blocked by
//!   either face); this test never does, and it also drops triangles behind the origin or beyond
//!   the light.
//! - **Corner-ray culling**: when all four corner rays pass strictly outside one edge plane of the
//!   triangle (the plane through the origin and the edge), every ray of the frustum does, since
//!   each is a convex combination of the corners.
//! - **Back-face culling** (the paper's, Table 1 "+culling"; option `backface`, off by default):
//!   a triangle whose plane has the frustum's origin strictly behind it (`(o − v0)·n < 0`, `n`
//!   the winding normal `(v1 − v0) × (v2 − v0)`). Exact on closed, outward-wound meshes seen from
//!   outside (a ray meets a front face before any back face), but it changes answers on open
//!   meshes, so the two tests above stay the default.
//!
//! The first two keep a margin for rounding, relative to the magnitudes involved: a triangle is
//! culled only when the test holds with room to spare, so culling never removes a triangle a
//! sample ray hits (property test in `tests`).

use glam::Vec3;

use crate::geometry::Triangle;
use crate::lanes::vector::{Native, Vector};
use crate::tracers::multi_frusta::frusta::{Frusta, MAX_FRUSTA};

/// Relative angle below which an edge-plane test does not cull, squared: `v − o` is rounded
/// relative to its own length, as the watertight test rounds it, and the sample directions are
/// normalized in f32, so both are off by ~1e-7 rad.
const ANGLE_TOLERANCE_SQ: f32 = 1e-10;

/// Rounding allowance per unit of magnitude in the plane test (f32 rounding is 6e-8; a few
/// roundings of the dot products and of the normalized sample rays stay well under 1e-6).
const RELATIVE_ROUNDING: f32 = 1e-6;

/// The frusta of `candidates` that `tri` cannot be culled for, one vector of frusta per pass at
/// the machine's width (`vector::Native`); with `backface`, also those seeing its back.
#[inline(always)]
pub fn keep_mask(frusta: &Frusta, tri: &Triangle, candidates: u64, backface: bool) -> u64 {
    keep_mask_with::<Native>(frusta, tri, candidates, backface)
}

/// `keep_mask` on vectors `V`.
#[inline(always)]
pub fn keep_mask_with<V: Vector>(
    frusta: &Frusta,
    tri: &Triangle,
    candidates: u64,
    backface: bool,
) -> u64 {
    let (e1, e2) = (tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]);
    // The plane test's rounding: relative to |n| and the lengths it is computed from, times the
    // distances involved (`RELATIVE_ROUNDING` per unit).
    let tri_scale =
        V::splat(RELATIVE_ROUNDING * (e1.cross(e2).length() + e1.length() * e2.length()));
    let tri_extent = V::splat(e1.abs().element_sum() + e2.abs().element_sum());
    let splat = |v: Vec3| v.to_array().map(V::splat);
    let (v, n) = (tri.v.map(splat), splat(e1.cross(e2)));
    let len = 64 - candidates.leading_zeros() as usize;
    let dot = |a: [V; 3], b: [V; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [V; 3], b: [V; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (zero, tolerance) = (V::splat(0.0), V::splat(ANGLE_TOLERANCE_SQ));
    let mut keep = 0u64;
    for base in (0..len).step_by(V::WIDTH) {
        let lanes = |x: &[f32; MAX_FRUSTA]| V::load(x, base);
        let origin: [V; 3] = std::array::from_fn(|a| lanes(&frusta.origin[a]));
        let corner = |q: usize| -> [V; 3] { std::array::from_fn(|a| lanes(&frusta.corner[q][a])) };
        let rel = |p: [V; 3]| [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        // Plane culling: origin and corner targets on one side. (Signed zeros aside, `0 − x` is
        // `−x`; the comparisons do not see the sign of a zero.)
        let to_v0 = rel(v[0]);
        let at_origin = zero - dot(n, to_v0);
        let distances = to_v0[0].abs() + to_v0[1].abs() + to_v0[2].abs() + lanes(&frusta.reach);
        let plane_slack = tri_scale * (distances + tri_extent);
        let below_slack = zero - plane_slack;
        let side = |q: usize| at_origin + dot(n, corner(q));
        let (s0, s1, s2, s3) = (side(0), side(1), side(2), side(3));
        // Comparisons: a NaN fails them and culls nothing.
        let all_above = at_origin.gt(plane_slack)
            & s0.gt(plane_slack)
            & s1.gt(plane_slack)
            & s2.gt(plane_slack)
            & s3.gt(plane_slack);
        let all_below = at_origin.lt(below_slack)
            & s0.lt(below_slack)
            & s1.lt(below_slack)
            & s2.lt(below_slack)
            & s3.lt(below_slack);
        // Corner-ray culling against the three edge planes through the origin.
        let e = [to_v0, rel(v[1]), rel(v[2])];
        // The corners all strictly outside the plane through the origin and edge (a, b), on
        // the far side from the third vertex `c`. (A closure called thrice, not an array
        // `map`, which LLVM leaves as a call passing vectors through memory.)
        let corners_outside = |a: [V; 3], b: [V; 3], c: [V; 3]| {
            let normal = cross(a, b);
            let room = tolerance * dot(normal, normal);
            let third = dot(normal, c);
            let mut all_out = (third * third).gt(room * dot(c, c));
            for q in 0..4 {
                let side = dot(normal, corner(q));
                let d_len_sq = lanes(&frusta.corner_len_sq[q]);
                all_out = all_out & (side * third).lt(zero) & (side * side).gt(room * d_len_sq);
            }
            all_out
        };
        let outside = corners_outside(e[0], e[1], e[2])
            | corners_outside(e[1], e[2], e[0])
            | corners_outside(e[2], e[0], e[1]);
        let mut culled = all_above | all_below | outside;
        if backface {
            // Back-face culling: the origin behind the triangle's plane (n = e1 × e2), so
            // every ray from it meets the back.
            culled = culled | at_origin.lt(zero);
        }
        keep |= V::bits(!culled) << base;
    }
    keep & candidates
}
