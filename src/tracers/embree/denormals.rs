//! Embree asks every thread that traces to flush denormals to zero (FTZ) and treat denormal inputs
//! as zero (DAZ) for speed ("Embree API / Performance Recommendations"). Those are MXCSR bits of
//! the calling thread, so they are set only for the duration of one Embree call and restored
//! after it: our own tracers on the same thread keep IEEE denormals.

/// MXCSR bit 15: flush-to-zero of denormal results.
const FTZ: u32 = 1 << 15;
/// MXCSR bit 6: denormal inputs are treated as zero.
const DAZ: u32 = 1 << 6;

/// While alive, the current thread runs with FTZ and DAZ set; dropping it restores the previous
/// MXCSR value.
pub struct FlushDenormals {
    previous: u32,
    // MXCSR is per thread: the guard must be dropped on the thread that made it.
    _not_send: std::marker::PhantomData<*const ()>,
}

impl FlushDenormals {
    #[inline]
    pub fn new() -> Self {
        let previous = mxcsr::read();
        mxcsr::write(previous | FTZ | DAZ);
        FlushDenormals {
            previous,
            _not_send: std::marker::PhantomData,
        }
    }
}

impl Drop for FlushDenormals {
    #[inline]
    fn drop(&mut self) {
        mxcsr::write(self.previous);
    }
}

/// `stmxcsr` / `ldmxcsr` through inline assembly: `std::arch`'s `_mm_getcsr`/`_mm_setcsr` are
/// deprecated.
#[cfg(target_arch = "x86_64")]
mod mxcsr {
    use std::arch::asm;

    #[inline]
    pub fn read() -> u32 {
        let mut csr = 0u32;
        // SAFETY: stmxcsr stores the 4-byte MXCSR to a valid, writable u32.
        unsafe { asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags)) };
        csr
    }

    #[inline]
    pub fn write(csr: u32) {
        // SAFETY: ldmxcsr loads MXCSR from a valid u32; every value we write is one read from
        // MXCSR with only the FTZ/DAZ bits changed, so no reserved bit is set.
        unsafe { asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags, readonly)) };
    }
}

/// Other architectures have no MXCSR; Embree's recommendation is x86-specific.
#[cfg(not(target_arch = "x86_64"))]
mod mxcsr {
    pub fn read() -> u32 {
        0
    }
    pub fn write(_: u32) {}
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    #[test]
    fn sets_ftz_daz_inside_and_restores_outside() {
        let before = mxcsr::read();
        assert_eq!(
            before & (FTZ | DAZ),
            0,
            "Rust threads start with IEEE denormals"
        );
        let tiny = std::hint::black_box(f32::MIN_POSITIVE);
        {
            let _guard = FlushDenormals::new();
            assert_eq!(mxcsr::read(), before | FTZ | DAZ);
            // FTZ: a result below the normal range becomes zero.
            assert_eq!(
                std::hint::black_box(tiny) / std::hint::black_box(4.0f32),
                0.0
            );
        }
        assert_eq!(mxcsr::read(), before);
        // Denormals are back once the guard is gone.
        assert!(std::hint::black_box(tiny) / std::hint::black_box(4.0f32) > 0.0);
    }
}
