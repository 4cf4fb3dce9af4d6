//! The bounding frustum of a packet (Overbeck et al. 2008 §4) and its culling tests (Eq. 1): a box
//! or triangle is culled when all its vertices lie outside the same side plane.
//!
//! Every frustum here has the same shape: along the packet's dominant axis `k` (the largest
//! component of the summed directions, §4.2) with `τ = σ·(p_k − k0)` the distance along it (`σ` the
//! side the rays travel to), the frustum is
//! `lo_j + τ·slope_lo_j ≤ p_j ≤ hi_j + τ·slope_hi_j` for the two other axes `j`, and `τ ≥ τ_near`.
//! Its four side planes are Eq. 2–3's planes through neighbouring corner rays, written in this
//! "simplified" form (§4.2–4.3: the corner rays' k-coordinate is ±1 and neighbours share a u or a
//! v). The class is decided from the data, never from the ray kind:
//!
//! - **Shared origin** (§4.1; camera rays of a pinhole): every origin is bitwise the same point
//!   `O`. Apex `O`, slopes the extremes of `d_j / (σ d_k)`. For an n×n block of pinhole rays those
//!   extremes are the corner rays' (a ratio of linear functions of screen position is extremal at
//!   the rectangle's corners), so this is §4.1's corner-ray frustum; taking them over all rays
//!   also bounds partial packets and packets not laid out as screen blocks.
//! - **Shared end point** (§4.2; point-light shadow rays): every ray's line passes within a small
//!   fraction of its length of one point `A`, which lies beyond every segment's end. The batch's
//!   shadow rays stop just short of the light (`render::rays::shadow_ray`), so `o + d·tmax` are not
//!   one point; we find `A` as the closest point of two of the lines and check the others. Apex `A`,
//!   dominant axis from the directions seen from the light (`−d`); the slopes are the extremes over
//!   both end points of every segment — the cone over `A` spanned by a segment's ends contains the
//!   segment, so the frustum is conservative whatever `A`'s rounding.
//! - **General** (§4.3; diffuse, reflection and mixed packets): a near plane at the origins'
//!   nearest `k` and a far plane at the scene box's farthest; the extremes of the rays' crossings
//!   of both planes give the corner rays' origins and directions. Every ray's part between the
//!   planes lies within the convex hull of those crossings, and no geometry lies past the far
//!   plane.
//!
//! **Far plane** (our addition): once every lane has a closest hit, no ray point that matters lies
//! beyond `τ_far`, the largest `τ` a ray reaches at the packet's largest current hit distance
//! (`clip_far`, after each leaf); boxes and triangles wholly beyond it are culled. Shared-origin
//! and general frusta only (along a shared-end packet `τ` decreases).
//!
//! A packet gets no frustum (no culling) when some ray does not travel strictly towards `σ` along
//! `k` (e.g. a diffuse packet whose bounces go both ways along every axis) or a value is not
//! finite.
//!
//! Rounding: every test compares against the bound widened by `eps = MARGIN·M·(1 + max|slope|)`,
//! `M` the largest coordinate magnitude involved (scene box, origins, apex). Computing a bound,
//! a slope times a distance, or a ray's point is off by a few ulps of `M·(1 + |slope|)`; the margin
//! is ~500 times that, so culling never drops something a ray's watertight test hits.

use glam::Vec3;

use crate::geometry::{Aabb, Rays, Triangle};

use super::workspace::lane_sum;

/// Relative width of the safety margin: 2⁻¹⁵ (module doc).
const MARGIN: f32 = 1.0 / 32768.0;
/// A packet's lines meet in one point when each passes that close to it, relative to the
/// distance from its origin (well above the shadow rays' rounding, far below any real spread).
const MEET_TOLERANCE: f32 = 1e-4;

/// How the frustum was built (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrustumKind {
    SharedOrigin,
    SharedEnd,
    General,
}

