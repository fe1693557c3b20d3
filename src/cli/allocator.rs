//! The tools' global allocator: the C library's, with the two changes of glibc's tunables
//! `glibc.malloc.hugetlb=1` and `glibc.malloc.trim_threshold`, which a running process cannot
//! set for itself.
//!
//! - Memory is advised for transparent huge pages (`madvise(MADV_HUGEPAGE)`): every block of
//!   2 MiB and more (sparse factors, their workspaces, assembled matrices), and the heap as it
//!   grows, where the small blocks live. A first touch then takes one page fault per 2 MiB instead
//!   of one per 4 KiB. Kernels whose huge pages are `always` or `never` ignore the advice.
//! - Freed memory is kept instead of returned to the system at once (the trim threshold raised,
//!   the heap grown 64 MiB at a time), so a factor allocated after another one was freed reuses
//!   pages already mapped.
//!
//! A solve of city10000 took 22 000 page faults, at about 1 µs each in a virtual machine; with
//! this, 1 600, and 0.77x the whole-process time (0.74-0.94x on the public files; the peak memory
//! up to a huge page per large block higher). Elsewhere than Linux with glibc it is the system
//! allocator unchanged. Allocation never changes a result, only where memory comes from.

use std::alloc::{GlobalAlloc, Layout, System};

/// The system allocator with large blocks on transparent huge pages; see the module docs. Each
/// tool's binary installs it: `#[global_allocator] static A: Allocator = Allocator;`.
pub struct Allocator;

/// The size of a transparent huge page on x86-64 and most aarch64 kernels, and the smallest
/// block worth advising.
const HUGE_PAGE: usize = 2 << 20;

// SAFETY: every method forwards to `System` with the same arguments; the advice only sets a flag
// on pages of the block just returned (and of the huge page it starts in).
unsafe impl GlobalAlloc for Allocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        advise_heap();
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        advise_heap();
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if new_size > layout.size() {
            advise(p, new_size);
            advise_heap();
        }
        p
    }
}

/// Marks the block [p, p + size) for huge pages, from the start of the huge page it begins in
/// (glibc's `madvise_thp` does the same: the block's own first bytes are rarely aligned).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn advise(p: *mut u8, size: usize) {
    if p.is_null() || size < HUGE_PAGE {
        return;
    }
    let start = p as usize & !(HUGE_PAGE - 1);
    let end = p as usize + size;
    // Advice only: a kernel without huge pages refuses it, and nothing else changes.
    // SAFETY: madvise reads no memory; the range is the block and the part of its first huge
    // page before it, all mapped (glibc's chunk header or heap memory below the block).
    unsafe {
        libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
    }
}

/// Marks for huge pages what the heap grew by since the last call, as glibc does under its
/// tunable at every growth of the heap: small blocks live there.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn advise_heap() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    /// The end of the heap when last advised (0: not yet seen).
    static ADVISED: AtomicUsize = AtomicUsize::new(0);
    // SAFETY: sbrk(0) only reads the current end of the heap.
    let end = unsafe { libc::sbrk(0) } as usize;
    let done = ADVISED.load(Ordering::Relaxed);
    if end <= done
        || ADVISED
            .compare_exchange(done, end, Ordering::Relaxed, Ordering::Relaxed)
            .is_err()
    {
        return;
    }
    if done != 0 {
        let start = done & !(HUGE_PAGE - 1);
        // SAFETY: as in `advise`: [start, end) is heap memory, mapped.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn advise(_p: *mut u8, _size: usize) {}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn advise_heap() {}

/// Sets glibc's heap to keep freed memory (trim threshold 1 GiB) and to grow 64 MiB at a time;
/// the tools call it first thing. Elsewhere a no-op.
pub fn configure() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets parameters of the allocator; no allocation is in progress.
    unsafe {
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks on either side of the huge-page size hold what is written to them through a
    /// reallocation that grows them past it, and zeroed blocks read zero.
    #[test]
    fn blocks_hold_their_contents() {
        for size in [64, HUGE_PAGE - 8, HUGE_PAGE, 3 * HUGE_PAGE + 24] {
            let layout = Layout::from_size_align(size, 8).unwrap();
            unsafe {
                let zeroed = Allocator.alloc_zeroed(layout);
                assert!(!zeroed.is_null());
                assert!(
                    std::slice::from_raw_parts(zeroed, size)
                        .iter()
                        .all(|&b| b == 0)
                );
                Allocator.dealloc(zeroed, layout);

                let p = Allocator.alloc(layout);
                assert!(!p.is_null());
                for k in 0..size {
                    *p.add(k) = (k % 251) as u8;
                }
                let grown = 2 * size + HUGE_PAGE;
                let q = Allocator.realloc(p, layout, grown);
                assert!(!q.is_null());
                assert!((0..size).all(|k| *q.add(k) == (k % 251) as u8));
                *q.add(grown - 1) = 7;
                Allocator.dealloc(q, Layout::from_size_align(grown, 8).unwrap());
            }
        }
    }
}
