//! A hint to the CPU to start loading an element it will read soon — the one place trompe
//! uses `unsafe`: the crate says `#![deny(unsafe_code)]` rather than `forbid` so that this module
//! alone may, because the fresh build's benchmark showed the hint pays (`docs/performance.md`).
//!
//! Why: an impostor build resolves each covered texel from its triangle (the mesh's vertex
//! indices, then the corners' positions and normals, then its material). Neighbouring texels
//! show unrelated triangles, and the rasterization just before has moved the mesh out of the
//! core's cache, so each texel waits twice on memory in a row. Reading the data ahead in safe
//! Rust does not help: a load that misses blocks the instructions after it from completing, and
//! the CPU soon stalls as before. A prefetch instruction completes at once and lets the load run
//! while the CPU works on the texels before it. On the bunny's 512² SPOC build, one thread, it
//! took the build from 1.61 – 1.65 × its bench peer to 1.49 – 1.51 ×.
//!
//! Invariants: a prefetch never changes a result (it reads nothing the program sees, and never
//! faults); an index outside the slice prefetches nothing; on CPUs other than x86-64 it does
//! nothing.

/// Asks the CPU to bring `items[index]` into its nearest cache; nothing when `index` is out of
/// range.
#[inline(always)]
pub(crate) fn prefetch<T>(items: &[T], index: usize) {
    if let Some(item) = items.get(index) {
        prefetch_element(item);
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(unsafe_code)]
fn prefetch_element<T>(item: &T) {
    use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
    let address = (item as *const T).cast::<i8>();
    // SAFETY: `_mm_prefetch` is an SSE instruction, and SSE is part of every x86-64 CPU (the
    // target's baseline), so the instruction exists. It is only a hint: it does not read memory
    // the program observes, cannot fault, and `address` comes from a live reference anyway.
    unsafe { _mm_prefetch::<_MM_HINT_T0>(address) }
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn prefetch_element<T>(_: &T) {}

#[cfg(test)]
mod tests {
    use super::prefetch;

    #[test]
    fn prefetch_is_harmless_in_and_out_of_range() {
        let v = vec![1u64, 2, 3];
        prefetch(&v, 0);
        prefetch(&v, 2);
        prefetch(&v, 3);
        prefetch(&v, usize::MAX);
        prefetch::<u8>(&[], 0);
        assert_eq!(v, [1, 2, 3]);
    }
}
