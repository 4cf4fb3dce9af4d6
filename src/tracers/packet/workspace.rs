//! One packet in flight: its SIMD rays, its frustum and interval bounds, and the index lists the
//! traversals keep. Allocated once per chunk of rays and reused for every packet of the chunk, so
//! the hot loop never allocates. Also the leaf step all four traversals share (Fig. 2, lines
//! 21–27): every triangle not culled by the frustum against every active SIMD ray, a moving
//! triangle (motion blur) at each lane's time.

use std::marker::PhantomData;

use crate::accel::{Bvh, BvhConfig, BvhNode};
use crate::geometry::{Hit, RayTests, Rays};
use crate::stats::{Event, Owners, Stats};

use super::frustum::Frustum;
use super::interval::IntervalPacket;
use super::order::ChildOrder;
use crate::lanes::{highest, SharedFrame, SimdRay};

/// What every traversal reads: the tree and its child order.
pub struct Tree<'a> {
    pub bvh: &'a Bvh,
    pub order: &'a ChildOrder,
}

impl Tree<'_> {
    #[inline(always)]
    pub fn node(&self, i: u32) -> &BvhNode {
        &self.bvh.nodes[i as usize]
    }

    #[inline(always)]
    pub fn depth<S: Stats>(&self, i: u32) -> usize {
        if S::ENABLED {
            self.bvh.depth[i as usize] as usize
        } else {
            0
        }
    }
}

/// A node waiting on a traversal stack with the packet's index (first active SIMD ray for
/// Ranged and IA, number of alive ones for Partition; unused by Masked).
#[derive(Clone, Copy, Default)]
pub struct Pending {
    pub node: u32,
    pub ia: u32,
}

/// Deep enough for any tree `Bvh::build` makes.
pub type Stack = [Pending; BvhConfig::DEPTH_LIMIT + 2];

/// `R`: the tests every lane runs (`robust`).
pub struct Packet<const L: usize, R: RayTests> {
    pub groups: Vec<SimdRay<L>>,
    /// Rays in the packet (the lanes in use over all SIMD rays).
    pub rays: usize,
    /// The packet's first ray among the kernel's rays (per-ray counters: `Owners`).
    pub first: usize,
    /// `0, 1, …, groups − 1`: Ranged and IA hand leaves a sub-slice of it.
    pub identity: Vec<u32>,
    /// Partition's index list `I` (§3.3).
    pub index: Vec<u32>,
    /// Masked's alive SIMD rays at the current node (its `rayMasks`, kept as a list).
    pub alive: Vec<u32>,
    pub frustum: Option<Frustum>,
    pub interval: Option<IntervalPacket>,
    /// Sign bits of the packet's summed direction: the front-to-back order.
    pub negative: [bool; 3],
    /// Lanes still without a hit (occlusion) or in use (closest hit).
    pub live: u32,
    /// The largest closest-hit distance over the packet's lanes (interval culling and the
    /// frustum's far plane).
    pub max_t: f32,
    /// The origin and watertight frame every lane of the packet shares, if one (camera rays):
    /// found once per packet, as it then holds for every SIMD ray a leaf tests — found per
    /// leaf over the leaf's SIMD rays it cost 4% of the wide traversal on camera rays.
    pub frame: Option<SharedFrame>,
    tests: PhantomData<R>,
}

impl<const L: usize, R: RayTests> Packet<L, R> {
    pub fn with_capacity(rays: usize) -> Self {
        let groups = rays.div_ceil(L);
        Packet {
            groups: vec![SimdRay::default(); groups],
            rays: 0,
            first: 0,
            identity: (0..groups as u32).collect(),
            index: Vec::with_capacity(groups),
            alive: Vec::with_capacity(groups),
            frustum: None,
            interval: None,
            negative: [false; 3],
            live: 0,
            max_t: f32::INFINITY,
            frame: None,
            tests: PhantomData,
        }
    }

