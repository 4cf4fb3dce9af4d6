//! Traversal with stream filtering (Gribble & Ramani 2008 §3.2, Fig. 3): at each node the box
//! filter keeps the rays that meet the node; an empty output stream ends the visit, a leaf runs
//! the intersection stage on it, an interior node sends it to both children, front to back.
//! The walk is the paper's recursion; a sub-stream is a prefix of its parent's, reordered in
//! place, so the far child filters the rays the near child handed back (their segments now
//! shortened by its hits).
//!
//! Occlusion: a ray ends at its first hit and is dropped from the stream — moved behind the
//! stream's live rays on the way back up, so no later filter tests it.

use crate::accel::Bvh;
use std::marker::PhantomData;

use crate::geometry::{Hit, RayTests, Rays, Triangle};
use crate::lanes::stream::{partition_by, SoaRays};
use crate::lanes::triangle_block::BlockTests;
use crate::lanes::LaneMask;
use crate::lanes::SimdRay;
use crate::stats::{Owners, Stats};
use crate::tracers::packet::ChildOrder;

use super::filter::filter;
use super::handoff::Handoff;
use super::rays::StreamRays;
use super::width::Width;

/// What a query answers per ray: the closest hit, or whether anything is hit (`ANY`: then a ray
/// ends at its first hit).
pub trait Answer {
    const ANY: bool;
    /// The triangle test `R` of every lane of `simd` for this query
    /// (`SimdRay::intersect::<R, ANY>`; the branch is on a constant, so each answer compiles to
    /// one of the two).
    #[inline(always)]
    fn intersect<R: RayTests, const L: usize>(simd: &mut SimdRay<L>, tri: &Triangle, prim: u32) {
        if Self::ANY {
            simd.intersect::<R, true>(tri, prim);
        } else {
            simd.intersect::<R, false>(tri, prim);
        }
    }
    /// One ray's traversal of the subtree under `node` for this query (`Handoff::trace::<ANY>`;
    /// `ray`: the stream, the ray's position in it, the chunk).
    #[inline(always)]
    fn trace_single<R: BlockTests, S: Stats, const L: usize>(
        handoff: &Handoff,
        bvh: &Bvh,
        node: u32,
        ray: (&StreamRays<L>, usize, &Rays<'_>),
        stats: &mut S,
    ) -> Hit {
        if Self::ANY {
            handoff.trace::<R, S, true, L>(bvh, node, ray, stats)
        } else {
            handoff.trace::<R, S, false, L>(bvh, node, ray, stats)
        }
    }
    fn record(&mut self, hit: Hit);
}

impl Answer for Hit {
    const ANY: bool = false;
    #[inline(always)]
    fn record(&mut self, hit: Hit) {
        *self = hit;
    }
}

impl Answer for bool {
    const ANY: bool = true;
    #[inline(always)]
    fn record(&mut self, _: Hit) {
        *self = true;
    }
}

/// One stream's walk through the tree: the tree, the chunk's rays, the stream, the leaf stage's
/// lane groups, and the answers by ray index. `R`: the box and triangle tests (`robust`).
pub struct Walk<'a, const L: usize, const N: usize, A: Answer, R: BlockTests> {
    pub bvh: &'a Bvh,
    pub order: &'a ChildOrder,
    pub input: Rays<'a>,
    /// Sub-streams of at most this many rays leave stream filtering at an inner node: each of
    /// their rays finishes the subtree on its own (`single`; 0: never, the paper's traversal).
    pub single: usize,
    /// The kernel those rays finish with.
    pub handoff: &'a Handoff,
    pub rays: &'a mut StreamRays<L>,
    /// One `SimdRay` per `L`-lane part of an `N`-wide group (`Width::GROUPS`).
    pub groups: &'a mut [SimdRay<L>],
    pub answers: &'a mut [A],
    pub tests: PhantomData<R>,
}

