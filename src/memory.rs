//! The memory budget: work whose estimated memory exceeds what this machine has free is refused
//! before anything is allocated, with the estimate (a usage error, exit code 2), instead of
//! failing halfway through an allocation.

use crate::error::{Error, Result};

/// Bytes one ray costs while its batch is traced: the SoA columns (origin, direction, interval,
/// time: 9 f32), its pixel id and packet flag, and its answer (a hit: 16 bytes), rounded up.
pub const BYTES_PER_RAY: u64 = 64;

/// Ray batches a run or render holds at once: camera rays and their hits, and the secondary
/// batch being built from them.
pub const BATCHES_HELD: u64 = 4;

/// Bytes of memory available to this process: `MemAvailable` of /proc/meminfo, or `None` where
/// it cannot be read (then nothing is refused).
pub fn available() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib = info
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse::<u64>()
        .ok()?;
    Some(kib * 1024)
}

/// The estimated memory of tracing `rays` rays per batch.
pub fn for_rays(rays: u64) -> u64 {
    rays.saturating_mul(BYTES_PER_RAY * BATCHES_HELD)
}

/// Refuses `what` when its estimated `bytes` exceed the memory available.
pub fn check(what: &str, bytes: u64) -> Result<()> {
    check_against(what, bytes, available())
}

fn check_against(what: &str, bytes: u64, available: Option<u64>) -> Result<()> {
    match available {
        Some(free) if bytes > free => Err(Error::usage(format!(
            "{what} needs an estimated {} of memory; this machine has {} available",
            gib(bytes),
            gib(free)
        ))),
        _ => Ok(()),
    }
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_above_the_free_memory_is_refused_with_the_estimate() {
        let rays = 1_000_000u64 * 1_000_000;
        let e =
            check_against("a 1000000×1000000 image", for_rays(rays), Some(24 << 30)).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let message = e.to_string();
        assert!(message.contains("238418579.1 GiB"), "{message}");
        assert!(message.contains("24.0 GiB available"), "{message}");
        assert!(check_against("small", for_rays(1 << 20), Some(24 << 30)).is_ok());
        assert!(check_against("unknown", u64::MAX, None).is_ok());
        assert!(available().is_some_and(|b| b > 0));
    }
}
