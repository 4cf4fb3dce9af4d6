//! The smallest and largest values of a stream, kept per lane of an `L`-wide accumulator so the
//! loop runs in SIMD lanes (selects, not `f32::min`); a NaN value is skipped.

/// `[[min, max]; Q]` of `value(i)` for `i` in `0..n`, `Q` quantities at once; `[∞, −∞]` when no
/// value is a number.
#[inline(always)]
pub fn min_max<const L: usize, const Q: usize>(
    n: usize,
    value: impl Fn(usize) -> [f32; Q],
) -> [[f32; 2]; Q] {
    let (mut lo, mut hi) = ([[f32::INFINITY; L]; Q], [[f32::NEG_INFINITY; L]; Q]);
    let mut bound = |l: usize, x: [f32; Q]| {
        for q in 0..Q {
            lo[q][l] = if x[q] < lo[q][l] { x[q] } else { lo[q][l] };
            hi[q][l] = if x[q] > hi[q][l] { x[q] } else { hi[q][l] };
        }
    };
    let whole = n / L * L;
    for base in (0..whole).step_by(L) {
        for l in 0..L {
            bound(l, value(base + l));
        }
    }
    // The tail as a whole vector too, its missing lanes repeating the last value (which moves no
    // extreme): a partial one compiled to masked stores, microcoded on AMD's AVX2 cores.
    if whole < n {
        for l in 0..L {
            bound(l, value((whole + l).min(n - 1)));
        }
    }
    std::array::from_fn(|q| {
        [
            lo[q].into_iter().fold(f32::INFINITY, f32::min),
            hi[q].into_iter().fold(f32::NEG_INFINITY, f32::max),
        ]
    })
}

/// The smallest lane; a NaN lane is skipped, and `∞` when no lane is a number. By comparisons
/// (one vector instruction each, where `f32::min` takes several), in four running lanes.
#[inline(always)]
pub fn lowest<const L: usize>(lanes: [f32; L]) -> f32 {
    let m = fold_in_fours(lanes, |a, b| if (b < a) | a.is_nan() { b } else { a });
    if m.is_nan() {
        f32::INFINITY
    } else {
        m
    }
}

/// The largest lane, as `lowest`; `−∞` when no lane is a number.
#[inline(always)]
pub fn highest<const L: usize>(lanes: [f32; L]) -> f32 {
    let m = fold_in_fours(lanes, |a, b| if (b > a) | a.is_nan() { b } else { a });
    if m.is_nan() {
        f32::NEG_INFINITY
    } else {
        m
    }
}

/// `pick` folded over the lanes in four running lanes (four-wide vector steps, where a
/// left-to-right fold is a chain of `L` scalar ones), then over those four; NaN when `L` = 0.
#[inline(always)]
fn fold_in_fours<const L: usize>(lanes: [f32; L], pick: impl Fn(f32, f32) -> f32) -> f32 {
    let mut acc = [f32::NAN; 4];
    let fours = lanes.chunks_exact(4);
    for (j, &x) in fours.remainder().iter().enumerate() {
        acc[j] = x;
    }
    for four in fours {
        for j in 0..4 {
            acc[j] = pick(acc[j], four[j]);
        }
    }
    pick(pick(acc[0], acc[1]), pick(acc[2], acc[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice_min_max<const L: usize>(x: &[f32]) -> [f32; 2] {
        min_max::<L, 1>(x.len(), |i| [x[i]])[0]
    }

    #[test]
    fn lowest_and_highest_skip_nans() {
        let x = [
            3.0,
            f32::NAN,
            -2.5,
            7.0,
            f32::NEG_INFINITY,
            1.0,
            f32::NAN,
            0.5,
        ];
        assert_eq!(lowest(x), f32::NEG_INFINITY);
        assert_eq!(highest(x), 7.0);
        assert_eq!(lowest([f32::NAN; 4]), f32::INFINITY);
        assert_eq!(highest([f32::NAN; 4]), f32::NEG_INFINITY);
        assert_eq!(highest([2.0, f32::NEG_INFINITY, 9.5, f32::NAN]), 9.5);
        assert_eq!(highest([f32::NAN, 1.0, f32::NAN, f32::NAN]), 1.0);
        // Every position of the extreme, at 16 lanes.
        for at in 0..16 {
            let mut x: [f32; 16] = std::array::from_fn(|i| i as f32 * 0.5 - 3.0);
            x[at] = -9.0;
            assert_eq!(lowest(x), -9.0);
            x[at] = 99.0;
            assert_eq!(highest(x), 99.0);
        }
    }

    #[test]
    fn min_max_ignores_nans_over_whole_lane_groups_and_the_rest() {
        // 37 values: whole groups and a rest at every width, extremes in both.
        let mut x: Vec<f32> = (0..37).map(|i| (i as f32 * 7.0) % 37.0 - 18.0).collect();
        x[3] = f32::NAN;
        x[20] = -40.0;
        x[35] = 50.0;
        x[36] = f32::NAN;
        for got in [slice_min_max::<4>, slice_min_max::<8>, slice_min_max::<16>] {
            assert_eq!(got(&x), [-40.0, 50.0]);
            assert_eq!(got(&x[..3]), [-18.0, -4.0]);
            assert_eq!(got(&[f32::NAN]), [f32::INFINITY, f32::NEG_INFINITY]);
        }
    }
}
