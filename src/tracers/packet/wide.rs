//! Large packets through a `W`-wide BVH (`width` = 4 or 8; `accel::WideBvh`), our addition beside
//! the paper's binary-tree traversals (Fuetterling et al. 2015 over a 4-wide tree; Wald, Benthin
//! and Boulos 2008 for the SIMD-across-children node test). It is Ranged traversal (App. A.1)
//! lifted to wide nodes:
//!
//! 1. At a node, one SIMD interval test (`IntervalPacket::survivors`, Wald et al. 2007 §4) of all
//!    `W` children against the whole packet's bounds — origins × reciprocal directions, clipped to
//!    the packet's largest current closest hit — drops every child no ray can meet; with
//!    `frustum` = true, one SIMD test of the children against the packet's frustum
//!    (`Frustum::survivors`, §4) drops more before they are pushed (shadow rays' shared end
//!    point: the interval of their spread origins bounds them loosely).
//! 2. The survivors go on the stack far to near, by their near corners along the packet's
//!    direction signs (Overbeck et al.'s `nearChild`/`farChild` generalised to W children), with
//!    the packet's first active SIMD ray `ia`.
//! 3. A popped child runs Ranged's `getFirstHit` from `ia` (its first SIMD ray, then the frustum if
//!    that one misses, then the rest) with the rays' current closest hits, so children behind
//!    hits found meanwhile are skipped. At a leaf, every SIMD ray after the first hit is tested
//!    against its box and only those that meet it test its triangles (Masked's leaf step, Fig. 2;
//!    `Packet::keep_hitting`, without a branch per verdict).
//!
//! Interior children's nodes are prefetched as they are pushed (our engineering): a popped child
//! reads its node only after its box tests, by which time the node's cache lines have arrived.
//!
//! Counters as the binary traversals': `node` for the root and for every child popped (tested),
//! box and triangle tests per lane of each SIMD ray tested; the node test is counted only as the
//! `BoxesCulled` it culls.
//!
//! Hits are exact for the same reasons as the binary traversals': every per-ray test is the
//! reference's slab and watertight test lane by lane, and both culls are conservative.

// Lane loops index several lane arrays in lock step: the indexed form is what LLVM vectorizes.
#![allow(clippy::needless_range_loop)]

use crate::accel::{WideBvh, WideChild};
use crate::geometry::ray::prefetch;
use crate::geometry::RayTests;
use crate::stats::{Event, Stats};

use super::ranged::first_hit_in;
use super::workspace::{ActiveRays, Packet, Tree};

/// A child waiting on the stack: slot `slot` of wide node `parent`, entered with `ia`.
#[derive(Clone, Copy, Default)]
struct Pending {
    parent: u32,
    slot: u32,
    ia: u32,
}

/// Deep enough for any tree: a wide node is no deeper than the binary node it came from
/// (`BvhConfig::DEPTH_LIMIT`), and each level leaves at most `W − 1 ≤ 7` siblings behind.
const STACK: usize = 8 * (crate::accel::BvhConfig::DEPTH_LIMIT + 2);

/// The traversal stack, made once per batch (6 KB: zeroing it per packet showed in profiles).
pub struct WideStack(Box<[Pending; STACK]>);

impl Default for WideStack {
    fn default() -> Self {
        WideStack(Box::new([Pending::default(); STACK]))
    }
}

