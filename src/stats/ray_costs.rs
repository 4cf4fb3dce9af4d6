//! Per-ray costs of a counting pass: each box test, triangle test and node visit charged to the
//! ray it was made for, so the costs of a batch can be drawn per pixel (`render::heatmap`).
//!
//! Attribution: a test run for one ray (a single-ray kernel's, one SIMD lane's, one stream
//! ray's) is that ray's; a test of a whole packet or frustum, counted once per ray or frustum
//! taking part, gives one to each of them. A node visit is shared by every ray that takes part
//! (a packet's, a stream's, a block of frusta's) and goes to them in turn: each gets its share,
//! rounded to whole visits, and the per-ray visits sum exactly to the pass's `nodes_visited`.
//! A frustum's counts (multi-frusta tracing) are spread over the rays of its pixels the same way.
//!
//! Lanes: a test made by one SIMD operation over rays (`Stats::aabb_tests`, `triangle_tests`)
//! gives each ray taking part one active lane and an equal share of the operation's lanes (its
//! own and the idle ones, in turn, rounded to whole lanes), so a ray's active ÷ lanes is the
//! utilisation of the operations it took part in, and the per-ray lanes sum exactly to the
//! pass's `simd_lanes_active` and `simd_lanes`.

use std::ops::Range;

/// The rays a count is charged to: indices into the rays a kernel was handed (a light-visibility
/// query: its shading points).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owners<'a> {
    /// Rays `start .. start + len`.
    Span { start: u32, len: u32 },
    /// Ray `base + i` for every set bit `i`.
    Bits { base: u32, bits: u64 },
    /// These rays (a stream's, in stream order).
    List(&'a [u32]),
    /// Ray `ray`, `n` times (`n` lanes of one frustum's rays, which counts as one ray).
    Repeat { ray: u32, n: u32 },
}

impl Owners<'_> {
    pub fn span(start: usize, len: usize) -> Owners<'static> {
        Owners::Span {
            start: start as u32,
            len: len as u32,
        }
    }

    pub fn len(self) -> u32 {
        match self {
            Owners::Span { len, .. } => len,
            Owners::Bits { bits, .. } => bits.count_ones(),
            Owners::List(rays) => rays.len() as u32,
            Owners::Repeat { n, .. } => n,
        }
    }

    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// The `k`-th owner (`k < len`), in increasing order.
    fn nth(self, k: u32) -> u32 {
        match self {
            Owners::Span { start, .. } => start + k,
            Owners::Bits { base, mut bits } => {
                (0..k).for_each(|_| bits &= bits - 1);
                base + bits.trailing_zeros()
            }
            Owners::List(rays) => rays[k as usize],
            Owners::Repeat { ray, .. } => ray,
        }
    }

    pub fn for_each(self, mut f: impl FnMut(u32)) {
        match self {
            Owners::Span { start, len } => (start..start + len).for_each(f),
            Owners::Bits { base, mut bits } => {
                while bits != 0 {
                    f(base + bits.trailing_zeros());
                    bits &= bits - 1;
                }
            }
            Owners::List(rays) => rays.iter().copied().for_each(f),
            Owners::Repeat { ray, n } => (0..n).for_each(|_| f(ray)),
        }
    }
}

/// Box tests, triangle tests, node visits and SIMD lanes per ray.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayCosts {
    pub boxes: Vec<u64>,
    pub triangles: Vec<u64>,
    pub nodes: Vec<u64>,
    /// Active lanes of the SIMD operations the ray took part in (one per operation) ...
    pub lanes_active: Vec<u64>,
    /// ... and its share of those operations' lanes.
    pub lanes: Vec<u64>,
    /// The ray a single-ray kernel traces now (`Stats::charge_ray`).
    pub(super) current: u32,
    /// Shared node visits so far: which owner the next one goes to.
    turn: u32,
    /// Lanes left over by even shares so far: which owner the next one goes to.
    lane_turn: u32,
}

