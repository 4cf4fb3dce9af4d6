//! Triangles and the watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013,
//! "Watertight Ray/Triangle Intersection"). Rays that pass through a shared edge or vertex hit
//! at least one of the triangles meeting there; degenerate triangles never hit and never make NaN.

use glam::Vec3;

use super::Aabb;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v: [Vec3; 3],
}

impl Triangle {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Triangle { v: [a, b, c] }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.v)
    }

    pub fn centroid(&self) -> Vec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }

    /// Unnormalised geometric normal (v1 − v0) × (v2 − v0).
    pub fn normal(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    pub fn area(&self) -> f32 {
        0.5 * self.normal().length()
    }

    pub fn is_finite(&self) -> bool {
        self.v.iter().all(|p| p.is_finite())
    }

    /// Each vertex moved linearly from this triangle's to `other`'s by `t` (motion blur: the
    /// triangle at time `t` of a shutter interval that starts at `self` and ends at `other`).
    #[inline(always)]
    pub fn lerp(&self, other: &Triangle, t: f32) -> Triangle {
        Triangle {
            v: [
                self.v[0].lerp(other.v[0], t),
                self.v[1].lerp(other.v[1], t),
                self.v[2].lerp(other.v[2], t),
            ],
        }
    }

    /// The point with Embree-convention barycentrics: `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        self.v[0] * (1.0 - u - v) + self.v[1] * u + self.v[2] * v
    }
}

/// A ray transformed once for many watertight triangle tests (Woop et al. §3, "pre-computation"):
/// the axis `kz` of largest |dir| becomes z, and a shear maps the direction onto +z.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: [f32; 3],
    k: [usize; 3],
    shear: [f32; 3],
}

/// Component `k` of `x`, by selects rather than indexing, so loops over many rays whose axes
/// differ lane by lane vectorize.
#[inline(always)]
pub fn axis_component(x: [f32; 3], k: usize) -> f32 {
    if k == 0 {
        x[0]
    } else if k == 1 {
        x[1]
    } else {
        x[2]
    }
}

/// Below this ratio of |U + V + W| to the magnitude of the edge functions' first products
/// (`edge_product_scale`), a ray that passes inside every edge has lost more than 4 of f32's 24
/// bits to cancellation: a needle-thin triangle (aspect ratio ≳ 16) or a grazing ray. There the
/// f32 edge functions put the hit distance off by up to 2⁴ times their rounding: at 2⁻¹¹ (the
/// bound until issue 30) a diffuse ray leaving one needle of a crowded fan for its neighbour
/// 10⁻² away got its distance up to 10⁻⁵ (90 ULPs of the coordinates) off, where the f64 truth
/// and Embree's robust test agree to 10⁻⁹; the stability suite's slivers were off by up to
/// 2·10⁻⁴ relative, or on the wrong side of the origin, at 2⁻¹⁰. f64 edge functions from the
/// same sheared coordinates are accurate to ~10⁻⁸.
pub const ILL_CONDITIONED: f32 = 1.0 / 16.0;

/// |cx·by| + |ax·cy| + |bx·ay|: one product of each edge function (U = cx·by − cy·bx, …). Where
/// an edge function cancels, its two products are nearly equal, so this is half the scale of
/// their rounding errors — at half the cost of summing all six.
#[inline(always)]
pub fn edge_product_scale(a: [f32; 2], b: [f32; 2], c: [f32; 2]) -> f32 {
    (c[0] * b[1]).abs() + (a[0] * c[1]).abs() + (b[0] * a[1]).abs()
}

/// Whether the f32 edge functions `u, v, w` (of product scale `scale`) must be redone in f64:
/// one is exactly zero, or the ray passes inside every edge with the edge functions
/// ill-conditioned (`ILL_CONDITIONED`). Rays passing outside an edge by more than rounding keep
/// their f32 answer, so the f64 path runs only for hits on needles and grazing hits.
#[inline(always)]
pub fn needs_f64(u: f32, v: f32, w: f32, scale: f32) -> bool {
    let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
    let inside = ((u >= 0.0) & (v >= 0.0) & (w >= 0.0)) | ((u <= 0.0) & (v <= 0.0) & (w <= 0.0));
    zero | (inside & ((u + v + w).abs() < ILL_CONDITIONED * scale))
}

