//! The kernel a short sub-stream's rays finish their subtree with (`single` > 0): the reference
//! tracer's binary traversal (`single_tree = 2`, `reference::trace_subtree`), or single rays
//! through the tree collapsed to 4 or 8 children per node (`single_tree = 4 | 8`,
//! `wide_single::trace_wide`), entered where the binary node the stream reached sits in it
//! (`WideBvh::entry`). Both find the reference's hits.

use std::sync::Arc;

use crate::accel::{Bvh, BvhOfWidth, WideNodes, WideTree};
use crate::geometry::{Hit, Rays};
use crate::lanes::triangle_block::BlockTests;
use crate::stats::Stats;
use crate::tracers::reference::trace_subtree;
use crate::tracers::wide_single::trace_wide;

use super::rays::StreamRays;

/// The wide tree the hand-off walks; `None`: the binary one.
pub struct Handoff(Option<Arc<WideTree>>);

impl Handoff {
    /// The hand-off over `tree` (the run builds the wide tree of `single_tree` when there is a
    /// hand-off, `single` > 0).
    pub fn new(tree: &BvhOfWidth, single: usize) -> Self {
        match (tree, single) {
            (BvhOfWidth::Wide(wide), 1..) => Handoff(Some(wide.clone())),
            _ => Handoff(None),
        }
    }

    /// One ray's traversal of the subtree under binary node `node`, whose box it meets: the ray
    /// at position `at` of the stream `rays` (of the chunk `input`), within its segment so far.
    /// The wide traversal reads the ray from the stream's own records (`StreamRays::wide_ray`),
    /// which lie in stream order where the filters left them, instead of gathering it from
    /// `input`'s eight columns at its index, scattered by the filters' reordering; the binary
    /// one needs the direction, which only `input` keeps. `R`: the box and triangle tests.
    #[inline(always)]
    pub fn trace<R: BlockTests, S: Stats, const ANY: bool, const L: usize>(
        &self,
        bvh: &Bvh,
        node: u32,
        (rays, at, input): (&StreamRays<L>, usize, &Rays<'_>),
        stats: &mut S,
    ) -> Hit {
        match self.0.as_deref().map(|tree| &tree.nodes) {
            None => {
                let mut ray = input.ray(rays.id(at));
                ray.tmax = rays.tmax(at);
                trace_subtree::<R, S, ANY>(bvh, node, &ray, stats)
            }
            Some(WideNodes::Four(wide)) => {
                let start = wide.entry[node as usize];
                let ray = rays.wide_ray::<R>(at, input);
                trace_wide::<4, R, S, ANY>(bvh, wide, start, &ray, stats)
            }
            Some(WideNodes::Eight(wide)) => {
                let start = wide.entry[node as usize];
                let ray = rays.wide_ray::<R>(at, input);
                trace_wide::<8, R, S, ANY>(bvh, wide, start, &ray, stats)
            }
        }
    }
}
