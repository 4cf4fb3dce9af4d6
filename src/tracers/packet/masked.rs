//! Masked traversal (Overbeck et al. 2008 §3.1, Fig. 2): at every node the SIMD rays are tested
//! from the first one on. At an interior node the scan stops at the first hit (Fig. 2 line 13) and
//! the whole packet descends; at a leaf every SIMD ray is tested and the alive ones (`rayMasks`,
//! kept here as a list of their indices) are tested against the leaf's triangles.
//!
//! The frustum test of line 8 comes first, before any ray test. Children front to back as in
//! Ranged (`order`).

use crate::geometry::RayTests;
use crate::stats::Stats;

use super::walk::RaySelection;
use super::workspace::{ActiveRays, Packet, Tree};

/// Fig. 2 `traverseBVH`.
pub struct Masked;

impl RaySelection for Masked {
    #[inline(always)]
    fn enter<const L: usize, R: RayTests, S: Stats>(
        packet: &mut Packet<L, R>,
        tree: &Tree,
        node: u32,
        _: u32,
        stats: &mut S,
    ) -> Option<u32> {
        let (depth, cell) = (tree.depth::<S>(node), tree.node(node));
        packet.alive.clear();
        if packet.frustum_culls(cell, stats) {
            return None;
        }
        for g in 0..packet.groups.len() as u32 {
            if packet.hits_box(g, cell, depth, stats) {
                packet.alive.push(g);
                if !cell.is_leaf() {
                    break;
                }
            }
        }
        (!packet.alive.is_empty()).then_some(0)
    }

    fn at_leaf<const L: usize, R: RayTests, S: Stats>(
        _: &Packet<L, R>,
        _: &Tree,
        _: u32,
        _: u32,
        _: &mut S,
    ) -> ActiveRays {
        ActiveRays::Alive
    }
}
