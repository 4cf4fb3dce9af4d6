//! Counters as a type parameter. Kernels are generic over `S: Stats` and guard every count with
//! `if S::ENABLED`, so `NoStats` compiles every count away and timing runs pay nothing, while
//! `Counters` records exact AABB tests, triangle tests and nodes visited, per BVH depth, plus the
//! algorithm-specific events of `Event` (mailbox hits, culled boxes, rays alive at leaves, ...).
//! A counting pass may also charge every box test, triangle test and node visit to the ray it was
//! made for (`RayCosts`, the per-pixel heat maps): kernels name the rays of each count (`Owners`).

mod ray_costs;

use std::ops::Range;

pub use ray_costs::{Owners, RayCosts};

pub trait Stats: Default + Send {
    const ENABLED: bool;
    fn ray(&mut self);
    fn node(&mut self, depth: usize);
    fn aabb_test(&mut self, depth: usize);
    fn triangle_test(&mut self, depth: usize);
    /// `n` occurrences of an algorithm-specific event.
    fn event(&mut self, event: Event, n: u64);

    /// Ray `i` of the kernel's rays is traced next, alone: the counts that follow without
    /// owners of their own (`aabb_test`, `triangle_test`, `node`) are its.
    #[inline(always)]
    fn charge_ray(&mut self, _i: usize) {}

    /// One box test for each ray of `owners` (a packet's lanes in use, a stream's rays), made by
    /// one SIMD operation over `lanes` lanes: `owners` are its active lanes (`RayCosts` lanes).
    #[inline(always)]
    fn aabb_tests(&mut self, depth: usize, owners: Owners<'_>, _lanes: u32) {
        (0..owners.len()).for_each(|_| self.aabb_test(depth));
    }

    /// One triangle test for each ray of `owners`, one SIMD operation over `lanes` lanes.
    #[inline(always)]
    fn triangle_tests(&mut self, depth: usize, owners: Owners<'_>, _lanes: u32) {
        (0..owners.len()).for_each(|_| self.triangle_test(depth));
    }

    /// One node visit shared by the rays of `owners` (a packet's, a stream's, a block's).
    #[inline(always)]
    fn node_shared(&mut self, depth: usize, _owners: Owners<'_>) {
        self.node(depth);
    }

    /// `f`'s counts, made over rays numbered `0..owners_of.len()` (shadow rays, frusta), each
    /// spread over the rays `owners_of[i]` of the caller's numbering (its shading point, its
    /// pixels: `RayCosts::add_spread`).
    #[inline(always)]
    fn relabelled<R>(&mut self, _owners_of: &[Range<u32>], f: impl FnOnce(&mut Self) -> R) -> R {
        f(self)
    }
}

