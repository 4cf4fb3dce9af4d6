//! A block of shadow frusta (Benthin & Wald 2009 §4.4): one frustum per shading point, from the
//! point's ray origin to the rectangle of the light, in (s, t), that bounds the point's live
//! samples. Stored lane by lane (structure of arrays over frusta), so the box test of every
//! frustum against one BVH box is one pass of vector operations (§4: "one SIMD test per node for
//! all frusta").
//!
//! A frustum is described by its origin `o` and its four corner rays `D_q = corner_q − o`, not
//! normalized: every live sample ray is `o + u·D`, u ∈ [0, 1], with `D` a convex combination of
//! the `D_q` (the light is affine in (s, t)). So bounds taken over the corners bound every ray,
//! exactly in real arithmetic; the margins of `Margins` cover rounding (the sample rays are
//! normalized, the corners are not).

use glam::Vec3;

use crate::geometry::Aabb;
use crate::lanes::vector::{Native, Vector};
use crate::tracers::visibility::QuadLight;

/// The most frusta traced together: the live mask of a block is one `u64`.
pub const MAX_FRUSTA: usize = 64;

/// Lanes per frustum field: `MAX_FRUSTA` floats.
type Lanes = [f32; MAX_FRUSTA];

/// The rounding allowance of the box test, from the scale of the scene.
#[derive(Clone, Copy, Debug)]
pub struct Margins {
    /// Distance by which boxes are grown and planes thickened: 1e-5 × the largest coordinate of
    /// the scene, the light and the origins (f32 rounding is 6e-8 of it).
    pub distance: f32,
}

impl Margins {
    pub fn new(scale: f32) -> Margins {
        Margins {
            distance: 1e-5 * scale.max(f32::MIN_POSITIVE),
        }
    }
}

/// The frusta of one block of shading points; lane `f` is frustum `f`.
#[derive(Clone)]
pub struct Frusta {
    pub len: usize,
    pub origin: [Lanes; 3],
    /// Corner rays `D_q` (q = 0..4), per axis.
    pub corner: [[Lanes; 3]; 4],
    /// `|D_q|²`.
    pub corner_len_sq: [Lanes; 4],
    /// The longest corner ray in the 1-norm (a bound of every ray's length, for rounding margins).
    pub reach: Lanes,
    /// Per axis, the reciprocal directions `[entry, exit]`: the rays enter the axis's slab at
    /// `u = (slab − o) · 1/D` with `D` the component of largest magnitude (the fastest ray) and
    /// leave it with the smallest; both carry the directions' sign (positive: entry through the
    /// low slab). 0 on a free axis, where the directions straddle 0 and the axis bounds nothing.
    pub rcp: [[Lanes; 2]; 3],
    /// +∞ on a free axis (the box test's entry −∞, exit +∞: no bound), else 0.
    pub free_inf: [Lanes; 3],
    /// The four side planes through the origin (normals per axis, pointing out of the frustum)
    /// and the slack of each (`|n|` × the distance margin): the interval test alone keeps every
    /// box along an axis the directions straddle, as shadow frusta straight under a light do.
    pub side: [[Lanes; 3]; 4],
    pub side_slack: [Lanes; 4],
    /// The (s, t) rectangle `[s0, s1] × [t0, t1]` of each frustum's live samples.
    pub rect: [[f32; 4]; MAX_FRUSTA],
}

impl Default for Frusta {
    fn default() -> Self {
        Frusta {
            len: 0,
            origin: [[0.0; MAX_FRUSTA]; 3],
            corner: [[[0.0; MAX_FRUSTA]; 3]; 4],
            corner_len_sq: [[0.0; MAX_FRUSTA]; 4],
            reach: [0.0; MAX_FRUSTA],
            rcp: [[[0.0; MAX_FRUSTA]; 2]; 3],
            free_inf: [[f32::INFINITY; MAX_FRUSTA]; 3],
            side: [[[0.0; MAX_FRUSTA]; 3]; 4],
            side_slack: [[0.0; MAX_FRUSTA]; 4],
            rect: [[0.0; 4]; MAX_FRUSTA],
        }
    }
}

/// The bits of `mask` in increasing order.
#[inline(always)]
pub fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let f = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            f
        })
    })
}

