//! A measured number with the range it spans over the run's timed passes: a time is its fastest
//! pass (`seconds_min`, the number every table shows) and spans up to its median pass
//! (`seconds_median`); a quantity derived from times spans what its inputs' ranges allow. Counts
//! (box tests, rays) are exact and span nothing. A verdict weighs a comparison against these
//! ranges: a difference inside them is noise (`report::judge`).

use super::selection::{field_value, Row};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// The number shown (from the fastest passes).
    pub value: f64,
    pub low: f64,
    pub high: f64,
}

impl Spread {
    /// An exact number.
    pub fn exact(value: f64) -> Spread {
        Spread {
            value,
            low: value,
            high: value,
        }
    }

    /// `value` within `[a, b]` (in either order).
    fn between(value: f64, a: f64, b: f64) -> Spread {
        Spread {
            value,
            low: a.min(b).min(value),
            high: a.max(b).max(value),
        }
    }

    /// Whether the range is a single number.
    pub fn is_exact(self) -> bool {
        self.low == self.high
    }

    pub fn times(self, other: Spread) -> Spread {
        let ends = [
            self.low * other.low,
            self.low * other.high,
            self.high * other.low,
            self.high * other.high,
        ];
        Spread::hull(self.value * other.value, ends)
    }

    pub fn divided_by(self, other: Spread) -> Spread {
        let ends = [
            self.low / other.low,
            self.low / other.high,
            self.high / other.low,
            self.high / other.high,
        ];
        Spread::hull(self.value / other.value, ends)
    }

    pub fn plus(self, other: Spread) -> Spread {
        Spread {
            value: self.value + other.value,
            low: self.low + other.low,
            high: self.high + other.high,
        }
    }

    pub fn minus(self, other: Spread) -> Spread {
        Spread {
            value: self.value - other.value,
            low: self.low - other.high,
            high: self.high - other.low,
        }
    }

    pub fn min(self, other: Spread) -> Spread {
        Spread {
            value: self.value.min(other.value),
            low: self.low.min(other.low),
            high: self.high.min(other.high),
        }
    }

    pub fn scaled(self, factor: f64) -> Spread {
        Spread::times(self, Spread::exact(factor))
    }

    fn hull(value: f64, ends: [f64; 4]) -> Spread {
        let low = ends.iter().copied().fold(value, f64::min);
        let high = ends.iter().copied().fold(value, f64::max);
        Spread { value, low, high }
    }

    /// `metric` of `row` with its spread: timed metrics span their fastest to their median pass
    /// (Embree's and the baselines' best too), the ones derived from them accordingly; any other
    /// metric is exact. `None` when the row has no number there.
    pub fn in_row(row: &Row, metric: &str) -> Option<Spread> {
        let number = |field: &str| field_value(row, field).parse::<f64>().ok();
        let value = number(metric)?;
        // A file from before a median column: no spread known, the number alone.
        let median_of = |fastest: &str, median: &str| -> Option<(f64, f64)> {
            Some((number(fastest)?, number(median).unwrap_or(number(fastest)?)))
        };
        let ours = median_of("seconds_min", "seconds_median");
        let ratio_to_ours = |best: Option<(f64, f64)>| -> Option<Spread> {
            let ((best_fast, best_slow), (fast, slow)) = (best?, ours?);
            Some(Spread::between(value, best_fast / slow, best_slow / fast))
        };
        let embree = median_of("embree_best_seconds", "embree_best_seconds_median");
        let baseline = median_of("baseline_best_seconds", "baseline_best_seconds_median");
        let spread = match metric {
            "seconds_min" => ours.map(|(_, slow)| Spread::between(value, value, slow)),
            "build_plus_trace_seconds" => {
                ours.map(|(fast, slow)| Spread::between(value, value, value - fast + slow))
            }
            "mrays_per_s" => {
                ours.map(|(fast, slow)| Spread::between(value, value, value * fast / slow))
            }
            "embree_best_seconds" => embree.map(|(_, slow)| Spread::between(value, value, slow)),
            "baseline_best_seconds" => {
                baseline.map(|(_, slow)| Spread::between(value, value, slow))
            }
            "x_embree_best" => ratio_to_ours(embree),
            "x_baseline_best" => ratio_to_ours(baseline),
            _ => None,
        };
        Some(spread.unwrap_or(Spread::exact(value)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::record::selection::row;

    #[test]
    fn times_span_their_fastest_to_their_median_pass_and_ratios_carry_both() {
        let r = row(&[
            ("seconds_min", "2"),
            ("seconds_median", "2.5"),
            ("embree_best_seconds", "1"),
            ("embree_best_seconds_median", "1.5"),
            ("x_embree_best", "0.5"),
            ("aabb_tests", "40"),
            ("rays", "4000000"),
            ("mrays_per_s", "2"),
        ]);
        let s = Spread::in_row(&r, "seconds_min").unwrap();
        assert_eq!((s.value, s.low, s.high), (2.0, 2.0, 2.5));
        // Embree 1–1.5 s over ours 2–2.5 s: 0.4 to 0.75.
        let x = Spread::in_row(&r, "x_embree_best").unwrap();
        assert_eq!((x.value, x.low, x.high), (0.5, 0.4, 0.75));
        let m = Spread::in_row(&r, "mrays_per_s").unwrap();
        assert_eq!((m.low, m.high), (1.6, 2.0));
        assert!(Spread::in_row(&r, "aabb_tests").unwrap().is_exact());
        assert_eq!(Spread::in_row(&r, "triangle_tests"), None);
        // An older file without Embree's median: Embree's side exact, ours still spread.
        let old = row(&[
            ("seconds_min", "2"),
            ("seconds_median", "2.5"),
            ("embree_best_seconds", "1"),
            ("x_embree_best", "0.5"),
        ]);
        let x = Spread::in_row(&old, "x_embree_best").unwrap();
        assert_eq!((x.low, x.high), (0.4, 0.5));
    }

    #[test]
    fn arithmetic_keeps_every_combination_of_the_ends_inside() {
        let a = Spread::between(2.0, 2.0, 3.0);
        let b = Spread::between(4.0, 4.0, 5.0);
        let q = a.divided_by(b);
        assert_eq!((q.value, q.low, q.high), (0.5, 0.4, 0.75));
        let p = a.times(b);
        assert_eq!((p.low, p.high), (8.0, 15.0));
        let s = a.plus(b);
        assert_eq!((s.value, s.low, s.high), (6.0, 6.0, 8.0));
        let d = b.minus(a);
        assert_eq!((d.value, d.low, d.high), (2.0, 1.0, 3.0));
        let m = a.min(b);
        assert_eq!((m.value, m.low, m.high), (2.0, 2.0, 3.0));
        let i = Spread::exact(1000.0).divided_by(a);
        assert_eq!((i.value, i.low, i.high), (500.0, 1000.0 / 3.0, 500.0));
    }
}
