//! Interval-arithmetic box culling for a whole packet (Wald, Boulos and Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies", §4; used by Boulos et al. 2007
//! §3.3): the packet is the interval of its origins and reciprocal directions per axis, and the
//! slab test run on intervals gives a range of entry and exit distances that contains every ray's.
//! When even the earliest possible entry lies beyond the latest possible exit, no ray hits the box.
//!
//! Exactness: the slab test's rounded operations (`(plane − o)·inv`, then `·FAR_SCALE`) are
//! monotone in each argument, so the rounded products at the corners of the intervals bound each
//! ray's own rounded values, and the cull never rejects a box the ray's `RayBoxTest` would accept.
//! An axis is used only when every ray's reciprocal direction on it is finite and has the same sign
//! bit (mixed signs or zero components: that axis does not restrict the packet).
//!
//! The latest exit is also clipped to the largest current closest hit of the packet (`max_t`), so
//! a box lying behind every ray's hit is culled at once — our choice: the paper's packets carry one
//! `tmax` per ray, and this is the packet-wide bound of those.

use crate::geometry::aabb::FAR_SCALE;
use crate::geometry::Rays;

#[derive(Clone, Copy, Debug)]
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
    pub fn new(rays: Rays<'_>) -> Self {
        let mut p = IntervalPacket {
            origin_lo: [f32::INFINITY; 3],
            origin_hi: [f32::NEG_INFINITY; 3],
            inv_lo: [f32::INFINITY; 3],
            inv_hi: [f32::NEG_INFINITY; 3],
            negative: [false; 3],
            usable: [true; 3],
            tmin: f32::INFINITY,
        };
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
            let corners = |plane: f32| {
                let (x0, x1) = (plane - self.origin_hi[a], plane - self.origin_lo[a]);
                [
                    x0 * self.inv_lo[a],
                    x0 * self.inv_hi[a],
                    x1 * self.inv_lo[a],
                    x1 * self.inv_hi[a],
                ]
            };
            let near_min = corners(near).into_iter().fold(f32::INFINITY, f32::min);
            let far_max = corners(far)
                .into_iter()
                .map(|t| t * FAR_SCALE)
                .fold(f32::NEG_INFINITY, f32::max);
            enter = enter.max(near_min);
            exit = exit.min(far_max);
        }
        enter > exit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Aabb, Ray, RayBatch, RayBoxTest, RayKind};
    use crate::random::SplitMix64;

    #[test]
    fn interval_culling_never_culls_a_box_a_ray_hits() {
        let mut rng = SplitMix64::new(5);
        let mut culled = 0;
        let trials = 20_000;
        for _ in 0..trials / 100 {
            let mut b = RayBatch::new(RayKind::Diffuse);
            let (o, d) = (rng.vec3(-2.0, 2.0), rng.direction());
            for i in 0..16 {
                let dir = (d + rng.vec3(-0.2, 0.2)).normalize();
                b.push(Ray::new(o + rng.vec3(-0.3, 0.3), dir, 0.0, 8.0), i);
            }
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
}
