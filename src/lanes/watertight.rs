//! The f32 stage of the watertight ray–triangle test (Woop, Benthin and Wald 2013) for `L` rays
//! at once, in structure-of-arrays lanes: what `SimdRay` and coherent grid traversal's lanes both
//! run. Each lane computes `WatertightRay::intersect`'s f32 operations in
//! its order (Rust never contracts `a·b + c` into an FMA), so a lane's verdict is the scalar
//! test's. The lane loops are branch-free over `[f32; L]`, which LLVM turns into L-wide vector
//! code (`target-cpu=native`; AVX-512 holds 16 lanes).
//!
//! Edge functions that come out exactly zero are ambiguous in f32, and ill-conditioned ones
//! (needles, grazing hits) imprecise; the scalar test recomputes them in f64
//! (`geometry::needs_f64`). Callers deal with those lanes (`needs_f64`): redo them in f64
//! (`redo_edges_in_f64`) or hand them to the scalar test.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use super::LaneMask;
use crate::geometry::triangle::{self, edge_product_scale};

/// A triangle vertex in every lane's frame: `[x, y, z][lane]`, relative to the lane's origin
/// along its axes `kx, ky, kz`.
pub type Permuted<const L: usize> = [[f32; L]; 3];

/// The axes `[kx, ky, kz]` the first `used` lanes all share (`axes[a][lane]`), if they do: then a
/// vertex is reordered once for every lane rather than picked lane by lane.
#[inline(always)]
pub fn common_axes<const L: usize>(axes: &[[u32; L]; 3], used: usize) -> Option<[usize; 3]> {
    let k0 = [axes[0][0], axes[1][0], axes[2][0]];
    let mut differ = 0u32;
    for (lanes, k) in axes.iter().zip(k0) {
        for &lane in &lanes[..used] {
            differ |= (lane != k) as u32;
        }
    }
    (differ == 0).then(|| k0.map(|k| k as usize))
}

/// Origin-relative coordinates `rel` (`[x, y, z][lane]`) reordered into each lane's watertight
/// frame `[kx, ky, kz]` (`axes[a][lane]`, the axes `WatertightRay` picks); `common`: the axes
/// every lane shares, if known (`common_axes`).
#[inline(always)]
pub fn in_lane_frames<const L: usize>(
    rel: [[f32; L]; 3],
    axes: &[[u32; L]; 3],
    common: Option<[usize; 3]>,
) -> Permuted<L> {
    match common {
        Some([kx, ky, kz]) => [rel[kx], rel[ky], rel[kz]],
        None => {
            let mut out = [[0.0f32; L]; 3];
            for (o, k) in out.iter_mut().zip(axes) {
                for l in 0..L {
                    o[l] = match k[l] {
                        0 => rel[0][l],
                        1 => rel[1][l],
                        _ => rel[2][l],
                    };
                }
            }
            out
        }
    }
}

/// The edge functions `[U, V, W][lane]` of the triangle `a, b, c` sheared into each lane's ray
/// space (`shear` = `[sx, sy, sz][lane]`), and the magnitude of the products they are
/// differences of (`edge_product_scale`).
#[inline(always)]
pub fn edge_functions<const L: usize>(
    shear: &[[f32; L]; 3],
    a: &Permuted<L>,
    b: &Permuted<L>,
    c: &Permuted<L>,
) -> ([[f32; L]; 3], [f32; L]) {
    let [sx, sy, _] = shear;
    let mut e = [[0.0f32; L]; 3];
    let mut scale = [0.0f32; L];
    for l in 0..L {
        let (ax, ay) = (a[0][l] - sx[l] * a[2][l], a[1][l] - sy[l] * a[2][l]);
        let (bx, by) = (b[0][l] - sx[l] * b[2][l], b[1][l] - sy[l] * b[2][l]);
        let (cx, cy) = (c[0][l] - sx[l] * c[2][l], c[1][l] - sy[l] * c[2][l]);
        e[0][l] = cx * by - cy * bx;
        e[1][l] = ax * cy - ay * cx;
        e[2][l] = bx * ay - by * ax;
        scale[l] = edge_product_scale([ax, ay], [bx, by], [cx, cy]);
    }
    (e, scale)
}

/// Whether any lane may hit: not every lane passes strictly outside an edge. A lane whose edge
/// functions have both signs and none is zero is a miss in the scalar test before any f64 redo
/// (it is not inside, so `geometry::needs_f64` is false there, and `accept` rejects it), so a
/// SIMD ray whose lanes all do is done here — most SIMD rays at most triangles of a leaf —
/// without the f64 check, the acceptance test and the hit update.
// `u != 0.0` rather than `!(u == 0.0)`: NaN counts as non-zero, as in the scalar test.
#[inline(always)]
pub fn any_may_hit<const L: usize>(e: &[[f32; L]; 3]) -> bool {
    let mut any = 0u32;
    for l in 0..L {
        let (u, v, w) = (e[0][l], e[1][l], e[2][l]);
        let outside = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
        let nonzero = (u != 0.0) & (v != 0.0) & (w != 0.0);
        any |= !(outside & nonzero) as u32;
    }
    any != 0
}

