//! The allocator's memory between the phases of a solve: free pages given back to the system
//! ([`release_free_memory`], [`release_for`]), a factor's room mapped ahead ([`Room`]), and the
//! top of the heap mapped ahead by the second core while a tool reads its input
//! ([`map_top_ahead`]).
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
    // What is left to map ahead would map again what is given back here.
    crate::linalg::parallel::drop_background();
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

/// The most bytes [`map_top_ahead`] maps: half the tools' mmap threshold (`cli::memory`), so
/// that its block comes from the heap and stays there once freed.
pub const TOP_AHEAD_MAX: usize = 16 << 20;

/// Bytes mapped per background task of [`map_top_ahead`]: 32 pages, about 40 µs, the longest
/// that a job given to the second core meanwhile waits.
const TOP_CHUNK: usize = 32 * 4096;

/// Maps the next `bytes` (at most [`TOP_AHEAD_MAX`]) of the allocator's heap on the second core
/// in the background ([`crate::linalg::parallel::in_background`]), for this thread to allocate
/// and write later: every fresh page costs a page fault at its first write (about 1.2 µs here,
/// 1.0 µs mapped by `madvise(MADV_POPULATE_WRITE)`), and a tool's second core is idle while its
/// first thread reads the input. A block of `bytes` is allocated and freed at once: it becomes
/// the free top of malloc's heap, which the tools keep mapped (`cli::memory`) and from which
/// this thread's next blocks are carved, from its start up, while the second core maps it from
/// its end down, chunk by chunk. Mapping writes nothing: a page it maps is the zero page a
/// first write would fault in, and a page mapped already is left as it is, so this thread may
/// allocate and write there meanwhile. For the tools' processes, whose allocator settings keep
/// the block in the heap: in a library's host it may be a mapping of its own, unmapped when
/// freed, and the range then maps nothing, or the pages of whatever is mapped there next
/// (writing nothing either way). Linux with glibc (the system call from 5.14: older kernels
/// refuse it and nothing is mapped); elsewhere, or on one core, nothing.
pub fn map_top_ahead(bytes: usize) {
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = bytes;
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let bytes = bytes.min(TOP_AHEAD_MAX);
        if bytes == 0 || !crate::linalg::parallel::second_core() {
            return;
        }
        // SAFETY: a block allocated and freed at once; only its address is kept, to map pages
        // there without reading or writing them.
        let start = unsafe {
            let block = libc::malloc(bytes);
            if block.is_null() {
                return;
            }
            libc::free(block);
            block as usize
        };
        let chunks = bytes.div_ceil(TOP_CHUNK);
        crate::linalg::parallel::in_background((0..chunks).rev().map(move |c| {
            let from = start + c * TOP_CHUNK;
            let to = (from + TOP_CHUNK).min(start + bytes);
            Box::new(move || populate(from, to)) as Box<dyn FnOnce() + Send>
        }));
    }
}

/// Maps the whole pages of the address range [from, to) for writing without writing them
/// (`MADV_POPULATE_WRITE`); pages mapped already stay as they are. A refusal (an old kernel, a
/// range not mapped) maps nothing.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn populate(from: usize, to: usize) {
    const PAGE: usize = 4096;
    let (first, end) = (from.next_multiple_of(PAGE), to / PAGE * PAGE);
    if end > first {
        // SAFETY: madvise changes no memory contents: it faults in pages of the calling
        // process's own mappings (private anonymous ones here: zero pages) as a first write
        // would, and fails without effect where there is no mapping.
        unsafe {
            libc::madvise(
                first as *mut libc::c_void,
                end - first,
                libc::MADV_POPULATE_WRITE,
            );
        }
    }
}

/// Room for a factor's values (see `SparseFactor::reuse`) whose pages two threads map together:
/// the second core allocates it ([`Room::prepare`]) and maps its pages chunk by chunk
/// ([`Room::map`]); the thread that factors takes it when its first factorization comes
/// ([`Room::take`]), mapping the chunks still unclaimed itself, so that it waits for one chunk
/// at most instead of the whole room; while it waits for the factor's analysis it maps the room
/// as soon as that sizes it ([`Room::map_once_prepared`]). A page's first write costs a page
/// fault (about 1 µs here); a first factorization that faults its own pages pays them on the
/// thread that factors (torus3D's first Newton LLᵀ took 43 ms on fresh pages, the second one
/// 30 ms). Where the thread that factors comes first (one core, or a second core still busy
/// before the room), it takes nothing and the room is never made.
pub struct Room {
    state: std::sync::Mutex<RoomState>,
    /// Signalled when the state leaves `Waiting` ([`Room::map_once_prepared`]).
    settled: std::sync::Condvar,
    /// The next chunk to claim.
    next: std::sync::atomic::AtomicUsize,
    /// The chunks mapped.
    done: std::sync::atomic::AtomicUsize,
}

