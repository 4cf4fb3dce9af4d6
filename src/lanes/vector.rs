//! Explicit f32 lane vectors, for kernels that put something other than rays in the lanes and
//! must run at a chosen width: the frusta kernels (`multi_frusta`'s `Frusta::box_masks`,
//! `cull::keep_mask`: one lane per frustum, §4 "one SIMD test per node for all frusta"),
//! `wide-single`'s test of a wide node's children and the reference tracer's child-pair test (one
//! lane per box). Plain lane loops there became 4- or 8-wide code only with the data copied to the
//! stack (LLVM prefers 256-bit vectors even on AVX-512 parts), or split the far planes into scalar
//! loads and shuffles (the wide-node test, checked in the assembly); explicit vectors load the
//! lanes straight from memory. Kernels are written once, generic over `Vector`.
//!
//! - `Avx512`: 16 lanes in a `__m512`, masks in a `__mmask16` (built with AVX-512F).
//! - `Avx2`: 8 lanes in a `__m256`, masks as lane vectors (built with AVX2).
//! - `Sse`: 4 lanes in a `__m128`, masks as lane vectors (SSE, the x86-64 baseline).
//! - `Portable<N>`: `N` lanes in an array, masks as bits: the reference the others are tested
//!   against, and the kernels' vector elsewhere.
//!
//! The intrinsics are `unsafe` only for the CPU features they need; their modules exist only when
//! the build enables those features, so every call is sound (the `unsafe` blocks below).
//!
//! `Native` is the widest the build targets (`target-cpu=native`, `.cargo/config.toml`). Every
//! operation is the IEEE operation of the portable lane, so all of them give the same bits:
//! `min`/`max` are `x < y ? x : y` / `x > y ? x : y` (what MINPS/MAXPS compute, NaN included).

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// A vector of `WIDTH` f32 lanes.
pub trait Vector:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Sized
{
    const WIDTH: usize;
    /// Per-lane booleans.
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    fn splat(x: f32) -> Self;
    /// Lanes `x[at..at + WIDTH]`.
    fn load(x: &[f32], at: usize) -> Self;
    fn abs(self) -> Self;
    /// The correctly rounded square root (as `f32::sqrt`).
    fn sqrt(self) -> Self;
    /// `self · a + b` rounded once (as `f32::mul_add`).
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `self < y ? self : y` per lane.
    fn min(self, y: Self) -> Self;
    /// `self > y ? self : y` per lane.
    fn max(self, y: Self) -> Self;
    fn lt(self, y: Self) -> Self::Mask;
    fn le(self, y: Self) -> Self::Mask;
    fn gt(self, y: Self) -> Self::Mask;
    /// `self == y` (false where either is NaN, as `==`).
    fn eq(self, y: Self) -> Self::Mask;
    /// `a` where `m`, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Lane `l`'s boolean as bit `l`.
    fn bits(m: Self::Mask) -> u64;
    /// The mask whose lane `l` is bit `l` of `bits` (`bits`' inverse).
    fn from_bits(bits: u64) -> Self::Mask;
    /// The lanes into `out[..WIDTH]`.
    fn store(self, out: &mut [f32]);
}

#[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
pub type Native = Avx512;
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    not(target_feature = "avx512f")
))]
pub type Native = Avx2;
#[cfg(not(all(
    target_arch = "x86_64",
    any(target_feature = "avx2", target_feature = "avx512f")
)))]
pub type Native = Portable<8>;

/// The build's 4-lane vector: `Sse` on x86-64 (its baseline), `Portable<4>` elsewhere.
#[cfg(target_arch = "x86_64")]
pub type Lanes4 = Sse;
#[cfg(not(target_arch = "x86_64"))]
pub type Lanes4 = Portable<4>;