impl RayCosts {
    pub fn new(rays: usize) -> RayCosts {
        RayCosts {
            boxes: vec![0; rays],
            triangles: vec![0; rays],
            nodes: vec![0; rays],
            lanes_active: vec![0; rays],
            lanes: vec![0; rays],
            ..RayCosts::default()
        }
    }

    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    pub(super) fn box_of_current(&mut self) {
        self.boxes[self.current as usize] += 1;
    }

    pub(super) fn triangle_of_current(&mut self) {
        self.triangles[self.current as usize] += 1;
    }

    pub(super) fn node_of_current(&mut self) {
        self.nodes[self.current as usize] += 1;
    }

    pub(super) fn node_shared(&mut self, owners: Owners) {
        if owners.is_empty() {
            return;
        }
        let k = self.turn % owners.len();
        self.turn = self.turn.wrapping_add(1);
        self.nodes[owners.nth(k) as usize] += 1;
    }

    /// One SIMD operation over `lanes` lanes, `owners` its active ones: one active lane to each
    /// owner and `lanes / a` of the lanes (`a` owners), the `lanes % a` left over one each to the
    /// next owners in turn.
    pub(super) fn lanes_shared(&mut self, owners: Owners, lanes: u32) {
        let a = owners.len();
        if a == 0 {
            return;
        }
        let (share, left) = (lanes / a, lanes % a);
        owners.for_each(|i| {
            self.lanes_active[i as usize] += 1;
            self.lanes[i as usize] += share as u64;
        });
        for j in 0..left {
            let k = self.lane_turn.wrapping_add(j) % a;
            self.lanes[owners.nth(k) as usize] += 1;
        }
        self.lane_turn = self.lane_turn.wrapping_add(left);
    }

    /// The columns, for adding one `RayCosts` into another.
    fn columns(&self) -> [&Vec<u64>; 5] {
        [
            &self.boxes,
            &self.triangles,
            &self.nodes,
            &self.lanes_active,
            &self.lanes,
        ]
    }

    fn columns_mut(&mut self) -> [&mut Vec<u64>; 5] {
        [
            &mut self.boxes,
            &mut self.triangles,
            &mut self.nodes,
            &mut self.lanes_active,
            &mut self.lanes,
        ]
    }

    /// Adds `other`'s costs, whose rays are this one's from `offset` on (a chunk's in its batch).
    pub fn add_at(&mut self, other: &RayCosts, offset: usize) {
        for (mine, theirs) in self.columns_mut().into_iter().zip(other.columns()) {
            for (m, t) in mine[offset..offset + theirs.len()].iter_mut().zip(theirs) {
                *m += t;
            }
        }
    }

