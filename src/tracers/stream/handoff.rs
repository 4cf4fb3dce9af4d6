//! The kernel a short sub-stream's rays finish their subtree with (`single` > 0): the reference
//! tracer's binary traversal (`single_tree = 2`, `reference::trace_subtree`), or single rays
//! through the tree collapsed to 4 or 8 children per node (`single_tree = 4 | 8`,
//! `wide_single::trace_wide`), entered where the binary node the stream reached sits in it
//! (`WideBvh::entry`). Both find the reference's hits.

use crate::accel::{Bvh, WideBvh};
use crate::geometry::{Hit, Ray};
use crate::stats::Stats;
use crate::tracers::packet::TreeWidth;
use crate::tracers::reference::trace_subtree;
use crate::tracers::wide_single::trace_wide;

pub enum Handoff {
    Binary,
    Four(WideBvh<4>),
    Eight(WideBvh<8>),
}

impl Handoff {
    /// The hand-off over a tree of `width` children per node, collapsed from `bvh` here (as the
    /// packet tracer's wide trees are) — only when there is a hand-off (`single` > 0).
    pub fn new(bvh: &Bvh, width: TreeWidth, single: usize) -> Self {
        match (width, single) {
            (_, 0) | (TreeWidth::Binary, _) => Handoff::Binary,
            (TreeWidth::Four, _) => Handoff::Four(WideBvh::collapse(bvh)),
            (TreeWidth::Eight, _) => Handoff::Eight(WideBvh::collapse(bvh)),
        }
    }

    /// One ray's traversal of the subtree under binary node `node`, whose box it meets.
    #[inline(always)]
    pub fn trace<S: Stats, const ANY: bool>(
        &self,
        bvh: &Bvh,
        node: u32,
        ray: &Ray,
        stats: &mut S,
    ) -> Hit {
        match self {
            Handoff::Binary => trace_subtree::<S, ANY>(bvh, node, ray, stats),
            Handoff::Four(wide) => {
                trace_wide::<4, S, ANY>(bvh, wide, wide.entry[node as usize], ray, stats)
            }
            Handoff::Eight(wide) => {
                trace_wide::<8, S, ANY>(bvh, wide, wide.entry[node as usize], ray, stats)
            }
        }
    }
}
