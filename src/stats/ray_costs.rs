//! Per-ray costs of a counting pass: each box test, triangle test and node visit charged to the
//! ray it was made for, so the costs of a batch can be drawn per pixel (`render::heatmap`).
//!
//! Attribution: a test run for one ray (a single-ray kernel's, one SIMD lane's, one stream
//! ray's) is that ray's; a test of a whole packet or frustum, counted once per ray or frustum
//! taking part, gives one to each of them. A node visit is shared by every ray that takes part
//! (a packet's, a stream's, a block of frusta's) and goes to them in turn: each gets its share,
//! rounded to whole visits, and the per-ray visits sum exactly to the pass's `nodes_visited`.
//! A frustum's counts (multi-frusta tracing) are spread over the rays of its pixels the same way.

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
        }
    }
}

/// Box tests, triangle tests and node visits per ray.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayCosts {
    pub boxes: Vec<u64>,
    pub triangles: Vec<u64>,
    pub nodes: Vec<u64>,
    /// The ray a single-ray kernel traces now (`Stats::charge_ray`).
    pub(super) current: u32,
    /// Shared node visits so far: which owner the next one goes to.
    turn: u32,
}

impl RayCosts {
    pub fn new(rays: usize) -> RayCosts {
        RayCosts {
            boxes: vec![0; rays],
            triangles: vec![0; rays],
            nodes: vec![0; rays],
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

    /// Adds `other`'s costs, whose rays are this one's from `offset` on (a chunk's in its batch).
    pub fn add_at(&mut self, other: &RayCosts, offset: usize) {
        for (mine, theirs) in [
            (&mut self.boxes, &other.boxes),
            (&mut self.triangles, &other.triangles),
            (&mut self.nodes, &other.nodes),
        ] {
            for (m, t) in mine[offset..offset + theirs.len()].iter_mut().zip(theirs) {
                *m += t;
            }
        }
    }

    /// Adds `other`'s costs, the `n` of its ray `i` spread over this one's rays `owners_of[i]`
    /// (`k` of them): `n / k` each and one more to the first `n % k`, so the sums stay exact.
    pub fn add_spread(&mut self, other: &RayCosts, owners_of: &[Range<u32>]) {
        for (mine, theirs) in [
            (&mut self.boxes, &other.boxes),
            (&mut self.triangles, &other.triangles),
            (&mut self.nodes, &other.nodes),
        ] {
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
        c.aabb_tests(2, Owners::span(0, 4));
        c.triangle_tests(
            2,
            Owners::Bits {
                base: 4,
                bits: 0b11,
            },
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
    fn relabelled_counts_reach_their_owners() {
        let mut c = Counters::attributing(6);
        // Four shadow rays of points 2, 2, 0, 1, then a frustum over rays 3..6.
        c.relabelled(&[2..3, 2..3, 0..1, 1..2, 3..6], |c| {
            c.aabb_tests(0, Owners::span(0, 4));
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
