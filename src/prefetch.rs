//! A cache hint for the hot loops that read scattered memory (tree nodes, voxel classes,
//! per-triangle lists): ask for the data a few steps before it is read.

/// Asks the CPU to bring the byte at `byte` into the cache (a hint: no effect on the result,
/// nothing read, whatever the address; nothing on targets without the instruction).
#[inline(always)]
pub(crate) fn prefetch(byte: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, whatever the address, and reads nothing the program
    // sees; SSE is part of the x86_64 baseline.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(byte.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = byte;
}