    /// Loads one packet; `frustum` and `interval` say which bounds the traversal uses.
    pub fn load(&mut self, rays: Rays<'_>, tree: &Tree, frustum: bool, interval: bool) {
        let count = rays.len().div_ceil(L);
        if self.groups.len() < count {
            self.groups.resize(count, SimdRay::default());
            self.identity = (0..count as u32).collect();
        }
        self.groups.truncate(count);
        self.rays = rays.len();
        let mut well_formed = 0;
        for (g, group) in self.groups.iter_mut().enumerate() {
            let first = g * L;
            well_formed += group.load::<R>(&rays, first, L.min(rays.len() - first));
        }
        // Summed lane-wise first (a sequential float sum is one long dependency chain); only
        // the signs are used.
        self.negative = [rays.dx, rays.dy, rays.dz].map(|d| lane_sum::<L>(d).is_sign_negative());
        self.index.clear();
        self.index.extend(0..count as u32);
        // Ill-formed rays are misses from the start (`SimdRay::load`); their directions and
        // intervals would poison the packet's bounds, so such a packet is traced unculled.
        let cull = well_formed as usize == rays.len();
        self.live = well_formed;
        // Read only with culling bounds, so only when every ray is well formed (no NaN).
        self.max_t = match cull && (frustum || interval) {
            true => self.farthest_hit(),
            false => f32::INFINITY,
        };
        let scene = &tree.bvh.nodes[Bvh::ROOT].bounds;
        self.frustum = if frustum && cull {
            Frustum::build::<L>(rays, scene)
        } else {
            None
        };
        self.interval = (interval && cull).then(|| IntervalPacket::from_lanes(&self.groups));
        // The shared frame is the watertight test's.
        self.frame = match R::ROBUST {
            true => SharedFrame::of(self.groups.iter()),
            false => None,
        };
    }

    /// The largest `tmax` over the packet's lanes (−∞ when none is live), folded lane-wise over
    /// the SIMD rays: one vector max per SIMD ray, not a chain of `L` scalar ones.
    #[inline(always)]
    pub fn farthest_hit(&self) -> f32 {
        let mut far = [f32::NEG_INFINITY; L];
        for g in &self.groups {
            for (f, &t) in far.iter_mut().zip(&g.tmax) {
                *f = if t > *f { t } else { *f };
            }
        }
        highest(far)
    }

    /// Writes the packet's closest hits to `out` (one per ray of the packet, in order); a ray
    /// without a hit gets `Hit::MISS`.
    pub fn store_hits(&self, out: &mut [Hit]) {
        for (g, slots) in self.groups.iter().zip(out[..self.rays].chunks_mut(L)) {
            g.store_hits(slots);
        }
    }

    /// Writes whether each ray of the packet is occluded to `out`, in order.
    pub fn store_occluded(&self, out: &mut [bool]) {
        for (g, slots) in self.groups.iter().zip(out[..self.rays].chunks_mut(L)) {
            for (slot, &prim) in slots.iter_mut().zip(&g.prim) {
                *slot = prim != Hit::NO_PRIM;
            }
        }
    }

