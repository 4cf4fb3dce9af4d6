//! Ranged traversal (Overbeck et al. 2008 §3.2, App. A.1; Lauterbach et al. 2006): the packet
//! carries `ia`, its first alive SIMD ray, down the tree; `getFirstHit` advances it, and at a leaf
//! `getLastHit` finds `ie`, so SIMD rays `[ia, ie)` are tested against the leaf's triangles.
//!
//! Choices the paper leaves open: children front to back by the packet's summed direction
//! (`order`); the frustum test of `getFirstHit` runs only after the first active ray misses, as in
//! the paper's listing; `getLastHit` does not consult the frustum (the leaf's box was just hit
//! by ray `ia`).

use crate::stats::Stats;

use super::workspace::{ActiveRays, Packet, Pending, Stack, Tree};

/// `getFirstHit`: the first SIMD ray from `ia` on that meets the box of `node`, or `n` (§3.2).
#[inline(always)]
pub fn first_hit<const L: usize, S: Stats>(
    packet: &Packet<L>,
    tree: &Tree,
    node: u32,
    ia: u32,
    stats: &mut S,
) -> u32 {
    let (n, depth, cell) = (
        packet.groups.len() as u32,
        tree.depth::<S>(node),
        tree.node(node),
    );
    if packet.hits_box(ia, cell, depth, stats) {
        return ia;
    }
    if packet.frustum_culls(cell, stats) {
        return n;
    }
    (ia + 1..n)
        .find(|&g| packet.hits_box(g, cell, depth, stats))
        .unwrap_or(n)
}

/// `getLastHit`: one past the last SIMD ray after `ia` that meets the box of `node` (`ia + 1`
/// when none does).
#[inline(always)]
fn last_hit<const L: usize, S: Stats>(
    packet: &Packet<L>,
    tree: &Tree,
    node: u32,
    ia: u32,
    stats: &mut S,
) -> u32 {
    let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
    (ia + 1..packet.groups.len() as u32)
        .rev()
        .find(|&g| packet.hits_box(g, cell, depth, stats))
        .map_or(ia + 1, |g| g + 1)
}

/// App. A.1 `rangedTraverseBVH`.
pub fn traverse<const L: usize, S: Stats, const ANY: bool>(
    packet: &mut Packet<L>,
    tree: &Tree,
    stats: &mut S,
) {
    let n = packet.groups.len() as u32;
    let mut stack: Stack = [Pending::default(); _];
    let mut top = 0;
    let (mut node, mut ia) = (0u32, 0u32);
    loop {
        if S::ENABLED {
            stats.node(tree.depth::<S>(node));
        }
        ia = first_hit(packet, tree, node, ia, stats);
        if ia < n {
            let cell = tree.node(node);
            if !cell.is_leaf() {
                let (near, far) = tree
                    .order
                    .near_far(node as usize, cell.first, packet.negative);
                stack[top] = Pending { node: far, ia };
                top += 1;
                node = near;
                continue;
            }
            let ie = last_hit(packet, tree, node, ia, stats);
            let depth = tree.depth::<S>(node);
            let done = packet.leaf::<S, ANY>(
                tree,
                cell,
                depth,
                ActiveRays::Identity(ia as usize..ie as usize),
                stats,
            );
            if done {
                return;
            }
        }
        if top == 0 {
            return;
        }
        top -= 1;
        (node, ia) = (stack[top].node, stack[top].ia);
    }
}
