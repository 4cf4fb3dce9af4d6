//! Interval-arithmetic box culling for a whole packet (Wald, Boulos and Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies", §4; used by Boulos et al. 2007
//! §3.3): the packet is the interval of its origins and reciprocal directions per axis, and the
//! slab test run on intervals gives a range of entry and exit distances that contains every ray's.
//! When even the earliest possible entry lies beyond the latest possible exit, no ray hits the box.
//!
//! Exactness: the slab test's rounded operations (`(plane − o)·inv`, and for the far plane
//! `(plane − o)·(inv·FAR_SCALE)`) are monotone in each argument, so the rounded products at the
//! corners of the intervals (the far ones with each reciprocal bound scaled as a ray's is) bound
//! each ray's own rounded values, and the cull never rejects a box the ray's `RayBoxTest` would
//! accept.
//! An axis is used only when every ray's reciprocal direction on it is finite and has the same sign
//! bit (mixed signs or zero components: that axis does not restrict the packet).
//!
//! The latest exit is also clipped to the largest current closest hit of the packet (`max_t`), so
//! a box lying behind every ray's hit is culled at once — our choice: the paper's packets carry one
//! `tmax` per ray, and this is the packet-wide bound of those.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use crate::geometry::aabb::FAR_SCALE;
#[cfg(test)]
use crate::geometry::Rays;
use crate::lanes::{highest, lowest, SimdRay};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntervalPacket {
    origin_lo: [f32; 3],
    origin_hi: [f32; 3],
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    negative: [bool; 3],
    usable: [bool; 3],
    tmin: f32,
}

impl IntervalPacket {
    /// The bounds of no ray, where both constructions start.
    const EMPTY: IntervalPacket = IntervalPacket {
        origin_lo: [f32::INFINITY; 3],
        origin_hi: [f32::NEG_INFINITY; 3],
        inv_lo: [f32::INFINITY; 3],
        inv_hi: [f32::NEG_INFINITY; 3],
        negative: [false; 3],
        usable: [true; 3],
        tmin: f32::INFINITY,
    };

    /// The definition `from_lanes` computes (kept for its test).
    #[cfg(test)]
    pub fn new(rays: Rays<'_>) -> Self {
        let mut p = IntervalPacket::EMPTY;
        for i in 0..rays.len() {
            let r = rays.ray(i);
            let (o, d) = (r.origin.to_array(), r.dir.to_array());
            for a in 0..3 {
                let inv = 1.0 / d[a];
                p.origin_lo[a] = p.origin_lo[a].min(o[a]);
                p.origin_hi[a] = p.origin_hi[a].max(o[a]);
                p.inv_lo[a] = p.inv_lo[a].min(inv);
                p.inv_hi[a] = p.inv_hi[a].max(inv);
                let neg = d[a].is_sign_negative();
                if i == 0 {
                    p.negative[a] = neg;
                }
                p.usable[a] &= inv.is_finite() && o[a].is_finite() && neg == p.negative[a];
            }
            p.tmin = p.tmin.min(r.tmin);
        }
        p
    }

