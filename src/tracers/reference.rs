//! The reference tracer: one ray at a time through the binary BVH, nearer child first. Robust by
//! construction — conservative slab test (Ize 2013) and watertight triangle test (Woop et al. 2013)
//! — it is the yardstick the packet, grid and stream tracers are checked and measured against.
//! Both children of a node are tested at once with SSE on the child-pair layout
//! (`accel::child_pairs`). Over a moving mesh (`Bvh::build_moving`) it tests each triangle where it
//! is at the ray's time (motion blur). With `robust = false` (`R = Fast`) it runs plain slabs and
//! Möller–Trumbore instead, as Embree's non-robust mode (`geometry::robustness`).

use std::marker::PhantomData;
use std::sync::Arc;

use crate::accel::child_pairs::PairRayTest;
use crate::accel::{Bvh, BvhConfig};
use crate::geometry::{Hit, Ray, RayBoxTest, RayTests, Robust};
use crate::stats::Stats;
use crate::tracers::kernel::SingleRayKernel;

/// `R`: the box and triangle tests (`robust`; `Robust` unless asked).
pub struct ReferenceTracer<R: RayTests = Robust> {
    bvh: Arc<Bvh>,
    tests: PhantomData<R>,
}

/// A node waiting on the stack: its index, its triangle range (`count > 0`: leaf) and the
/// distance at which the ray enters its box.
#[derive(Clone, Copy, Default)]
struct Pending {
    index: u32,
    first: u32,
    count: u32,
    enter: f32,
}

impl ReferenceTracer {
    /// The robust tracer (conservative slabs, watertight triangles).
    pub fn new(bvh: Arc<Bvh>) -> Self {
        Self::with_tests(bvh)
    }
}

impl<R: RayTests> ReferenceTracer<R> {
    pub fn with_tests(bvh: Arc<Bvh>) -> Self {
        ReferenceTracer {
            bvh,
            tests: PhantomData,
        }
    }
}

impl<R: RayTests> SingleRayKernel for ReferenceTracer<R> {
    #[inline(always)]
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit {
        let bvh = &*self.bvh;
        if S::ENABLED {
            stats.ray();
        }
        if bvh.is_empty() {
            return Hit::MISS;
        }
        if S::ENABLED {
            stats.aabb_test(0);
        }
        let root = &bvh.nodes[Bvh::ROOT];
        match RayBoxTest::new(ray.origin, ray.dir).hit_with::<R>(&root.bounds, ray.tmin, ray.tmax) {
            Some(_) => trace_subtree::<R, S, ANY>(bvh, Bvh::ROOT as u32, ray, stats),
            None => Hit::MISS,
        }
    }
}

/// A leaf's triangles, `first .. first + count` of the tree's `triangles`, at `depth` (counters).
#[derive(Clone, Copy)]
pub struct LeafRange {
    pub first: u32,
    pub count: u32,
    pub depth: usize,
}

/// What the leaf stage reads of a ray: its triangle test's ray (`R`: the watertight frame, or
/// the ray itself for Möller–Trumbore), where its segment starts, and its time (motion blur).
#[derive(Clone, Copy)]
pub struct LeafRay<R: RayTests = Robust> {
    pub tris: R::TriangleRay,
    pub tmin: f32,
    pub time: f32,
}

impl<R: RayTests> LeafRay<R> {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        LeafRay {
            tris: R::triangle_ray(ray.origin, ray.dir),
            tmin: ray.tmin,
            time: ray.time,
        }
    }
}

/// The reference tracer's leaf stage, shared with the wide single-ray traversal so both find
/// bit-identical hits: each triangle's test (`R`) within `[ray.tmin, tmax]`, a hit becoming
/// `best` and shortening `tmax`. Returns whether to stop (`ANY` and something was hit).
#[inline(always)]
pub fn intersect_leaf<R: RayTests, S: Stats, const ANY: bool>(
    bvh: &Bvh,
    ray: &LeafRay<R>,
    leaf: LeafRange,
    tmax: &mut f32,
    best: &mut Hit,
    stats: &mut S,
) -> bool {
    for i in leaf.first as usize..(leaf.first + leaf.count) as usize {
        if S::ENABLED {
            stats.triangle_test(leaf.depth);
        }
        // A moving triangle is tested where it is at the ray's time: the watertight test
        // precomputes per ray, not per triangle (Boulos et al. 2007 §4).
        let moved;
        let tri = match &bvh.motion_end {
            None => &bvh.triangles[i],
            Some(end) => {
                moved = bvh.triangles[i].lerp(&end[i], ray.time);
                &moved
            }
        };
        if let Some((t, u, v)) = R::intersect(&ray.tris, tri, ray.tmin, *tmax) {
            *best = Hit {
                t,
                prim: bvh.prim_ids[i],
                u,
                v,
            };
            if ANY {
                return true;
            }
            *tmax = t;
        }
    }
    false
}

/// The reference traversal of the subtree under `node`, whose box `ray` is known to meet: the
/// closest hit (`ANY`: the first found) within `[ray.tmin, ray.tmax]`, or a miss. The stream
/// tracer hands the rays of a short sub-stream to it (`stream`'s `single` parameter). `R`: the
/// box and triangle tests.
#[inline(always)]
pub fn trace_subtree<R: RayTests, S: Stats, const ANY: bool>(
    bvh: &Bvh,
    node: u32,
    ray: &Ray,
    stats: &mut S,
) -> Hit {
    let mut best = Hit::MISS;
    let (tmin, mut tmax) = (ray.tmin, ray.tmax);
    let depth = |i: u32| {
        if S::ENABLED {
            bvh.depth[i as usize] as usize
        } else {
            0
        }
    };
    let boxes = PairRayTest::with::<R>(ray.origin, ray.dir);
    let leaf_ray = LeafRay::<R>::new(ray);
    // Far children wait here with their entry distance, so a pop can skip boxes that now lie
    // beyond the closest hit without testing them again.
    let mut stack = [Pending::default(); BvhConfig::DEPTH_LIMIT + 2];
    let mut top = 0;
    let start = &bvh.nodes[node as usize];
    let mut node = Pending {
        index: node,
        first: start.first,
        count: start.count,
        enter: tmin,
    };
    loop {
        if S::ENABLED {
            stats.node(depth(node.index));
        }
        if node.count > 0 {
            let leaf = LeafRange {
                first: node.first,
                count: node.count,
                depth: depth(node.index),
            };
            if intersect_leaf::<R, S, ANY>(bvh, &leaf_ray, leaf, &mut tmax, &mut best, stats) {
                return best;
            }
        } else {
            let pair = &bvh.pairs[node.index as usize];
            if S::ENABLED {
                stats.aabb_test(depth(node.first));
                stats.aabb_test(depth(node.first + 1));
            }
            let (enter, hit) = boxes.test(pair, tmin, tmax);
            let child = |c: usize| Pending {
                index: node.first + c as u32,
                first: pair.first[c],
                count: pair.count[c],
                enter: enter[c],
            };
            match hit {
                0b11 => {
                    let (near, far) = if enter[0] <= enter[1] { (0, 1) } else { (1, 0) };
                    stack[top] = child(far);
                    top += 1;
                    node = child(near);
                    continue;
                }
                0b01 => {
                    node = child(0);
                    continue;
                }
                0b10 => {
                    node = child(1);
                    continue;
                }
                _ => {}
            }
        }
        // Pop, skipping nodes now beyond the closest hit.
        loop {
            if top == 0 {
                return best;
            }
            top -= 1;
            if stack[top].enter <= tmax {
                node = stack[top];
                break;
            }
        }
    }
}
