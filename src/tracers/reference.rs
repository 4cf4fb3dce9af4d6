//! The reference tracer: one ray at a time through the binary BVH, nearer child first. Robust by
//! construction — conservative slab test (Ize 2013) and watertight triangle test (Woop et al. 2013)
//! — it is the yardstick the packet, grid and stream tracers are checked and measured against.

use std::sync::Arc;

use crate::accel::{Bvh, BvhConfig};
use crate::geometry::{Hit, Ray, RayBoxTest, Rays, WatertightRay};
use crate::stats::Stats;
use crate::tracers::Kernel;

pub struct ReferenceTracer {
    bvh: Arc<Bvh>,
}

impl ReferenceTracer {
    pub fn new(bvh: Arc<Bvh>) -> Self {
        ReferenceTracer { bvh }
    }

    /// Closest hit (`ANY = false`) or first hit found (`ANY = true`, for occlusion).
    #[inline(always)]
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit {
        let bvh = &*self.bvh;
        let mut best = Hit::MISS;
        if S::ENABLED {
            stats.ray();
        }
        if bvh.is_empty() {
            return best;
        }
        let boxes = RayBoxTest::new(ray.origin, ray.dir);
        let tris = WatertightRay::new(ray.origin, ray.dir);
        let (tmin, mut tmax) = (ray.tmin, ray.tmax);
        let depth = |i: usize| if S::ENABLED { bvh.depth[i] as usize } else { 0 };

        if S::ENABLED {
            stats.aabb_test(0);
        }
        if boxes
            .hit(&bvh.nodes[Bvh::ROOT].bounds, tmin, tmax)
            .is_none()
        {
            return best;
        }
        // Far children wait here with their entry distance, so a pop can skip boxes that now lie
        // beyond the closest hit without testing them again.
        let mut stack = [(0u32, 0.0f32); BvhConfig::DEPTH_LIMIT + 2];
        let mut top = 0;
        let mut index = Bvh::ROOT;
        loop {
            let node = &bvh.nodes[index];
            if S::ENABLED {
                stats.node(depth(index));
            }
            if node.is_leaf() {
                for i in node.first as usize..(node.first + node.count) as usize {
                    if S::ENABLED {
                        stats.triangle_test(depth(index));
                    }
                    if let Some((t, u, v)) = tris.intersect(&bvh.triangles[i], tmin, tmax) {
                        best = Hit {
                            t,
                            prim: bvh.prim_ids[i],
                            u,
                            v,
                        };
                        if ANY {
                            return best;
                        }
                        tmax = t;
                    }
                }
            } else {
                let (a, b) = (node.first as usize, node.first as usize + 1);
                if S::ENABLED {
                    stats.aabb_test(depth(a));
                    stats.aabb_test(depth(b));
                }
                let ta = boxes.hit(&bvh.nodes[a].bounds, tmin, tmax);
                let tb = boxes.hit(&bvh.nodes[b].bounds, tmin, tmax);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, t_far) = if ta <= tb { (a, b, tb) } else { (b, a, ta) };
                        stack[top] = (far as u32, t_far);
                        top += 1;
                        index = near;
                        continue;
                    }
                    (Some(_), None) => {
                        index = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        index = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping nodes now beyond the closest hit.
            loop {
                if top == 0 {
                    return best;
                }
                top -= 1;
                let (node, t_enter) = stack[top];
                if t_enter <= tmax {
                    index = node as usize;
                    break;
                }
            }
        }
    }
}

impl Kernel for ReferenceTracer {
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        for (i, hit) in hits.iter_mut().enumerate() {
            *hit = self.trace::<S, false>(&rays.ray(i), stats);
        }
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        for (i, o) in occluded.iter_mut().enumerate() {
            *o = self.trace::<S, true>(&rays.ray(i), stats).is_hit();
        }
    }
}
