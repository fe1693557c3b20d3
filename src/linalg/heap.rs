//! Giving the allocator's free memory back to the system between the phases of a large solve.
//!
//! A Newton step at 10⁶ poses allocates and frees vectors of 8 to 31 MB (the trial point, the
//! gradient and its coordinates, the positions' right-hand side); glibc's malloc keeps such
//! blocks in its heaps (the tools raise its mmap threshold to 32 MiB, `cli::memory`), where the
//! holes they leave grew the resident memory by some 15 MiB a step while the live memory stayed
//! the same, and the second core's arenas kept about 100 MiB of the setup's freed blocks.
//! [`release_free_memory`] returns the free pages of every arena (`malloc_trim`: whole free pages
//! inside the heaps, `madvise`d away, as well as their tops); [`release_for`] does so for
//! systems of [`RELEASE_FROM_ROWS`] rows and more only.

/// Returns the allocator's free pages to the system (glibc on Linux; elsewhere nothing). The
/// memory stays the allocator's: a later block placed there takes fresh pages (a page fault at
/// each first write).
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim works under malloc's own locks on its own free chunks; it reads and
    // writes no memory of ours.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// The rows of a linear system from which [`release_for`] gives the free memory back. Below it
/// the re-faulted pages cost more than the memory is worth: before each Newton factorization,
/// CPU time +7% on victoriaPark, +4% on city10000, +2% on M3500 (medians of 11 interleaved
/// runs); at 10⁶ planar poses (3·10⁶ Newton rows) the peak fell by 90 MiB at no cost in time.
pub const RELEASE_FROM_ROWS: usize = 1 << 20;

/// [`release_free_memory`] where a system has at least [`RELEASE_FROM_ROWS`] rows.
pub fn release_for(rows: usize) {
    if rows >= RELEASE_FROM_ROWS {
        release_free_memory();
    }
}