/// Implements the arithmetic operators of a vector type from binary functions.
#[cfg(target_arch = "x86_64")]
macro_rules! arithmetic {
    ($t:ty, $add:expr, $sub:expr, $mul:expr, $div:expr) => {
        impl Add for $t {
            type Output = $t;
            #[inline(always)]
            fn add(self, y: $t) -> $t {
                $add(self, y)
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline(always)]
            fn sub(self, y: $t) -> $t {
                $sub(self, y)
            }
        }
        impl Mul for $t {
            type Output = $t;
            #[inline(always)]
            fn mul(self, y: $t) -> $t {
                $mul(self, y)
            }
        }
        impl Div for $t {
            type Output = $t;
            #[inline(always)]
            fn div(self, y: $t) -> $t {
                $div(self, y)
            }
        }
    };
}

// On x86 builds with AVX2 or AVX-512, `Portable` is there as the tests' reference only.
#[cfg(any(
    test,
    not(all(
        target_arch = "x86_64",
        any(target_feature = "avx2", target_feature = "avx512f")
    ))
))]
pub use portable::{BitMask, Portable};

#[cfg(any(
    test,
    not(all(
        target_arch = "x86_64",
        any(target_feature = "avx2", target_feature = "avx512f")
    ))
))]
mod portable {
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

    use super::Vector;

    /// `N` lanes in an array; masks are the lanes' bits.
    #[derive(Clone, Copy, Debug)]
    pub struct Portable<const N: usize>(pub [f32; N]);

    /// `Portable`'s mask: bit `l` for lane `l` (bits at and above `N` are meaningless).
    #[derive(Clone, Copy, Debug)]
    pub struct BitMask(u64);

    impl BitAnd for BitMask {
        type Output = BitMask;
        #[inline(always)]
        fn bitand(self, y: BitMask) -> BitMask {
            BitMask(self.0 & y.0)
        }
    }
    impl BitOr for BitMask {
        type Output = BitMask;
        #[inline(always)]
        fn bitor(self, y: BitMask) -> BitMask {
            BitMask(self.0 | y.0)
        }
    }
    impl Not for BitMask {
        type Output = BitMask;
        #[inline(always)]
        fn not(self) -> BitMask {
            BitMask(!self.0)
        }
    }

    impl<const N: usize> Portable<N> {
        #[inline(always)]
        fn map2(self, y: Self, f: impl Fn(f32, f32) -> f32) -> Self {
            Portable(std::array::from_fn(|l| f(self.0[l], y.0[l])))
        }

        #[inline(always)]
        fn test(self, y: Self, f: impl Fn(f32, f32) -> bool) -> BitMask {
            BitMask((0..N).fold(0, |m, l| m | (f(self.0[l], y.0[l]) as u64) << l))
        }
    }

    /// `Sse`'s own operations, for `Lanes4` off x86-64.
    impl Portable<4> {
        /// The lanes `[x0, x1, x2, x3]`.
        #[inline(always)]
        pub fn new(x: [f32; 4]) -> Self {
            Portable(x)
        }

        /// Lanes 2, 3, 0, 1: the halves swapped.
        #[inline(always)]
        pub fn swap_halves(self) -> Self {
            let [a, b, c, d] = self.0;
            Portable([c, d, a, b])
        }
    }

    impl<const N: usize> Add for Portable<N> {
        type Output = Self;
        #[inline(always)]
        fn add(self, y: Self) -> Self {
            self.map2(y, |a, b| a + b)
        }
    }
    impl<const N: usize> Sub for Portable<N> {
        type Output = Self;
        #[inline(always)]
        fn sub(self, y: Self) -> Self {
            self.map2(y, |a, b| a - b)
        }
    }
    impl<const N: usize> Mul for Portable<N> {
        type Output = Self;
        #[inline(always)]
        fn mul(self, y: Self) -> Self {
            self.map2(y, |a, b| a * b)
        }
    }
    impl<const N: usize> Div for Portable<N> {
        type Output = Self;
        #[inline(always)]
        fn div(self, y: Self) -> Self {
            self.map2(y, |a, b| a / b)
        }
    }