impl WatertightRay {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        // The axis of the largest |component| (ties to x, then y) and the other two in the order
        // that keeps the triangle's winding when that component is negative, by selects rather
        // than branches: on incoherent rays the branches' outcome is random.
        let is_x = (a.x >= a.y) & (a.x >= a.z);
        let is_y = !is_x & (a.y >= a.z);
        let kz = usize::from(!is_x) * (1 + usize::from(!is_y));
        let d = dir.to_array();
        let dz = d[kz];
        // [kx, ky] for each kz, positive then negative dz.
        const AXES: [[usize; 2]; 6] = [[1, 2], [2, 0], [0, 1], [2, 1], [0, 2], [1, 0]];
        let [kx, ky] = AXES[kz + 3 * usize::from(dz < 0.0)];
        let pick = |k: usize| d[k];
        WatertightRay {
            origin: origin.to_array(),
            k: [kx, ky, kz],
            shear: [pick(kx) / dz, pick(ky) / dz, 1.0 / dz],
        }
    }

    /// The precomputed origin, axes `[kx, ky, kz]` and shear `[sx, sy, sz]`: for SIMD versions of
    /// `intersect` over many rays, which must compute bit for bit what it computes.
    #[inline(always)]
    pub fn parts(&self) -> ([f32; 3], [usize; 3], [f32; 3]) {
        (self.origin, self.k, self.shear)
    }

    /// The ray from `origin` whose direction gave the axes `k` and shear `shear` (`parts`), as
    /// `new` makes it: for callers that keep the frame, not the direction (the stream tracer).
    #[inline(always)]
    pub fn from_parts(origin: [f32; 3], k: [usize; 3], shear: [f32; 3]) -> Self {
        WatertightRay { origin, k, shear }
    }

    /// `(t, u, v)` if the ray hits `tri` with `tmin <= t <= tmax`; both faces count.
    #[inline(always)]
    pub fn intersect(&self, tri: &Triangle, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let o = self.origin;
        let rel = |p: Vec3| {
            let p = p.to_array();
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        };
        let (a, b, c) = (rel(tri.v[0]), rel(tri.v[1]), rel(tri.v[2]));
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        let outside = |u: f32, v: f32, w: f32| {
            (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)
        };
        // Outside, with no zero edge function: no f64 redo (`needs_f64`) can follow, so done
        // without computing its scale.
        if u != 0.0 && v != 0.0 && w != 0.0 && outside(u, v, w) {
            return None;
        }
        // Exactly zero edge functions are ambiguous in f32 (Woop et al. §4), and ill-conditioned
        // ones are imprecise: redo them in f64.
        if needs_f64(u, v, w, edge_product_scale([ax, ay], [bx, by], [cx, cy])) {
            let f = |x: f32| x as f64;
            u = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
            v = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
            w = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
        }
        if outside(u, v, w) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz];
        watertight_hit(u, v, w, t_scaled, tmin, tmax)
    }
}

