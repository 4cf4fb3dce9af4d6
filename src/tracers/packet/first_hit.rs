//! First-hit traversal with interval-arithmetic culling (Wald, Boulos and Shirley 2007 §4, as used
//! by Boulos et al. 2007 §3.3): at a node the packet's first active SIMD ray is tested; if it hits,
//! the whole packet descends at once. Otherwise the interval bounds of the packet (`interval`) try
//! to cull the box for every ray; only if they cannot are the remaining SIMD rays tested one by
//! one for a first hit. The index of the first hit is carried down (as Ranged's `ia`), and a leaf
//! tests every SIMD ray from it to the end of the packet, as Wald et al. do (no `getLastHit`).
//!
//! With `frustum` on, the frustum also culls boxes after the interval test, and triangles at the
//! leaves. Children front to back by the packet's summed direction (`order`).

use crate::stats::{Event, Stats};

use super::workspace::{ActiveRays, Packet, Pending, Stack, Tree};

/// The first SIMD ray from `ia` on that meets the box of `node`, or `n`.
#[inline(always)]
fn first_hit<const L: usize, S: Stats>(
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
    let interval = packet
        .interval
        .as_ref()
        .expect("IA traversal loads interval bounds");
    if interval.culls(
        cell.bounds.min.to_array(),
        cell.bounds.max.to_array(),
        packet.max_t,
    ) {
        if S::ENABLED {
            stats.event(Event::BoxesCulled, 1);
        }
        return n;
    }
    if packet.frustum_culls(cell, stats) {
        return n;
    }
    (ia + 1..n)
        .find(|&g| packet.hits_box(g, cell, depth, stats))
        .unwrap_or(n)
}

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
            let depth = tree.depth::<S>(node);
            let active = ActiveRays::Identity(ia as usize..n as usize);
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