#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    pub kind: FrustumKind,
    k: usize,
    /// The two other axes.
    j: [usize; 2],
    sigma: f32,
    k0: f32,
    lo: [f32; 2],
    hi: [f32; 2],
    slope_lo: [f32; 2],
    slope_hi: [f32; 2],
    tau_near: f32,
    /// Far plane: no ray point lies beyond `τ = far_base + far_rate·t` for `t` at most the
    /// packet's largest current closest hit (`clip_far`); ∞ until then, and always for shared end
    /// points (their τ decreases along the rays).
    tau_far: f32,
    far_base: f32,
    far_rate: f32,
    eps: f32,
}

/// Extremes of a set of values.
#[derive(Clone, Copy)]
struct Range {
    lo: f32,
    hi: f32,
}

/// The per-lane extremes of a frustum set-up's `L`-wide accumulators folded into its two slope
/// ranges and its nearest depth (min and max of non-NaN values do not depend on the order).
fn fold_lanes<const L: usize>(
    lo: &[[f32; L]; 2],
    hi: &[[f32; L]; 2],
    near: &[f32; L],
) -> ([Range; 2], f32) {
    let slope = [0, 1].map(|s| Range {
        lo: lo[s].iter().copied().fold(f32::INFINITY, f32::min),
        hi: hi[s].iter().copied().fold(f32::NEG_INFINITY, f32::max),
    });
    (slope, near.iter().copied().fold(f32::INFINITY, f32::min))
}

impl Range {
    const EMPTY: Range = Range {
        lo: f32::INFINITY,
        hi: f32::NEG_INFINITY,
    };
    fn add(&mut self, x: f32) {
        self.lo = self.lo.min(x);
        self.hi = self.hi.max(x);
    }
}

fn max_abs(v: Vec3) -> f32 {
    v.abs().max_element()
}

impl Frustum {
    /// The frustum of `rays` (one packet) in a scene bounded by `scene`, or `None` when the
    /// packet cannot be bounded (module doc). `L`: the tracer's lane width, the width of the
    /// running extremes.
    pub fn build<const L: usize>(rays: Rays<'_>, scene: &Aabb) -> Option<Frustum> {
        let n = rays.len();
        if n == 0 || scene.is_empty() {
            return None;
        }
        // Summed lane-wise, as the packet's front-to-back order is (a sequential sum is one long
        // dependency chain).
        let dir_sum = Vec3::from_array([rays.dx, rays.dy, rays.dz].map(lane_sum::<L>));
        let k = dir_sum.abs().max_position();
        let j = [(k + 1) % 3, (k + 2) % 3];
        let scale = max_abs(scene.min).max(max_abs(scene.max));
        let same = |v: &[f32]| v.iter().all(|&x| x == v[0]);
        if same(rays.ox) && same(rays.oy) && same(rays.oz) {
            return Self::shared_origin::<L>(rays, k, j, dir_sum[k].signum(), scale);
        }
        if let Some(apex) = shared_end::<L>(rays) {
            if let Some(f) = Self::shared_end::<L>(rays, apex, k, j, -dir_sum[k].signum(), scale) {
                return Some(f);
            }
        }
        Self::general(rays, scene, k, j, dir_sum[k].signum(), scale)
    }