/// The watertight test's last stage, from the edge functions `u, v, w` of a ray inside the
/// triangle with `u + v + w ≠ 0` and its scaled distance `t_scaled`: `(t, u, v)` if
/// `t = t_scaled / (u + v + w)` lies in `[tmin, tmax]`, compared before dividing. Shared with the
/// 4-triangle block test (`lanes::triangle_block`), which finishes its hitting lanes here.
#[inline(always)]
pub fn watertight_hit(
    u: f32,
    v: f32,
    w: f32,
    t_scaled: f32,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    let det = u + v + w;
    let (t_scaled, abs_det) = if det < 0.0 {
        (-t_scaled, -det)
    } else {
        (t_scaled, det)
    };
    if t_scaled < tmin * abs_det || t_scaled > tmax * abs_det {
        return None;
    }
    let inv = 1.0 / det;
    let t = t_scaled / abs_det;
    // Embree convention: u weights v1, v weights v2.
    t.is_finite().then_some((t, v * inv, w * inv))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    fn shoot(o: Vec3, d: Vec3, t: &Triangle) -> Option<(f32, f32, f32)> {
        WatertightRay::new(o, d).intersect(t, 0.0, f32::INFINITY)
    }

    #[test]
    fn interior_hit_has_distance_and_barycentrics() {
        let (t, u, v) = shoot(Vec3::new(0.25, 0.5, 1.0), -Vec3::Z, &tri()).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        assert!(tri().point(u, v).distance(Vec3::new(0.25, 0.5, 0.0)) < 1e-6);
        // Back face counts too.
        assert!(shoot(Vec3::new(0.25, 0.25, -1.0), Vec3::Z, &tri()).is_some());
    }

    #[test]
    fn edges_and_vertices_are_hit() {
        for p in [
            Vec3::new(0.5, 0.0, 0.0), // edge v0-v1
            Vec3::new(0.0, 0.5, 0.0), // edge v0-v2
            Vec3::new(0.5, 0.5, 0.0), // hypotenuse
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
        ] {
            assert!(
                shoot(p + Vec3::Z, -Vec3::Z, &tri()).is_some(),
                "point {p:?}"
            );
        }
        assert!(shoot(Vec3::new(0.6, 0.6, 1.0), -Vec3::Z, &tri()).is_none());
    }

    #[test]
    fn shared_edge_is_hit_by_at_least_one_of_two_triangles() {
        // Two triangles sharing the diagonal of the unit square; rays along the diagonal.
        let a = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0));
        let b = Triangle::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        for i in 1..100 {
            let s = i as f32 / 100.0;
            // Aim exactly at a point of the shared diagonal.
            let d = Vec3::new(0.013, -0.007, -1.0);
            let o = Vec3::new(s, s, 0.0) - d;
            assert!(
                shoot(o, d, &a).is_some() || shoot(o, d, &b).is_some(),
                "ray {i} fell through the shared edge"
            );
        }
    }

    #[test]
    fn degenerate_triangles_never_hit_and_never_nan() {
        let degenerate = [
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0), // collinear
            Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO), // a point
            Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::Y),      // two equal vertices
        ];
        for t in &degenerate {
            for d in [
                -Vec3::Z,
                Vec3::new(0.3, 0.1, -1.0),
                -Vec3::Y,
                Vec3::new(-0.0, -1.0, 0.0),
            ] {
                let o = Vec3::new(0.5, 0.5, 1.0);
                let r = shoot(o, d, t);
                assert!(r.is_none(), "degenerate {t:?} hit by {d:?}: {r:?}");
            }
        }
    }

    #[test]
    fn distance_range_is_respected() {
        let r = WatertightRay::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        assert!(r.intersect(&tri(), 0.0, 0.5).is_none());
        assert!(r.intersect(&tri(), 1.5, 9.0).is_none());
        assert!(r.intersect(&tri(), 1.0, 1.0).is_some());
    }

    #[test]
    fn axis_parallel_and_negative_zero_directions() {
        let t = Triangle::new(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        );
        assert!(shoot(Vec3::new(1.0, 0.2, 0.2), Vec3::new(-1.0, 0.0, -0.0), &t).is_some());
        assert!(shoot(Vec3::new(-1.0, 0.2, 0.2), Vec3::new(1.0, -0.0, -0.0), &t).is_some());
    }

    /// The frame is Woop et al.'s: `kz` the axis of the largest |component| (ties to the lower
    /// axis), `kx, ky` the next two in cyclic order, swapped when that component is negative
    /// (−0.0 is not), and the shear from the picked components; on ties, zeros and both signs.
    #[test]
    fn frame_is_the_largest_axis_with_winding_kept() {
        let values = [0.0, -0.0, 1.0, -1.0, 0.5, -2.0, 2.0];
        for x in values {
            for y in values {
                for z in values {
                    let d = [x, y, z];
                    let a = d.map(f32::abs);
                    let kz = (0..3).fold(0, |best, k| if a[k] > a[best] { k } else { best });
                    let (next, after) = ((kz + 1) % 3, (kz + 2) % 3);
                    let (kx, ky) = if d[kz] < 0.0 {
                        (after, next)
                    } else {
                        (next, after)
                    };
                    let (_, k, shear) = WatertightRay::new(Vec3::ZERO, Vec3::from(d)).parts();
                    assert_eq!(k, [kx, ky, kz], "dir {d:?}");
                    let want = [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]];
                    assert_eq!(shear.map(f32::to_bits), want.map(f32::to_bits), "dir {d:?}");
                }
            }
        }
    }
}
