//! The lane layer: rays in structure-of-arrays lanes of a const width `L` (4, 8 or 16: SSE, AVX2,
//! AVX-512), and the per-lane tests every coherent tracer runs on them. Lane loops are plain,
//! branch-free loops over `[f32; L]` that LLVM turns into one vector instruction per operation at
//! the machine's width (`target-cpu=native`). A loop writes each lane of its outputs once and
//! unconditionally: a store under a lane mask, or of a select with the same slot's old value,
//! becomes a masked store (`vmaskmovps`), native on AVX-512 but microcoded on AMD's AVX2 cores,
//! where it cost the stream filter 15–30% (`SimdRay::intersect_permuted`, `slab` show the two ways
//! around it).
//!
//! - `LaneMask<L>`: which lanes a test passed (one bit per lane).
//! - `vector`: explicit f32 vectors (`Avx512`, `Avx2`, `Sse`, `Portable<N>`; `Native` the
//!   build's widest, `Lanes4` its 4-lane one: `Sse`, or `Portable<4>` off x86-64) for kernels with something other than rays in the lanes: frusta, a node's
//!   children.
//! - `BroadcastRay<V>`: one ray in every lane of a `vector`, for tests with boxes in the lanes.
//! - `SharedFrame`: the origin and watertight axes all lanes of some SIMD rays share, so a
//!   triangle is made relative to it once for all of them.
//! - `SimdRay<L>`: `L` rays traced in lock step with their closest hits (the packet tracer's
//!   SIMD ray, Overbeck et al. 2008 §2.1), running `slab` and `watertight` per lane.
//! - `slab`: the ray–box test per lane, bit for bit `RayBoxTest::hit_with::<R>` (conservative,
//!   Ize 2013, with `Robust`; plain with `Fast`).
//! - `watertight`: the f32 stage of the watertight ray–triangle test (Woop et al. 2013) per lane,
//!   bit for bit `WatertightRay::intersect` (`robust = true`).
//! - `moller`: the Möller–Trumbore test per lane, bit for bit `MollerRay::intersect`
//!   (`robust = false`).
//! - `stream`: in-place compaction and partition of a stream of rays in SoA columns by a lane
//!   predicate — what coherent grid traversal drops finished rays with, and what stream filtering
//!   (Gribble & Ramani 2008) is built on.
//! - `triangle_block`: four triangles of a leaf in one SoA block, and one ray's test against all
//!   four, bit for bit the scalar leaf (the wide single-ray walk's leaves).
//! - `prefetch`: cache prefetch hints (an instruction on x86-64, nothing elsewhere).
//! - `min_max`: running per-lane bounds of a stream (the frusta's extremes); `lowest` and
//!   `highest` of one lane array.
//!
//! A tracer picks `L` once (its `lanes` parameter) and every lane type and test of its kernel
//! takes that `L`; `with_lanes!` (`dispatch`) turns the run-time count into the kernel's const.
//! Likewise its tests `R: RayTests` (its `robust` parameter, `geometry::robustness`): every box
//! and triangle test of the lane layer takes `R`.

mod broadcast_ray;
mod dispatch;
mod mask;
mod min_max;
pub mod moller;
pub mod prefetch;
mod shared_frame;
mod simd_ray;
pub mod slab;
pub mod stream;
pub mod triangle_block;
pub mod vector;
pub mod watertight;

pub use broadcast_ray::BroadcastRay;
pub(crate) use dispatch::{with_lanes, with_width};
pub use mask::LaneMask;
pub use min_max::{highest, lowest, min_max};
pub use shared_frame::SharedFrame;
pub use simd_ray::SimdRay;

/// The lane widths a tracer may be built with (`lanes` parameter).
pub const WIDTHS: [usize; 3] = [4, 8, 16];
