//! The Möller–Trumbore ray–triangle test (`geometry::moller`, the test of `robust = false`) for `L`
//! rays at once, in structure-of-arrays lanes: what the lane tracers run where the scalar tracers
//! run `MollerRay::intersect`. Each lane performs the scalar test's f32 operations in its order
//! (glam's `cross` and `dot` written out; Rust never contracts `a·b + c` into an FMA), so a lane's
//! verdict, distance and barycentrics are the scalar test's bit for bit. Branch-free over
//! `[f32; L]`, which LLVM turns into L-wide vector code.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use crate::geometry::Triangle;

/// A triangle as the test reads it in every lane: its first vertex and the two edges from it,
/// `[x, y, z][lane]` (the same in every lane for a static triangle; per lane for one moving).
#[derive(Clone, Copy, Debug)]
pub struct MollerLanes<const L: usize> {
    pub v0: [[f32; L]; 3],
    pub e1: [[f32; L]; 3],
    pub e2: [[f32; L]; 3],
}

/// Which lanes hit, and each lane's distance and barycentrics (`u` weights v1, `v` weights v2);
/// only the hitting lanes' values mean anything.
pub struct LaneHits<const L: usize> {
    pub hit: [bool; L],
    pub t: [f32; L],
    pub u: [f32; L],
    pub v: [f32; L],
}

impl<const L: usize> MollerLanes<L> {
    /// `tri` in every lane: its edges computed once, as the scalar test computes them.
    #[inline(always)]
    pub fn broadcast(tri: &Triangle) -> Self {
        let [v0, v1, v2] = tri.v;
        let (e1, e2) = (v1 - v0, v2 - v0);
        let lanes = |p: glam::Vec3| [[p.x; L], [p.y; L], [p.z; L]];
        MollerLanes {
            v0: lanes(v0),
            e1: lanes(e1),
            e2: lanes(e2),
        }
    }

    /// A triangle per lane, `tri(l)` (a moving triangle where each lane's ray meets it).
    #[inline(always)]
    pub fn per_lane(used: usize, tri: impl Fn(usize) -> Triangle) -> Self {
        let mut lanes = MollerLanes {
            v0: [[0.0; L]; 3],
            e1: [[0.0; L]; 3],
            e2: [[0.0; L]; 3],
        };
        for l in 0..used {
            let [v0, v1, v2] = tri(l).v;
            let (e1, e2) = (v1 - v0, v2 - v0);
            for a in 0..3 {
                lanes.v0[a][l] = v0[a];
                lanes.e1[a][l] = e1[a];
                lanes.e2[a][l] = e2[a];
            }
        }
        lanes
    }