    fn shared_origin<const L: usize>(
        rays: Rays<'_>,
        k: usize,
        j: [usize; 2],
        sigma: f32,
        scale: f32,
    ) -> Option<Self> {
        let o = rays.ray(0).origin;
        let d = [rays.dx, rays.dy, rays.dz];
        let (dk, du, dv) = (d[k], d[j[0]], d[j[1]]);
        // Extremes kept per lane of an L-wide accumulator (the tracer's lane width) so the loop
        // vectorizes; NaN or infinite slopes are caught by `finish`, non-positive or infinite
        // `along` by `ok`; a NaN slope is skipped (a ray with a NaN direction hits nothing).
        // Whole vectors of rays (`lanes`), each lane updated with a constant index: a running
        // index `i % L` compiled to masked stores, which AMD's AVX2 cores run microcoded.
        let (mut lo, mut hi) = ([[f32::INFINITY; L]; 2], [[f32::NEG_INFINITY; L]; 2]);
        let (mut near, mut along_max, mut ok) = ([f32::INFINITY; L], [0.0f32; L], [true; L]);
        for base in (0..rays.len()).step_by(L) {
            let [dk, du, dv, tmin] = [dk, du, dv, rays.tmin].map(|src| lanes::<L>(src, base));
            for l in 0..L {
                let along = sigma * dk[l];
                ok[l] &= (along > 0.0) & (along < f32::INFINITY);
                let inv = 1.0 / along;
                for (s, d) in [du[l], dv[l]].into_iter().enumerate() {
                    let x = d * inv;
                    lo[s][l] = if x < lo[s][l] { x } else { lo[s][l] };
                    hi[s][l] = if x > hi[s][l] { x } else { hi[s][l] };
                }
                let t = tmin[l] * along;
                near[l] = if t < near[l] { t } else { near[l] };
                along_max[l] = if along > along_max[l] {
                    along
                } else {
                    along_max[l]
                };
            }
        }
        if ok.contains(&false) {
            return None;
        }
        let (slope, tau_near) = fold_lanes(&lo, &hi, &near);
        let apex = [o[j[0]], o[j[1]]];
        let far = [0.0, along_max.iter().copied().fold(0.0, f32::max)];
        Self::finish(
            FrustumKind::SharedOrigin,
            k,
            j,
            sigma,
            o[k],
            apex,
            apex,
            slope,
            tau_near,
            far,
            scale.max(max_abs(o)),
        )
    }

    /// The §4.2 frustum of apex `apex`. Extremes kept per lane of an `L`-wide accumulator and
    /// the checks folded, not returned early, so the loop vectorizes (ray by ray, with the apex
    /// search, it took as long as tracing the packet's shadow rays); min and max of non-NaN
    /// values do not depend on the order, so the frustum is the same.
    fn shared_end<const L: usize>(
        rays: Rays<'_>,
        apex: Vec3,
        k: usize,
        j: [usize; 2],
        sigma: f32,
        scale: f32,
    ) -> Option<Self> {
        let (o, d) = ([rays.ox, rays.oy, rays.oz], [rays.dx, rays.dy, rays.dz]);
        // The axes' arrays picked once: indexing by `k` and `j` inside the loop kept it scalar.
        let (ok_, dk) = (o[k], d[k]);
        let (ou, du, ov, dv) = (o[j[0]], d[j[0]], o[j[1]], d[j[1]]);
        let (ak, au, av) = (apex[k], apex[j[0]], apex[j[1]]);
        let (mut lo, mut hi) = ([[f32::INFINITY; L]; 2], [[f32::NEG_INFINITY; L]; 2]);
        let (mut near, mut magnitude) = ([f32::INFINITY; L], [0.0f32; L]);
        let mut ok = [true; L];
        for base in (0..rays.len()).step_by(L) {
            let [ok_, dk, ou, du, ov, dv, t0, t1] =
                [ok_, dk, ou, du, ov, dv, rays.tmin, rays.tmax].map(|src| lanes::<L>(src, base));
            for l in 0..L {
                for t in [t0[l], t1[l]] {
                    // `Ray::at`: the same operations, so the same point.
                    let (pk, pu, pv) = (ok_[l] + dk[l] * t, ou[l] + du[l] * t, ov[l] + dv[l] * t);
                    let tau = sigma * (pk - ak);
                    ok[l] &= (tau > 0.0) & pk.is_finite() & pu.is_finite() & pv.is_finite();
                    let (x, y) = ((pu - au) / tau, (pv - av) / tau);
                    lo[0][l] = if x < lo[0][l] { x } else { lo[0][l] };
                    hi[0][l] = if x > hi[0][l] { x } else { hi[0][l] };
                    lo[1][l] = if y < lo[1][l] { y } else { lo[1][l] };
                    hi[1][l] = if y > hi[1][l] { y } else { hi[1][l] };
                    near[l] = if tau < near[l] { tau } else { near[l] };
                    let m = pk.abs().max(pu.abs()).max(pv.abs());
                    magnitude[l] = if m > magnitude[l] { m } else { magnitude[l] };
                }
            }
        }
        let ok = ok.iter().all(|&o| o);
        if !ok {
            return None;
        }
        let (slope, tau_near) = fold_lanes(&lo, &hi, &near);
        let magnitude = magnitude
            .iter()
            .copied()
            .fold(scale.max(max_abs(apex)), f32::max);
        let a = [apex[j[0]], apex[j[1]]];
        let far = [f32::INFINITY, f32::INFINITY];
        Self::finish(
            FrustumKind::SharedEnd,
            k,
            j,
            sigma,
            apex[k],
            a,
            a,
            slope,
            tau_near,
            far,
            magnitude,
        )
    }

