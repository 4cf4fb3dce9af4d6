//! Interleaved sampling with a static sample set (Keller & Heidrich 2001, "Interleaved Sampling";
//! used by Boulos et al. 2007 §4): a fixed table of `K×K` sample patterns tiled over the image, so
//! pixel `(x, y)` uses pattern `(x mod K, y mod K)`. The table is built once from a seed: the same
//! frame renders identically every time, and consecutive frames see the same samples, so there is
//! no temporal scintillation (Boulos §4: "a static sample set ... removes the temporal
//! scintillation artifacts").
//!
//! Construction, per 2D dimension pair: the unit square is cut into `(K·m)²` cells, `m² = spp`.
//! Pattern `p` owns one sub-cell offset `(i, j)` in every `K×K` block of cells, so each pattern
//! alone is an `m×m` jittered (stratified) set and the `K²` patterns of a `K×K` pixel block
//! together are a `(K·m)×(K·m)` jittered set — the interleaving of Keller & Heidrich: neighbouring
//! pixels fill each other's gaps. Which offset a pattern owns is permuted per dimension pair, and
//! the order of a pattern's samples is shuffled per dimension pair, so the dimensions (pixel
//! position, lens, light, gloss) are not correlated with each other.

use crate::error::{Error, Result};
use crate::random::SplitMix64;

/// Patterns per image row and column: pixel `(x, y)` uses pattern `(x mod K) + K·(y mod K)`.
pub const K: u32 = 4;
/// 2D dimension pairs each sample carries (pixel, lens, time, and three per bounce).
pub const DIMENSION_PAIRS: usize = 32;

/// The static sample set: `K²` patterns × `DIMENSION_PAIRS` × `spp` points in [0, 1)².
#[derive(Clone, Debug, PartialEq)]
pub struct SampleTable {
    spp: u32,
    /// Side of the per-pattern strata grid: `strata² = spp`.
    strata: u32,
    points: Vec<[f32; 2]>,
}

impl SampleTable {
    /// The table for `spp` samples per pixel (a perfect square: 1, 4, 16, 64, ...), from `seed`.
    pub fn new(spp: u32, seed: u64) -> Result<SampleTable> {
        let strata = (spp as f64).sqrt().round() as u32;
        if spp == 0 || strata * strata != spp {
            return Err(Error::usage(format!(
                "samples per pixel must be a perfect square (1, 4, 16, 64, ...), got {spp}"
            )));
        }
        let patterns = (K * K) as usize;
        let n = spp as usize;
        let mut rng = SplitMix64::new(seed);
        let mut points = vec![[0.0f32; 2]; patterns * DIMENSION_PAIRS * n];
        let cells = (K * strata) as f32;
        for pair in 0..DIMENSION_PAIRS {
            // Which of the K×K sub-cell offsets each pattern owns in this dimension pair.
            let offsets = shuffled(patterns, &mut rng);
            for (pattern, &offset) in offsets.iter().enumerate() {
                let (i, j) = (offset as u32 % K, offset as u32 / K);
                let order = shuffled(n, &mut rng);
                for (s, &stratum) in order.iter().enumerate() {
                    let (a, b) = (stratum as u32 % strata, stratum as u32 / strata);
                    let x = ((a * K + i) as f32 + rng.unit()) / cells;
                    let y = ((b * K + j) as f32 + rng.unit()) / cells;
                    // f32 rounding can carry (c + ξ)/cells to 1.0: keep samples in [0, 1).
                    points[(pattern * DIMENSION_PAIRS + pair) * n + s] =
                        [x.min(ONE_BELOW), y.min(ONE_BELOW)];
                }
            }
        }
        Ok(SampleTable {
            spp,
            strata,
            points,
        })
    }

    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Side of the strata grid of one pattern (`strata² = spp`).
    pub fn strata(&self) -> u32 {
        self.strata
    }

    /// Which pattern pixel `(x, y)` uses.
    pub fn pattern_of(x: u32, y: u32) -> usize {
        ((x % K) + K * (y % K)) as usize
    }

    /// Sample `sample` of pixel `(x, y)` in dimension pair `pair`.
    #[inline]
    pub fn get(&self, x: u32, y: u32, sample: u32, pair: usize) -> (f32, f32) {
        debug_assert!(pair < DIMENSION_PAIRS && sample < self.spp);
        let n = self.spp as usize;
        let [u, v] =
            self.points[(Self::pattern_of(x, y) * DIMENSION_PAIRS + pair) * n + sample as usize];
        (u, v)
    }
}

/// The largest f32 below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// A seeded permutation of `0..n` (Fisher–Yates).
fn shuffled(n: usize, rng: &mut SplitMix64) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_square_sample_counts_are_rejected() {
        assert!(SampleTable::new(0, 1).is_err());
        assert!(SampleTable::new(8, 1).is_err());
        assert_eq!(SampleTable::new(64, 1).unwrap().strata(), 8);
    }

    #[test]
    fn table_is_deterministic_and_seeded() {
        let a = SampleTable::new(16, 7).unwrap();
        assert_eq!(a, SampleTable::new(16, 7).unwrap());
        assert_ne!(a, SampleTable::new(16, 8).unwrap());
    }

    #[test]
    fn pixels_k_apart_share_a_pattern_and_neighbours_do_not() {
        let t = SampleTable::new(16, 3).unwrap();
        for pair in [0, 5, DIMENSION_PAIRS - 1] {
            for s in 0..16 {
                assert_eq!(t.get(1, 2, s, pair), t.get(1 + K, 2, s, pair));
                assert_eq!(t.get(1, 2, s, pair), t.get(1 + 3 * K, 2 + K, s, pair));
            }
        }
        assert_ne!(t.get(1, 2, 0, 0), t.get(2, 2, 0, 0));
    }

    #[test]
    fn each_pattern_is_stratified_and_a_pixel_block_interleaves_them() {
        let t = SampleTable::new(16, 11).unwrap();
        let m = t.strata();
        for pair in [0, 1, 9] {
            let mut fine = vec![0u32; (K * m * K * m) as usize];
            for (x, y) in (0..K).flat_map(|y| (0..K).map(move |x| (x, y))) {
                // One sample in each of the m×m strata of this pixel's pattern.
                let mut coarse = vec![0u32; (m * m) as usize];
                for s in 0..16 {
                    let (u, v) = t.get(x, y, s, pair);
                    assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
                    coarse[((v * m as f32) as u32 * m + (u * m as f32) as u32) as usize] += 1;
                    let c = K * m;
                    fine[((v * c as f32) as u32 * c + (u * c as f32) as u32) as usize] += 1;
                }
                assert!(
                    coarse.iter().all(|&c| c == 1),
                    "pixel ({x},{y}): {coarse:?}"
                );
            }
            // The 16 pixels of a 4×4 block together: one sample in each of the 16×16 cells.
            assert!(fine.iter().all(|&c| c == 1), "pair {pair}");
        }
    }
}
