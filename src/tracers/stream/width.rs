//! The SIMD width `N` of the paper (Gribble & Ramani 2008 §4: 4, 8, 12, 16, 32, 64) on the lane
//! layer's `L` lanes: `N ≤ L` uses the first `N` lanes of one `L`-lane group (12 of 16); `N > L`
//! is `N / L` groups of `L` lanes processed as one logical `N`-wide group (32 and 64 on 16 lanes:
//! the machine has no wider registers, so a group's parts run one after the other). Utilisation
//! is counted per logical group: a group issues `N` lanes however few of them hold rays.

pub struct Width<const L: usize, const N: usize>;

/// The lanes `L` width `N` runs on: its own where the lane layer has it (4, 8), else 16.
pub const fn lanes_for(n: usize) -> usize {
    if n <= 8 {
        n
    } else {
        16
    }
}

impl<const L: usize, const N: usize> Width<L, N> {
    /// Rays per `L`-lane group.
    pub const GROUP: usize = if N < L { N } else { L };
    /// `L`-lane groups per `N`-wide group.
    pub const GROUPS: usize = N / Self::GROUP;

    /// Lanes issued to process `len` rays: whole `N`-wide groups.
    #[inline(always)]
    pub fn issued(len: usize) -> u64 {
        (len.div_ceil(N) * N) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_map_onto_lane_groups() {
        assert_eq!((Width::<4, 4>::GROUP, Width::<4, 4>::GROUPS), (4, 1));
        assert_eq!((Width::<16, 12>::GROUP, Width::<16, 12>::GROUPS), (12, 1));
        assert_eq!((Width::<16, 16>::GROUP, Width::<16, 16>::GROUPS), (16, 1));
        assert_eq!((Width::<16, 64>::GROUP, Width::<16, 64>::GROUPS), (16, 4));
        assert_eq!(Width::<16, 12>::issued(13), 24);
        assert_eq!(Width::<16, 64>::issued(13), 64);
        assert_eq!(Width::<8, 8>::issued(0), 0);
        assert_eq!(
            [4, 8, 12, 16, 32, 64].map(lanes_for),
            [4, 8, 16, 16, 16, 16]
        );
    }
}
