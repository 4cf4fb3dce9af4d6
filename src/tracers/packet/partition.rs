//! Partition traversal (Overbeck et al. 2008 §3.3, App. A.2): an index list `I` of the SIMD rays
//! is partitioned in place at every node so that the alive ones come first (`partRays`), and the
//! packet carries only their count `ia`. Leaves test exactly the alive SIMD rays `I[0..ia)`.
//!
//! Two slips of the paper's listings are corrected: `partRays` returns 0, not `size(R)`, when the
//! frustum culls the box (its callers treat `ia = 0` as "no ray alive"), and A.2's leftover
//! `getLastHit` call at a leaf is dropped (its result is unused there). Children are visited front
//! to back as in Ranged (`order`). Popping a node restores its `ia`: the subtree below only
//! permuted `I[0..ia)` among itself, so those entries are still the node's alive SIMD rays.

use crate::stats::Stats;

use super::workspace::{ActiveRays, Packet, Pending, Stack, Tree};

/// `partRays`: moves the SIMD rays among `I[0..ia)` that meet the box of `node` to the front and
/// returns their count.
#[inline(always)]
fn part_rays<const L: usize, S: Stats>(
    packet: &mut Packet<L>,
    tree: &Tree,
    node: u32,
    ia: u32,
    stats: &mut S,
) -> u32 {
    let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
    if packet.frustum_culls(cell, stats) {
        return 0;
    }
    let mut ie = 0;
    for i in 0..ia as usize {
        let g = packet.index[i];
        if packet.hits_box(g, cell, depth, stats) {
            packet.index.swap(ie, i);
            ie += 1;
        }
    }
    ie as u32
}

/// App. A.2 `partitionTraverseBVH`.
pub fn traverse<const L: usize, S: Stats, const ANY: bool>(
    packet: &mut Packet<L>,
    tree: &Tree,
    stats: &mut S,
) {
    let mut stack: Stack = [Pending::default(); _];
    let mut top = 0;
    let (mut node, mut ia) = (0u32, packet.groups.len() as u32);
    loop {
        if S::ENABLED {
            stats.node(tree.depth::<S>(node));
        }
        ia = part_rays(packet, tree, node, ia, stats);
        if ia > 0 {
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
            let depth = tree.depth::<S>(node);
            let active = ActiveRays::Index(ia as usize);
            if packet.leaf::<S, ANY>(tree, cell, depth, active, stats) {
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