    impl<const N: usize> Vector for Portable<N> {
        const WIDTH: usize = N;
        type Mask = BitMask;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Portable([x; N])
        }
        #[inline(always)]
        fn load(x: &[f32], at: usize) -> Self {
            Portable(x[at..at + N].try_into().unwrap())
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Portable(self.0.map(f32::abs))
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Portable(self.0.map(f32::sqrt))
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Portable(std::array::from_fn(|l| self.0[l].mul_add(a.0[l], b.0[l])))
        }
        #[inline(always)]
        fn min(self, y: Self) -> Self {
            self.map2(y, |a, b| if a < b { a } else { b })
        }
        #[inline(always)]
        fn max(self, y: Self) -> Self {
            self.map2(y, |a, b| if a > b { a } else { b })
        }
        #[inline(always)]
        fn lt(self, y: Self) -> BitMask {
            self.test(y, |a, b| a < b)
        }
        #[inline(always)]
        fn le(self, y: Self) -> BitMask {
            self.test(y, |a, b| a <= b)
        }
        #[inline(always)]
        fn gt(self, y: Self) -> BitMask {
            self.test(y, |a, b| a > b)
        }
        #[inline(always)]
        fn eq(self, y: Self) -> BitMask {
            self.test(y, |a, b| a == b)
        }
        #[inline(always)]
        fn select(m: BitMask, a: Self, b: Self) -> Self {
            Portable(std::array::from_fn(|l| {
                if m.0 >> l & 1 == 1 {
                    a.0[l]
                } else {
                    b.0[l]
                }
            }))
        }
        #[inline(always)]
        fn bits(m: BitMask) -> u64 {
            m.0 & (u64::MAX >> (64 - N))
        }
        #[inline(always)]
        fn from_bits(bits: u64) -> BitMask {
            BitMask(bits)
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            out[..N].copy_from_slice(&self.0);
        }
    }
}

#[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
pub use avx512::Avx512;

#[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
mod avx512 {
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    use super::Vector;

    /// 16 lanes in a `__m512`.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx512(__m512);

    arithmetic!(
        Avx512,
        |x: Avx512, y: Avx512| Avx512(unsafe { _mm512_add_ps(x.0, y.0) }),
        |x: Avx512, y: Avx512| Avx512(unsafe { _mm512_sub_ps(x.0, y.0) }),
        |x: Avx512, y: Avx512| Avx512(unsafe { _mm512_mul_ps(x.0, y.0) }),
        |x: Avx512, y: Avx512| Avx512(unsafe { _mm512_div_ps(x.0, y.0) })
    );

    impl Vector for Avx512 {
        const WIDTH: usize = 16;
        type Mask = __mmask16;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Avx512(unsafe { _mm512_set1_ps(x) })
        }
        #[inline(always)]
        fn load(x: &[f32], at: usize) -> Self {
            let lanes = &x[at..at + 16];
            // SAFETY: `lanes` holds the 16 floats read (unaligned load).
            Avx512(unsafe { _mm512_loadu_ps(lanes.as_ptr()) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            Avx512(unsafe { _mm512_abs_ps(self.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Avx512(unsafe { _mm512_sqrt_ps(self.0) })
        }
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Avx512(unsafe { _mm512_fmadd_ps(self.0, a.0, b.0) })
        }
        #[inline(always)]
        fn min(self, y: Self) -> Self {
            Avx512(unsafe { _mm512_min_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn max(self, y: Self) -> Self {
            Avx512(unsafe { _mm512_max_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn lt(self, y: Self) -> __mmask16 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, y.0) }
        }
        #[inline(always)]
        fn le(self, y: Self) -> __mmask16 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, y.0) }
        }
        #[inline(always)]
        fn gt(self, y: Self) -> __mmask16 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, y.0) }
        }
        #[inline(always)]
        fn eq(self, y: Self) -> __mmask16 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, y.0) }
        }
        #[inline(always)]
        fn select(m: __mmask16, a: Self, b: Self) -> Self {
            Avx512(unsafe { _mm512_mask_blend_ps(m, b.0, a.0) })
        }
        #[inline(always)]
        fn bits(m: __mmask16) -> u64 {
            m as u64
        }
        #[inline(always)]
        fn from_bits(bits: u64) -> __mmask16 {
            bits as __mmask16
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..16];
            // SAFETY: `out` has room for the 16 floats written.
            unsafe { _mm512_storeu_ps(out.as_mut_ptr(), self.0) }
        }
    }
}

