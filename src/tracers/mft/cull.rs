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
//! Both keep a margin for rounding (`Margins`): a triangle is culled only when the test holds with
//! room to spare, so culling never removes a triangle a sample ray hits (property test in
//! `tests`).

use glam::Vec3;

use crate::geometry::Triangle;
use crate::tracers::mft::frusta::{Frusta, Margins};

/// Relative angle below which an edge-plane test does not cull (f32 rounding of the edge
/// normals and of the normalized sample directions is ~1e-7).
const ANGLE_TOLERANCE_SQ: f32 = 1e-10;

/// The frusta of `candidates` that `tri` cannot be culled for.
#[inline(always)]
pub fn keep_mask(frusta: &Frusta, tri: &Triangle, candidates: u64, m: &Margins) -> u64 {
    let [v0, v1, v2] = tri.v;
    let n = (v1 - v0).cross(v2 - v0);
    let plane_slack = 4.0 * n.length() * m.distance;
    let len = 64 - candidates.leading_zeros() as usize;
    let mut keep = 0u64;
    for base in (0..len).step_by(16) {
        let mut lanes = [false; 16];
        for (l, slot) in lanes.iter_mut().enumerate() {
            *slot = keeps(frusta, base + l, [v0, v1, v2], n, plane_slack, m);
        }
        for (l, &k) in lanes.iter().enumerate() {
            keep |= (k as u64) << (base + l);
        }
    }
    keep & candidates
}

#[inline(always)]
fn keeps(frusta: &Frusta, f: usize, v: [Vec3; 3], n: Vec3, plane_slack: f32, m: &Margins) -> bool {
    let o = Vec3::new(
        frusta.origin[0][f],
        frusta.origin[1][f],
        frusta.origin[2][f],
    );
    let corner = |q: usize| {
        Vec3::new(
            frusta.corner[q][0][f],
            frusta.corner[q][1][f],
            frusta.corner[q][2][f],
        )
    };
    let d = [corner(0), corner(1), corner(2), corner(3)];
    // Plane culling: origin and corner targets on one side.
    let at_origin = n.dot(o - v[0]);
    let side = |q: usize| at_origin + n.dot(d[q]);
    let (s0, s1, s2, s3) = (side(0), side(1), side(2), side(3));
    let all_above = at_origin.min(s0).min(s1.min(s2)).min(s3) > plane_slack;
    let all_below = at_origin.max(s0).max(s1.max(s2)).max(s3) < -plane_slack;
    // Corner-ray culling against the three edge planes through the origin.
    let e = [v[0] - o, v[1] - o, v[2] - o];
    let e_len_sq = [
        e[0].length_squared(),
        e[1].length_squared(),
        e[2].length_squared(),
    ];
    // Rounding of `e` is relative to the scene scale, not to `|e|`: near triangles need more room.
    let nearest = e_len_sq[0].min(e_len_sq[1]).min(e_len_sq[2]);
    let tolerance_sq = ANGLE_TOLERANCE_SQ * (1.0 + 1e10 * m.distance_sq / nearest);
    let mut outside = false;
    for (i, j, k) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        let normal = e[i].cross(e[j]);
        let normal_sq = normal.length_squared();
        let third = normal.dot(e[k]);
        let apart = |x: f32, len_sq: f32| x * x > tolerance_sq * normal_sq * len_sq;
        let mut all_out = apart(third, e_len_sq[k]);
        for (q, dq) in d.iter().enumerate() {
            let c = normal.dot(*dq);
            all_out &= (c * third < 0.0) & apart(c, frusta.corner_len_sq[q][f]);
        }
        outside |= all_out;
    }
    !(all_above | all_below | outside)
}