enum RoomState {
    Waiting,
    /// Allocated, not yet taken.
    Ready(Vec<f64>),
    Taken,
}

/// Bytes mapped per claim of [`Room::map`]: 64 pages, about 80 µs of page faults.
const CHUNK: usize = 64 * 4096;

/// The number of [`CHUNK`]s of a room of `len` values.
fn chunks(len: usize) -> usize {
    (len * std::mem::size_of::<f64>()).div_ceil(CHUNK)
}

impl Default for Room {
    fn default() -> Self {
        Self::new()
    }
}

impl Room {
    pub fn new() -> Self {
        Room {
            state: std::sync::Mutex::new(RoomState::Waiting),
            settled: std::sync::Condvar::new(),
            next: Default::default(),
            done: Default::default(),
        }
    }

    fn state(&self) -> std::sync::MutexGuard<'_, RoomState> {
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Allocates room for `len` values (unmapped: zeroed memory from the system), unless it was
    /// taken already.
    pub fn prepare(&self, len: usize) {
        let mut state = self.state();
        if let RoomState::Waiting = *state {
            *state = RoomState::Ready(vec![0.0f64; len]);
            self.settled.notify_all();
        }
    }

    /// Maps the pages of the chunks not yet claimed, one claim at a time.
    pub fn map(&self) {
        let (first, len) = match &mut *self.state() {
            RoomState::Ready(values) => (values.as_mut_ptr() as usize, values.len()),
            _ => return,
        };
        let (count, bytes) = (chunks(len), len * std::mem::size_of::<f64>());
        use std::sync::atomic::Ordering;
        loop {
            let c = self.next.fetch_add(1, Ordering::AcqRel);
            if c >= count {
                return;
            }
            let end = ((c + 1) * CHUNK).min(bytes);
            let mut at = c * CHUNK;
            while at < end {
                // SAFETY: `first + at` is inside the values (at < their size in bytes, a
                // multiple of 8 apart from `first`), which stay allocated, unmoved and unread
                // while chunks are claimed (the state holds them until `take`, which waits for
                // every claimed chunk); each chunk is claimed by one thread only. A zero is
                // written where a zero is: the page is mapped, the values unchanged.
                unsafe {
                    std::ptr::write_volatile((first + at) as *mut f64, 0.0);
                }
                at += 4096;
            }
            self.done.fetch_add(1, Ordering::AcqRel);
            // A pause for a factorization's side on offer (a chunk takes about 0.1 ms).
            crate::linalg::parallel::take_offer();
        }
    }

    /// The room, its unclaimed chunks mapped here and the claimed ones waited for; an empty
    /// vector where none was prepared (and then none will be).
    pub fn take(&self) -> Vec<f64> {
        let count = {
            let mut state = self.state();
            match &*state {
                RoomState::Ready(values) => chunks(values.len()),
                _ => {
                    *state = RoomState::Taken;
                    return Vec::new();
                }
            }
        };
        self.map();
        while self.done.load(std::sync::atomic::Ordering::Acquire) < count {
            std::thread::yield_now();
        }
        match std::mem::replace(&mut *self.state(), RoomState::Taken) {
            RoomState::Ready(values) => values,
            _ => Vec::new(),
        }
    }

    /// Takes nothing: a room not prepared yet never will be.
    pub fn forgo(&self) {
        let mut state = self.state();
        if let RoomState::Waiting = *state {
            *state = RoomState::Taken;
            self.settled.notify_all();
        }
    }

