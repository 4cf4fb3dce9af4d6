//! Single rays through the wide BVH (`accel::WideBvh`, 4 or 8 children per node, collapsed from
//! the binary SAH tree): the single-ray traversal of production ray tracers (Wald, Benthin and
//! Boulos 2008 "Getting rid of packets"; Embree's `bvh_intersector1`, Ernst and Greiner 2008),
//! SIMD across a node's children instead of across rays. Our addition, not one of the papers': it
//! is the stream tracer's hand-off kernel (`stream`'s `single_tree`) and shows on its own, beside
//! `embree3-1`, what one ray at a time costs on a wide tree.
//!
//! - **Node**: one slab test of the ray against all `W` children (`slab`: 8 at a time in AVX2,
//!   else SSE groups of 4), within `[tmin, tmax]` with `tmax` the current closest hit.
//! - **Order**: a lone child met is entered at once (Embree's `BVHNNodeTraverser1Hit` does the
//!   same; on incoherent rays it is the common case, and it saves the stack's store and load);
//!   otherwise the children met go on the stack far to near by entry distance, so the nearest is
//!   popped first (occlusion rays push them unsorted, as Embree's any-hit traversal); a popped
//!   child whose entry lies beyond the closest hit found meanwhile is skipped untested. A pushed
//!   child's node or leaf triangles are prefetched (a wide node spans four cache lines and the
//!   walk is bound by their loads: the siblings' misses overlap).
//! - **Leaves**: blocks of four triangles, each tested against the ray at once (`leaf`; Embree's
//!   `Triangle4`), finding bit for bit what the reference tracer's leaf stage finds
//!   (`reference::intersect_leaf`: the watertight test, in the leaf's order; moving triangles at
//!   the ray's time, by that stage itself), and the slab verdicts are the reference's, so every
//!   ray gets the reference's closest hit (up to the order in which triangles at exactly equal
//!   distance are met). Occlusion stops at the first hit.
//! - **`robust`**: `true` (default) as above; `false` (`R = Fast`) plain slabs and Möller–Trumbore,
//!   as Embree's non-robust mode, for a like-for-like comparison with it (`geometry::robustness`):
//!   then the hits are `reference`'s with `robust = false`.
//!
//! Counters: `ray` per ray; `node(depth)` per wide node whose children are tested and per leaf
//! whose triangles are; `aabb_test(depth)` per child slot tested (the children's depth);
//! `triangle_test(depth)` per triangle tested.

mod leaf;
mod slab;

use std::marker::PhantomData;
use std::mem::MaybeUninit;
use std::sync::Arc;

use crate::accel::{Bvh, BvhConfig, WideBvh, WideEntry, WideNode, WideNodes, WideTree};
use crate::error::{Error, Result};
use crate::geometry::{Hit, Ray, RayTests, Robust};
use crate::lanes::prefetch::{self, Level};
use crate::lanes::triangle_block::BlockTests;
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::kernel::SingleRayKernel;
use crate::tracers::reference::LeafRay;
use leaf::WideLeaf;

pub use slab::WideRayTest;

/// Single rays through a wide tree of either width (the walk is generic over it; which one is a
/// branch per ray, always taken the same way). `R`: the box and triangle tests (`robust`;
/// `Robust` unless asked).
pub struct WideSingleTracer<R: RayTests = Robust> {
    tree: Arc<WideTree>,
    tests: PhantomData<R>,
}

impl<R: RayTests> WideSingleTracer<R> {
    /// Over `tree`, built by the run as the structure of this tracer's `width`.
    pub fn new(tree: Arc<WideTree>) -> Self {
        WideSingleTracer {
            tree,
            tests: PhantomData,
        }
    }
}

/// Children per node (`width`) of the tracer's tree.
pub const WIDTHS: [usize; 2] = [4, 8];
pub const PARAMS: &[&str] = &["width"];

/// Children per node of the tracer's tree (`width`): its typed configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Width {
    Four,
    Eight,
}