impl Frusta {
    /// Frustum `f` from `origin` to the light's (s, t) rectangle `rect`: its corner rays (then
    /// `derive`).
    pub fn set(&mut self, f: usize, origin: Vec3, light: &QuadLight, rect: [f32; 4]) {
        for (a, o) in origin.to_array().into_iter().enumerate() {
            self.origin[a][f] = o;
        }
        self.rect[f] = rect;
        self.aim(f, light);
    }

    /// Recomputes frustum `f`'s corner rays from its origin and rectangle (then `derive`).
    pub fn aim(&mut self, f: usize, light: &QuadLight) {
        let origin = Vec3::new(self.origin[0][f], self.origin[1][f], self.origin[2][f]);
        let [s0, s1, t0, t1] = self.rect[f];
        let corners = [(s0, t0), (s1, t0), (s0, t1), (s1, t1)].map(|(s, t)| {
            let d = light.point(s, t) - origin;
            d.to_array()
        });
        self.set_corners(f, corners);
    }

    /// Frustum `f`'s corner rays become `corners` (`D_q`, in the order (s0, t0), (s1, t0),
    /// (s0, t1), (s1, t1) of a parallelogram; then `derive`).
    pub fn set_corners(&mut self, f: usize, corners: [[f32; 3]; 4]) {
        for (q, d) in corners.iter().enumerate() {
            for (axis, &x) in self.corner[q].iter_mut().zip(d) {
                axis[f] = x;
            }
        }
    }

    /// What follows from the corner rays, for the frusta of `changed`: `reach`, `corner_len_sq`
    /// and, given `bounds`, the box-test bounds (interval reciprocals and side planes). All the
    /// frusta a block sets up or re-aims at once, one vector of frusta per pass (`vector::Native`):
    /// the per-block set-up was a scalar loop per frustum.
    pub fn derive(&mut self, changed: u64, bounds: Option<&Margins>) {
        self.derive_with::<Native>(changed, bounds)
    }

