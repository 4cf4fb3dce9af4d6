//! The box filter (Gribble & Ramani 2008 §3.1 "SIMD processing", §3.2 "Traversal"): the stream's
//! rays are tested against a node's box `N` at a time, giving a mask per group, and the stream
//! is partitioned in place by the masks (`lanes::stream::partition_by`) — the rays whose segment
//! `[tmin, closest hit so far]` meets the box first, the others after. Each lane runs the
//! reference tracer's slab test of `R` bit for bit (`lanes::slab`: conservative, or plain with
//! `robust = false`).

use crate::geometry::{Aabb, RayTests};
use crate::lanes::stream::partition_by;
use crate::lanes::LaneMask;
use crate::stats::{Event, Owners, Stats};

use super::rays::StreamRays;
use super::width::Width;

/// `filter<BoxTest(bounds)>` over the rays `0..len` of the stream (at tree depth `depth`):
/// returns how many meet the box (now `0..that`), and, per axis, whether most of them travel in
/// the negative direction (the sub-stream's dominant direction, which orders the node's children
/// front to back).
#[inline(always)]
pub fn filter<const L: usize, const N: usize, R: RayTests, S: Stats>(
    rays: &mut StreamRays<L>,
    len: usize,
    bounds: &Aabb,
    depth: usize,
    stats: &mut S,
) -> (usize, [bool; 3]) {
    let group = Width::<L, N>::GROUP;
    if S::ENABLED {
        let issued = Width::<L, N>::issued(len);
        stats.aabb_tests(depth, Owners::List(&rays.ids(len)), issued as u32);
        stats.event(Event::StreamBoxTests, 1);
        stats.event(Event::TraversalLanesActive, len as u64);
        stats.event(Event::TraversalLanesIssued, issued);
    }
    let (lo, hi) = (bounds.min.to_array(), bounds.max.to_array());
    let mut negative = [0u32; 3];
    let hit = partition_by::<L, _>(rays, len, group, |rays, base| {
        let lanes = rays.slab_lanes(base);
        let pass = lanes.slabs().hits::<R>(lo, hi) & LaneMask::first((len - base).min(group));
        for (a, n) in negative.iter_mut().enumerate() {
            *n += (pass & LaneMask::from_fn(|l| lanes.negative(a, l))).count();
        }
        pass
    });
    (hit, negative.map(|n| 2 * n as usize > hit))
}
