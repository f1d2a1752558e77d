//! A cache hint for data-dependent walks over big arrays (light BVH refits).

/// Asks the CPU to start loading `items[i]` (every cache line of it) into the cache: a hint,
/// nothing on targets other than x86-64.
#[inline(always)]
pub(crate) fn prefetch<T>(items: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(item) = items.get(i) {
        let start = (item as *const T).cast::<i8>();
        for line in (0..std::mem::size_of::<T>()).step_by(64) {
            // SAFETY: the address lies within a live element, and a prefetch never faults.
            unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(start.add(line)) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, i);
}