    fn general(
        rays: Rays<'_>,
        scene: &Aabb,
        k: usize,
        j: [usize; 2],
        sigma: f32,
        scale: f32,
    ) -> Option<Self> {
        let mut k0 = if sigma > 0.0 {
            f32::INFINITY
        } else {
            f32::NEG_INFINITY
        };
        let mut magnitude = scale;
        for i in 0..rays.len() {
            let r = rays.ray(i);
            let forward = sigma * r.dir[k] > 0.0;
            if !forward || !r.dir.is_finite() || !r.origin.is_finite() {
                return None;
            }
            k0 = if sigma > 0.0 {
                k0.min(r.origin[k])
            } else {
                k0.max(r.origin[k])
            };
            magnitude = magnitude.max(max_abs(r.origin));
        }
        let tau_of = |x: f32| sigma * (x - k0);
        // The far plane: no geometry lies beyond the scene box.
        let tau_far = tau_of(scene.min[k])
            .max(tau_of(scene.max[k]))
            .max(magnitude * MARGIN)
            .max(f32::MIN_POSITIVE);
        let (mut near, mut far) = ([Range::EMPTY; 2], [Range::EMPTY; 2]);
        let mut tau_near = f32::INFINITY;
        let (mut far_base, mut far_rate) = (0.0f32, 0.0f32);
        for i in 0..rays.len() {
            let r = rays.ray(i);
            let along = sigma * r.dir[k];
            let tau_o = tau_of(r.origin[k]);
            for s in 0..2 {
                let ratio = r.dir[j[s]] / along;
                near[s].add(r.origin[j[s]] - tau_o * ratio);
                far[s].add(r.origin[j[s]] + (tau_far - tau_o) * ratio);
            }
            tau_near = tau_near.min(tau_o + r.tmin.min(0.0) * along);
            far_base = far_base.max(tau_o);
            far_rate = far_rate.max(along);
        }
        for s in 0..2 {
            magnitude = magnitude.max(near[s].lo.abs()).max(near[s].hi.abs());
            magnitude = magnitude.max(far[s].lo.abs()).max(far[s].hi.abs());
        }
        let slope = [0, 1].map(|s| Range {
            lo: (far[s].lo - near[s].lo) / tau_far,
            hi: (far[s].hi - near[s].hi) / tau_far,
        });
        Self::finish(
            FrustumKind::General,
            k,
            j,
            sigma,
            k0,
            [near[0].lo, near[1].lo],
            [near[0].hi, near[1].hi],
            slope,
            tau_near,
            [far_base, far_rate],
            magnitude,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        kind: FrustumKind,
        k: usize,
        j: [usize; 2],
        sigma: f32,
        k0: f32,
        lo: [f32; 2],
        hi: [f32; 2],
        slope: [Range; 2],
        tau_near: f32,
        [far_base, far_rate]: [f32; 2],
        magnitude: f32,
    ) -> Option<Frustum> {
        let steepest = slope
            .iter()
            .map(|s| s.lo.abs().max(s.hi.abs()))
            .fold(0.0f32, f32::max);
        let eps = MARGIN * magnitude * (1.0 + steepest);
        let values = [
            lo[0],
            lo[1],
            hi[0],
            hi[1],
            slope[0].lo,
            slope[0].hi,
            slope[1].lo,
            slope[1].hi,
            k0,
            tau_near,
            eps,
        ];
        values.iter().all(|v| v.is_finite()).then_some(Frustum {
            kind,
            k,
            j,
            sigma,
            k0,
            lo,
            hi,
            slope_lo: [slope[0].lo, slope[1].lo],
            slope_hi: [slope[0].hi, slope[1].hi],
            tau_near,
            tau_far: f32::INFINITY,
            far_base,
            far_rate,
            eps,
        })
    }

    /// Moves the far plane to where the rays are when they reach distance `max_t`, the packet's
    /// largest current closest hit (our addition to §4: boxes behind every ray's hit are culled
    /// for the whole packet). Never moves it outwards past ∞ for shared end points.
    #[inline(always)]
    pub fn clip_far(&mut self, max_t: f32) {
        let far = self.far_base + max_t * self.far_rate;
        if far.is_finite() {
            self.tau_far = far;
        }
    }

    #[inline(always)]
    fn tau(&self, x: f32) -> f32 {
        self.sigma * (x - self.k0)
    }

    /// Whether no ray of the packet can meet the box `[lo, hi]` (Eq. 1 with the box's vertex
    /// nearest to each plane).
    #[inline(always)]
    pub fn culls_box(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        let (ta, tb) = (self.tau(lo[self.k]), self.tau(hi[self.k]));
        let (t_near, t_far) = if ta < tb { (ta, tb) } else { (tb, ta) };
        if t_far < self.tau_near - self.eps || t_near > self.tau_far + self.eps {
            return true;
        }
        for s in 0..2 {
            let axis = self.j[s];
            let (sl, sh) = (self.slope_lo[s], self.slope_hi[s]);
            if hi[axis] - (sl * t_near).min(sl * t_far) < self.lo[s] - self.eps {
                return true;
            }
            if lo[axis] - (sh * t_near).max(sh * t_far) > self.hi[s] + self.eps {
                return true;
            }
        }
        false
    }

    /// `culls_box` for `W` boxes at once (`lo[axis][box]`, `hi[axis][box]`; a wide BVH node's
    /// children), by the same operations box by box, so each box gets `culls_box`'s verdict: bit
    /// `b` set when box `b` is not culled. One SIMD pass over a node's children where the per-box
    /// test ran once per child popped.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    pub fn survivors<const W: usize>(&self, lo: &[[f32; W]; 3], hi: &[[f32; W]; 3]) -> u32 {
        let mut culled = [false; W];
        let (near_limit, far_limit) = (self.tau_near - self.eps, self.tau_far + self.eps);
        let (mut t_near, mut t_far) = ([0.0f32; W], [0.0f32; W]);
        for b in 0..W {
            let (ta, tb) = (self.tau(lo[self.k][b]), self.tau(hi[self.k][b]));
            (t_near[b], t_far[b]) = if ta < tb { (ta, tb) } else { (tb, ta) };
            culled[b] = (t_far[b] < near_limit) | (t_near[b] > far_limit);
        }
        for s in 0..2 {
            let axis = self.j[s];
            let (sl, sh) = (self.slope_lo[s], self.slope_hi[s]);
            let (below, above) = (self.lo[s] - self.eps, self.hi[s] + self.eps);
            for b in 0..W {
                let low = hi[axis][b] - (sl * t_near[b]).min(sl * t_far[b]);
                let high = lo[axis][b] - (sh * t_near[b]).max(sh * t_far[b]);
                culled[b] |= (low < below) | (high > above);
            }
        }
        let mut mask = 0;
        for b in 0..W {
            mask |= (!culled[b] as u32) << b;
        }
        mask
    }

