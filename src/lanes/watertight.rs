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
