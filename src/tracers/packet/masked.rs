//! Masked traversal (Overbeck et al. 2008 §3.1, Fig. 2): at every node the SIMD rays are tested
//! from the first one on. At an interior node the scan stops at the first hit (Fig. 2 line 13) and
//! the whole packet descends; at a leaf every SIMD ray is tested and the alive ones (`rayMasks`,
//! kept here as a list of their indices) are tested against the leaf's triangles.
//!
//! The frustum test of line 8 comes first, before any ray test. Children front to back as in
//! Ranged (`order`).

use crate::stats::Stats;

use super::workspace::{ActiveRays, Packet, Pending, Stack, Tree};

/// Fig. 2 `traverseBVH`.
pub fn traverse<const L: usize, S: Stats, const ANY: bool>(
    packet: &mut Packet<L>,
    tree: &Tree,
    stats: &mut S,
) {
    let n = packet.groups.len() as u32;
    let mut stack: Stack = [Pending::default(); _];
    let mut top = 0;
    let mut node = 0u32;
    loop {
        let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
        if S::ENABLED {
            stats.node(depth);
        }
        packet.alive.clear();
        if !packet.frustum_culls(cell, stats) {
            for g in 0..n {
                if packet.hits_box(g, cell, depth, stats) {
                    packet.alive.push(g);
                    if !cell.is_leaf() {
                        break;
                    }
                }
            }
        }
        if !packet.alive.is_empty() {
            if !cell.is_leaf() {
                let (near, far) = tree
                    .order
                    .near_far(node as usize, cell.first, packet.negative);
                stack[top] = Pending { node: far, ia: 0 };
                top += 1;
                node = near;
                continue;
            }
            if packet.leaf::<S, ANY>(tree, cell, depth, ActiveRays::Alive, stats) {
                return;
            }
        }
        if top == 0 {
            return;
        }
        top -= 1;
        node = stack[top].node;
    }
}
