//! Quasi-Monte Carlo point sets for light samples (Benthin & Wald 2009 §4.5: "we use either
//! Hammersley or Larcher-Pillichshammer QMC samples [Kollig and Keller 2002]").
//!
//! Both are digital `(0, m, 2)`-nets in base 2 of `n = 2^m` points: point `i` is
//! `(i / n, φ(i))`, where `φ` is a base-2 radical inverse given by a generator matrix — the van
//! der Corput sequence (bit reversal) for Hammersley, the Larcher–Pillichshammer matrix for LP.
//! Every elementary interval of area `1/n` (`2^a × 2^(m−a)` grids, any `a`) holds exactly one
//! point. Following Kollig & Keller 2002 (§2.1), each radical inverse is computed column by
//! column: bit `j` of `i` XORs column `j` of the generator matrix into the result.
//!
//! Interleaving (Keller & Heidrich 2001; Benthin §4.5): the `sets · per_set` points of one net are
//! split into `sets` disjoint sets, one per pixel of a `K×K` tile, so each pixel alone is a
//! stratified set and the tile together is the whole net (`interleaved_sets`).

use crate::error::{Error, Result};

/// Which generator matrix the second coordinate uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Net {
    /// van der Corput radical inverse: the Hammersley point set.
    Hammersley,
    /// The Larcher–Pillichshammer radical inverse (Kollig & Keller 2002, §2.1).
    LarcherPillichshammer,
}

impl Net {
    /// The radical inverse of `i` as a 32-bit fraction (the result / 2³²).
    pub fn radical_inverse_bits(self, mut i: u32) -> u32 {
        let mut result = 0u32;
        // Column j of the generator matrix, MSB first: van der Corput's is the unit vector
        // (bit reversal); LP's has the top j + 1 bits set.
        let mut column = 1u32 << 31;
        while i != 0 {
            if i & 1 == 1 {
                result ^= column;
            }
            i >>= 1;
            column = match self {
                Net::Hammersley => column >> 1,
                Net::LarcherPillichshammer => column | column >> 1,
            };
        }
        result
    }

    /// The radical inverse of `i` in [0, 1).
    pub fn radical_inverse(self, i: u32) -> f64 {
        self.radical_inverse_bits(i) as f64 / (1u64 << 32) as f64
    }

    /// Point `i` of the `2^m`-point net: `(i / 2^m, φ(i))`.
    pub fn point(self, i: u32, m: u32) -> [f32; 2] {
        let x = i as f64 / (1u64 << m) as f64;
        // φ(i) of an m-bit i has only its top m bits set: exact in f32 for m ≤ 24.
        [x as f32, self.radical_inverse(i) as f32]
    }

    /// The `sets · per_set` points of one net, as `sets` disjoint sets of `per_set` points one
    /// after another (`per_set` and `sets` powers of 4). Set `s` holds the points whose index has
    /// its middle bits equal to `s`, its top and bottom `log₄ per_set` bits free: the top bits
    /// are the first coordinate's top bits and the bottom ones (through a triangular generator
    /// matrix) the second's, so each set has one point in each cell of a `√per_set × √per_set`
    /// grid; the sets differ in where inside the cells their points lie.
    pub fn interleaved_sets(self, per_set: u32, sets: u32) -> Result<Vec<[f32; 2]>> {
        let power_of_four = |n: u32| n.is_power_of_two() && n.trailing_zeros().is_multiple_of(2);
        let q = per_set.trailing_zeros() / 2;
        let m = q * 2 + sets.trailing_zeros();
        if !power_of_four(per_set) || !power_of_four(sets) || m > 24 {
            return Err(Error::usage(format!(
                "{} light samples come in powers of 4 (1, 4, 16, 64, 256, ...) with at most 2^24 in all: {per_set} per set × {sets} sets",
                self.name()
            )));
        }
        let mut points = Vec::with_capacity((per_set * sets) as usize);
        for set in 0..sets {
            for free in 0..per_set {
                let (high, low) = (free >> q, free & ((1 << q) - 1));
                let i = high << (m - q) | set << q | low;
                points.push(self.point(i, m));
            }
        }
        Ok(points)
    }

