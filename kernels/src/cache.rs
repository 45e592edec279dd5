//! The L2 cache's size, which sets how much of a packed operand one block of tiles may use.
//! Blocking changes only the order in which tiles are computed, never a tile's arithmetic, so
//! machines with different caches still compute the same bits.

use std::sync::atomic::{AtomicUsize, Ordering};

/// What we assume when the CPU does not say: the smallest L2 of the machines we run on.
const FALLBACK: usize = 512 * 1024;

static L2: AtomicUsize = AtomicUsize::new(0);

/// Bytes of this core's L2 cache (CPUID leaf 0x8000_0006, which Intel and AMD both fill in).
pub(crate) fn l2_bytes() -> usize {
    match L2.load(Ordering::Relaxed) {
        0 => {
            let bytes = detect().filter(|&b| b >= 64 * 1024).unwrap_or(FALLBACK);
            L2.store(bytes, Ordering::Relaxed);
            bytes
        }
        bytes => bytes,
    }
}

#[cfg(target_arch = "x86_64")]
fn detect() -> Option<usize> {
    use std::arch::x86_64::__cpuid;
    // CPUID exists on every x86-64 CPU; the extended leaf is read only if offered.
    if __cpuid(0x8000_0000).eax < 0x8000_0006 {
        return None;
    }
    let kib = __cpuid(0x8000_0006).ecx >> 16;
    Some(kib as usize * 1024)
}

#[cfg(not(target_arch = "x86_64"))]
fn detect() -> Option<usize> {
    None
}