impl Width {
    /// The `width` parameter (4 or 8, default 8), checked.
    pub fn from_params(params: &Params) -> Result<Width> {
        match params.get_or("width", 8usize)? {
            4 => Ok(Width::Four),
            8 => Ok(Width::Eight),
            width => Err(Error::usage(format!(
                "wide-single tracer: width must be one of {WIDTHS:?} (children per BVH node; got {width})"
            ))),
        }
    }

    /// Children per node.
    pub fn children(self) -> usize {
        match self {
            Width::Four => 4,
            Width::Eight => 8,
        }
    }
}

impl<R: BlockTests> SingleRayKernel for WideSingleTracer<R> {
    #[inline(always)]
    fn trace<S: Stats, const ANY: bool>(&self, ray: &Ray, stats: &mut S) -> Hit {
        if S::ENABLED {
            stats.ray();
        }
        let bvh = &self.tree.bvh;
        match &self.tree.nodes {
            WideNodes::Four(wide) => trace_from_root::<4, R, S, ANY>(bvh, wide, ray, stats),
            WideNodes::Eight(wide) => trace_from_root::<8, R, S, ANY>(bvh, wide, ray, stats),
        }
    }
}

/// `ray` from the root of `wide` (a miss for an empty tree).
#[inline(always)]
fn trace_from_root<const W: usize, R: BlockTests, S: Stats, const ANY: bool>(
    bvh: &Bvh,
    wide: &WideBvh<W>,
    ray: &Ray,
    stats: &mut S,
) -> Hit {
    if wide.is_empty() {
        return Hit::MISS;
    }
    let root = wide.entry[Bvh::ROOT];
    trace_wide::<W, R, S, ANY>(bvh, wide, root, &WideRay::<R>::new(ray), stats)
}

/// One ray as `trace_wide` reads it: its test of a wide node's children, what the leaf stage
/// reads, and its segment's end.
#[derive(Clone, Copy)]
pub struct WideRay<R: RayTests = Robust> {
    pub boxes: WideRayTest<R>,
    pub leaf: LeafRay<R>,
    pub tmax: f32,
}

impl<R: RayTests> WideRay<R> {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        WideRay {
            boxes: WideRayTest::new(ray.origin, ray.dir),
            leaf: LeafRay::new(ray),
            tmax: ray.tmax,
        }
    }
}

/// A child waiting on the stack: an interior wide node (`count = 0`: node `first`) or a leaf
/// (`count` triangles in the blocks from `first`), and the distance at which the ray enters its
/// box. 12 bytes: its depth (counters
/// only) waits beside it in an array the uncounted traversal never touches.
#[derive(Clone, Copy)]
struct Pending {
    first: u32,
    count: u32,
    enter: f32,
}

/// Asks for all of `node`'s cache lines (a wide node spans several).
#[inline(always)]
fn prefetch_node<const W: usize>(node: &WideNode<W>) {
    let base = node as *const WideNode<W> as *const u8;
    for offset in (0..std::mem::size_of::<WideNode<W>>()).step_by(prefetch::LINE) {
        prefetch::line(base.wrapping_add(offset), Level::Near);
    }
}

/// The widest node this traversal takes.
const MAX_WIDTH: usize = 8;

/// Deep enough for any tree of at most `MAX_WIDTH` children: a wide node is no deeper than the
/// binary node it came from, and each level leaves at most `W − 1` siblings behind (plus the
/// slots of the entry node).
const STACK: usize = MAX_WIDTH * (BvhConfig::DEPTH_LIMIT + 2);

