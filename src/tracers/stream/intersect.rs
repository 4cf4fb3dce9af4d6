//! The intersection stage (Gribble & Ramani 2008 §3.2 "Intersection"): a leaf's sub-stream is
//! tested against each of the leaf's triangles `N` rays at a time, every lane running the
//! reference tracer's triangle test bit for bit (`SimdRay::intersect`), and the hits are
//! scattered to the rays' slots. As in the paper's implementation, no filter stack splits the
//! test into stages (its leaf streams are too short to pay for one). Occlusion rays that hit are
//! dropped from the stream after the leaf; a group stops early once all its rays have hit.

use crate::accel::BvhNode;
use crate::geometry::Hit;
use crate::lanes::triangle_block::BlockTests;
use crate::stats::{Event, Owners, Stats};

use super::traverse::{Answer, Walk};
use super::width::Width;

impl<const L: usize, const N: usize, A: Answer, R: BlockTests> Walk<'_, L, N, A, R> {
    /// Intersects the rays `0..len` with the triangles of `leaf` (at depth `depth`). Returns how
    /// many rays are still live, moved to the front.
    pub fn leaf<S: Stats>(
        &mut self,
        leaf: &BvhNode,
        depth: usize,
        len: usize,
        stats: &mut S,
    ) -> usize {
        let group = Width::<L, N>::GROUP;
        if S::ENABLED {
            stats.event(Event::LeavesVisited, 1);
            stats.event(Event::LeafActiveRays, len as u64);
        }
        let triangles = leaf.first as usize..(leaf.first + leaf.count) as usize;
        for base in (0..len).step_by(N) {
            for (g, simd) in self.groups.iter_mut().enumerate() {
                let at = base + g * group;
                let used = len.saturating_sub(at).min(group);
                if used > 0 {
                    self.rays
                        .load_triangle_lanes::<R>(at, used, &self.input, simd);
                } else {
                    simd.used = 0;
                    simd.tmax = [f32::NEG_INFINITY; L];
                }
            }
            for i in triangles.clone() {
                let live: u32 = self.groups.iter().map(|simd| simd.live_lanes()).sum();
                if live == 0 {
                    break;
                }
                if S::ENABLED {
                    stats.triangle_tests(depth, Owners::List(&self.live_ids(base)), N as u32);
                    stats.event(Event::IntersectionLanesActive, live as u64);
                    stats.event(Event::IntersectionLanesIssued, N as u64);
                }
                let (tri, prim) = (&self.bvh.triangles[i], self.bvh.prim_ids[i]);
                for simd in self.groups.iter_mut() {
                    if simd.live_lanes() > 0 {
                        A::intersect::<R, L>(simd, tri, prim);
                    }
                }
            }
            for (g, simd) in self.groups.iter().enumerate() {
                let at = base + g * group;
                for l in 0..simd.used as usize {
                    if simd.prim[l] != Hit::NO_PRIM {
                        self.answers[self.rays.id(at + l)].record(simd.hit(l));
                        self.rays.set_tmax(at + l, simd.tmax[l]);
                    }
                }
            }
        }
        self.live(len)
    }

    /// The chunk indices of the live lanes of the groups loaded from stream position `base`.
    fn live_ids(&self, base: usize) -> Vec<u32> {
        let group = Width::<L, N>::GROUP;
        let mut ids = Vec::new();
        for (g, simd) in self.groups.iter().enumerate() {
            let live = (0..L).filter(|&l| simd.tmax[l] != f32::NEG_INFINITY);
            ids.extend(live.map(|l| self.rays.id(base + g * group + l) as u32));
        }
        ids
    }
}