// On AVX-512 builds too: 8 lanes are the width of an 8-wide node's children (`wide_single`).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
pub use avx2::Avx2;

#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod avx2 {
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

    use super::Vector;

    /// 8 lanes in a `__m256`.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx2(__m256);

    /// `Avx2`'s mask: all bits of a lane set where true.
    #[derive(Clone, Copy, Debug)]
    pub struct LaneMask(__m256);

    impl BitAnd for LaneMask {
        type Output = LaneMask;
        #[inline(always)]
        fn bitand(self, y: LaneMask) -> LaneMask {
            LaneMask(unsafe { _mm256_and_ps(self.0, y.0) })
        }
    }
    impl BitOr for LaneMask {
        type Output = LaneMask;
        #[inline(always)]
        fn bitor(self, y: LaneMask) -> LaneMask {
            LaneMask(unsafe { _mm256_or_ps(self.0, y.0) })
        }
    }
    impl Not for LaneMask {
        type Output = LaneMask;
        #[inline(always)]
        fn not(self) -> LaneMask {
            let ones = unsafe { _mm256_castsi256_ps(_mm256_set1_epi32(-1)) };
            LaneMask(unsafe { _mm256_xor_ps(self.0, ones) })
        }
    }

    arithmetic!(
        Avx2,
        |x: Avx2, y: Avx2| Avx2(unsafe { _mm256_add_ps(x.0, y.0) }),
        |x: Avx2, y: Avx2| Avx2(unsafe { _mm256_sub_ps(x.0, y.0) }),
        |x: Avx2, y: Avx2| Avx2(unsafe { _mm256_mul_ps(x.0, y.0) }),
        |x: Avx2, y: Avx2| Avx2(unsafe { _mm256_div_ps(x.0, y.0) })
    );

    impl Vector for Avx2 {
        const WIDTH: usize = 8;
        type Mask = LaneMask;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Avx2(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn load(x: &[f32], at: usize) -> Self {
            let lanes = &x[at..at + 8];
            // SAFETY: `lanes` holds the 8 floats read (unaligned load).
            Avx2(unsafe { _mm256_loadu_ps(lanes.as_ptr()) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            let magnitude = unsafe { _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX)) };
            Avx2(unsafe { _mm256_and_ps(self.0, magnitude) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Avx2(unsafe { _mm256_sqrt_ps(self.0) })
        }
        #[cfg(target_feature = "fma")]
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Avx2(unsafe { _mm256_fmadd_ps(self.0, a.0, b.0) })
        }
        /// Without FMA instructions, lane by lane (`f32::mul_add`'s bits).
        #[cfg(not(target_feature = "fma"))]
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            let lanes = |v: Self| {
                let mut out = [0.0; 8];
                v.store(&mut out);
                out
            };
            let (x, y, z) = (lanes(self), lanes(a), lanes(b));
            Avx2::load(
                &std::array::from_fn::<f32, 8, _>(|l| x[l].mul_add(y[l], z[l])),
                0,
            )
        }
        #[inline(always)]
        fn min(self, y: Self) -> Self {
            Avx2(unsafe { _mm256_min_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn max(self, y: Self) -> Self {
            Avx2(unsafe { _mm256_max_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn lt(self, y: Self) -> LaneMask {
            LaneMask(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, y.0) })
        }
        #[inline(always)]
        fn le(self, y: Self) -> LaneMask {
            LaneMask(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, y.0) })
        }
        #[inline(always)]
        fn gt(self, y: Self) -> LaneMask {
            LaneMask(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, y.0) })
        }
        #[inline(always)]
        fn eq(self, y: Self) -> LaneMask {
            LaneMask(unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, y.0) })
        }
        #[inline(always)]
        fn select(m: LaneMask, a: Self, b: Self) -> Self {
            Avx2(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
        }
        #[inline(always)]
        fn bits(m: LaneMask) -> u64 {
            unsafe { _mm256_movemask_ps(m.0) as u32 as u64 }
        }
        #[inline(always)]
        fn from_bits(bits: u64) -> LaneMask {
            // Lane `l` all ones where bit `l` is set: the broadcast bits against each lane's bit.
            let lane_bits = unsafe { _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128) };
            let set = unsafe { _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane_bits) };
            LaneMask(unsafe { _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bits)) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..8];
            // SAFETY: `out` has room for the 8 floats written.
            unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub use sse::{Sse, SseMask};

