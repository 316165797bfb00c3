//! Memory that readers fill: advice to the system on how to back it.

/// Asks the system to back `v`'s reserved memory with transparent huge pages (Linux's
/// `madvise(MADV_HUGEPAGE)` on the 2 MiB-aligned part of a reservation of 4 MiB or more; a
/// system set to `madvise` gives them only so asked). Filling a gigabyte of fresh 4 KiB pages
/// costs a fault every 4 KiB, which on these machines took longer than reading the file
/// (docs/SCALING.md, "Reading another solver's matrices"). Only advice: the memory, its
/// contents and what is resident (pages are still made as they are touched) are unchanged, and
/// a refusal is ignored.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
pub(crate) fn huge_pages<T>(v: &Vec<T>) {
    const HUGE: usize = 2 << 20;
    let bytes = v.capacity() * std::mem::size_of::<T>();
    if bytes < 2 * HUGE {
        return;
    }
    let p = v.as_ptr() as usize;
    let start = p.div_ceil(HUGE) * HUGE;
    let end = (p + bytes) / HUGE * HUGE;
    if end > start {
        // SAFETY: [start, end) lies within `v`'s own allocation (its capacity), and
        // MADV_HUGEPAGE changes only how the kernel backs those pages, not their contents or
        // their validity.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn huge_pages<T>(_: &Vec<T>) {}