    /// The test of every lane's ray (`origin`, `dir`, segment `[tmin, tmax]`) against the
    /// lane's triangle: `MollerRay::intersect`'s operations and verdict, lane by lane.
    // The comparisons are written to fail on NaN, as the scalar test's.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline(always)]
    pub fn intersect(
        &self,
        origin: &[[f32; L]; 3],
        dir: &[[f32; L]; 3],
        tmin: &[f32; L],
        tmax: &[f32; L],
    ) -> LaneHits<L> {
        let mut out = LaneHits {
            hit: [false; L],
            t: [0.0; L],
            u: [0.0; L],
            v: [0.0; L],
        };
        let (v0, e1, e2) = (&self.v0, &self.e1, &self.e2);
        for l in 0..L {
            let (dx, dy, dz) = (dir[0][l], dir[1][l], dir[2][l]);
            let (ax, ay, az) = (e1[0][l], e1[1][l], e1[2][l]);
            let (bx, by, bz) = (e2[0][l], e2[1][l], e2[2][l]);
            // p = d × e2, det = e1 · p
            let (px, py, pz) = (dy * bz - by * dz, dz * bx - bz * dx, dx * by - bx * dy);
            let det = ax * px + ay * py + az * pz;
            let inv = 1.0 / det;
            // s = o − v0, u = (s · p) / det
            let sx = origin[0][l] - v0[0][l];
            let sy = origin[1][l] - v0[1][l];
            let sz = origin[2][l] - v0[2][l];
            let u = (sx * px + sy * py + sz * pz) * inv;
            // q = s × e1, v = (d · q) / det, t = (e2 · q) / det
            let (qx, qy, qz) = (sy * az - ay * sz, sz * ax - az * sx, sx * ay - ax * sy);
            let v = (dx * qx + dy * qy + dz * qz) * inv;
            let t = (bx * qx + by * qy + bz * qz) * inv;
            out.hit[l] = (det != 0.0)
                & (0.0..=1.0).contains(&u)
                & (v >= 0.0)
                & (u + v <= 1.0)
                & (t >= tmin[l])
                & (t <= tmax[l])
                & t.is_finite();
            out.t[l] = t;
            out.u[l] = u;
            out.v[l] = v;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::moller::MollerRay;
    use crate::random::SplitMix64;
    use glam::Vec3;

    /// Every lane's verdict, distance and barycentrics are `MollerRay::intersect`'s, bit for
    /// bit, for static and per-lane triangles, with rays through edges, parallel ones and
    /// degenerate triangles among random ones.
    fn lanes_are_the_scalar_test<const L: usize>() {
        let mut rng = SplitMix64::new(5);
        let mut hits = 0;
        for round in 0..500 {
            let tris: Vec<Triangle> = (0..L)
                .map(|l| {
                    let p = rng.vec3(-1.0, 1.0);
                    let (a, b) = (rng.vec3(-1.0, 1.0), rng.vec3(-1.0, 1.0));
                    match (round + l) % 11 {
                        0 => Triangle::new(p, p + a, p + a * 2.0), // degenerate
                        _ => Triangle::new(p, p + a, p + b),
                    }
                })
                .collect();
            let rays: Vec<(Vec3, Vec3, f32, f32)> = (0..L)
                .map(|l| {
                    let o = rng.vec3(-2.0, 2.0);
                    let tri = &tris[l];
                    // Aimed at a vertex, an edge's midpoint, or anywhere.
                    let target = match (round + l) % 5 {
                        0 => tri.v[1],
                        1 => (tri.v[0] + tri.v[2]) * 0.5,
                        _ => rng.vec3(-1.0, 1.0),
                    };
                    let d = match (round + l) % 13 {
                        0 => Vec3::X,
                        _ => target - o,
                    };
                    (o, d, rng.range(0.0, 0.5), rng.range(0.5, 3.0))
                })
                .collect();
            let lane = |f: fn(&(Vec3, Vec3, f32, f32)) -> Vec3| -> [[f32; L]; 3] {
                [0, 1, 2].map(|a| std::array::from_fn(|l| f(&rays[l])[a]))
            };
            let (origin, dir) = (lane(|r| r.0), lane(|r| r.1));
            let tmin = std::array::from_fn(|l| rays[l].2);
            let tmax = std::array::from_fn(|l| rays[l].3);
            let moving =
                MollerLanes::<L>::per_lane(L, |l| tris[l]).intersect(&origin, &dir, &tmin, &tmax);
            let fixed =
                MollerLanes::<L>::broadcast(&tris[0]).intersect(&origin, &dir, &tmin, &tmax);
            for (l, &(o, d, t0, t1)) in rays.iter().enumerate() {
                for (got, tri) in [(&moving, &tris[l]), (&fixed, &tris[0])] {
                    let want = MollerRay::new(o, d).intersect(tri, t0, t1);
                    let bits = |(t, u, v): (f32, f32, f32)| [t, u, v].map(f32::to_bits);
                    let lane = got.hit[l].then(|| bits((got.t[l], got.u[l], got.v[l])));
                    assert_eq!(lane, want.map(bits), "L = {L}, round {round}, lane {l}");
                    hits += want.is_some() as usize;
                }
            }
        }
        // Not vacuous: many hits among the misses.
        assert!(hits > 50 * L, "{hits} hits");
    }

    #[test]
    fn lanes_agree_bit_for_bit_with_the_scalar_test() {
        lanes_are_the_scalar_test::<4>();
        lanes_are_the_scalar_test::<8>();
        lanes_are_the_scalar_test::<16>();
    }
}
