//! Buffers placed against a protected page, for the tests of every call raylab makes into a C or
//! C++ library (Embree 3 and 4, tinybvh, Embree's BVH builder): a buffer that ends exactly where
//! a `PROT_NONE` page begins (or begins exactly where one ends) turns a library's read or write
//! past it into a fault in the test, where a heap or stack buffer would let it pass unnoticed and
//! corrupt a user's run.
//!
//! A fault kills the test process; the handler installed here first prints which guarded call
//! was running, so the failure names the entry point, ISA and placement. Guarded calls are
//! serialised (`Guarded::call`) so that name is the right one.

use std::ffi::c_void;
use std::marker::PhantomData;
use std::mem::ManuallyDrop;
use std::ptr::{self, NonNull};
use std::sync::atomic::{AtomicPtr, Ordering};
use std::sync::{Mutex, Once, PoisonError};

/// Where the buffer sits against its guard page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// The last byte of the buffer is the last byte before a protected page.
    EndsAtGuard,
    /// The first byte of the buffer is the first byte after a protected page.
    StartsAfterGuard,
}

impl Placement {
    pub const BOTH: [Placement; 2] = [Placement::EndsAtGuard, Placement::StartsAfterGuard];
}

/// `len` values of `T` in their own mapping, flush against a protected page on the side
/// `placement` names (and the mapping's other end protected too).
pub struct Guarded<T> {
    map: NonNull<c_void>,
    map_len: usize,
    data: NonNull<T>,
    len: usize,
    _owns: PhantomData<T>,
}

fn page_size() -> usize {
    // SAFETY: sysconf with a valid name.
    unsafe { libc::sysconf(libc::_SC_PAGESIZE) as usize }
}

impl<T> Guarded<T> {
    /// `values` moved into place as `placement` says (they are plain C records: never dropped).
    /// Panics if `T`'s alignment does not allow the placement (the buffer's size must be a
    /// multiple of it to end at a page).
    pub fn new(values: Vec<T>, placement: Placement) -> Self {
        let page = page_size();
        let bytes = std::mem::size_of_val(values.as_slice());
        let pages = bytes.div_ceil(page).max(1);
        // A guard page before and after the data pages.
        let map_len = (pages + 2) * page;
        // SAFETY: an anonymous private mapping; checked for failure below.
        let map = unsafe {
            libc::mmap(
                ptr::null_mut(),
                map_len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        assert_ne!(map, libc::MAP_FAILED, "mmap of {map_len} bytes");
        let base = map.cast::<u8>();
        // SAFETY: both guard pages lie inside the mapping.
        unsafe {
            assert_eq!(libc::mprotect(base.cast(), page, libc::PROT_NONE), 0);
            assert_eq!(
                libc::mprotect(base.add((pages + 1) * page).cast(), page, libc::PROT_NONE),
                0
            );
        }
        let start = match placement {
            Placement::StartsAfterGuard => page,
            Placement::EndsAtGuard => (pages + 1) * page - bytes,
        };
        // SAFETY: `start .. start + bytes` lies in the accessible pages.
        let data = unsafe { base.add(start) }.cast::<T>();
        assert!(
            data.is_aligned(),
            "{bytes} bytes of {} cannot end at a page aligned",
            std::any::type_name::<T>()
        );
        let len = values.len();
        let mut values = ManuallyDrop::new(values);
        // SAFETY: room for `len` aligned values, not overlapping `values`, whose elements are
        // moved (the Vec's buffer is freed below without dropping them).
        unsafe {
            ptr::copy_nonoverlapping(values.as_ptr(), data, len);
            values.set_len(0);
            ManuallyDrop::drop(&mut values);
        }
        Guarded {
            map: NonNull::new(map).expect("mmap returned null"),
            map_len,
            data: NonNull::new(data).expect("inside a mapping"),
            len,
            _owns: PhantomData,
        }
    }

    pub fn as_mut_slice(&mut self) -> &mut [T] {
        // SAFETY: `len` initialised values owned by `self`.
        unsafe { std::slice::from_raw_parts_mut(self.data.as_ptr(), self.len) }
    }

    pub fn as_mut_ptr(&mut self) -> *mut T {
        self.data.as_ptr()
    }
}

/// Runs `f` as the guarded call named `what`: one at a time in the process, and a fault
/// inside it prints `what` before the process dies.
pub fn call<R>(what: &str, f: impl FnOnce() -> R) -> R {
    static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(PoisonError::into_inner);
    install_handler();
    let name = Box::into_raw(Box::new(format!(
        "\nguard page hit: a library read or wrote past the buffer during {what}\n"
    )));
    let previous = CURRENT.swap(name, Ordering::SeqCst);
    let result = f();
    CURRENT.store(previous, Ordering::SeqCst);
    // SAFETY: made by Box::into_raw above and no longer reachable from CURRENT.
    drop(unsafe { Box::from_raw(name) });
    result
}

impl<T> Drop for Guarded<T> {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `new`, unmapped once.
        unsafe { libc::munmap(self.map.as_ptr(), self.map_len) };
    }
}

/// The message of the guarded call running now (null outside one).
static CURRENT: AtomicPtr<String> = AtomicPtr::new(ptr::null_mut());

fn install_handler() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // SAFETY: a plain sigaction for SIGSEGV and SIGBUS with a handler that only calls
        // async-signal-safe functions (write, signal, raise).
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_fault as *const () as usize;
            action.sa_flags = libc::SA_RESETHAND;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(libc::SIGSEGV, &action, ptr::null_mut());
            libc::sigaction(libc::SIGBUS, &action, ptr::null_mut());
        }
    });
}

extern "C" fn on_fault(signal: libc::c_int) {
    let message = CURRENT.load(Ordering::SeqCst);
    if !message.is_null() {
        // SAFETY: CURRENT holds a live String while its guarded call runs; write is
        // async-signal-safe.
        unsafe {
            let text = &*message;
            libc::write(2, text.as_ptr().cast(), text.len());
        }
    }
    // SA_RESETHAND restored the default action: raising again ends the process with the signal.
    // SAFETY: raise is async-signal-safe.
    unsafe { libc::raise(signal) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_buffer_is_flush_against_its_guard_page() {
        let page = page_size();
        for placement in Placement::BOTH {
            let mut g = Guarded::new(vec![7u32; 5], placement);
            assert_eq!(g.as_mut_slice(), &[7; 5]);
            let address = g.as_mut_ptr() as usize;
            match placement {
                Placement::EndsAtGuard => assert_eq!((address + 20) % page, 0),
                Placement::StartsAfterGuard => assert_eq!(address % page, 0),
            }
        }
    }
}