    /// `new` from the packet's rays already in SIMD lanes (`SimdRay::load`, every lane in use
    /// well formed): the same bounds (the lanes hold the same origins and the same `1/d`), taken
    /// lane-wise so they vectorize — built ray by ray they cost as much as the traversal. The
    /// padding lanes `load` makes (tmin = ∞, origin 0, direction (1, 1, 1)) change neither
    /// `tmin`, nor the finiteness, nor the count of negative directions, so only the origin and
    /// reciprocal bounds need to skip them.
    pub fn from_lanes<const L: usize>(groups: &[SimdRay<L>]) -> Self {
        let mut p = IntervalPacket::EMPTY;
        let Some(first) = groups.first() else {
            return p;
        };
        let rays: u32 = groups.iter().map(|g| g.used).sum();
        for a in 0..3 {
            let (mut o_lo, mut o_hi) = ([f32::INFINITY; L], [f32::NEG_INFINITY; L]);
            let (mut i_lo, mut i_hi) = ([f32::INFINITY; L], [f32::NEG_INFINITY; L]);
            let (mut negatives, mut infinite) = ([0u32; L], [0u32; L]);
            for g in groups {
                for l in 0..L {
                    let used = (l as u32) < g.used;
                    let (o, inv) = (g.origin[a][l], g.inv_dir[a][l]);
                    o_lo[l] = if used & (o < o_lo[l]) { o } else { o_lo[l] };
                    o_hi[l] = if used & (o > o_hi[l]) { o } else { o_hi[l] };
                    i_lo[l] = if used & (inv < i_lo[l]) { inv } else { i_lo[l] };
                    i_hi[l] = if used & (inv > i_hi[l]) { inv } else { i_hi[l] };
                    negatives[l] += g.negative[a][l];
                    infinite[l] |= !(inv.is_finite() & o.is_finite()) as u32;
                }
            }
            let negative_rays: u32 = negatives.iter().sum();
            p.origin_lo[a] = lowest(o_lo);
            p.origin_hi[a] = highest(o_hi);
            p.inv_lo[a] = lowest(i_lo);
            p.inv_hi[a] = highest(i_hi);
            p.negative[a] = first.negative[a][0] != 0;
            p.usable[a] =
                infinite.iter().all(|&i| i == 0) && (negative_rays == 0 || negative_rays == rays);
        }
        let mut tmin = [f32::INFINITY; L];
        for g in groups {
            for l in 0..L {
                tmin[l] = if g.tmin[l] < tmin[l] {
                    g.tmin[l]
                } else {
                    tmin[l]
                };
            }
        }
        p.tmin = lowest(tmin);
        p
    }

    /// Whether no ray of the packet, with its segment clipped to at most `max_t`, meets the box
    /// `[lo, hi]`.
    #[inline(always)]
    pub fn culls(&self, lo: [f32; 3], hi: [f32; 3], max_t: f32) -> bool {
        let mut enter = self.tmin;
        let mut exit = max_t;
        for a in 0..3 {
            if !self.usable[a] {
                continue;
            }
            let (near, far) = if self.negative[a] {
                (hi[a], lo[a])
            } else {
                (lo[a], hi[a])
            };
            let corners = |plane: f32, scale: f32| {
                let (x0, x1) = (plane - self.origin_hi[a], plane - self.origin_lo[a]);
                let (i0, i1) = (self.inv_lo[a] * scale, self.inv_hi[a] * scale);
                [x0 * i0, x0 * i1, x1 * i0, x1 * i1]
            };
            let near_min = corners(near, 1.0).into_iter().fold(f32::INFINITY, f32::min);
            let far_max = corners(far, FAR_SCALE)
                .into_iter()
                .fold(f32::NEG_INFINITY, f32::max);
            enter = enter.max(near_min);
            exit = exit.min(far_max);
        }
        enter > exit
    }
}

