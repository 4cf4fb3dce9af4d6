//! The per-cell kernel of coherent grid traversal (Wald et al. 2006 §2.3): a packet on its walk
//! retires the rays whose hits lie behind the slice it enters, and tests each cell's triangles —
//! mailboxed, frustum-culled — against its active rays, `L` at a time.

use super::frustum::{MarchFrame, MarchFrustum};
use super::setup::Workspace;
use super::traversal::SliceVisitor;
use super::{CgtConfig, CULL_MIN_RAYS};
use crate::accel::Grid;
use crate::geometry::{Hit, RayTests};
use crate::stats::{Event, Owners, Stats};

/// Something told about every cell a packet visits (`()` for tracing, a list for tests).
pub trait CellObserver {
    fn visit(&mut self, cell: [u32; 3]);
}

impl CellObserver for () {
    #[inline(always)]
    fn visit(&mut self, _: [u32; 3]) {}
}

impl CellObserver for Vec<[u32; 3]> {
    fn visit(&mut self, cell: [u32; 3]) {
        self.push(cell);
    }
}

/// A packet on its walk: decides when its rays are done and tests the triangles of each cell.
pub(super) struct Packet<'a, const L: usize, R: RayTests, S, O, const ANY: bool> {
    pub(super) grid: &'a Grid,
    pub(super) frame: &'a MarchFrame,
    pub(super) frustum: &'a MarchFrustum,
    pub(super) config: &'a CgtConfig,
    pub(super) group: &'a [u32],
    pub(super) ws: &'a mut Workspace<L, R>,
    pub(super) hits: &'a mut [Hit],
    pub(super) stats: &'a mut S,
    pub(super) observer: &'a mut O,
}

impl<const L: usize, R: RayTests, S: Stats, O: CellObserver, const ANY: bool>
    Packet<'_, L, R, S, O, ANY>
{
    /// The chunk indices of the rays in the lanes (per-ray counters).
    fn lane_rays(&self) -> Vec<u32> {
        let lanes = &self.ws.lanes;
        (0..lanes.len())
            .map(|slot| self.group[lanes.ray[slot] as usize])
            .collect()
    }

    /// The triangle's vertices in march coordinates (for culling).
    #[inline]
    fn march_vertices(&self, id: u32) -> [[f32; 3]; 3] {
        let g = self.grid;
        g.triangles[id as usize].v.map(|p| {
            self.frame
                .point((g.local(p) - g.bounds.min) * g.inv_cell_size)
        })
    }
}

impl<const L: usize, R: RayTests, S: Stats, O: CellObserver, const ANY: bool> SliceVisitor
    for Packet<'_, L, R, S, O, ANY>
{
    fn begin_slice(&mut self, slice: u32) -> bool {
        // A ray is done when the slab about to be entered starts past its hit or its end
        // (§2.3 early termination, per ray); the margin covers rounding of s.
        let start = slice as f32 - self.frustum.eps();
        if self.ws.lanes.any_s_limit_below(start) {
            self.ws.lanes.retain(|s_limit| s_limit >= start);
        }
        !self.ws.lanes.is_empty()
    }

    fn count(&mut self, event: Event, n: u64) {
        if S::ENABLED {
            self.stats.event(event, n);
        }
    }

    fn cell(&mut self, index: usize, cell: [u32; 3]) {
        if self.ws.lanes.is_empty() {
            return; // every ray found its occluder earlier in this slice
        }
        if S::ENABLED {
            let rays = self.lane_rays();
            self.stats.node_shared(0, Owners::List(&rays));
        }
        self.observer.visit(cell);
        let grid = self.grid;
        let ids =
            &grid.cell_tris[grid.cell_start[index] as usize..grid.cell_start[index + 1] as usize];
        if S::ENABLED && !ids.is_empty() {
            self.stats.event(Event::LeavesVisited, 1);
            self.stats
                .event(Event::LeafActiveRays, self.ws.lanes.len() as u64);
        }
        for &id in ids {
            if self.config.mailbox && !self.ws.mailbox.insert(id) {
                if S::ENABLED {
                    self.stats.event(Event::MailboxHits, 1);
                }
                continue;
            }
            // Culling costs about a 4-ray triangle test (§2.3): it pays only for more rays.
            if self.config.cull
                && self.ws.lanes.len() > CULL_MIN_RAYS
                && self.frustum.culls(&self.march_vertices(id))
            {
                if S::ENABLED {
                    self.stats.event(Event::TrianglesCulled, 1);
                }
                continue;
            }
            let tri = &grid.triangles[id as usize];
            if S::ENABLED {
                // `LaneRays::intersect` runs over the active rays in whole SIMD rays of `L`.
                let rays = self.lane_rays();
                let lanes = rays.len().div_ceil(L) * L;
                self.stats
                    .triangle_tests(0, Owners::List(&rays), lanes as u32);
            }
            let ws = &mut *self.ws;
            let (hits, group, march, d_s) = (&mut *self.hits, self.group, &ws.march, &ws.d_s);
            let mut any_done = false;
            ws.lanes.intersect(tri, |lanes, slot, t, u, v| {
                let p = lanes.ray[slot] as usize;
                hits[group[p] as usize] = Hit { t, prim: id, u, v };
                if ANY {
                    lanes.s_limit[slot] = f32::NEG_INFINITY;
                    any_done = true;
                } else {
                    lanes.s_limit[slot] = lanes.s_limit[slot].min(march.o_s[p] + t * d_s[p]);
                }
            });
            if any_done {
                ws.lanes.retain(|s_limit| s_limit != f32::NEG_INFINITY);
                if ws.lanes.is_empty() {
                    return;
                }
            }
        }
    }
}