/// The lanes whose edge functions the scalar test redoes in f64 (`geometry::needs_f64`).
#[inline(always)]
pub fn needs_f64<const L: usize>(e: &[[f32; L]; 3], scale: &[f32; L]) -> LaneMask<L> {
    LaneMask::from_fn(|l| triangle::needs_f64(e[0][l], e[1][l], e[2][l], scale[l]))
}

/// Which lanes hit, from their edge functions: inside (all of one sign), a non-zero determinant
/// and a distance in `[tmin, tmax]`. Also each lane's scaled distance and |determinant|
/// (`t = t_scaled / abs_det`).
// The negated comparisons are the scalar test's, NaN cases included.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[inline(always)]
pub fn accept<const L: usize>(
    e: &[[f32; L]; 3],
    sz: &[f32; L],
    z: [&[f32; L]; 3],
    tmin: &[f32; L],
    tmax: &[f32; L],
) -> ([bool; L], [f32; L], [f32; L]) {
    let (mut hit, mut t_scaled, mut abs_det) = ([false; L], [0.0f32; L], [0.0f32; L]);
    for l in 0..L {
        let (u, v, w) = (e[0][l], e[1][l], e[2][l]);
        let outside = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
        let det = u + v + w;
        let ts = u * sz[l] * z[0][l] + v * sz[l] * z[1][l] + w * sz[l] * z[2][l];
        let (ts, ad) = if det < 0.0 { (-ts, -det) } else { (ts, det) };
        let in_range = !(ts < tmin[l] * ad) & !(ts > tmax[l] * ad);
        hit[l] = !outside & (det != 0.0) & in_range;
        t_scaled[l] = ts;
        abs_det[l] = ad;
    }
    (hit, t_scaled, abs_det)
}

/// The edge functions of the lanes in `redo`, recomputed in f64 from the same sheared
/// coordinates, exactly as `WatertightRay::intersect` does.
#[cold]
pub fn redo_edges_in_f64<const L: usize>(
    shear: &[[f32; L]; 3],
    a: &Permuted<L>,
    b: &Permuted<L>,
    c: &Permuted<L>,
    e: &mut [[f32; L]; 3],
    redo: LaneMask<L>,
) {
    let [sx, sy, _] = shear;
    let f = |x: f32| x as f64;
    for l in redo.iter() {
        let (ax, ay) = (a[0][l] - sx[l] * a[2][l], a[1][l] - sy[l] * a[2][l]);
        let (bx, by) = (b[0][l] - sx[l] * b[2][l], b[1][l] - sy[l] * b[2][l]);
        let (cx, cy) = (c[0][l] - sx[l] * c[2][l], c[1][l] - sy[l] * c[2][l]);
        e[0][l] = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
        e[1][l] = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
        e[2][l] = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Edge functions `[U, V, W]` of four lanes, one lane per case.
    fn lanes(cases: [[f32; 3]; 4]) -> [[f32; 4]; 3] {
        [0, 1, 2].map(|k| cases.map(|c| c[k]))
    }

    #[test]
    fn only_lanes_strictly_outside_an_edge_are_certain_misses() {
        let outside = [1.0, -2.0, 3.0];
        // Each case alone in lane 0, the other lanes strictly outside.
        let with = |case: [f32; 3]| any_may_hit(&lanes([case, outside, outside, outside]));
        assert!(!with(outside), "every lane strictly outside");
        assert!(with([1.0, 2.0, 3.0]), "inside, front face");
        assert!(with([-1.0, -2.0, -3.0]), "inside, back face");
        // A zero edge function with both signs elsewhere: the f64 redo decides.
        assert!(with([0.0, -2.0, 3.0]));
        assert!(with([-0.0, -2.0, 3.0]));
        // NaN is non-zero and neither sign, as in the scalar test: with both signs in the other
        // two, a certain miss; with one sign only, not.
        assert!(!with([f32::NAN, -2.0, 3.0]));
        assert!(with([f32::NAN, 2.0, 3.0]));
    }

    /// `any_may_hit` is false only where the scalar test misses: every lane of a certain-miss
    /// group is a miss of `WatertightRay::intersect` without f64 (`needs_f64` false) and
    /// rejected by `accept`.
    #[test]
    fn a_certain_miss_needs_no_f64_and_is_rejected() {
        let e = lanes([
            [1.0, -2.0, 3.0],
            [-1e-30, 5.0, 1.0],
            [f32::NAN, -1.0, 1.0],
            [f32::INFINITY, -1.0, 1.0],
        ]);
        assert!(!any_may_hit(&e));
        assert_eq!(needs_f64(&e, &[1.0; 4]), LaneMask::NONE);
        let one = [1.0f32; 4];
        let (hit, _, _) = accept(&e, &one, [&one, &one, &one], &[0.0; 4], &[f32::MAX; 4]);
        assert_eq!(hit, [false; 4]);
    }
}