    /// Whether no ray of the packet can meet `tri` (Eq. 1 on its three vertices).
    #[inline(always)]
    pub fn culls_triangle(&self, tri: &Triangle) -> bool {
        let tau = tri.v.map(|p| self.tau(p[self.k]));
        if tau.iter().all(|&t| t < self.tau_near - self.eps)
            || tau.iter().all(|&t| t > self.tau_far + self.eps)
        {
            return true;
        }
        for s in 0..2 {
            let axis = self.j[s];
            let below =
                (0..3).all(|i| tri.v[i][axis] - self.slope_lo[s] * tau[i] < self.lo[s] - self.eps);
            let above =
                (0..3).all(|i| tri.v[i][axis] - self.slope_hi[s] * tau[i] > self.hi[s] + self.eps);
            if below || above {
                return true;
            }
        }
        false
    }
}

/// Lanes `base .. base + L` of a batch's array; past its end, copies of ray `base` (a repeated
/// ray changes no extreme and no verdict of the folds over the rays).
#[inline(always)]
fn lanes<const L: usize>(src: &[f32], base: usize) -> [f32; L] {
    match src.get(base..base + L) {
        Some(full) => <[f32; L]>::try_from(full).expect("L lanes"),
        None => std::array::from_fn(|l| src.get(base + l).copied().unwrap_or(src[base])),
    }
}