/// Events that only some algorithms have. Each is one column of runs.csv (empty for tracers that
/// cannot count internals); a tracer that never raises an event reports 0 for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// Packets (or sub-packets after a split) started; rays / packets = mean packet occupancy.
    Packets,
    /// Ray–triangle tests skipped because the packet had already tested the triangle (mailbox).
    MailboxHits,
    /// Triangles rejected by a frustum (or interval) test for a whole packet, before any ray test.
    TrianglesCulled,
    /// BVH boxes rejected for a whole packet by a frustum or interval-arithmetic test.
    BoxesCulled,
    /// Leaves (BVH) or cells with triangles (grid) reached by a packet.
    LeavesVisited,
    /// Active rays summed over `LeavesVisited`: the mean number of rays alive at a leaf.
    LeafActiveRays,
    /// Grid slices a packet stepped through.
    SlicesStepped,
    /// Empty macrocells skipped.
    MacrocellsSkipped,
    /// Box filters run (stream filtering: one per node a stream is tested against).
    /// `TraversalLanesActive / StreamBoxTests` = the mean stream length at box tests.
    StreamBoxTests,
    /// Rays in the streams of the box filters: the SIMD lanes traversal fills.
    TraversalLanesActive,
    /// SIMD lanes traversal issues: each box filter's stream rounded up to whole groups of the
    /// SIMD width. `TraversalLanesActive / TraversalLanesIssued` = traversal's SIMD utilisation.
    TraversalLanesIssued,
    /// Live rays in the groups tested against triangles, per triangle (lanes that do work).
    IntersectionLanesActive,
    /// SIMD lanes intersection issues: the SIMD width per group and triangle.
    /// `IntersectionLanesActive / IntersectionLanesIssued` = intersection's SIMD utilisation.
    IntersectionLanesIssued,
    /// Shading filters run by the path renderer (`render::path`, Gribble & Ramani 2008 Fig. 4):
    /// one per non-empty sub-stream a shading operation runs over. Recorded on the bounce's
    /// closest-hit batch. `ShadeLanesActive / ShadeFilters` = the mean shading stream length.
    ShadeFilters,
    /// Rays in the shading filters' sub-streams.
    ShadeLanesActive,
    /// SIMD lanes shading issues: each sub-stream rounded up to whole groups of the SIMD width.
    /// `ShadeLanesActive / ShadeLanesIssued` = shading's SIMD utilisation.
    ShadeLanesIssued,
    /// Box tests of a block of frusta (multi-frusta tracing): one per box, for all the block's
    /// frusta at once (Benthin & Wald 2009 Table 1 "#AABB tests").
    FrustumBoxTests,
    /// Frusta tested at inner nodes, summed: ÷ inner-node visits = frusta per node.
    FrustaAtNodes,
    /// Triangles fetched at leaves, once per block (Benthin & Wald 2009 "#tris", Fig. 6).
    TrianglesAccessed,
    /// Of those, triangles left to at least one frustum after culling ("#tris +culling").
    TrianglesKept,
    /// (Frustum, triangle) pairs tested with the frustum's rays ("#isec").
    FrustumTriangleTests,
    /// Rays generated on demand inside frusta at leaves.
    RaysOnDemand,
}

impl Event {
    pub const ALL: [Event; 22] = [
        Event::Packets,
        Event::MailboxHits,
        Event::TrianglesCulled,
        Event::BoxesCulled,
        Event::LeavesVisited,
        Event::LeafActiveRays,
        Event::SlicesStepped,
        Event::MacrocellsSkipped,
        Event::StreamBoxTests,
        Event::TraversalLanesActive,
        Event::TraversalLanesIssued,
        Event::IntersectionLanesActive,
        Event::IntersectionLanesIssued,
        Event::ShadeFilters,
        Event::ShadeLanesActive,
        Event::ShadeLanesIssued,
        Event::FrustumBoxTests,
        Event::FrustaAtNodes,
        Event::TrianglesAccessed,
        Event::TrianglesKept,
        Event::FrustumTriangleTests,
        Event::RaysOnDemand,
    ];
    pub const COUNT: usize = Event::ALL.len();

    /// The runs.csv column.
    pub fn name(self) -> &'static str {
        match self {
            Event::Packets => "packets",
            Event::MailboxHits => "mailbox_hits",
            Event::TrianglesCulled => "triangles_culled",
            Event::BoxesCulled => "boxes_culled",
            Event::LeavesVisited => "leaves_visited",
            Event::LeafActiveRays => "leaf_active_rays",
            Event::SlicesStepped => "slices_stepped",
            Event::MacrocellsSkipped => "macrocells_skipped",
            Event::StreamBoxTests => "stream_box_tests",
            Event::TraversalLanesActive => "traversal_lanes_active",
            Event::TraversalLanesIssued => "traversal_lanes_issued",
            Event::IntersectionLanesActive => "intersection_lanes_active",
            Event::IntersectionLanesIssued => "intersection_lanes_issued",
            Event::ShadeFilters => "shade_filters",
            Event::ShadeLanesActive => "shade_lanes_active",
            Event::ShadeLanesIssued => "shade_lanes_issued",
            Event::FrustumBoxTests => "frustum_box_tests",
            Event::FrustaAtNodes => "frusta_at_nodes",
            Event::TrianglesAccessed => "triangles_accessed",
            Event::TrianglesKept => "triangles_kept",
            Event::FrustumTriangleTests => "frustum_triangle_tests",
            Event::RaysOnDemand => "rays_on_demand",
        }
    }
}