#[cfg(target_arch = "x86_64")]
mod sse {
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

    use super::Vector;

    /// 4 lanes in a `__m128`.
    #[derive(Clone, Copy, Debug)]
    pub struct Sse(__m128);

    /// `Sse`'s mask: all bits of a lane set where true.
    #[derive(Clone, Copy, Debug)]
    pub struct SseMask(__m128);

    impl BitAnd for SseMask {
        type Output = SseMask;
        #[inline(always)]
        fn bitand(self, y: SseMask) -> SseMask {
            SseMask(unsafe { _mm_and_ps(self.0, y.0) })
        }
    }
    impl BitOr for SseMask {
        type Output = SseMask;
        #[inline(always)]
        fn bitor(self, y: SseMask) -> SseMask {
            SseMask(unsafe { _mm_or_ps(self.0, y.0) })
        }
    }
    impl Not for SseMask {
        type Output = SseMask;
        #[inline(always)]
        fn not(self) -> SseMask {
            let ones = unsafe { _mm_castsi128_ps(_mm_set1_epi32(-1)) };
            SseMask(unsafe { _mm_xor_ps(self.0, ones) })
        }
    }

    arithmetic!(
        Sse,
        |x: Sse, y: Sse| Sse(unsafe { _mm_add_ps(x.0, y.0) }),
        |x: Sse, y: Sse| Sse(unsafe { _mm_sub_ps(x.0, y.0) }),
        |x: Sse, y: Sse| Sse(unsafe { _mm_mul_ps(x.0, y.0) }),
        |x: Sse, y: Sse| Sse(unsafe { _mm_div_ps(x.0, y.0) })
    );

    impl Sse {
        /// The lanes `[x0, x1, x2, x3]`.
        #[inline(always)]
        pub fn new(x: [f32; 4]) -> Self {
            Sse(unsafe { _mm_setr_ps(x[0], x[1], x[2], x[3]) })
        }

        /// Lanes 2, 3, 0, 1: the halves swapped (one SHUFPS).
        #[inline(always)]
        pub fn swap_halves(self) -> Self {
            Sse(unsafe { _mm_shuffle_ps::<0b01_00_11_10>(self.0, self.0) })
        }
    }