/// The point all lines of `rays` pass through, beyond every segment's end, if there is one
/// (module doc, "shared end point"). Both passes over the rays read the batch's arrays and fold
/// their verdicts without an early exit, so they vectorize.
fn shared_end<const L: usize>(rays: Rays<'_>) -> Option<Vec3> {
    let n = rays.len();
    if n < 2 || !rays.tmax.iter().fold(true, |all, t| all & t.is_finite()) {
        return None;
    }
    let origin = |i: usize| Vec3::new(rays.ox[i], rays.oy[i], rays.oz[i]);
    let dir = |i: usize| Vec3::new(rays.dx[i], rays.dy[i], rays.dz[i]);
    let arrays = [
        rays.ox, rays.oy, rays.oz, rays.dx, rays.dy, rays.dz, rays.tmax,
    ];
    let d0 = dir(0);
    // The line most different in direction from the first pins the point down best: the last
    // of the largest `|d0 × d|²` (ray 0's own is 0, and padding repeats a chunk's first ray, so
    // neither changes which), kept per lane so the search vectorizes. A non-finite one (no
    // point to find) ends the search.
    let (mut best, mut at) = ([f32::NEG_INFINITY; L], [0u32; L]);
    for base in (0..n).step_by(L) {
        let [_, _, _, dx, dy, dz, _] = arrays.map(|src| lanes::<L>(src, base));
        for l in 0..L {
            let spread = d0.cross(Vec3::new(dx[l], dy[l], dz[l])).length_squared();
            let later = spread >= best[l];
            best[l] = if later { spread } else { best[l] };
            let i = if base + l < n { base + l } else { base };
            at[l] = if later { i as u32 } else { at[l] };
        }
    }
    let largest = best.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if !largest.is_finite() || largest == 0.0 {
        return None;
    }
    let other = (0..L)
        .filter(|&l| best[l] == largest)
        .map(|l| at[l] as usize)
        .max()?;
    let d1 = dir(other);
    let w = origin(0) - origin(other);
    let (a, b, c) = (d0.dot(d0), d0.dot(d1), d1.dot(d1));
    let (d, e) = (d0.dot(w), d1.dot(w));
    let denom = a * c - b * b;
    let independent = denom > 1e-12 * a * c;
    if !independent {
        return None;
    }
    let p0 = origin(0) + d0 * ((b * e - c * d) / denom);
    let p1 = origin(other) + d1 * ((a * e - b * d) / denom);
    let apex = (p0 + p1) * 0.5;
    let mut meets = [true; L];
    for base in (0..n).step_by(L) {
        let [ox, oy, oz, dx, dy, dz, tmax] = arrays.map(|src| lanes::<L>(src, base));
        for l in 0..L {
            let dir = Vec3::new(dx[l], dy[l], dz[l]);
            let to_apex = apex - Vec3::new(ox[l], oy[l], oz[l]);
            let along = to_apex.dot(dir) / dir.length_squared();
            let off = to_apex.cross(dir).length() / dir.length();
            meets[l] &= (along >= tmax[l]) & (off <= MEET_TOLERANCE * to_apex.length());
        }
    }
    let meets = meets.iter().all(|&m| m);
    meets.then_some(apex)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, RayBatch, RayBoxTest, RayKind, WatertightRay};
    use crate::random::SplitMix64;

    fn batch(rays: &[Ray]) -> RayBatch {
        let mut b = RayBatch::new(RayKind::Primary);
        rays.iter()
            .enumerate()
            .for_each(|(i, r)| b.push(*r, i as u32));
        b
    }

    /// An 8×8 pinhole block, shadow rays from scattered points to one light, and a general packet
    /// of rays with scattered origins and spread directions.
    fn packets(rng: &mut SplitMix64) -> Vec<(FrustumKind, Vec<Ray>)> {
        let eye = rng.vec3(-3.0, 3.0);
        let (x0, y0) = (rng.range(-1.0, 0.8), rng.range(-1.0, 0.8));
        let primary = (0..64)
            .map(|i| {
                let (x, y) = ((i % 8) as f32, (i / 8) as f32);
                let d = Vec3::new(x0 + x * 0.03, y0 + y * 0.03, -1.0).normalize();
                Ray::new(eye, d, 0.0, 4.0 + (i % 5) as f32)
            })
            .collect();
        let light = rng.vec3(-3.0, 3.0);
        let centre = rng.vec3(-3.0, 3.0);
        let shadow = (0..64)
            .map(|_| {
                let o = centre + rng.vec3(-0.4, 0.4);
                let to = light - o;
                let dist = to.length();
                Ray::new(o, to / dist, 0.0, dist * (1.0 - 1e-4))
            })
            .collect();
        let base = rng.direction();
        let general = (0..64)
            .map(|_| {
                let d = (base + rng.vec3(-0.3, 0.3)).normalize();
                Ray::new(centre + rng.vec3(-0.5, 0.5), d, 0.0, rng.range(2.0, 6.0))
            })
            .collect();
        vec![
            (FrustumKind::SharedOrigin, primary),
            (FrustumKind::SharedEnd, shadow),
            (FrustumKind::General, general),
        ]
    }

    #[test]
    fn frustum_never_culls_what_a_ray_hits() {
        let mut rng = SplitMix64::new(2026);
        let scene = Aabb::new(Vec3::splat(-6.0), Vec3::splat(6.0));
        let mut checked = [0usize; 3];
        let mut culled = [0usize; 3];
        for _ in 0..60 {
            for (kind, rays) in packets(&mut rng) {
                let b = batch(&rays);
                let Some(mut f) = Frustum::build::<16>(b.view(), &scene) else {
                    panic!("{kind:?} packet got no frustum");
                };
                f.clip_far(rays.iter().fold(0.0f32, |m, r| m.max(r.tmax)));
                assert_eq!(f.kind, kind);
                for _ in 0..200 {
                    let c = rng.vec3(-5.0, 5.0);
                    let bx = Aabb::new(c, c + rng.vec3(0.0, 1.5));
                    let tri = Triangle::new(c, c + rng.vec3(-2.0, 2.0), c + rng.vec3(-2.0, 2.0));
                    let box_hit = rays.iter().any(|r| {
                        RayBoxTest::new(r.origin, r.dir)
                            .hit(&bx, r.tmin, r.tmax)
                            .is_some()
                    });
                    let tri_hit = rays.iter().any(|r| {
                        WatertightRay::new(r.origin, r.dir)
                            .intersect(&tri, r.tmin, r.tmax)
                            .is_some()
                    });
                    let (cb, ct) = (
                        f.culls_box(bx.min.to_array(), bx.max.to_array()),
                        f.culls_triangle(&tri),
                    );
                    assert!(!(box_hit && cb), "{kind:?} frustum culled a box a ray hits");
                    assert!(
                        !(tri_hit && ct),
                        "{kind:?} frustum culled a triangle a ray hits"
                    );
                    let i = kind as usize;
                    checked[i] += 2;
                    culled[i] += cb as usize + ct as usize;
                }
            }
        }
        // The test must be able to fail: each class culls a good share of the random geometry.
        for i in 0..3 {
            assert!(
                culled[i] * 4 > checked[i],
                "class {i}: {} of {} culled",
                culled[i],
                checked[i]
            );
        }
    }

    #[test]
    fn survivors_of_eight_boxes_are_the_boxes_culls_box_keeps() {
        let mut rng = SplitMix64::new(77);
        let scene = Aabb::new(Vec3::splat(-6.0), Vec3::splat(6.0));
        let mut culled = 0;
        for _ in 0..40 {
            for (kind, rays) in packets(&mut rng) {
                let b = batch(&rays);
                let mut f = Frustum::build::<16>(b.view(), &scene).expect("a frustum");
                f.clip_far(rays.iter().fold(0.0f32, |m, r| m.max(r.tmax)));
                for _ in 0..20 {
                    let (mut lo, mut hi) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
                    for c in 0..8 {
                        let l = rng.vec3(-5.0, 5.0);
                        let h = l + rng.vec3(0.0, 1.5);
                        for a in 0..3 {
                            (lo[a][c], hi[a][c]) = (l[a], h[a]);
                        }
                    }
                    let want = (0..8).fold(0u32, |m, c| {
                        let (l, h) = ([0, 1, 2].map(|a| lo[a][c]), [0, 1, 2].map(|a| hi[a][c]));
                        m | (!f.culls_box(l, h) as u32) << c
                    });
                    assert_eq!(f.survivors(&lo, &hi), want, "{kind:?}");
                    culled += (!want & 0xff).count_ones();
                }
            }
        }
        assert!(culled > 1000, "only {culled} boxes culled");
    }

    #[test]
    fn the_frustum_does_not_depend_on_the_lane_width() {
        // Packets of every length cut from the test packets, so a partial last vector of lanes
        // (padded with copies of a ray) holds different rays: the one-lane build has no padding.
        let mut rng = SplitMix64::new(11);
        let scene = Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0));
        let mut built = 0;
        for _ in 0..20 {
            for (_, rays) in packets(&mut rng) {
                for n in [1, 5, 17, 37, 63] {
                    for first in [0, 64 - n] {
                        let b = batch(&rays[first..first + n]);
                        let one = format!("{:?}", Frustum::build::<1>(b.view(), &scene));
                        for wide in [
                            format!("{:?}", Frustum::build::<4>(b.view(), &scene)),
                            format!("{:?}", Frustum::build::<8>(b.view(), &scene)),
                            format!("{:?}", Frustum::build::<16>(b.view(), &scene)),
                        ] {
                            assert_eq!(wide, one, "{n} rays from {first}");
                        }
                        built += one.starts_with("Some") as usize;
                    }
                }
            }
        }
        assert!(built > 400, "only {built} frusta built");
    }

    #[test]
    fn packets_going_both_ways_get_no_frustum() {
        let rays = [
            Ray::new(Vec3::ZERO, Vec3::X, 0.0, 1.0),
            Ray::new(Vec3::Y, -Vec3::X, 0.0, 1.0),
        ];
        let b = batch(&rays);
        assert!(Frustum::build::<16>(b.view(), &Aabb::new(Vec3::splat(-1.0), Vec3::ONE)).is_none());
    }
}