/// Walks the packet through `wide` (module doc). `tree` holds the triangles the leaves index.
pub fn traverse_wide<const W: usize, const L: usize, R: RayTests, S: Stats, const ANY: bool>(
    packet: &mut Packet<L, R>,
    tree: &Tree,
    wide: &WideBvh<W>,
    stack: &mut WideStack,
    stats: &mut S,
) {
    let stack = &mut *stack.0;
    let mut top = 0;
    let mut node = 0u32;
    let mut ia = 0u32;
    if S::ENABLED {
        stats.node_shared(0, packet.owners());
    }
    loop {
        expand(packet, wide, node, ia, stack, &mut top, stats);
        // Pop until an interior child is entered.
        loop {
            if top == 0 {
                return;
            }
            top -= 1;
            let Pending {
                parent,
                slot,
                ia: at,
            } = stack[top];
            let cell = &wide.nodes[parent as usize];
            let depth = if S::ENABLED {
                wide.depth[parent as usize] as usize + 1
            } else {
                0
            };
            if S::ENABLED {
                stats.node_shared(depth, packet.owners());
            }
            let (lo, hi) = cell.child_box(slot as usize);
            let culls = |p: &Packet<L, R>, s: &mut S| p.frustum_culls_bounds(lo, hi, s);
            let Some(first) = first_hit_in(packet, lo, hi, at, depth, stats, culls) else {
                continue;
            };
            match cell.child(slot as usize) {
                WideChild::Node(child) => {
                    (node, ia) = (child, first);
                    break;
                }
                WideChild::Leaf { block, count } => {
                    // Only the SIMD rays that meet the leaf's box test its triangles (Masked's
                    // leaf step, Fig. 2): one box test saves a SIMD ray the triangle tests of
                    // every triangle of the leaf, where Ranged's `getLastHit` range would test
                    // every SIMD ray between the first and the last that meet it.
                    packet.keep_hitting(first, lo, hi, depth, stats);
                    let triangles = wide.triangles(block, count);
                    let active = ActiveRays::Alive;
                    if packet.leaf::<S, ANY>(tree, triangles, depth, active, stats) {
                        return;
                    }
                }
                WideChild::Empty => unreachable!("empty slots never survive the node test"),
            }
        }
    }
}

/// Steps 1–2 of the module doc at wide node `node`, entered with first active SIMD ray `ia`.
#[inline(always)]
fn expand<const W: usize, const L: usize, R: RayTests, S: Stats>(
    packet: &Packet<L, R>,
    wide: &WideBvh<W>,
    node: u32,
    ia: u32,
    stack: &mut [Pending; STACK],
    top: &mut usize,
    stats: &mut S,
) {
    let cell = &wide.nodes[node as usize];
    let used = cell.used();
    let mut survivors = used;
    if let Some(interval) = &packet.interval {
        survivors &= interval.survivors(&cell.lo, &cell.hi, packet.max_t);
    }
    if let Some(frustum) = &packet.frustum {
        survivors &= frustum.survivors(&cell.lo, &cell.hi);
    }
    if S::ENABLED {
        let culled = (used & !survivors).count_ones();
        stats.event(Event::BoxesCulled, culled as u64);
    }
    // Distance key of each child's near corner along the packet's direction signs: the
    // nearer child has the smaller key.
    let mut key = [0.0f32; W];
    for (a, &negative) in packet.negative.iter().enumerate() {
        for c in 0..W {
            key[c] += if negative {
                -cell.hi[a][c]
            } else {
                cell.lo[a][c]
            };
        }
    }
    // Push far to near: the nearest child ends on top. Insertion sort of at most W slots.
    let mut order = [0u32; W];
    let mut n = 0;
    while survivors != 0 {
        let c = survivors.trailing_zeros();
        survivors &= survivors - 1;
        let mut i = n;
        while i > 0 && key[order[i - 1] as usize] < key[c as usize] {
            order[i] = order[i - 1];
            i -= 1;
        }
        order[i] = c;
        n += 1;
    }
    for &slot in &order[..n] {
        stack[*top] = Pending {
            parent: node,
            slot,
            ia,
        };
        *top += 1;
        // A child node is read only after its box tests, so asked for now it is in the cache
        // by then (each wide node is several cache lines, and otherwise missed once per visit).
        if let WideChild::Node(child) = cell.child(slot as usize) {
            prefetch(std::slice::from_ref(&wide.nodes[child as usize]));
        }
    }
}
