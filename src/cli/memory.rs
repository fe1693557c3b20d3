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

/// Heap bytes mapped ahead per byte of the input ([`map_heap_ahead`]). The first thread of a solve
/// writes fresh heap pages of 6 to 10 times its input's size on the planar files (MIT 6.3, M3500
/// 6.7, city10000 9.5), 9 to 13 times on the 3D ones (smallGrid3D 9.1, sphere_bignoise_vertex3
/// 12.9).
const AHEAD_PER_INPUT_BYTE: u64 = 8;

/// The smallest input whose heap [`map_heap_ahead`] maps: below, graphs of a few hundred edges
/// at most, solved in a few milliseconds, where the mapping gains nothing. The same code mapping
/// from 64 KiB against from 128 KiB (15 interleaved pairs): 125-pose generated 3D worlds of
/// 89-91 KB 1.00 (median of 18 files, 0.98-1.03), smallGrid3D (101 KB) 1.01, MIT (121 KB)
/// 1.00, CSAIL (128 KB) 0.99. Against the binary before the mapping, the 400-pose worlds
/// (290-330 KB) take 0.99 of their time and the 1000-pose ones (about 750 KB) 0.98 (medians of
/// 18 files, 7 pairs each; the same bytes out).
const AHEAD_FROM_BYTES: u64 = 128 << 10;

/// The largest input whose heap [`map_heap_ahead`] maps. Above it the most that is mapped
/// ([`crate::linalg::heap::TOP_AHEAD_MAX`]) is a small share of the solve's memory, whose
/// large blocks are mapped on their own, and it may stay unused: at 10⁶ poses (233 MB) the peak
/// grew from 1899-1907 MiB to 1898-1936 MiB (three runs each), the time the same within the
/// spread (12.5-12.9 s against 12.7-13.2 s); at 10⁵ poses (23 MB) 0.98 of the time (11
/// interleaved pairs), the peak 4 MiB higher.
const AHEAD_UP_TO_BYTES: u64 = 32 << 20;

/// Has the second core map the heap pages that the solve will write first
/// ([`crate::linalg::heap::map_top_ahead`]), [`AHEAD_PER_INPUT_BYTE`] per byte of the input
/// file, while this thread reads it: the pages' faults leave the first thread's path. An input
/// read from stdin, smaller than [`AHEAD_FROM_BYTES`] or larger than [`AHEAD_UP_TO_BYTES`],
/// maps nothing. Whole process, against no mapping ahead (21 to 31 interleaved pairs): kitti_08
/// 0.91, city10000 0.94, M3500c 0.97, parking-garage, ais2klinik, kitti_00, manhattan and
/// torus3D 0.98, M3500, sphere2500 and sphere_bignoise_vertex3 0.98-0.99, cubicle, MIT, CSAIL
/// and smallGrid3D 0.99, intel 1.01 (the same bytes out on the 46 public files). A new binary's
/// layout alone moves a small solve by a few percent (the 125-pose worlds, mapped nothing,
/// 1.02 against the binary before): MIT, CSAIL and smallGrid3D, below [`AHEAD_FROM_BYTES`]
/// now, gained nothing measurable from the mapping itself. Mapping 4
/// bytes per byte of input gained as much on the planar files and nothing on the 3D ones; 12
/// and 16 lost 2-6% on kitti_00 and city10000 (the pages beyond the solve's own are mapped
/// first); the second core's own heap mapped ahead as well delayed its first tasks (M3500
/// 1.01).
pub fn map_heap_ahead(input: &str) {
    if input == "-" {
        return;
    }
    let Ok(meta) = std::fs::metadata(input) else {
        return;
    };
    if meta.is_file() && (AHEAD_FROM_BYTES..=AHEAD_UP_TO_BYTES).contains(&meta.len()) {
        let bytes = meta.len().saturating_mul(AHEAD_PER_INPUT_BYTE);
        crate::linalg::heap::map_top_ahead(usize::try_from(bytes).unwrap_or(usize::MAX));
    }
}

/// The peak resident memory (KiB) from which [`release_beside`] gives the free pages back. Below
/// it the second core's wake-up and the trim's locks cost more than the exit saves: MIT (8.4 MiB
/// peak, 2.3 MB free in the heaps) 1.015x slower whole process, intel (12 MiB) 0.99.
const RELEASE_FROM_KIB: i64 = 16 << 10;

/// `work()` (the output's writing) on this thread while the second core gives the allocator's
/// free pages back to the system ([`crate::linalg::heap::release_free_memory`]), where the
/// process's peak resident memory reached [`RELEASE_FROM_KIB`]. The blocks kept for reuse
/// ([`tune`]) are free once the solve returns; left to the process's exit they are unmapped
/// after the output is written, on the path to the tool's end: cityTrees10000 holds 27 MB free
/// there, and its last thread ended 2.9 ms after `exit_group`. Given back beside the write,
/// whole process against the exit's unmapping (41 interleaved pairs): cityTrees10000 0.97,
/// city10000 0.98, M3500 0.93, manhattan 0.97, victoriaPark 0.99, ais2klinik 1.01.
pub fn release_beside<R>(work: impl FnOnce() -> R) -> R {
    // The peak first: one system call, where the cores' count may read the cgroup's files.
    if peak_resident_kib() < RELEASE_FROM_KIB || !crate::linalg::parallel::second_core() {
        return work();
    }
    crate::linalg::parallel::join(work, crate::linalg::heap::release_free_memory).0
}

/// The process's peak resident memory in KiB (Linux's `ru_maxrss`); 0 where unknown.
fn peak_resident_kib() -> i64 {
    #[cfg(target_os = "linux")]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage writes the struct it is given, which is zeroed and large enough.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } == 0 {
            // SAFETY: initialized by the successful call (zeroed before it in any case).
            return unsafe { usage.assume_init() }.ru_maxrss;
        }
    }
    0
}