impl<const L: usize, const N: usize, A: Answer, R: BlockTests> Walk<'_, L, N, A, R> {
    /// Fig. 3 `traverse(node, in_stream)` with the stream's rays `0..len` (`len > 0`). Returns
    /// how many of them are still live, moved to the front (all of them, but for occlusion).
    pub fn visit<S: Stats>(&mut self, node: u32, len: usize, stats: &mut S) -> usize {
        let cell = self.bvh.nodes[node as usize];
        let depth = if S::ENABLED {
            self.bvh.depth[node as usize] as usize
        } else {
            0
        };
        if S::ENABLED {
            stats.node_shared(depth, Owners::List(&self.rays.ids(len)));
        }
        let (hit, negative) = filter::<L, N, R, S>(self.rays, len, &cell.bounds, depth, stats);
        if hit == 0 {
            return len;
        }
        let live = if cell.is_leaf() {
            self.leaf(&cell, depth, hit, stats)
        } else if hit <= self.single {
            self.single_rays(node, hit, stats)
        } else {
            let (near, far) = self.order.near_far(node as usize, cell.first, negative);
            let live = self.visit(near, hit, stats);
            if live > 0 {
                self.visit(far, live, stats)
            } else {
                0
            }
        };
        drop_finished(self.rays, live, hit, len)
    }
}

impl<const L: usize, const N: usize, A: Answer, R: BlockTests> Walk<'_, L, N, A, R> {
    /// The rays `0..len`, which meet `node`'s box, each traverse its subtree alone, depth first
    /// (`handoff`: the reference tracer's traversal or the wide tree's, with the same hits). Returns how many are still
    /// live, moved to the front.
    fn single_rays<S: Stats>(&mut self, node: u32, len: usize, stats: &mut S) -> usize {
        for at in 0..len {
            stats.charge_ray(self.rays.id(at));
            let ray = (&*self.rays, at, &self.input);
            let hit = A::trace_single::<R, S, L>(self.handoff, self.bvh, node, ray, stats);
            if hit.is_hit() {
                self.answers[self.rays.id(at)].record(hit);
                self.rays
                    .set_tmax(at, if A::ANY { f32::NEG_INFINITY } else { hit.t });
            }
        }
        self.live(len)
    }

    /// How many of the rays `0..len` are still live (all of them, but for occlusion: those that
    /// have not hit), moved to the front.
    pub fn live(&mut self, len: usize) -> usize {
        if !A::ANY {
            return len;
        }
        partition_by::<L, _>(self.rays, len, Width::<L, N>::GROUP, |rays, base| {
            LaneMask::from_fn(|l| rays.tmax(base + l) != f32::NEG_INFINITY)
        })
    }
}

/// The rays `0..len` are live `0..live`, finished `live..hit` and live again `hit..len` (they
/// missed the node): moves the finished ones to the end, swapping as few rays as there are in
/// the smaller run, and returns how many are live.
fn drop_finished<R: SoaRays>(rays: &mut R, live: usize, hit: usize, len: usize) -> usize {
    let (finished, missed) = (hit - live, len - hit);
    for i in 0..finished.min(missed) {
        rays.swap_rays(live + i, len - 1 - i);
    }
    len - finished
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ray ids in one column.
    struct Ids(Vec<u32>);

    impl SoaRays for Ids {
        fn move_ray(&mut self, from: usize, to: usize) {
            self.0[to] = self.0[from];
        }
        fn swap_rays(&mut self, a: usize, b: usize) {
            self.0.swap(a, b);
        }
    }

    #[test]
    fn finished_rays_go_behind_the_live_ones() {
        // live 0 1, finished 2 3 4, missed 5 6; then finished 2, missed 3 4 5 6; then none.
        for (live, hit, len) in [(2, 5, 7), (2, 3, 7), (3, 3, 5), (0, 4, 4)] {
            let mut ids = Ids((0..len as u32).collect());
            let n = drop_finished(&mut ids, live, hit, len);
            assert_eq!(n, len - (hit - live));
            let mut front: Vec<u32> = ids.0[..n].to_vec();
            front.sort_unstable();
            let want: Vec<u32> = (0..live as u32).chain(hit as u32..len as u32).collect();
            assert_eq!(front, want, "{live} {hit} {len}");
        }
    }
}