    /// Adds `other`'s costs, the `n` of its ray `i` spread over this one's rays `owners_of[i]`
    /// (`k` of them): `n / k` each and one more to the first `n % k`, so the sums stay exact.
    pub fn add_spread(&mut self, other: &RayCosts, owners_of: &[Range<u32>]) {
        for (mine, theirs) in self.columns_mut().into_iter().zip(other.columns()) {
            for (owners, &n) in owners_of.iter().zip(theirs) {
                let k = owners.len() as u64;
                for (j, owner) in owners.clone().enumerate() {
                    mine[owner as usize] += n / k + u64::from((j as u64) < n % k);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::{Counters, Stats};

    #[test]
    fn owners_enumerate_spans_and_bits() {
        let mut seen = Vec::new();
        Owners::Bits {
            base: 10,
            bits: 0b1010_0001,
        }
        .for_each(|i| seen.push(i));
        assert_eq!(seen, vec![10, 15, 17]);
        assert_eq!(
            Owners::Bits {
                base: 10,
                bits: 0b1010_0001
            }
            .nth(2),
            17
        );
        assert_eq!(Owners::span(4, 3).len(), 3);
        assert_eq!(Owners::span(4, 3).nth(2), 6);
    }

    #[test]
    fn every_count_lands_on_one_ray_and_the_sums_match() {
        let mut c = Counters::attributing(8);
        c.charge_ray(5);
        c.aabb_test(0);
        c.triangle_test(1);
        c.node(0);
        c.aabb_tests(2, Owners::span(0, 4), 4);
        c.triangle_tests(
            2,
            Owners::Bits {
                base: 4,
                bits: 0b11,
            },
            4,
        );
        // Seven visits shared by rays 0..4: two each to rays 0..3, one to ray 3.
        (0..7).for_each(|_| c.node_shared(0, Owners::span(0, 4)));
        let costs = c.per_ray.clone().unwrap();
        assert_eq!(costs.boxes, vec![1, 1, 1, 1, 0, 1, 0, 0]);
        assert_eq!(costs.triangles, vec![0, 0, 0, 0, 1, 2, 0, 0]);
        assert_eq!(costs.nodes, vec![2, 2, 2, 1, 0, 1, 0, 0]);
        assert_eq!(costs.boxes.iter().sum::<u64>(), c.aabb_tests);
        assert_eq!(costs.triangles.iter().sum::<u64>(), c.triangle_tests);
        assert_eq!(costs.nodes.iter().sum::<u64>(), c.nodes_visited);
        assert_eq!(c.aabb_by_depth, vec![1, 0, 4]);
    }

    #[test]
    fn lanes_give_each_active_ray_its_share_of_the_operation() {
        let mut c = Counters::attributing(8);
        // A 4-wide SIMD ray over rays 4..8 with lanes 1 and 3 masked off (rays 4 and 6
        // active): each active ray one active lane and 4 / 2 = 2 of the lanes.
        let half = Owners::Bits {
            base: 4,
            bits: 0b0101,
        };
        c.aabb_tests(0, half, 4);
        // An 8-lane stream filter over 3 rays (2, 4, 7): 8 / 3 = 2 lanes each, the 2 left over
        // to the first two in turn (rays 2 and 4) ...
        c.triangle_tests(1, Owners::List(&[2, 4, 7]), 8);
        // ... and the next operation's one left over goes on from there (ray 7).
        c.triangle_tests(1, Owners::List(&[2, 4, 7]), 4);
        // One frustum (ray 0) with 3 of its 16 SIMD lanes live: 3 active of 16.
        c.triangle_tests(1, Owners::Repeat { ray: 0, n: 3 }, 16);
        // A fully busy 4-wide box test.
        c.aabb_tests(0, Owners::span(4, 4), 4);
        let costs = c.per_ray.clone().unwrap();
        assert_eq!(costs.lanes_active, vec![3, 0, 2, 0, 4, 1, 2, 3]);
        // Ray 4: 2 (half busy) + 3 (8 / 3 and one left over) + 1 (4 / 3) + 1 (fully busy).
        assert_eq!(costs.lanes, vec![16, 0, 4, 0, 7, 1, 3, 5]);
        assert_eq!(c.simd_lanes_active, 2 + 3 + 3 + 3 + 4);
        assert_eq!(c.simd_lanes, 4 + 8 + 4 + 16 + 4);
        assert_eq!(costs.lanes_active.iter().sum::<u64>(), c.simd_lanes_active);
        assert_eq!(costs.lanes.iter().sum::<u64>(), c.simd_lanes);
        // Lanes ride along with the tests they were recorded for.
        assert_eq!(costs.boxes, vec![0, 0, 0, 0, 2, 1, 2, 1]);
        assert_eq!(costs.triangles, vec![3, 0, 2, 0, 2, 0, 0, 2]);
    }

    #[test]
    fn relabelled_counts_reach_their_owners() {
        let mut c = Counters::attributing(6);
        // Four shadow rays of points 2, 2, 0, 1, then a frustum over rays 3..6.
        c.relabelled(&[2..3, 2..3, 0..1, 1..2, 3..6], |c| {
            c.aabb_tests(0, Owners::span(0, 4), 4);
            c.charge_ray(1);
            c.triangle_test(0);
            c.charge_ray(4);
            (0..5).for_each(|_| c.aabb_test(1));
        });
        let costs = c.per_ray.unwrap();
        assert_eq!(costs.boxes, vec![1, 1, 2, 2, 2, 1]);
        assert_eq!(costs.triangles, vec![0, 0, 1, 0, 0, 0]);
    }
}