    /// `derive` on vectors `V`: each lane computes the scalar formulas' operations in their order
    /// (glam's `cross`, `dot`, `length`), so the bits are those of one frustum at a time; minima
    /// and maxima keep the running bound on NaN, as `f32::min`/`max` do.
    pub fn derive_with<V: Vector>(&mut self, changed: u64, bounds: Option<&Margins>) {
        let (zero, inf) = (V::splat(0.0), V::splat(f32::INFINITY));
        let dot = |a: [V; 3], b: [V; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [V; 3], b: [V; 3]| {
            [
                a[1] * b[2] - b[1] * a[2],
                a[2] * b[0] - b[2] * a[0],
                a[0] * b[1] - b[0] * a[1],
            ]
        };
        for base in (0..MAX_FRUSTA).step_by(V::WIDTH) {
            let every = u64::MAX >> (64 - V::WIDTH);
            let lanes = changed >> base & every;
            if lanes == 0 {
                continue;
            }
            // Only the lanes of `changed` are written. A whole vector of them (every frustum of a
            // new block) is stored as it is: the blend with the old lanes compiles to a masked
            // store, which AMD's AVX2 cores run microcoded.
            let whole = lanes == every;
            let mask = V::from_bits(lanes);
            let put = |field: &mut Lanes, new: V| match whole {
                true => new.store(&mut field[base..]),
                false => V::select(mask, new, V::load(field, base)).store(&mut field[base..]),
            };
            let d: [[V; 3]; 4] =
                std::array::from_fn(|q| std::array::from_fn(|a| V::load(&self.corner[q][a], base)));
            let mut reach = zero;
            for (q, [x, y, z]) in d.into_iter().enumerate() {
                reach = (x.abs() + y.abs() + z.abs()).max(reach);
                put(&mut self.corner_len_sq[q], x * x + y * y + z * z);
            }
            put(&mut self.reach, reach);
            let Some(m) = bounds else { continue };
            // Corners in cyclic order around the rectangle: 0, 1, 3, 2.
            let ring = [d[0], d[1], d[3], d[2]];
            let centre: [V; 3] = std::array::from_fn(|a| d[0][a] + d[1][a] + d[2][a] + d[3][a]);
            for k in 0..4 {
                let n = cross(ring[k], ring[(k + 1) % 4]);
                // Pointing out of the frustum (`× −1` is the exact negation).
                let inwards = dot(n, centre).gt(zero);
                let n = n.map(|x| V::select(inwards, x * V::splat(-1.0), x));
                for (a, x) in n.into_iter().enumerate() {
                    put(&mut self.side[k][a], x);
                }
                put(
                    &mut self.side_slack[k],
                    dot(n, n).sqrt() * V::splat(m.distance),
                );
            }
            for a in 0..3 {
                let lo = d.iter().fold(inf, |lo, d| d[a].min(lo));
                let hi = d.iter().fold(zero - inf, |hi, d| d[a].max(hi));
                let (rcp_lo, rcp_hi) = (V::splat(1.0) / lo, V::splat(1.0) / hi);
                // Bounded when the directions keep one sign (a NaN fails both tests) and both
                // reciprocals are finite: an infinite one (subnormal direction) would make 0·∞
                // in the box test.
                let finite = |x: V| x.abs().lt(inf);
                let bounded = (lo.gt(zero) | hi.lt(zero)) & finite(rcp_lo) & finite(rcp_hi);
                put(&mut self.free_inf[a], V::select(bounded, zero, inf));
                // Positive directions: the largest is `hi`; negative ones: `lo`.
                let (entry, exit) = (
                    V::select(lo.gt(zero), rcp_hi, rcp_lo),
                    V::select(lo.gt(zero), rcp_lo, rcp_hi),
                );
                put(&mut self.rcp[a][0], V::select(bounded, entry, zero));
                put(&mut self.rcp[a][1], V::select(bounded, exit, zero));
            }
        }
    }

    /// Per box of `boxes`, the frusta of `candidates` whose rays may meet it: an
    /// interval-arithmetic slab test on `o + u·D`, u ∈ [0, 1] (per axis, no ray is in the box
    /// before the fastest ray reaches the entry slab nor after the slowest leaves the exit slab),
    /// and the four side planes. One vector of frusta per pass, at the
    /// machine's width (`vector::Native`); the frusta are loaded once for all `B` boxes (both
    /// children of a node).
    #[inline(always)]
    pub fn box_masks<const B: usize>(
        &self,
        boxes: [&Aabb; B],
        candidates: u64,
        m: &Margins,
    ) -> [u64; B] {
        self.box_masks_with::<Native, B>(boxes, candidates, m)
    }

    /// The lanes `box_masks` issues for the frusta of `candidates`: up to the last one, in
    /// whole vectors (per-ray lane counts, `Stats::aabb_tests`).
    pub fn lanes_issued(candidates: u64) -> u32 {
        let len = 64 - candidates.leading_zeros() as usize;
        (len.div_ceil(Native::WIDTH) * Native::WIDTH) as u32
    }

    /// `box_masks` on vectors `V`. Minima and maxima are compare-and-select (one instruction;
    /// `f32::min`'s NaN rule costs three): a NaN, which finite boxes and reciprocals never make,
    /// keeps the running bound, so it never culls.
    ///
    /// One product per slab, not the four of general interval arithmetic: with the slab's
    /// relative bound `x` of either sign, `x · 1/D_entry` is the least entry where `x ≥ 0` (on the
    /// ray's side) and negative, so below the running 0, where not; likewise at the exit, where a
    /// negative product culls either way. The rounding allowance is applied once to the
    /// intersection of the axes' intervals: it is monotone, so that is the same as per axis.
    #[inline(always)]
    pub fn box_masks_with<V: Vector, const B: usize>(
        &self,
        boxes: [&Aabb; B],
        candidates: u64,
        m: &Margins,
    ) -> [u64; B] {
        let lo = boxes.map(|b| (b.min - Vec3::splat(m.distance)).to_array());
        let hi = boxes.map(|b| (b.max + Vec3::splat(m.distance)).to_array());
        let len = 64 - candidates.leading_zeros() as usize;
        let zero = V::splat(0.0);
        // Products are rounded: bounds are widened by a relative 1e-6 (rounding is 1.2e-7).
        let widen = V::splat(1e-6);
        let mut masks = [0u64; B];
        for base in (0..len).step_by(V::WIDTH) {
            let lanes = |x: &Lanes| V::load(x, base);
            let mut near = [zero; B];
            let mut far = [V::splat(f32::INFINITY); B];
            let mut depth = [[zero; 4]; B];
            for a in 0..3 {
                let o = lanes(&self.origin[a]);
                let (entry, exit) = (lanes(&self.rcp[a][0]), lanes(&self.rcp[a][1]));
                let ascending = entry.gt(zero);
                let free_inf = lanes(&self.free_inf[a]);
                let minus_free_inf = zero - free_inf;
                let side: [V; 4] = std::array::from_fn(|k| lanes(&self.side[k][a]));
                let positive = side.map(|n| n.gt(zero));
                for i in 0..B {
                    let (x0, x1) = (V::splat(lo[i][a]) - o, V::splat(hi[i][a]) - o);
                    // Fused: the product's bits (± 0 adds nothing), or ∓∞ on a free axis.
                    let enter = V::select(ascending, x0, x1).mul_add(entry, minus_free_inf);
                    let leave = V::select(ascending, x1, x0).mul_add(exit, free_inf);
                    near[i] = enter.max(near[i]);
                    far[i] = leave.min(far[i]);
                    // Per side plane, the box corner deepest inside it (fused: one rounding
                    // fewer than the margins allow for).
                    for k in 0..4 {
                        depth[i][k] = side[k].mul_add(V::select(positive[k], x0, x1), depth[i][k]);
                    }
                }
            }
            let slack: [V; 4] = std::array::from_fn(|k| lanes(&self.side_slack[k]));
            for i in 0..B {
                // `near` ≥ 0.
                let near = near[i] - widen * near[i];
                let far = (far[i] + widen * far[i].abs()).min(V::splat(1.0));
                let mut inside = near.le(far);
                for k in 0..4 {
                    inside = inside & depth[i][k].le(slack[k]);
                }
                masks[i] |= V::bits(inside) << base;
            }
        }
        masks.map(|mask| mask & candidates)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_come_in_order() {
        assert_eq!(
            bits(0b1011 | 1 << 63).collect::<Vec<_>>(),
            vec![0, 1, 3, 63]
        );
        assert_eq!(bits(0).count(), 0);
    }

    #[test]
    fn a_frustum_meets_the_boxes_its_rays_cross_and_misses_the_others() {
        // From the origin to a 2 × 2 light at height 10 over x, z ∈ [−1, 1].
        let light = QuadLight {
            corner: Vec3::new(-1.0, 10.0, -1.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
        };
        let mut frusta = Frusta {
            len: 1,
            ..Frusta::default()
        };
        let m = Margins::new(10.0);
        frusta.set(0, Vec3::ZERO, &light, [0.0, 1.0, 0.0, 1.0]);
        frusta.derive(1, Some(&m));
        let free = |a: usize| frusta.free_inf[a][0] == f32::INFINITY;
        assert!(free(0) && !free(1) && free(2));
        let cube = |c: Vec3| Aabb::new(c - Vec3::splat(0.1), c + Vec3::splat(0.1));
        // At height 5 the frustum spans x, z ∈ [−0.5, 0.5].
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.5, 5.0, 0.0))], 1, &m),
            [1]
        );
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.0, 9.95, 0.95))], 1, &m),
            [1]
        );
        // Beside it (only the side planes see it), above the light, below the origin.
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.0, 1.0, 0.5))], 1, &m),
            [0]
        );
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(-0.5, 2.0, 0.0))], 1, &m),
            [0]
        );
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.0, 11.0, 0.0))], 1, &m),
            [0]
        );
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.0, -1.0, 0.0))], 1, &m),
            [0]
        );
    }

    /// One frustum's derived fields by the scalar formulas (glam), in `derive`'s order:
    /// `[reach, |D_q|² ×4, side normals ×12, side slacks ×4, free_inf ×3, rcp ×6]`.
    fn scalar_derived(corners: [[f32; 3]; 4], m: &Margins) -> Vec<f32> {
        let d = corners.map(Vec3::from_array);
        let mut out = vec![d.iter().map(|d| d.abs().element_sum()).fold(0.0, f32::max)];
        out.extend(d.iter().map(|d| d.length_squared()));
        let ring = [d[0], d[1], d[3], d[2]];
        let centre = d[0] + d[1] + d[2] + d[3];
        let mut slack = Vec::new();
        for k in 0..4 {
            let n = ring[k].cross(ring[(k + 1) % 4]);
            let n = if n.dot(centre) > 0.0 { -n } else { n };
            out.extend(n.to_array());
            slack.push(n.length() * m.distance);
        }
        out.extend(slack);
        let mut rcp = Vec::new();
        for a in 0..3 {
            let lo = d.iter().map(|d| d[a]).fold(f32::INFINITY, f32::min);
            let hi = d.iter().map(|d| d[a]).fold(f32::NEG_INFINITY, f32::max);
            let free =
                !(lo > 0.0 || hi < 0.0) || !(1.0 / lo).is_finite() || !(1.0 / hi).is_finite();
            out.push(if free { f32::INFINITY } else { 0.0 });
            let (entry, exit) = if lo > 0.0 { (hi, lo) } else { (lo, hi) };
            rcp.extend(if free {
                [0.0; 2]
            } else {
                [1.0 / entry, 1.0 / exit]
            });
        }
        out.extend(rcp);
        out
    }

    /// Frustum `f`'s derived fields in `scalar_derived`'s order.
    fn derived(frusta: &Frusta, f: usize) -> Vec<f32> {
        let mut out = vec![frusta.reach[f]];
        out.extend(frusta.corner_len_sq.iter().map(|x| x[f]));
        out.extend(frusta.side.iter().flatten().map(|x| x[f]));
        out.extend(frusta.side_slack.iter().map(|x| x[f]));
        out.extend(frusta.free_inf.iter().map(|x| x[f]));
        out.extend(frusta.rcp.iter().flatten().map(|x| x[f]));
        out
    }

    #[test]
    fn derive_gives_the_scalar_formulas_bits_in_the_changed_lanes_only() {
        use crate::lanes::vector::Portable;
        use crate::random::SplitMix64;
        let mut rng = SplitMix64::new(21);
        let m = Margins::new(3.0);
        let bits_of = |v: Vec<f32>| v.into_iter().map(f32::to_bits).collect::<Vec<_>>();
        for round in 0..50 {
            let mut frusta = Frusta::default();
            let mut corners = Vec::new();
            for f in 0..MAX_FRUSTA {
                // Straddling and one-signed axes, zeros, subnormal and NaN components.
                let c: [[f32; 3]; 4] = std::array::from_fn(|_| {
                    std::array::from_fn(|_| match rng.next_u64() % 8 {
                        0 => 0.0,
                        1 => -0.0,
                        2 => 1e-40,
                        3 if round % 5 == 0 => f32::NAN,
                        _ => rng.range(-3.0, 3.0) + if f % 2 == 0 { 5.0 } else { 0.0 },
                    })
                });
                frusta.set_corners(f, c);
                corners.push(c);
            }
            // Random lanes, and masks with whole vectors of 8 and 16 changed frusta beside partial
            // ones and none (a whole vector is stored without the blend).
            let changed = match (round / 3) % 3 {
                0 => rng.next_u64(),
                1 => 0xFFFF_0000_FFFF_00F0,
                _ => u64::MAX,
            };
            let bounds = (round % 3 != 0).then_some(&m);
            let untouched = Frusta::default();
            let mut portable = frusta.clone();
            frusta.derive(changed, bounds);
            portable.derive_with::<Portable<8>>(changed, bounds);
            for (f, c) in corners.into_iter().enumerate() {
                let mut want = scalar_derived(c, &m);
                if changed >> f & 1 == 0 {
                    want = derived(&untouched, f);
                } else if bounds.is_none() {
                    want.truncate(5);
                    want.extend_from_slice(&derived(&untouched, f)[5..]);
                }
                let want = bits_of(want);
                assert_eq!(
                    bits_of(derived(&frusta, f)),
                    want,
                    "round {round}, frustum {f}"
                );
                assert_eq!(
                    bits_of(derived(&portable, f)),
                    want,
                    "round {round}, frustum {f}"
                );
            }
        }
    }

    #[test]
    fn an_axis_whose_reciprocal_overflows_bounds_nothing() {
        // A light in the plane y = 1e-39 (subnormal) seen from the origin: every corner ray's y
        // is 1e-39, whose reciprocal is +∞, so y is free, as is an axis the rays straddle.
        let light = QuadLight {
            corner: Vec3::new(-1.0, 1e-39, -1.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
        };
        let mut frusta = Frusta {
            len: 1,
            ..Frusta::default()
        };
        let m = Margins::new(1.0);
        frusta.set(0, Vec3::ZERO, &light, [0.0, 1.0, 0.0, 1.0]);
        frusta.derive(1, Some(&m));
        assert_eq!(frusta.free_inf[1][0], f32::INFINITY);
        assert_eq!(
            [frusta.free_inf[0][0], frusta.free_inf[2][0]],
            [f32::INFINITY; 2]
        );
        // A box the rays cross (at y ≈ 0, inside the light's footprint) is kept.
        let cube = |c: Vec3| Aabb::new(c - Vec3::splat(0.1), c + Vec3::splat(0.1));
        assert_eq!(
            frusta.box_masks([&cube(Vec3::new(0.5, 0.0, 0.5))], 1, &m),
            [1]
        );
    }
}
