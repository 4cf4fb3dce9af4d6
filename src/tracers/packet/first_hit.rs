//! First-hit traversal with interval-arithmetic culling (Wald, Boulos and Shirley 2007 §4, as used
//! by Boulos et al. 2007 §3.3): at a node the packet's first active SIMD ray is tested; if it hits,
//! the whole packet descends at once. Otherwise the interval bounds of the packet (`interval`) try
//! to cull the box for every ray; only if they cannot are the remaining SIMD rays tested one by
//! one for a first hit. The index of the first hit is carried down (as Ranged's `ia`), and a leaf
//! tests every SIMD ray from it to the end of the packet, as Wald et al. do (no `getLastHit`).
//!
//! With `frustum` on, the frustum also culls boxes after the interval test, and triangles at the
//! leaves. Children front to back by the packet's summed direction (`order`).

use crate::geometry::RayTests;
use crate::stats::{Event, Stats};

use super::ranged::first_hit;
use super::walk::RaySelection;
use super::workspace::{ActiveRays, Packet, Tree};

pub struct FirstHit;

impl RaySelection for FirstHit {
    /// The first SIMD ray from `ia` on that meets the box of `node`; when ray `ia` misses, the
    /// interval bounds, then the frustum, may cull the box for the whole packet.
    #[inline(always)]
    fn enter<const L: usize, R: RayTests, S: Stats>(
        packet: &mut Packet<L, R>,
        tree: &Tree,
        node: u32,
        ia: u32,
        stats: &mut S,
    ) -> Option<u32> {
        first_hit(packet, tree, node, ia, stats, |p, cell, s| {
            // No interval bounds: a packet with an ill-formed ray (`Packet::load`).
            let culled = p.interval.as_ref().is_some_and(|interval| {
                interval.culls(
                    cell.bounds.min.to_array(),
                    cell.bounds.max.to_array(),
                    p.max_t,
                )
            });
            if culled {
                if S::ENABLED {
                    s.event(Event::BoxesCulled, 1);
                }
                return true;
            }
            p.frustum_culls(cell, s)
        })
    }

    fn at_leaf<const L: usize, R: RayTests, S: Stats>(
        packet: &Packet<L, R>,
        _: &Tree,
        _: u32,
        ia: u32,
        _: &mut S,
    ) -> ActiveRays {
        ActiveRays::Identity(ia as usize..packet.groups.len())
    }
}
