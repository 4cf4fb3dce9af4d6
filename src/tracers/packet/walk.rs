//! The depth-first walk all four traversals share (Overbeck et al. 2008 Fig. 2 / App. A): test a
//! node, descend to the nearer child with the farther one on a stack (front to back by `order`),
//! run the leaf step, pop. What differs between the algorithms is only how a node narrows the
//! packet's active SIMD rays and which of them a leaf tests: that is a `RaySelection`.

use crate::geometry::RayTests;
use crate::stats::Stats;

use super::workspace::{ActiveRays, Packet, Pending, Stack, Tree};

/// One traversal algorithm's per-node ray selection. The state `ia` travels down the tree and is
/// restored from the stack (Ranged/IA: the first active SIMD ray; Partition: the number of alive
/// ones at the front of the index list; Masked: unused).
pub trait RaySelection {
    /// The state at the root (the first SIMD ray, by default).
    fn root<const L: usize, R: RayTests>(_: &Packet<L, R>) -> u32 {
        0
    }

    /// Tests the box of `node` against the packet: the state below it, or `None` when no ray
    /// meets it (the subtree is skipped).
    fn enter<const L: usize, R: RayTests, S: Stats>(
        packet: &mut Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> Option<u32>;

    /// The SIMD rays a leaf entered with state `ia` tests against its triangles.
    fn at_leaf<const L: usize, R: RayTests, S: Stats>(
        packet: &Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> ActiveRays;
}

/// Walks the packet through the tree with the selection `Sel` and the tests `R`.
pub fn traverse<Sel: RaySelection, const L: usize, R: RayTests, S: Stats, const ANY: bool>(
    packet: &mut Packet<L, R>,
    tree: &Tree,
    stats: &mut S,
) {
    let mut stack: Stack = [Pending::default(); _];
    let mut top = 0;
    let (mut node, mut ia) = (0u32, Sel::root(packet));
    loop {
        let depth = tree.depth::<S>(node);
        if S::ENABLED {
            stats.node_shared(depth, packet.owners());
        }
        if let Some(below) = Sel::enter(packet, tree, node, ia, stats) {
            ia = below;
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
            let active = Sel::at_leaf(packet, tree, node, ia, stats);
            let triangles = cell.first as usize..(cell.first + cell.count) as usize;
            if packet.leaf::<S, ANY>(tree, triangles, depth, active, stats) {
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