    /// A guard that forgoes the room when dropped, also while unwinding, unless it was prepared
    /// by then: for the thread that prepares it, so that [`Room::map_once_prepared`] never
    /// waits for ever.
    pub fn settled_on_drop(&self) -> SettledOnDrop<'_> {
        SettledOnDrop(self)
    }

    /// Waits until the room is prepared (or forgone), then maps its chunks not yet claimed
    /// ([`Room::map`]): for the thread that factors, while it waits for the factor's analysis,
    /// which prepares the room as soon as it knows the values' count. The analysis must prepare
    /// or forgo the room whatever happens (else this waits for ever).
    pub fn map_once_prepared(&self) {
        let mut state = self.state();
        while let RoomState::Waiting = *state {
            state = self
                .settled
                .wait(state)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
        }
        drop(state);
        self.map();
    }
}

/// Forgoes a [`Room`] not prepared when dropped ([`Room::settled_on_drop`]).
pub struct SettledOnDrop<'a>(&'a Room);

impl Drop for SettledOnDrop<'_> {
    fn drop(&mut self) {
        self.0.forgo();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mapping pages ahead writes nothing: values written before stay (pages mapped already),
    /// fresh memory stays zero (pages mapped by it), over ranges that start and end inside
    /// pages; and values written by another thread while the same pages are mapped, chunk by
    /// chunk from the end down as [`map_top_ahead`] maps them, are all there after.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn mapping_ahead_writes_nothing() {
        let value = |k: usize| (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let written: Vec<u64> = (0..300_000).map(value).collect();
        let fresh = vec![0u64; 300_000];
        for values in [&written, &fresh] {
            let from = values.as_ptr() as usize;
            let to = from + values.len() * 8;
            populate(from + 100, to - 100);
            populate(from, to);
        }
        assert!(fresh.iter().all(|&v| v == 0));
        assert!(written.iter().enumerate().all(|(k, &v)| v == value(k)));
        for _ in 0..4 {
            let mut raced = vec![0u64; 1 << 20];
            let (from, bytes) = (raced.as_ptr() as usize, raced.len() * 8);
            std::thread::scope(|scope| {
                scope.spawn(|| {
                    for (k, v) in raced.iter_mut().enumerate() {
                        *v = value(k);
                    }
                });
                for c in (0..bytes.div_ceil(TOP_CHUNK)).rev() {
                    let at = from + c * TOP_CHUNK;
                    populate(at, (at + TOP_CHUNK).min(from + bytes));
                }
            });
            assert!(raced.iter().enumerate().all(|(k, &v)| v == value(k)));
        }
    }

    /// The room's values (zeros) come back whole whichever thread maps which chunks; a room
    /// taken or forgone before it is prepared stays empty.
    #[test]
    fn a_room_is_taken_whole_or_not_at_all() {
        for len in [0, 1, 511, 512, 100_000, 1 << 20] {
            let room = Room::new();
            std::thread::scope(|scope| {
                room.prepare(len);
                scope.spawn(|| room.map());
                let values = room.take();
                assert_eq!(values.len(), len);
                assert!(values.iter().all(|&v| v == 0.0));
            });
        }
        let room = Room::new();
        assert!(room.take().is_empty());
        room.prepare(1000);
        room.map();
        assert!(room.take().is_empty());
        let room = Room::new();
        room.forgo();
        room.prepare(1000);
        assert!(room.take().is_empty());
    }

    /// A thread that waits to map a room maps every chunk once another thread prepares it, and
    /// stops waiting where the room is forgone instead, also by a preparer that panics before
    /// preparing it (its guard).
    #[test]
    fn a_room_is_mapped_once_prepared_and_never_waited_for_in_vain() {
        let len = 100_000;
        let room = Room::new();
        std::thread::scope(|scope| {
            scope.spawn(|| {
                std::thread::sleep(std::time::Duration::from_millis(20));
                let _settled = room.settled_on_drop();
                room.prepare(len);
            });
            room.map_once_prepared();
            use std::sync::atomic::Ordering;
            assert_eq!(room.done.load(Ordering::Acquire), chunks(len));
        });
        let values = room.take();
        assert_eq!(values.len(), len);
        assert!(values.iter().all(|&v| v == 0.0));
        let room = Room::new();
        std::thread::scope(|scope| {
            let preparer = scope.spawn(|| {
                let _settled = room.settled_on_drop();
                std::thread::sleep(std::time::Duration::from_millis(20));
                panic!("the analysis failed before the room");
            });
            room.map_once_prepared();
            assert!(preparer.join().is_err());
        });
        assert!(room.take().is_empty());
    }
}