    impl Vector for Sse {
        const WIDTH: usize = 4;
        type Mask = SseMask;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Sse(unsafe { _mm_set1_ps(x) })
        }
        #[inline(always)]
        fn load(x: &[f32], at: usize) -> Self {
            let lanes = &x[at..at + 4];
            // SAFETY: `lanes` holds the 4 floats read (unaligned load).
            Sse(unsafe { _mm_loadu_ps(lanes.as_ptr()) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            let magnitude = unsafe { _mm_castsi128_ps(_mm_set1_epi32(i32::MAX)) };
            Sse(unsafe { _mm_and_ps(self.0, magnitude) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            Sse(unsafe { _mm_sqrt_ps(self.0) })
        }
        #[cfg(target_feature = "fma")]
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            Sse(unsafe { _mm_fmadd_ps(self.0, a.0, b.0) })
        }
        /// Without FMA instructions, lane by lane (`f32::mul_add`'s bits).
        #[cfg(not(target_feature = "fma"))]
        #[inline(always)]
        fn mul_add(self, a: Self, b: Self) -> Self {
            let lanes = |v: Self| {
                let mut out = [0.0; 4];
                v.store(&mut out);
                out
            };
            let (x, y, z) = (lanes(self), lanes(a), lanes(b));
            Sse::new(std::array::from_fn(|l| x[l].mul_add(y[l], z[l])))
        }
        #[inline(always)]
        fn min(self, y: Self) -> Self {
            Sse(unsafe { _mm_min_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn max(self, y: Self) -> Self {
            Sse(unsafe { _mm_max_ps(self.0, y.0) })
        }
        // The SSE comparisons are ordered: false when either lane is NaN.
        #[inline(always)]
        fn lt(self, y: Self) -> SseMask {
            SseMask(unsafe { _mm_cmplt_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn le(self, y: Self) -> SseMask {
            SseMask(unsafe { _mm_cmple_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn gt(self, y: Self) -> SseMask {
            SseMask(unsafe { _mm_cmpgt_ps(self.0, y.0) })
        }
        #[inline(always)]
        fn eq(self, y: Self) -> SseMask {
            SseMask(unsafe { _mm_cmpeq_ps(self.0, y.0) })
        }
        #[cfg(target_feature = "sse4.1")]
        #[inline(always)]
        fn select(m: SseMask, a: Self, b: Self) -> Self {
            Sse(unsafe { _mm_blendv_ps(b.0, a.0, m.0) })
        }
        /// Without SSE4.1's BLENDVPS: `a & m | b & !m`.
        #[cfg(not(target_feature = "sse4.1"))]
        #[inline(always)]
        fn select(m: SseMask, a: Self, b: Self) -> Self {
            Sse(unsafe { _mm_or_ps(_mm_and_ps(m.0, a.0), _mm_andnot_ps(m.0, b.0)) })
        }
        #[inline(always)]
        fn bits(m: SseMask) -> u64 {
            unsafe { _mm_movemask_ps(m.0) as u32 as u64 }
        }
        #[inline(always)]
        fn from_bits(bits: u64) -> SseMask {
            // Lane `l` all ones where bit `l` is set: the broadcast bits against each lane's bit.
            let lane_bits = unsafe { _mm_setr_epi32(1, 2, 4, 8) };
            let set = unsafe { _mm_and_si128(_mm_set1_epi32(bits as i32), lane_bits) };
            SseMask(unsafe { _mm_castsi128_ps(_mm_cmpeq_epi32(set, lane_bits)) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..4];
            // SAFETY: `out` has room for the 4 floats written.
            unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) }
        }
    }
}

#[cfg(test)]
// The agreement helpers compare x86-64's vectors against `Portable`; elsewhere only it is left.
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
mod tests {
    use super::*;
    use crate::random::SplitMix64;

    const SPECIALS: [f32; 10] = [
        0.0,
        -0.0,
        1.0,
        -2.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e-40,
        -3e38,
        7.25,
    ];

    /// `n` values, half of them signed zeros, infinities, NaN, subnormals or huge.
    fn values(rng: &mut SplitMix64, n: usize) -> Vec<f32> {
        (0..n)
            .map(|_| {
                if rng.unit() < 0.5 {
                    SPECIALS[(rng.unit() * 10.0) as usize % 10]
                } else {
                    rng.range(-4.0, 4.0)
                }
            })
            .collect()
    }

    /// Every operation of `V` gives `Portable`'s bits, lane for lane.
    fn agrees_with_portable<V: Vector, const N: usize>() {
        assert_eq!(V::WIDTH, N);
        let mut rng = SplitMix64::new(7);
        let bits = |v: V| -> Vec<u32> {
            let mut out = [0.0; N];
            v.store(&mut out);
            out.map(f32::to_bits).to_vec()
        };
        let want = |p: Portable<N>| -> Vec<u32> { p.0.map(f32::to_bits).to_vec() };
        for _ in 0..500 {
            let (x, y, z) = (
                values(&mut rng, N),
                values(&mut rng, N),
                values(&mut rng, N),
            );
            let (vx, vy, vz) = (V::load(&x, 0), V::load(&y, 0), V::load(&z, 0));
            let (px, py, pz) = (
                Portable::<N>::load(&x, 0),
                Portable::<N>::load(&y, 0),
                Portable::<N>::load(&z, 0),
            );
            assert_eq!(bits(vx + vy), want(px + py));
            assert_eq!(bits(vx - vy), want(px - py));
            assert_eq!(bits(vx * vy), want(px * py));
            assert_eq!(bits(vx / vy), want(px / py));
            assert_eq!(bits(vx.sqrt()), want(px.sqrt()));
            assert_eq!(bits(vx.mul_add(vy, vz)), want(px.mul_add(py, pz)));
            assert_eq!(bits(vx.abs()), want(px.abs()));
            assert_eq!(bits(vx.min(vy)), want(px.min(py)));
            assert_eq!(bits(vx.max(vy)), want(px.max(py)));
            assert_eq!(bits(V::splat(x[0])), want(Portable::splat(x[0])));
            let mask = |m: V::Mask| V::bits(m);
            let reference = |m: BitMask| Portable::<N>::bits(m);
            assert_eq!(mask(vx.lt(vy)), reference(px.lt(py)));
            assert_eq!(mask(vx.le(vy)), reference(px.le(py)));
            assert_eq!(mask(vx.gt(vy)), reference(px.gt(py)));
            assert_eq!(mask(vx.eq(vy)), reference(px.eq(py)));
            let (vm, pm) = (vx.lt(vz), px.lt(pz));
            assert_eq!(mask(vm & vx.gt(vy)), reference(pm & px.gt(py)));
            assert_eq!(mask(vm | vx.gt(vy)), reference(pm | px.gt(py)));
            assert_eq!(mask(!vm), reference(!pm));
            let lanes = rng.next_u64();
            assert_eq!(
                mask(V::from_bits(lanes)),
                reference(Portable::<N>::from_bits(lanes))
            );
            assert_eq!(V::bits(V::from_bits(lanes)), lanes & (u64::MAX >> (64 - N)));
            assert_eq!(
                bits(V::select(vm, vx, vy)),
                want(Portable::select(pm, px, py))
            );
        }
    }

    #[test]
    fn portable_lanes_are_the_scalar_operations() {
        let p = Portable([1.0, f32::NAN, -0.0, 3.0]);
        let q = Portable([2.0, 1.0, 0.0, f32::NAN]);
        // min/max keep the second operand on NaN and on equal zeros, as MINPS/MAXPS do.
        assert_eq!(
            p.min(q).0.map(f32::to_bits),
            [1.0, 1.0, 0.0, f32::NAN].map(f32::to_bits)
        );
        assert_eq!(
            p.max(q).0.map(f32::to_bits),
            [2.0, 1.0, 0.0, f32::NAN].map(f32::to_bits)
        );
        assert_eq!(Portable::<4>::bits(p.lt(q)), 0b0001);
        // -0 equals +0, NaN equals nothing.
        assert_eq!(Portable::<4>::bits(p.eq(q)), 0b0100);
        assert_eq!(Portable::<4>::bits(!p.lt(q)), 0b1110);
        assert_eq!(
            Portable::new([1.0, 2.0, 3.0, 4.0]).swap_halves().0,
            [3.0, 4.0, 1.0, 2.0]
        );
    }

    #[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
    #[test]
    fn avx512_lanes_agree_with_portable_lanes() {
        agrees_with_portable::<Avx512, 16>();
    }

    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[test]
    fn avx2_lanes_agree_with_portable_lanes() {
        agrees_with_portable::<Avx2, 8>();
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse_lanes_agree_with_portable_lanes() {
        agrees_with_portable::<Sse, 4>();
        let x = Sse::new([1.0, 2.0, 3.0, 4.0]);
        let mut out = [0.0; 4];
        x.swap_halves().store(&mut out);
        assert_eq!(out, [3.0, 4.0, 1.0, 2.0]);
    }
}
