//! Cache prefetch hints, the one place raylab issues them: `PREFETCHT0`/`PREFETCHT1` on x86-64
//! (part of its SSE baseline); on other targets nothing, which is the portable path (a hint never
//! changes a result).

/// Bytes per cache line.
pub const LINE: usize = 64;

/// How close to the core a prefetched line should land.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Every level, L1 included: for data the next few steps read (a node, a leaf).
    Near,
    /// L2 and beyond: for data read later (the rays of the next batch).
    Far,
}

/// Asks for the cache line holding `address` at `level`. Never faults, whatever the address.
#[inline(always)]
pub fn line(address: *const u8, level: Level) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0, _MM_HINT_T1};
        // SAFETY: SSE is part of the x86-64 baseline, and a prefetch never faults.
        unsafe {
            match level {
                Level::Near => _mm_prefetch::<_MM_HINT_T0>(address as *const i8),
                Level::Far => _mm_prefetch::<_MM_HINT_T1>(address as *const i8),
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (address, level);
}