impl IntervalPacket {
    /// `culls` for `W` boxes at once (`lo[axis][box]`, `hi[axis][box]`; a wide BVH node's
    /// children), by the same operations box by box, so each box gets `culls`'s verdict: bit `b`
    /// set when box `b` may be met by some ray (is not culled).
    #[inline(always)]
    pub fn survivors<const W: usize>(
        &self,
        lo: &[[f32; W]; 3],
        hi: &[[f32; W]; 3],
        max_t: f32,
    ) -> u32 {
        let mut enter = [self.tmin; W];
        let mut exit = [max_t; W];
        for a in 0..3 {
            if !self.usable[a] {
                continue;
            }
            let (near, far) = if self.negative[a] {
                (&hi[a], &lo[a])
            } else {
                (&lo[a], &hi[a])
            };
            let (o_lo, o_hi, i_lo, i_hi) = (
                self.origin_lo[a],
                self.origin_hi[a],
                self.inv_lo[a],
                self.inv_hi[a],
            );
            let (f_lo, f_hi) = (i_lo * FAR_SCALE, i_hi * FAR_SCALE);
            for b in 0..W {
                let (x0, x1) = (near[b] - o_hi, near[b] - o_lo);
                let near_min = f32::INFINITY
                    .min(x0 * i_lo)
                    .min(x0 * i_hi)
                    .min(x1 * i_lo)
                    .min(x1 * i_hi);
                let (y0, y1) = (far[b] - o_hi, far[b] - o_lo);
                let far_max = f32::NEG_INFINITY
                    .max(y0 * f_lo)
                    .max(y0 * f_hi)
                    .max(y1 * f_lo)
                    .max(y1 * f_hi);
                enter[b] = enter[b].max(near_min);
                exit[b] = exit[b].min(far_max);
            }
        }
        let mut mask = 0;
        // `culls`'s `enter > exit`, negated as it is (a NaN keeps the box).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        for b in 0..W {
            mask |= (!(enter[b] > exit[b]) as u32) << b;
        }
        mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Aabb, Ray, RayBatch, RayBoxTest, RayKind, Robust};
    use crate::random::SplitMix64;

    /// `n` rays about one random origin and direction (origins ±0.3, directions ±`spread`
    /// before normalising), `tmin` drawn from `tmin` (an empty range: its start), `tmax` 8.
    fn coherent_batch(
        rng: &mut SplitMix64,
        n: usize,
        spread: f32,
        tmin: std::ops::Range<f32>,
    ) -> RayBatch {
        let mut b = RayBatch::new(RayKind::Diffuse);
        let (o, d) = (rng.vec3(-2.0, 2.0), rng.direction());
        for i in 0..n {
            let dir = (d + rng.vec3(-spread, spread)).normalize();
            let t0 = match tmin.is_empty() {
                true => tmin.start,
                false => rng.range(tmin.start, tmin.end),
            };
            b.push(Ray::new(o + rng.vec3(-0.3, 0.3), dir, t0, 8.0), i as u32);
        }
        b
    }

    #[test]
    fn interval_culling_never_culls_a_box_a_ray_hits() {
        let mut rng = SplitMix64::new(5);
        let mut culled = 0;
        let trials = 20_000;
        for _ in 0..trials / 100 {
            let b = coherent_batch(&mut rng, 16, 0.2, 0.0..0.0);
            let p = IntervalPacket::new(b.view());
            for _ in 0..100 {
                let c = rng.vec3(-4.0, 4.0);
                let bx = Aabb::new(c, c + rng.vec3(0.0, 1.0));
                let hit = (0..b.len()).any(|i| {
                    let r = b.ray(i);
                    RayBoxTest::new(r.origin, r.dir)
                        .hit(&bx, r.tmin, r.tmax)
                        .is_some()
                });
                let cull = p.culls(bx.min.to_array(), bx.max.to_array(), 8.0);
                assert!(!(hit && cull), "culled a box a ray hits");
                culled += cull as usize;
            }
        }
        assert!(culled * 2 > trials, "only {culled} of {trials} culled");
    }

    #[test]
    fn bounds_from_lanes_equal_bounds_from_rays() {
        let mut rng = SplitMix64::new(21);
        for n in [1usize, 5, 16, 37, 64] {
            let b = coherent_batch(&mut rng, n, 0.4, 0.0..0.1);
            let rays = b.view();
            let mut groups = vec![SimdRay::<16>::default(); n.div_ceil(16)];
            for (g, group) in groups.iter_mut().enumerate() {
                group.load::<Robust>(&rays, g * 16, 16.min(n - g * 16));
            }
            assert_eq!(
                IntervalPacket::from_lanes(&groups),
                IntervalPacket::new(rays),
                "{n} rays"
            );
        }
    }

    #[test]
    fn survivors_of_eight_boxes_are_the_boxes_culls_keeps() {
        let mut rng = SplitMix64::new(9);
        for _ in 0..500 {
            let b = coherent_batch(&mut rng, 16, 0.2, 0.0..0.0);
            let p = IntervalPacket::new(b.view());
            let (mut lo, mut hi) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
            for c in 0..7 {
                let l = rng.vec3(-4.0, 4.0);
                let h = l + rng.vec3(0.0, 1.0);
                for a in 0..3 {
                    (lo[a][c], hi[a][c]) = (l[a], h[a]);
                }
            }
            // Slot 7 empty, as a wide node's unused slots (+∞ … −∞).
            for a in 0..3 {
                (lo[a][7], hi[a][7]) = (f32::INFINITY, f32::NEG_INFINITY);
            }
            let want = (0..8).fold(0u32, |m, c| {
                let (l, h) = ([0, 1, 2].map(|a| lo[a][c]), [0, 1, 2].map(|a| hi[a][c]));
                m | (!p.culls(l, h, 6.0) as u32) << c
            });
            assert_eq!(want & (1 << 7), 0, "the empty slot is culled");
            assert_eq!(p.survivors(&lo, &hi, 6.0), want);
        }
    }
}
