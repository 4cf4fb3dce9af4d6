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
//!
//! Both keep a margin for rounding, relative to the magnitudes involved: a triangle is culled only when the test holds with
//! room to spare, so culling never removes a triangle a sample ray hits (property test in
//! `tests`).

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use crate::geometry::Triangle;
use crate::tracers::mft::frusta::{Frusta, MAX_FRUSTA, W};

/// Relative angle below which an edge-plane test does not cull, squared: `v − o` is rounded
/// relative to its own length, as the watertight test rounds it, and the sample directions are
/// normalized in f32, so both are off by ~1e-7 rad.
const ANGLE_TOLERANCE_SQ: f32 = 1e-10;

/// Rounding allowance per unit of magnitude in the plane test (f32 rounding is 6e-8; a few
/// roundings of the dot products and of the normalized sample rays stay well under 1e-6).
const RELATIVE_ROUNDING: f32 = 1e-6;

/// The frusta of `candidates` that `tri` cannot be culled for: 16 frusta per pass of plain lane
/// loops, which LLVM vectorizes.
#[inline(always)]
pub fn keep_mask(frusta: &Frusta, tri: &Triangle, candidates: u64) -> u64 {
    let [v0, v1, v2] = tri.v.map(|v| v.to_array());
    let (e1, e2) = (tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]);
    let n = e1.cross(e2).to_array();
    // The plane test's rounding: relative to |n| and the lengths it is computed from, times the
    // distances involved (`RELATIVE_ROUNDING` per unit).
    let tri_scale = RELATIVE_ROUNDING * (e1.cross(e2).length() + e1.length() * e2.length());
    let tri_extent = e1.abs().element_sum() + e2.abs().element_sum();
    let len = 64 - candidates.leading_zeros() as usize;
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let mut keep = 0u64;
    for base in (0..len).step_by(W) {
        let lanes = |x: &[f32; MAX_FRUSTA]| -> [f32; W] { x[base..base + W].try_into().unwrap() };
        let o: [[f32; W]; 3] = std::array::from_fn(|a| lanes(&frusta.origin[a]));
        let d: [[[f32; W]; 3]; 4] =
            std::array::from_fn(|q| std::array::from_fn(|a| lanes(&frusta.corner[q][a])));
        let d_len_sq: [[f32; W]; 4] = std::array::from_fn(|q| lanes(&frusta.corner_len_sq[q]));
        let reach = lanes(&frusta.reach);
        for l in 0..W {
            let origin = [o[0][l], o[1][l], o[2][l]];
            let corner = |q: usize| [d[q][0][l], d[q][1][l], d[q][2][l]];
            let rel = |v: [f32; 3]| [v[0] - origin[0], v[1] - origin[1], v[2] - origin[2]];
            // Plane culling: origin and corner targets on one side.
            let to_v0 = rel(v0);
            let at_origin = -dot(n, to_v0);
            let distances = to_v0[0].abs() + to_v0[1].abs() + to_v0[2].abs() + reach[l];
            let plane_slack = tri_scale * (distances + tri_extent);
            let (s0, s1) = (at_origin + dot(n, corner(0)), at_origin + dot(n, corner(1)));
            let (s2, s3) = (at_origin + dot(n, corner(2)), at_origin + dot(n, corner(3)));
            // Comparisons, not `f32::min` (whose NaN rule costs three instructions a step): a
            // NaN fails them and culls nothing.
            let all_above = (at_origin > plane_slack)
                & (s0 > plane_slack)
                & (s1 > plane_slack)
                & (s2 > plane_slack)
                & (s3 > plane_slack);
            let all_below = (at_origin < -plane_slack)
                & (s0 < -plane_slack)
                & (s1 < -plane_slack)
                & (s2 < -plane_slack)
                & (s3 < -plane_slack);
            // Corner-ray culling against the three edge planes through the origin.
            let e = [to_v0, rel(v1), rel(v2)];
            let e_len_sq = [dot(e[0], e[0]), dot(e[1], e[1]), dot(e[2], e[2])];
            let mut outside = false;
            for (i, j, k) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
                let normal = cross(e[i], e[j]);
                let room = ANGLE_TOLERANCE_SQ * dot(normal, normal);
                let third = dot(normal, e[k]);
                let mut all_out = third * third > room * e_len_sq[k];
                for q in 0..4 {
                    let c = dot(normal, corner(q));
                    all_out &= (c * third < 0.0) & (c * c > room * d_len_sq[q][l]);
                }
                outside |= all_out;
            }
            let kept = !(all_above | all_below | outside);
            keep |= (kept as u64) << (base + l);
        }
    }
    keep & candidates
}
