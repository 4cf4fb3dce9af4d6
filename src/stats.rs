//! Counters as a type parameter. Kernels are generic over `S: Stats` and guard every count with
//! `if S::ENABLED`, so `NoStats` compiles every count away and timing runs pay nothing, while
//! `Counters` records exact AABB tests, triangle tests and nodes visited, per BVH depth, plus the
//! algorithm-specific events of `Event` (mailbox hits, culled boxes, rays alive at leaves, ...).

pub trait Stats: Default + Send {
    const ENABLED: bool;
    fn ray(&mut self);
    fn node(&mut self, depth: usize);
    fn aabb_test(&mut self, depth: usize);
    fn triangle_test(&mut self, depth: usize);
    /// `n` occurrences of an algorithm-specific event.
    fn event(&mut self, event: Event, n: u64);
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
}

fn bump(by_depth: &mut Vec<u64>, depth: usize) {
    if by_depth.len() <= depth {
        by_depth.resize(depth + 1, 0);
    }
    by_depth[depth] += 1;
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
    }
    #[inline]
    fn aabb_test(&mut self, depth: usize) {
        self.aabb_tests += 1;
        bump(&mut self.aabb_by_depth, depth);
    }
    #[inline]
    fn triangle_test(&mut self, depth: usize) {
        self.triangle_tests += 1;
        bump(&mut self.triangle_by_depth, depth);
    }
    #[inline]
    fn event(&mut self, event: Event, n: u64) {
        self.events[event as usize] += n;
    }
}

impl Counters {
    pub fn get(&self, event: Event) -> u64 {
        self.events[event as usize]
    }

    pub fn merge(&mut self, other: &Counters) {
        self.rays += other.rays;
        self.nodes_visited += other.nodes_visited;
        self.aabb_tests += other.aabb_tests;
        self.triangle_tests += other.triangle_tests;
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
