//! The kernel a short sub-stream's rays finish their subtree with (`single` > 0): the reference
//! tracer's binary traversal (`single_tree = 2`, `reference::trace_subtree`), or single rays
//! through the tree collapsed to 4 or 8 children per node (`single_tree = 4 | 8`,
//! `wide_single::trace_wide`), entered where the binary node the stream reached sits in it
//! (`WideBvh::entry`). Both find the reference's hits.

use crate::accel::{Bvh, WideBvh};
use crate::geometry::{Hit, Rays, Robust};
use crate::stats::Stats;
use crate::tracers::packet::TreeWidth;
use crate::tracers::reference::trace_subtree;
use crate::tracers::wide_single::trace_wide;

use super::rays::StreamRays;

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

    /// One ray's traversal of the subtree under binary node `node`, whose box it meets: the ray
    /// at position `at` of the stream `rays` (of the chunk `input`), within its segment so far.
    /// The wide traversal reads the ray from the stream's own records (`StreamRays::wide_ray`),
    /// which lie in stream order where the filters left them, instead of gathering it from
    /// `input`'s eight columns at its index, scattered by the filters' reordering; the binary
    /// one needs the direction, which only `input` keeps.
    #[inline(always)]
    pub fn trace<S: Stats, const ANY: bool, const L: usize>(
        &self,
        bvh: &Bvh,
        node: u32,
        (rays, at, input): (&StreamRays<L>, usize, &Rays<'_>),
        stats: &mut S,
    ) -> Hit {
        match self {
            Handoff::Binary => {
                let mut ray = input.ray(rays.id(at));
                ray.tmax = rays.tmax(at);
                trace_subtree::<Robust, S, ANY>(bvh, node, &ray, stats)
            }
            Handoff::Four(wide) => {
                let start = wide.entry[node as usize];
                trace_wide::<4, Robust, S, ANY>(bvh, wide, start, &rays.wide_ray(at), stats)
            }
            Handoff::Eight(wide) => {
                let start = wide.entry[node as usize];
                trace_wide::<8, Robust, S, ANY>(bvh, wide, start, &rays.wide_ray(at), stats)
            }
        }
    }
}