/// Counts nothing; every method is empty and inlined away.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl Stats for NoStats {
    const ENABLED: bool = false;
    #[inline(always)]
    fn ray(&mut self) {}
    #[inline(always)]
    fn node(&mut self, _: usize) {}
    #[inline(always)]
    fn aabb_test(&mut self, _: usize) {}
    #[inline(always)]
    fn triangle_test(&mut self, _: usize) {}
    #[inline(always)]
    fn event(&mut self, _: Event, _: u64) {}
}

/// Exact counts for one tracer on one ray kind. Depth-indexed vectors grow on demand; depth is the
/// BVH depth of the node whose box is tested (the root is depth 0) or of the leaf holding the
/// triangle.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Counters {
    pub rays: u64,
    pub nodes_visited: u64,
    pub aabb_tests: u64,
    pub triangle_tests: u64,
    pub aabb_by_depth: Vec<u64>,
    pub triangle_by_depth: Vec<u64>,
    /// Indexed by `Event as usize`.
    pub events: [u64; Event::COUNT],
    /// Of the box and triangle tests, those made by SIMD operations over rays (packets, streams,
    /// cgt's cells, blocks of frusta): their active lanes, and the lanes the operations had.
    /// `simd_lanes_active / simd_lanes` = the pass's lane utilisation (the `lanes` heat map).
    #[serde(default)]
    pub simd_lanes_active: u64,
    #[serde(default)]
    pub simd_lanes: u64,
    /// The same box tests, triangle tests and node visits per ray, when the pass attributes them
    /// (`Counters::attributing`).
    #[serde(skip)]
    pub per_ray: Option<RayCosts>,
}

fn bump(by_depth: &mut Vec<u64>, depth: usize) {
    bump_by(by_depth, depth, 1);
}

/// Which tests `Counters::add_tests` adds.
#[derive(Clone, Copy)]
enum Test {
    Box,
    Triangle,
}

fn bump_by(by_depth: &mut Vec<u64>, depth: usize, n: u64) {
    if by_depth.len() <= depth {
        by_depth.resize(depth + 1, 0);
    }
    by_depth[depth] += n;
}

impl Stats for Counters {
    const ENABLED: bool = true;
    #[inline]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline]
    fn node(&mut self, _depth: usize) {
        self.nodes_visited += 1;
        if let Some(costs) = &mut self.per_ray {
            costs.node_of_current();
        }
    }
    #[inline]
    fn aabb_test(&mut self, depth: usize) {
        self.aabb_tests += 1;
        bump(&mut self.aabb_by_depth, depth);
        if let Some(costs) = &mut self.per_ray {
            costs.box_of_current();
        }
    }
    #[inline]
    fn triangle_test(&mut self, depth: usize) {
        self.triangle_tests += 1;
        bump(&mut self.triangle_by_depth, depth);
        if let Some(costs) = &mut self.per_ray {
            costs.triangle_of_current();
        }
    }
    #[inline]
    fn event(&mut self, event: Event, n: u64) {
        self.events[event as usize] += n;
    }
    #[inline]
    fn charge_ray(&mut self, i: usize) {
        if let Some(costs) = &mut self.per_ray {
            costs.current = i as u32;
        }
    }
    #[inline]
    fn aabb_tests(&mut self, depth: usize, owners: Owners<'_>, lanes: u32) {
        self.add_tests(Test::Box, depth, owners, lanes);
    }
    #[inline]
    fn triangle_tests(&mut self, depth: usize, owners: Owners<'_>, lanes: u32) {
        self.add_tests(Test::Triangle, depth, owners, lanes);
    }
    #[inline]
    fn node_shared(&mut self, _depth: usize, owners: Owners<'_>) {
        self.nodes_visited += 1;
        if let Some(costs) = &mut self.per_ray {
            costs.node_shared(owners);
        }
    }
    fn relabelled<R>(&mut self, owners_of: &[Range<u32>], f: impl FnOnce(&mut Self) -> R) -> R {
        let Some(outer) = self.per_ray.take() else {
            return f(self);
        };
        self.per_ray = Some(RayCosts::new(owners_of.len()));
        let result = f(self);
        let inner = self.per_ray.replace(outer).expect("put back above");
        self.per_ray
            .as_mut()
            .expect("just put back")
            .add_spread(&inner, owners_of);
        result
    }
}

