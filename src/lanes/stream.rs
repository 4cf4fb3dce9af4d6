//! A stream of rays in structure-of-arrays columns, compacted or partitioned in place: the
//! primitive of stream filtering (Gribble & Ramani 2008 §3: a filter tests the active rays `N`
//! at a time and packs those that continue in front of those that are done), and how coherent
//! grid traversal drops its finished rays.

use super::LaneMask;

/// Rays in SoA columns that can be moved as wholes, every column at once.
pub trait SoaRays {
    /// Copies ray `from` over ray `to`, in every column.
    fn move_ray(&mut self, from: usize, to: usize);
    /// Exchanges rays `a` and `b`, in every column.
    fn swap_rays(&mut self, a: usize, b: usize);
}

/// Packs the rays of `0..len` that pass `keep` at the front, in their order, and returns how many
/// they are; what lies behind them is left over (a cheaper move than a swap, for rays that are
/// dropped).
#[inline]
pub fn compact<R: SoaRays>(rays: &mut R, len: usize, keep: impl Fn(&R, usize) -> bool) -> usize {
    let mut kept = 0;
    for i in 0..len {
        if keep(rays, i) {
            if kept != i {
                rays.move_ray(i, kept);
            }
            kept += 1;
        }
    }
    kept
}

/// Partitions the rays of `0..len` in place by a SIMD test of `L` rays at a time: `test(rays,
/// base)` gives the lanes of rays `base .. base + L` that pass (lanes past `len` are ignored).
/// The passing rays come first, in their order, then the others (reordered); returns the split.
/// Each group is tested before anything in it moves.
#[inline]
pub fn partition<const L: usize, R: SoaRays>(
    rays: &mut R,
    len: usize,
    test: impl FnMut(&R, usize) -> LaneMask<L>,
) -> usize {
    partition_by(rays, len, L, test)
}

/// As `partition` with only the first `group` (≤ `L`) lanes of each `L`-lane test in use: the
/// groups are `group` rays long (a 12-wide SIMD unit on 16 lanes, Gribble & Ramani 2008 §4).
/// `test(rays, base)` still reads `L` lanes from `base`; lanes from `group` on are ignored.
#[inline]
pub fn partition_by<const L: usize, R: SoaRays>(
    rays: &mut R,
    len: usize,
    group: usize,
    mut test: impl FnMut(&R, usize) -> LaneMask<L>,
) -> usize {
    debug_assert!(group >= 1 && group <= L);
    let mut kept = 0;
    for base in (0..len).step_by(group) {
        // Swaps only touch slots below the current one, so this group is still as it was.
        let pass = test(rays, base) & LaneMask::first((len - base).min(group));
        for lane in pass.iter() {
            if kept != base + lane {
                rays.swap_rays(base + lane, kept);
            }
            kept += 1;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two columns: an id and a value the tests read.
    #[derive(Clone, Debug, PartialEq)]
    struct Stream {
        id: Vec<u32>,
        value: Vec<f32>,
    }

    impl SoaRays for Stream {
        fn move_ray(&mut self, from: usize, to: usize) {
            self.id[to] = self.id[from];
            self.value[to] = self.value[from];
        }
        fn swap_rays(&mut self, a: usize, b: usize) {
            self.id.swap(a, b);
            self.value.swap(a, b);
        }
    }

    fn stream(n: usize) -> Stream {
        Stream {
            id: (0..n as u32).collect(),
            value: (0..n).map(|i| ((i * 7) % 5) as f32).collect(),
        }
    }

    /// The lanes of a group whose value is below 2, evaluated L lanes at a time.
    fn below_two<const L: usize>(s: &Stream, base: usize) -> LaneMask<L> {
        let mut flags = [false; L];
        for (l, f) in flags.iter_mut().enumerate() {
            *f = s.value.get(base + l).is_some_and(|&v| v < 2.0);
        }
        LaneMask::from_bools(&flags)
    }

    fn partitions_by_lanes<const L: usize>() {
        // Values (i·7) mod 5 for i = 0..16: 0 2 4 1 3 0 2 4 1 3 0 2 4 1 3 0. Below 2: ids 0, 3,
        // 5, 8, 10, 13, 15, in order; 37 rays: a stream longer than several groups.
        for n in [16, 37] {
            let mut s = stream(n);
            let split = partition::<L, _>(&mut s, n, below_two::<L>);
            let expected: Vec<u32> = (0..n as u32).filter(|i| (i * 7) % 5 < 2).collect();
            assert_eq!(split, expected.len(), "L = {L}, n = {n}");
            assert_eq!(s.id[..split], expected[..], "L = {L}, n = {n}");
            assert!(s.value[..split].iter().all(|&v| v < 2.0));
            assert!(s.value[split..].iter().all(|&v| v >= 2.0));
            // Every ray is still there, once.
            let mut ids = s.id.clone();
            ids.sort_unstable();
            assert_eq!(ids, (0..n as u32).collect::<Vec<_>>());
        }
        // A partial stream: the rays past `len` are neither tested nor moved.
        let mut s = stream(16);
        let split = partition::<L, _>(&mut s, 6, below_two::<L>);
        assert_eq!((split, &s.id[..3]), (3, &[0, 3, 5][..]));
        assert_eq!(s.id[6..], stream(16).id[6..]);
    }

    #[test]
    fn partition_keeps_the_passing_rays_in_order_at_every_width() {
        partitions_by_lanes::<4>();
        partitions_by_lanes::<8>();
        partitions_by_lanes::<16>();
    }

    /// Groups of 12 rays on 16 lanes: the same split as 16-lane groups, and the test never sees
    /// a lane past the group as passing.
    #[test]
    fn partition_by_twelve_of_sixteen_lanes() {
        for n in [12, 16, 37] {
            let mut s = stream(n + 16);
            let mut tested = vec![];
            let split = partition_by::<16, _>(&mut s, n, 12, |s, base| {
                tested.push(base);
                below_two::<16>(s, base)
            });
            let expected: Vec<u32> = (0..n as u32).filter(|i| (i * 7) % 5 < 2).collect();
            assert_eq!(split, expected.len(), "n = {n}");
            assert_eq!(s.id[..split], expected[..], "n = {n}");
            assert_eq!(tested, (0..n).step_by(12).collect::<Vec<_>>());
            assert_eq!(s.id[n..], stream(n + 16).id[n..], "rays past len stay");
        }
    }

    #[test]
    fn compaction_keeps_order_and_counts() {
        let mut s = stream(16);
        let kept = compact(&mut s, 16, |s, i| s.value[i] >= 3.0);
        assert_eq!(kept, 6);
        assert_eq!(s.id[..kept], [2, 4, 7, 9, 12, 14]);
    }
}