/// One ray's traversal (module doc) of the subtree at `start` (its slots of its wide node, whose
/// boxes are tested here): the closest hit (`ANY`: the first found) within `[ray.leaf.tmin,
/// ray.tmax]`, or a miss. `wide` was collapsed from `bvh`, whose triangles the leaves index.
/// `R`: the box and triangle tests.
#[inline(always)]
pub fn trace_wide<const W: usize, R: BlockTests, S: Stats, const ANY: bool>(
    bvh: &Bvh,
    wide: &WideBvh<W>,
    start: WideEntry,
    ray: &WideRay<R>,
    stats: &mut S,
) -> Hit {
    const {
        assert!(
            W <= MAX_WIDTH,
            "wide single rays take at most 8 children per node"
        )
    };
    let mut best = Hit::MISS;
    let (tmin, mut tmax) = (ray.leaf.tmin, ray.tmax);
    let boxes = &ray.boxes;
    // Uninitialised: zeroing kilobytes of stack per ray would cost more than a short traversal;
    // only entries below `top`, all written first, are read. `depths` is written and read only
    // when counting.
    let mut stack = [const { MaybeUninit::<Pending>::uninit() }; STACK];
    let mut depths = [const { MaybeUninit::<u8>::uninit() }; STACK];
    let mut top = 0;
    let (mut node, mut slots) = (start.node, start.slots);
    loop {
        let cell = &wide.nodes[node as usize];
        let depth = if S::ENABLED {
            wide.depth[node as usize]
        } else {
            0
        };
        if S::ENABLED {
            stats.node(depth as usize);
            let tested = (slots & cell.used()).count_ones();
            (0..tested).for_each(|_| stats.aabb_test(depth as usize + 1));
        }
        let (enter, hit) = boxes.test::<W>(cell, tmin, tmax);
        let mut hit = hit & slots;
        // The child entered at once, without a stack round trip (0: none): a lone one met (the
        // common case on incoherent rays); for occlusion, the last one met, the others pushed
        // below in slot order (Embree's any-hit traversal is unsorted too; entering it measured
        // 3–9% faster than popping it). Its entry lies within the closest hit, so nothing is
        // skipped that the pop below would not skip either.
        let entered = if ANY && hit != 0 {
            let last = 1 << (31 - hit.leading_zeros());
            hit &= !last;
            last
        } else if hit & hit.wrapping_sub(1) == 0 {
            std::mem::take(&mut hit)
        } else {
            0
        };
        // Push the other children met, keeping this node's run of the stack sorted far to near
        // (equal entries: the later slot first, as popped); occlusion's unsorted, in slot order:
        // any hit ends it, so near-first order buys little and the sort costs every node.
        let base = top;
        while hit != 0 {
            let c = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            let child = Pending {
                first: cell.first[c],
                count: cell.count[c],
                enter: enter[c],
            };
            // Its node or triangles are read soon (the nearest child next): start the loads
            // now, so the children's misses overlap.
            if child.count == 0 {
                prefetch_node(&wide.nodes[child.first as usize]);
            } else {
                leaf::prefetch(wide, child.first);
            }
            let mut at = top;
            // SAFETY: entries base..top were written by this loop.
            while !ANY
                && at > base
                && unsafe { stack[at - 1].assume_init_ref() }.enter < child.enter
            {
                stack[at] = stack[at - 1];
                if S::ENABLED {
                    depths[at] = depths[at - 1];
                }
                at -= 1;
            }
            stack[at].write(child);
            if S::ENABLED {
                depths[at].write(depth + 1);
            }
            top += 1;
        }
        if entered != 0 {
            let c = entered.trailing_zeros() as usize;
            if cell.count[c] == 0 {
                (node, slots) = (cell.first[c], u32::MAX);
                continue;
            }
            let leaf = WideLeaf {
                block: cell.first[c],
                count: cell.count[c],
                depth: depth as usize + 1,
            };
            if leaf::visit::<W, R, S, ANY>(bvh, wide, &ray.leaf, leaf, &mut tmax, &mut best, stats)
            {
                return best;
            }
        }
        // Pop the nearest, skipping children now beyond the closest hit, until an interior node.
        loop {
            if top == 0 {
                return best;
            }
            top -= 1;
            // SAFETY: every entry below the old `top` was written by a push (and its depth, when
            // counting).
            let next = unsafe { stack[top].assume_init() };
            if next.enter > tmax {
                continue;
            }
            if next.count == 0 {
                (node, slots) = (next.first, u32::MAX);
                break;
            }
            let leaf = WideLeaf {
                block: next.first,
                count: next.count,
                depth: if S::ENABLED {
                    unsafe { depths[top].assume_init() as usize }
                } else {
                    0
                },
            };
            if leaf::visit::<W, R, S, ANY>(bvh, wide, &ray.leaf, leaf, &mut tmax, &mut best, stats)
            {
                return best;
            }
        }
    }
}