    pub fn name(self) -> &'static str {
        match self {
            Net::Hammersley => "hammersley",
            Net::LarcherPillichshammer => "lp",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radical_inverses_match_hand_worked_values() {
        // van der Corput: bit reversal.
        let vdc: Vec<f64> = (0..8).map(|i| Net::Hammersley.radical_inverse(i)).collect();
        assert_eq!(vdc, [0.0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875]);
        // Larcher–Pillichshammer (Kollig & Keller 2002): columns 1, 11, 111, ... (binary, MSB
        // first), so φ(2) = 0.11₂, φ(3) = 0.1₂ ⊕ 0.11₂ = 0.01₂, φ(6) = 0.11₂ ⊕ 0.111₂ = 0.001₂.
        let lp: Vec<f64> = (0..8)
            .map(|i| Net::LarcherPillichshammer.radical_inverse(i))
            .collect();
        assert_eq!(lp, [0.0, 0.5, 0.75, 0.25, 0.875, 0.375, 0.125, 0.625]);
        // The first 2^k values of either are a permutation of the multiples of 2^-k.
        for net in [Net::Hammersley, Net::LarcherPillichshammer] {
            let mut v: Vec<u32> = (0..1024)
                .map(|i| net.radical_inverse_bits(i) >> 22)
                .collect();
            v.sort();
            assert_eq!(v, (0..1024).collect::<Vec<_>>(), "{net:?}");
        }
        assert_eq!(Net::Hammersley.point(3, 2), [0.75, 0.75]);
        assert_eq!(Net::Hammersley.point(1, 3), [0.125, 0.5]);
    }

    /// Whether `points` (2^m of them) have exactly one point in every elementary interval of
    /// area 2^-m: the (0, m, 2)-net property.
    fn is_net(points: &[[f32; 2]], m: u32) -> bool {
        (0..=m).all(|a| {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut cells = vec![0u32; nx * ny];
            for &[x, y] in points {
                let (cx, cy) = ((x * nx as f32) as usize, (y * ny as f32) as usize);
                cells[cy * nx + cx] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    }

    #[test]
    fn the_union_of_the_tile_sets_is_a_net_and_each_set_is_stratified() {
        for net in [Net::Hammersley, Net::LarcherPillichshammer] {
            for (per_set, sets) in [(16, 16), (4, 16), (64, 16), (256, 1)] {
                let points = net.interleaved_sets(per_set, sets).unwrap();
                let m = (per_set * sets).trailing_zeros();
                assert!(is_net(&points, m), "{net:?} {per_set}×{sets}");
                let side = (per_set as f32).sqrt() as usize;
                for set in points.chunks(per_set as usize) {
                    let mut cells = vec![0u32; side * side];
                    for &[x, y] in set {
                        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                        let (cx, cy) = ((x * side as f32) as usize, (y * side as f32) as usize);
                        cells[cy * side + cx] += 1;
                    }
                    assert!(
                        cells.iter().all(|&c| c == 1),
                        "{net:?} {per_set}: {cells:?}"
                    );
                }
            }
        }
        // The sets are different points of the net.
        let sets = Net::LarcherPillichshammer.interleaved_sets(16, 16).unwrap();
        assert_ne!(sets[..16], sets[16..32]);
    }

    #[test]
    fn sample_counts_other_than_powers_of_four_are_refused() {
        assert!(Net::Hammersley.interleaved_sets(8, 16).is_err());
        assert!(Net::Hammersley.interleaved_sets(9, 16).is_err());
        assert!(Net::Hammersley.interleaved_sets(16, 8).is_err());
        assert!(Net::Hammersley.interleaved_sets(0, 16).is_err());
        assert!(Net::LarcherPillichshammer
            .interleaved_sets(1 << 12, 1 << 14)
            .is_err());
        assert_eq!(Net::Hammersley.interleaved_sets(1, 16).unwrap().len(), 16);
    }
}
