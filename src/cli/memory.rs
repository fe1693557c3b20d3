//! The allocator's settings for the tools' processes (never for a library's host, such as the
//! Python interpreter that loads the extension).
//!
//! glibc's malloc serves a large request with its own `mmap` (from 128 KiB, a threshold that it
//! raises, up to 32 MiB, as such blocks are freed) and unmaps it again on `free`, and it hands
//! the top of its heap back to the system beyond a threshold. A solve allocates and frees
//! blocks of the problem's size phase after phase (the chordal start's factor, L's, Newton's,
//! the certificate's, the text of the output), and every fresh page costs a page fault at its
//! first write, about 3 µs on the virtual machines measured (0.8 ms per MB, against 0.03 ms per
//! MB to write it again). Keeping blocks up to [`KEEP`] in the heap lets later phases reuse the
//! pages that earlier ones mapped; larger blocks (10⁶ poses) are still mapped and unmapped on
//! their own, so the peak memory does not grow by what the heap would keep of them.
//!
//! The free top of the heap is kept up to [`TRIM`]: at 10⁶ poses each Newton step's vectors
//! (the gradient, its coordinates, the trial point, the positions' right-hand side: 8 to 32 MB
//! each) lie at the top of the heap, and with the top trimmed at 32 MiB every step mapped them
//! afresh. With 256 MiB the solve's page faults fell from 1.76 to 1.59 million (10%), for 12 MB
//! more peak memory (2894 to 2906 MiB). Without mmap at all (every block in the heap) they fell
//! to 1.30 million, but the heap's holes took the peak to 3.7 GiB.

/// The largest block that stays in the heap after it is freed: glibc's largest mmap threshold
/// (`mallopt` refuses more).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const KEEP: libc::c_int = 32 << 20;

/// The free top of the heap that stays mapped for later blocks.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM: libc::c_int = 256 << 20;

/// Applies the settings (glibc on Linux; elsewhere nothing). Called once, first thing in a
/// tool's process, before any allocation that these settings should cover.
pub fn tune() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt sets two of malloc's parameters under malloc's own lock; it reads and
    // writes no memory of ours. A refusal (return value 0) leaves glibc's defaults: correct,
    // only slower.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, KEEP);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM);
    }
}
