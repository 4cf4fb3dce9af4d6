//! Partition traversal (Overbeck et al. 2008 §3.3, App. A.2): an index list `I` of the SIMD rays
//! is partitioned in place at every node so that the alive ones come first (`partRays`), and the
//! packet carries only their count `ia`. Leaves test exactly the alive SIMD rays `I[0..ia)`.
//!
//! Two slips of the paper's listings are corrected: `partRays` returns 0, not `size(R)`, when the
//! frustum culls the box (its callers treat `ia = 0` as "no ray alive"), and A.2's leftover
//! `getLastHit` call at a leaf is dropped (its result is unused there). Children are visited front
//! to back as in Ranged (`order`). Popping a node restores its `ia`: the subtree below only
//! permuted `I[0..ia)` among itself, so those entries are still the node's alive SIMD rays.

use crate::geometry::RayTests;
use crate::stats::Stats;

use super::walk::RaySelection;
use super::workspace::{ActiveRays, Packet, Tree};

/// App. A.2 `partitionTraverseBVH`.
pub struct Partition;

impl RaySelection for Partition {
    fn root<const L: usize, R: RayTests>(packet: &Packet<L, R>) -> u32 {
        packet.groups.len() as u32
    }

    /// `partRays`: moves the SIMD rays among `I[0..ia)` that meet the box of `node` to the front
    /// and keeps their count.
    #[inline(always)]
    fn enter<const L: usize, R: RayTests, S: Stats>(
        packet: &mut Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> Option<u32> {
        let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
        if packet.frustum_culls(cell, stats) {
            return None;
        }
        let mut ie = 0;
        for i in 0..ia as usize {
            let g = packet.index[i];
            if packet.hits_box(g, cell, depth, stats) {
                packet.index.swap(ie, i);
                ie += 1;
            }
        }
        (ie > 0).then_some(ie as u32)
    }

    fn at_leaf<const L: usize, R: RayTests, S: Stats>(
        _: &Packet<L, R>,
        _: &Tree,
        _: u32,
        ia: u32,
        _: &mut S,
    ) -> ActiveRays {
        ActiveRays::Index(ia as usize)
    }
}