impl Counters {
    /// Counters that also charge each count to one of `rays` rays (`per_ray`).
    pub fn attributing(rays: usize) -> Counters {
        Counters {
            per_ray: Some(RayCosts::new(rays)),
            ..Counters::default()
        }
    }

    /// One `test` per ray of `owners` at `depth`, one SIMD operation over `lanes` lanes: into
    /// the count, its per-depth column and the lane totals, and, when attributing, into each
    /// owner's costs.
    fn add_tests(&mut self, test: Test, depth: usize, owners: Owners<'_>, lanes: u32) {
        let (total, by_depth) = match test {
            Test::Box => (&mut self.aabb_tests, &mut self.aabb_by_depth),
            Test::Triangle => (&mut self.triangle_tests, &mut self.triangle_by_depth),
        };
        let n = owners.len() as u64;
        *total += n;
        bump_by(by_depth, depth, n);
        self.simd_lanes_active += n;
        self.simd_lanes += lanes as u64;
        if let Some(costs) = &mut self.per_ray {
            let column = match test {
                Test::Box => &mut costs.boxes,
                Test::Triangle => &mut costs.triangles,
            };
            owners.for_each(|i| column[i as usize] += 1);
            costs.lanes_shared(owners, lanes);
        }
    }

    pub fn get(&self, event: Event) -> u64 {
        self.events[event as usize]
    }

    /// Adds `other`'s counts (and its per-ray costs, when both have them, to the same rays).
    pub fn merge(&mut self, other: &Counters) {
        self.merge_at(other, 0);
    }

    /// Adds `other`'s counts; its per-ray costs, when both have them, to this one's rays from
    /// `offset` on (a chunk's counters into its batch's).
    pub fn merge_at(&mut self, other: &Counters, offset: usize) {
        if let (Some(mine), Some(theirs)) = (&mut self.per_ray, &other.per_ray) {
            mine.add_at(theirs, offset);
        }
        self.rays += other.rays;
        self.nodes_visited += other.nodes_visited;
        self.aabb_tests += other.aabb_tests;
        self.triangle_tests += other.triangle_tests;
        self.simd_lanes_active += other.simd_lanes_active;
        self.simd_lanes += other.simd_lanes;
        for (mine, theirs) in self.events.iter_mut().zip(&other.events) {
            *mine += theirs;
        }
        for (mine, theirs) in [
            (&mut self.aabb_by_depth, &other.aabb_by_depth),
            (&mut self.triangle_by_depth, &other.triangle_by_depth),
        ] {
            if mine.len() < theirs.len() {
                mine.resize(theirs.len(), 0);
            }
            for (m, t) in mine.iter_mut().zip(theirs) {
                *m += t;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_merge_adds_and_extends_depths() {
        let mut a = Counters::default();
        a.ray();
        a.aabb_test(0);
        a.triangle_test(2);
        let mut b = Counters::default();
        b.ray();
        b.aabb_test(3);
        b.node(1);
        b.event(Event::MailboxHits, 3);
        a.event(Event::MailboxHits, 2);
        a.merge(&b);
        assert_eq!(a.get(Event::MailboxHits), 5);
        assert_eq!(a.get(Event::Packets), 0);
        assert_eq!(
            (a.rays, a.aabb_tests, a.triangle_tests, a.nodes_visited),
            (2, 2, 1, 1)
        );
        assert_eq!(a.aabb_by_depth, vec![1, 0, 0, 1]);
        assert_eq!(a.triangle_by_depth, vec![0, 0, 1]);
    }

    #[test]
    fn no_stats_is_zero_sized() {
        assert_eq!(std::mem::size_of::<NoStats>(), 0);
    }
}
