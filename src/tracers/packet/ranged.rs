//! Ranged traversal (Overbeck et al. 2008 §3.2, App. A.1; Lauterbach et al. 2006): the packet
//! carries `ia`, its first alive SIMD ray, down the tree; `getFirstHit` advances it, and at a leaf
//! `getLastHit` finds `ie`, so SIMD rays `[ia, ie)` are tested against the leaf's triangles.
//!
//! Choices the paper leaves open: children front to back by the packet's summed direction
//! (`order`); the frustum test of `getFirstHit` runs only after the first active ray misses, as in
//! the paper's listing; `getLastHit` does not consult the frustum (the leaf's box was just hit
//! by ray `ia`).

use crate::accel::BvhNode;
use crate::geometry::RayTests;
use crate::stats::Stats;

use super::walk::RaySelection;
use super::workspace::{ActiveRays, Packet, Tree};

/// The first SIMD ray from `ia` on that meets the box of `node`, or `None`: ray `ia` is tested
/// first; only when it misses may `culls` reject the box for the whole packet, and otherwise the
/// rays after it are tested in order (Ranged's `getFirstHit`; IA's first-hit test with interval
/// culling).
#[inline(always)]
pub fn first_hit<const L: usize, R: RayTests, S: Stats>(
    packet: &Packet<L, R>,
    tree: &Tree,
    node: u32,
    ia: u32,
    stats: &mut S,
    culls: impl FnOnce(&Packet<L, R>, &BvhNode, &mut S) -> bool,
) -> Option<u32> {
    let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
    let (lo, hi) = (cell.bounds.min.to_array(), cell.bounds.max.to_array());
    first_hit_in(packet, lo, hi, ia, depth, stats, |p, s| culls(p, cell, s))
}

/// `first_hit` for the box `[lo, hi]` at `depth`.
#[inline(always)]
pub fn first_hit_in<const L: usize, R: RayTests, S: Stats>(
    packet: &Packet<L, R>,
    lo: [f32; 3],
    hi: [f32; 3],
    ia: u32,
    depth: usize,
    stats: &mut S,
    culls: impl FnOnce(&Packet<L, R>, &mut S) -> bool,
) -> Option<u32> {
    let n = packet.groups.len() as u32;
    if packet.hits_bounds(ia, lo, hi, depth, stats) {
        return Some(ia);
    }
    if culls(packet, stats) {
        return None;
    }
    (ia + 1..n).find(|&g| packet.hits_bounds(g, lo, hi, depth, stats))
}

/// App. A.1 `rangedTraverseBVH`.
pub struct Ranged;

impl RaySelection for Ranged {
    /// `getFirstHit`: the first SIMD ray from `ia` on that meets the box of `node` (§3.2).
    #[inline(always)]
    fn enter<const L: usize, R: RayTests, S: Stats>(
        packet: &mut Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> Option<u32> {
        first_hit(packet, tree, node, ia, stats, |p, cell, s| {
            p.frustum_culls(cell, s)
        })
    }

    /// `getLastHit`: SIMD rays up to one past the last one after `ia` that meets the leaf's box.
    #[inline(always)]
    fn at_leaf<const L: usize, R: RayTests, S: Stats>(
        packet: &Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> ActiveRays {
        let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
        let ie = (ia + 1..packet.groups.len() as u32)
            .rev()
            .find(|&g| packet.hits_box(g, cell, depth, stats))
            .map_or(ia + 1, |g| g + 1);
        ActiveRays::Identity(ia as usize..ie as usize)
    }
}
