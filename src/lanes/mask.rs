//! Which of `L` lanes a test passed: bit `l` for lane `l`, never a bit at or above `L`.

use std::ops::{BitAnd, BitOr};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaneMask<const L: usize>(u32);

impl<const L: usize> LaneMask<L> {
    const FITS: () = assert!(L >= 1 && L <= 32, "lane masks hold at most 32 lanes");

    pub const NONE: Self = LaneMask(0);

    /// The first `n` lanes (`n ≤ L`).
    #[inline(always)]
    pub fn first(n: usize) -> Self {
        let () = Self::FITS;
        debug_assert!(n <= L);
        LaneMask(if n >= 32 { u32::MAX } else { (1u32 << n) - 1 })
    }

    /// The lanes whose flag is set (branch-free, so it vectorizes).
    #[inline(always)]
    pub fn from_bools(flags: &[bool; L]) -> Self {
        Self::from_fn(|l| flags[l])
    }

    /// The lanes `l` for which `pass(l)` holds, evaluated for every lane without branching.
    #[inline(always)]
    pub fn from_fn(pass: impl Fn(usize) -> bool) -> Self {
        let () = Self::FITS;
        LaneMask((0..L).fold(0, |m, l| m | (pass(l) as u32) << l))
    }

    #[inline(always)]
    pub fn bits(self) -> u32 {
        self.0
    }

    #[inline(always)]
    pub fn any(self) -> bool {
        self.0 != 0
    }

    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0.count_ones()
    }

    #[inline(always)]
    pub fn contains(self, lane: usize) -> bool {
        self.0 >> lane & 1 == 1
    }

    /// The set lanes, lowest first.
    #[inline(always)]
    pub fn iter(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let lane = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                lane
            })
        })
    }
}

impl<const L: usize> BitOr for LaneMask<L> {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, other: Self) -> Self {
        LaneMask(self.0 | other.0)
    }
}

impl<const L: usize> BitAnd for LaneMask<L> {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, other: Self) -> Self {
        LaneMask(self.0 & other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_name_their_lanes() {
        let m = LaneMask::<8>::from_bools(&[true, false, false, true, false, false, false, true]);
        assert_eq!(m.bits(), 0b1000_1001);
        assert_eq!(m.iter().collect::<Vec<_>>(), [0, 3, 7]);
        assert_eq!((m.count(), m.contains(3), m.contains(4)), (3, true, false));
        assert_eq!((m & LaneMask::first(4)).iter().collect::<Vec<_>>(), [0, 3]);
        assert_eq!(LaneMask::<16>::first(16).bits(), 0xFFFF);
        assert_eq!(LaneMask::<32>::first(32).bits(), u32::MAX);
        assert!(!LaneMask::<4>::NONE.any() && (LaneMask::<4>::NONE | m4()).any());
    }

    fn m4() -> LaneMask<4> {
        LaneMask::first(1)
    }
}