    /// The rays of the packet (per-ray counters).
    pub fn owners(&self) -> Owners<'static> {
        Owners::span(self.first, self.rays)
    }

    /// The rays in the lanes of SIMD ray `g`.
    fn group_owners(&self, g: u32) -> Owners<'static> {
        Owners::span(
            self.first + g as usize * L,
            self.groups[g as usize].used as usize,
        )
    }

    /// Whether SIMD ray `g` meets the box of `node`, counting one box test per lane in use.
    #[inline(always)]
    pub fn hits_box<S: Stats>(&self, g: u32, node: &BvhNode, depth: usize, stats: &mut S) -> bool {
        let (lo, hi) = (node.bounds.min.to_array(), node.bounds.max.to_array());
        self.hits_bounds(g, lo, hi, depth, stats)
    }

    /// As `hits_box` for the box `[lo, hi]`.
    #[inline(always)]
    pub fn hits_bounds<S: Stats>(
        &self,
        g: u32,
        lo: [f32; 3],
        hi: [f32; 3],
        depth: usize,
        stats: &mut S,
    ) -> bool {
        let group = &self.groups[g as usize];
        if S::ENABLED {
            stats.aabb_tests(depth, self.group_owners(g), L as u32);
        }
        group.hits_box::<R>(lo, hi)
    }

    /// Masked's leaf step (Fig. 2) after SIMD ray `first`, which meets the box `[lo, hi]`:
    /// `alive` becomes `first` and every later SIMD ray that meets the box. Filled without a
    /// branch on the verdicts (each SIMD ray is written, and the length advanced by its verdict):
    /// whether a SIMD ray meets a leaf is close to a coin toss, which a branch mispredicts.
    #[inline(always)]
    pub fn keep_hitting<S: Stats>(
        &mut self,
        first: u32,
        lo: [f32; 3],
        hi: [f32; 3],
        depth: usize,
        stats: &mut S,
    ) {
        let mut alive = std::mem::take(&mut self.alive);
        alive.clear();
        alive.resize(self.groups.len() - first as usize, first);
        let mut kept = 1;
        for g in first + 1..self.groups.len() as u32 {
            alive[kept] = g;
            kept += self.hits_bounds(g, lo, hi, depth, stats) as usize;
        }
        alive.truncate(kept);
        self.alive = alive;
    }

    /// Whether the frustum culls the box of `node` for the whole packet (counted as a culled box).
    #[inline(always)]
    pub fn frustum_culls<S: Stats>(&self, node: &BvhNode, stats: &mut S) -> bool {
        let (lo, hi) = (node.bounds.min.to_array(), node.bounds.max.to_array());
        self.frustum_culls_bounds(lo, hi, stats)
    }

    /// As `frustum_culls` for the box `[lo, hi]`.
    #[inline(always)]
    pub fn frustum_culls_bounds<S: Stats>(
        &self,
        lo: [f32; 3],
        hi: [f32; 3],
        stats: &mut S,
    ) -> bool {
        let culled = self.frustum.as_ref().is_some_and(|f| f.culls_box(lo, hi));
        if S::ENABLED && culled {
            stats.event(Event::BoxesCulled, 1);
        }
        culled
    }

    /// Fig. 2 lines 21–27: every triangle of a leaf (`triangles`, indices into the tree's) the
    /// frustum does not cull, against the SIMD rays `active`. With `ANY` (occlusion) lanes end at their first hit. Returns whether the
    /// packet is done (occlusion: every lane occluded).
    #[inline(always)]
    pub fn leaf<S: Stats, const ANY: bool>(
        &mut self,
        tree: &Tree,
        triangles: std::ops::Range<usize>,
        depth: usize,
        active: ActiveRays,
        stats: &mut S,
    ) -> bool {
        let ids = match active {
            ActiveRays::Identity(range) => &self.identity[range],
            ActiveRays::Index(n) => &self.index[..n],
            ActiveRays::Alive => &self.alive[..],
        };
        if S::ENABLED {
            stats.event(Event::LeavesVisited, 1);
            let lanes: u32 = ids
                .iter()
                .map(|&g| self.groups[g as usize].live_lanes())
                .sum();
            stats.event(Event::LeafActiveRays, lanes as u64);
        }
        let bvh = tree.bvh;
        let first = self.first;
        // Camera rays share one origin and frame across the packet: each triangle is then made
        // relative to it once, not once per SIMD ray (`SharedFrame`).
        let shared = self.frame;
        // Lanes that found a closer hit here: without any, no `tmax` changed and the packet's
        // largest one (`max_t`) still holds, so its recount over every SIMD ray is skipped.
        let mut found = 0;
        for i in triangles {
            if S::ENABLED {
                stats.event(Event::TrianglesAccessed, 1);
            }
            let tri = &bvh.triangles[i];
            // A moving triangle is not where `tri` says at the rays' times: no triangle culling
            // (boxes are swept, so box culling stays exact).
            let moving_end = bvh.motion_end.as_ref().map(|end| &end[i]);
            if let Some(f) = self.frustum.as_ref().filter(|_| moving_end.is_none()) {
                if f.culls_triangle(tri) {
                    if S::ENABLED {
                        stats.event(Event::TrianglesCulled, 1);
                    }
                    continue;
                }
            }
            let prim = bvh.prim_ids[i];
            let relative = shared.map(|frame| frame.relative(tri));
            for &g in ids {
                let group = &mut self.groups[g as usize];
                if S::ENABLED {
                    stats.triangle_tests(
                        depth,
                        Owners::span(first + g as usize * L, group.used as usize),
                        L as u32,
                    );
                }
                let hits = match (moving_end, &relative) {
                    (None, Some(rel)) => group.intersect_relative::<ANY>(rel, prim),
                    (None, None) => group.intersect::<R, ANY>(tri, prim),
                    (Some(close), _) => group.intersect_moving::<R, ANY>(tri, close, prim),
                };
                found += hits;
                if ANY {
                    self.live -= hits;
                    if self.live == 0 {
                        return true;
                    }
                }
            }
        }
        if !ANY && found > 0 && (self.interval.is_some() || self.frustum.is_some()) {
            self.max_t = self.farthest_hit();
        }
        if let Some(f) = self.frustum.as_mut().filter(|_| !ANY) {
            // Also after a leaf without hits: the first leaf moves the far plane in from ∞.
            f.clip_far(self.max_t);
        }
        false
    }
}

/// The sum of `x`, accumulated in `L` lanes.
pub fn lane_sum<const L: usize>(x: &[f32]) -> f32 {
    let mut acc = [0.0f32; L];
    let chunks = x.chunks_exact(L);
    let rest: f32 = chunks.remainder().iter().sum();
    for chunk in chunks {
        for (a, v) in acc.iter_mut().zip(chunk) {
            *a += v;
        }
    }
    acc.iter().sum::<f32>() + rest
}

/// Which SIMD rays a leaf tests.
pub enum ActiveRays {
    /// SIMD rays `range` (Ranged: `[ia, ie)`; IA: `[ia, n)`).
    Identity(std::ops::Range<usize>),
    /// The first `n` entries of the index list (Partition).
    Index(usize),
    /// Masked's alive list.
    Alive,
}
