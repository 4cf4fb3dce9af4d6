//! A run-time width to the const-generic kernels: a tracer reads its lane count (`lanes`, or
//! stream filtering's `width`) from its configuration as a value, while its kernels take it as a
//! const parameter, so each width is a kernel of its own. This is the one place the two meet:
//! `with_lanes!` over the lane layer's widths (`WIDTHS`), `with_width!` over any list.

/// `$body` with the const `$N` bound to `$value` when it is one of the listed widths, to the last
/// one otherwise (configurations check their values when parsed, so that arm is the last width's
/// own). Every arm is `$body` monomorphised at its width:
/// `with_width!(width, N in [4, 8, 12] => kernel::<N>())`.
macro_rules! with_width {
    ($value:expr, $N:ident in [$($w:literal),+] => $body:expr) => {{
        let value: usize = $value;
        $crate::lanes::with_width!(@pick value, $N, [$($w),+], $body)
    }};
    (@pick $value:ident, $N:ident, [$last:literal], $body:expr) => {{
        const $N: usize = $last;
        $body
    }};
    (@pick $value:ident, $N:ident, [$w:literal, $($rest:literal),+], $body:expr) => {
        if $value == $w {
            const $N: usize = $w;
            $body
        } else {
            $crate::lanes::with_width!(@pick $value, $N, [$($rest),+], $body)
        }
    };
}

/// `$body` with the const `$L` bound to the lane count `$value` (`WIDTHS`: 4, 8, else 16):
/// `with_lanes!(config.lanes, L => self.trace::<L, S>(rays, stats))`.
macro_rules! with_lanes {
    ($value:expr, $L:ident => $body:expr) => {
        $crate::lanes::with_width!($value, $L in [4, 8, 16] => $body)
    };
}

pub(crate) use {with_lanes, with_width};

#[cfg(test)]
mod tests {
    use crate::lanes::WIDTHS;

    fn width<const N: usize>() -> usize {
        N
    }

    #[test]
    fn each_lane_count_runs_the_kernel_of_its_width() {
        for lanes in WIDTHS {
            assert_eq!(with_lanes!(lanes, L => width::<L>()), lanes);
        }
    }

    #[test]
    fn any_other_value_runs_the_last_width() {
        let widths = |n: usize| with_width!(n, N in [4, 8, 12, 64] => width::<N>());
        assert_eq!([4, 8, 12, 64].map(widths), [4, 8, 12, 64]);
        assert_eq!(widths(3), 64);
    }
}
