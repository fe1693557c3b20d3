//! Both cores, the same bits as one: independent computations side by side on a second thread
//! (the second core's, kept for the process), each computed exactly as it would be
//! alone, so that no result depends on the thread count.
//! Only whole tasks run in parallel (an analysis beside a descent, an ordering beside an
//! assembly, the two sides of a split factorization); no sum is split by the thread count: where
//! a task computes a partial sum ([`super::tree_factor`]), it is the same partial sum on one
//! core, computed there one task after the other.

use std::sync::OnceLock;

/// Whether the process has more than one CPU (its affinity and cgroup quota included), asked
/// once.
fn more_than_one_cpu() -> bool {
    static SECOND: OnceLock<bool> = OnceLock::new();
    *SECOND.get_or_init(|| std::thread::available_parallelism().is_ok_and(|c| c.get() > 1))
}

std::thread_local! {
    /// Whether this thread runs the tasks it gives itself ([`alone`]).
    static ALONE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether a second thread can run beside this one: more than one CPU available to the process,
/// and this thread not told to work [`alone`].
pub fn second_core() -> bool {
    !ALONE.with(std::cell::Cell::get) && more_than_one_cpu()
}

/// Graphs of fewer edges are solved on one thread ([`alone`]): their whole solve costs less than
/// handing work to the second core does (its thread's start, std's reading of the cgroup quota,
/// a wake-up per task). Whole process, alone against two cores: tinyGrid3D (11 edges) 0.90
/// (41 interleaved pairs); generated planar graphs of 21 and 38 edges 0.96-0.99; 3D worlds of
/// 53-111 edges the same time either way, within the spread; smallGrid3D (297 edges) takes
/// 0.9 of its one-core time with two.
pub const SHARED_FROM_EDGES: usize = 50;

/// `work()` for a graph of `terms` edges (and observations): [`alone`] below
/// [`SHARED_FROM_EDGES`], else as it is.
pub fn alone_if_small<R>(terms: usize, work: impl FnOnce() -> R) -> R {
    if terms < SHARED_FROM_EDGES {
        alone(work)
    } else {
        work()
    }
}

/// `work()` with every task it gives ([`join`], [`ahead`], [`halves`], [`when_idle`]) run on
/// this thread, as on one core: the same bits (module docs), none of the second core's costs.
/// For a computation too small to share ([`SHARED_FROM_EDGES`]).
pub fn alone<R>(work: impl FnOnce() -> R) -> R {
    /// Restores the thread's setting, also while unwinding.
    struct Restore(bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            ALONE.with(|a| a.set(self.0));
        }
    }
    let _restore = Restore(ALONE.with(|a| a.replace(true)));
    work()
}

/// The tasks that [`ahead`] is running on the second core now.
static AHEAD: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Whether a second core is there and not busy with work built [`ahead`]: where a computation
/// can split itself between two threads without a third one competing for the two cores. The
/// answer may change from call to call; a caller's results must not depend on it.
pub fn second_core_idle() -> bool {
    second_core() && AHEAD.load(std::sync::atomic::Ordering::Acquire) == 0
}

/// Counts a task in [`AHEAD`] while it lives.
struct Busy;

impl Busy {
    fn new() -> Self {
        AHEAD.fetch_add(1, std::sync::atomic::Ordering::AcqRel);
        Busy
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        AHEAD.fetch_sub(1, std::sync::atomic::Ordering::AcqRel);
    }
}

/// `(a(), b())`: `b` on a second thread when [`second_core`], else after `a` on this one. A panic
/// in `b` is resumed here.
pub fn join<RA, RB: Send>(a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> (RA, RB) {
    if !second_core() {
        let ra = a();
        return (ra, b());
    }
    beside(a, b)
}

/// `(a(), b())` with `b` on the second core's thread ([`Worker`]) where it is free, else on a
/// scoped thread of its own; `a` here. A panic in `b` is resumed here.
fn beside<RA, RB: Send>(a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> (RA, RB) {
    let Some(worker) = worker().filter(|w| w.claim()) else {
        return std::thread::scope(|scope| {
            let hb = scope.spawn(b);
            let ra = a();
            let rb = hb
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (ra, rb)
        });
    };
    let slot = std::sync::Mutex::new(None);
    let latch = std::sync::Arc::new(Latch::default());
    // Free before the caller hears of it, so that its next task finds the thread free.
    // SAFETY: this function does not return (nor unwind past `b`'s captures and `slot`) before
    // the job has run and opened the latch: `wait` below waits for it, also while `a` panics.
    let job = unsafe { erased_job(b, &slot, latch.clone(), || worker.release()) };
    worker.give(job);
    let wait = WaitOnDrop(&latch);
    let ra = a();
    drop(wait);
    (ra, take_result(&slot))
}

/// A job for another thread, its lifetime erased ([`erased_job`]).
type Job = Box<dyn FnOnce() + Send + 'static>;

/// The job that runs `b`, leaves its result (or its panic) in `slot`, calls `then` and opens
/// `latch` (shared: the thread that runs the job still holds it while it opens it), its
/// lifetime erased for another thread; `slot` is not touched after the latch opens.
///
/// # Safety
/// The job borrows `b`'s captures, `slot` and `then`'s: the caller keeps them alive until the
/// latch has opened, or the job has been dropped unrun.
unsafe fn erased_job<'a, RB: Send + 'a>(
    b: impl FnOnce() -> RB + Send + 'a,
    slot: &'a std::sync::Mutex<Option<std::thread::Result<RB>>>,
    latch: std::sync::Arc<Latch>,
    then: impl FnOnce() + Send + 'a,
) -> Job {
    let job: Box<dyn FnOnce() + Send + 'a> = Box::new(move || {
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(b));
        *lock(slot) = Some(result);
        then();
        latch.open();
    });
    // SAFETY: the caller's contract.
    unsafe {
        std::mem::transmute::<Box<dyn FnOnce() + Send + 'a>, Box<dyn FnOnce() + Send + 'static>>(
            job,
        )
    }
}

/// The result a job of [`erased_job`] left, its panic resumed.
fn take_result<RB>(slot: &std::sync::Mutex<Option<std::thread::Result<RB>>>) -> RB {
    lock(slot)
        .take()
        .expect("the job has run")
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

/// `(a(), b())` as [`join`], and where the second core is busy with work built [`ahead`], `b`
/// offered to it instead of waiting for it: that work takes the offer at its next pause
/// ([`take_offer`]) and runs `b` there, unless this thread, done with `a`, comes back for `b`
/// first and runs it itself. For the two sides of a split factorization that would otherwise run
/// one after the other here while the second core builds the certificate's analysis (torus3D's
/// first Newton LLᵀ: 49 ms on one core, 33 ms on two). Whichever thread runs `b`, it is the
/// same computation: the same results. A panic in `b` is resumed here.
pub fn join_or_offer<RA, RB: Send>(
    a: impl FnOnce() -> RA,
    b: impl FnOnce() -> RB + Send,
) -> (RA, RB) {
    if !second_core() || second_core_idle() {
        return join(a, b);
    }
    offer_in(&OFFER, a, b)
}

/// A pause in work built [`ahead`]: runs the task on offer ([`join_or_offer`]), if there is one,
/// before that work goes on. Called between the steps of the analyses the second core builds
/// ahead, so that an offer waits at most one step.
pub fn take_offer() {
    take_offer_from(&OFFER);
}

/// A slot for a task on offer, with the thread that offered it.
type Offers = std::sync::Mutex<Option<(std::thread::ThreadId, Job)>>;

/// The task on offer to the second core ([`join_or_offer`]).
static OFFER: Offers = std::sync::Mutex::new(None);

/// Runs the task in `offers`, if there is one.
fn take_offer_from(offers: &Offers) {
    let job = lock(offers).take();
    if let Some((_, job)) = job {
        job();
    }
}

/// [`join_or_offer`] with `b` put in `offers`: `a` here, then `b` taken back and run here unless
/// a [`take_offer_from`] took it meanwhile (then its end waited for). Where `offers` holds a task
/// already (an enclosing call's), `b` simply runs here after `a`.
fn offer_in<RA, RB: Send>(
    offers: &Offers,
    a: impl FnOnce() -> RA,
    b: impl FnOnce() -> RB + Send,
) -> (RA, RB) {
    let slot = std::sync::Mutex::new(None);
    let latch = std::sync::Arc::new(Latch::default());
    // SAFETY: before this function returns (or unwinds past `b`'s captures and `slot`) the job
    // is either taken back unrun, or run, here or by the thread that took it, and waited for
    // ([`Withdraw`]).
    let job = unsafe { erased_job(b, &slot, latch.clone(), || ()) };
    let me = std::thread::current().id();
    let mut offered = lock(offers);
    if offered.is_some() {
        drop(offered);
        let ra = a();
        job();
        return (ra, take_result(&slot));
    }
    *offered = Some((me, job));
    drop(offered);
    let withdraw = Withdraw {
        offers,
        latch: &latch,
        me,
    };
    let ra = a();
    if let Some(job) = withdraw.back() {
        job();
    }
    drop(withdraw);
    (ra, take_result(&slot))
}

/// Takes an offer of [`offer_in`] back unrun if it is still there, else waits for the thread
/// that took it to finish it, when dropped (also while `a` unwinds).
struct Withdraw<'a> {
    offers: &'a Offers,
    latch: &'a Latch,
    me: std::thread::ThreadId,
}

impl Withdraw<'_> {
    /// The job, if it is still on offer.
    fn back(&self) -> Option<Job> {
        let mut offered = lock(self.offers);
        match &*offered {
            Some((owner, _)) if *owner == self.me => offered.take().map(|(_, job)| job),
            _ => None,
        }
    }
}

impl Drop for Withdraw<'_> {
    fn drop(&mut self) {
        if self.back().is_none() {
            self.latch.wait();
        }
    }
}

/// The second core's thread: started at the first task given to a second core and kept for the
/// process, so that a task costs a wake-up (about 40 µs here) instead of a thread's start
/// (its stack, its thread-local state and a clone, paid by the caller): whole process 0.95-0.99
/// on seven public files. Either way a task can start late where the kernel's own work holds the
/// other core (its softirqs after the previous process, seen here for 2.3 ms): the Newton
/// system's task started 2.1-2.7 ms late in 6 of 20 runs of M3500 with this thread, 1-2.9 ms in
/// 8 of 20 with a thread per task.
struct Worker {
    state: std::sync::Mutex<WorkerState>,
    wake: std::sync::Condvar,
}

#[derive(Default)]
struct WorkerState {
    job: Option<Job>,
    /// Claimed for a job ([`Worker::claim`]) or running the idle tasks.
    busy: bool,
    /// A solver has let the tasks left by [`when_idle`] start ([`let_idle_tasks_start`]).
    idle_ready: bool,
    /// The tasks left by [`in_background`], the next one first.
    background: std::collections::VecDeque<Job>,
}

/// Locks a mutex whatever a panicking holder left (the data here stay consistent).
fn lock<T>(m: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The second core's thread, where there is a second core and its thread could be started, in
/// the process that started it: a process forked from it (Python's multiprocessing, say) has
/// not the thread, and gives its tasks threads of their own.
fn worker() -> Option<&'static Worker> {
    if !second_core() {
        return None;
    }
    WORKER.get_or_init(|| {
        if !more_than_one_cpu() {
            return None;
        }
        let worker: &'static Worker = Box::leak(Box::new(Worker {
            state: std::sync::Mutex::new(WorkerState::default()),
            wake: std::sync::Condvar::new(),
        }));
        let thread = std::thread::Builder::new()
            .name("second-core".into())
            .spawn(move || worker.serve())
            .ok()?;
        start_elsewhere(&thread);
        Some((std::process::id(), worker))
    });
    started_worker()
}

/// Moves a thread just started to a CPU other than this thread's, where the process may run on
/// another: Linux may queue a new thread on its parent's CPU (it did for the second core's thread
/// in about half of smallGrid3D's runs, the other core idle), where it waits for the parent to
/// block and the two run one after the other until a load balance separates them, some
/// milliseconds later. The thread's CPUs are narrowed to the others and at once widened again:
/// the first call moves it, the second leaves it where it is, free to go anywhere after. Not
/// moved, as the process's first thread, smallGrid3D took 1.10 and MIT 1.035 of the time they
/// take with another thread started before it (300 interleaved pairs); moved, the same time as
/// with it (0.99-1.01). Where a thread runs changes no result.
fn start_elsewhere(thread: &std::thread::JoinHandle<()>) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::os::unix::thread::JoinHandleExt;
        let size = std::mem::size_of::<libc::cpu_set_t>();
        // SAFETY: cpu_set_t is a plain bit set, zeroed before use; sched_getaffinity and
        // pthread_setaffinity_np read and write the sets given, of `size` bytes, for this
        // process and the live thread `thread` holds (joinable, so its pthread_t is valid).
        unsafe {
            let here = libc::sched_getcpu();
            let mut all = std::mem::zeroed::<libc::cpu_set_t>();
            let Ok(here) = usize::try_from(here) else {
                return;
            };
            if libc::sched_getaffinity(0, size, &mut all) != 0 {
                return;
            }
            let mut others = all;
            libc::CPU_CLR(here, &mut others);
            if libc::CPU_COUNT(&others) == 0 {
                return;
            }
            let id = thread.as_pthread_t();
            if libc::pthread_setaffinity_np(id, size, &others) == 0 {
                libc::pthread_setaffinity_np(id, size, &all);
            }
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = thread;
}

/// The second core's thread once started ([`worker`]), in this process.
static WORKER: OnceLock<Option<(u32, &'static Worker)>> = OnceLock::new();

/// The second core's thread if it has been started in this process; `None` without starting it.
fn started_worker() -> Option<&'static Worker> {
    let (process, worker) = (*WORKER.get()?)?;
    (process == std::process::id()).then_some(worker)
}

impl Worker {
    /// Runs the jobs given, and the idle tasks once they may start, for the process's life.
    fn serve(&self) {
        loop {
            let job = {
                let mut state = lock(&self.state);
                loop {
                    if let Some(job) = state.job.take() {
                        break Some(job);
                    }
                    if state.idle_ready && !state.busy {
                        state.idle_ready = false;
                        state.busy = true;
                        break None;
                    }
                    // A background task leaves the thread free: a job given meanwhile waits
                    // for that task's end only.
                    if !state.busy
                        && let Some(task) = state.background.pop_front()
                    {
                        break Some(task);
                    }
                    state = self.wake.wait(state).unwrap_or_else(|p| p.into_inner());
                }
            };
            match job {
                // A job frees the thread itself ([`beside`]); a background task never took it.
                Some(job) => job(),
                None => {
                    run_idle_runners();
                    lock(&self.state).busy = false;
                }
            }
        }
    }

    /// Claims the thread for a job; false if it is busy.
    fn claim(&self) -> bool {
        let mut state = lock(&self.state);
        !std::mem::replace(&mut state.busy, true)
    }

    /// Hands the claimed thread its job.
    fn give(&self, job: Job) {
        lock(&self.state).job = Some(job);
        self.wake.notify_one();
    }

    /// Frees the thread after a job.
    fn release(&self) {
        lock(&self.state).busy = false;
    }

    /// Leaves background tasks ([`in_background`]), each one's panic caught and dropped.
    fn leave(&self, tasks: impl IntoIterator<Item = Box<dyn FnOnce() + Send + 'static>>) {
        lock(&self.state)
            .background
            .extend(tasks.into_iter().map(|task| -> Job {
                Box::new(move || {
                    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(task));
                })
            }));
        self.wake.notify_one();
    }

    /// Drops the background tasks not started.
    fn drop_left(&self) {
        lock(&self.state).background.clear();
    }

    /// Lets the idle tasks start once the thread is free.
    fn idle_ready(&self) {
        lock(&self.state).idle_ready = true;
        self.wake.notify_one();
    }
}

/// Leaves `tasks` to the second core's thread, to run one after the other whenever it has no
/// job ([`join`], [`ahead`]) and no [`when_idle`] tasks to run: work worth doing only with a
/// core to spare, each task short, since a job given meanwhile waits for the task in progress.
/// Nobody waits for them: on one core (or in a process forked without the thread) they are
/// dropped unrun, as are those still left at [`drop_background`]. A panicking task is caught
/// and dropped. Each must leave every result the same whether it runs or not.
pub fn in_background(tasks: impl IntoIterator<Item = Box<dyn FnOnce() + Send + 'static>>) {
    if let Some(worker) = worker() {
        worker.leave(tasks);
    }
}

/// [`in_background`] where the second core's thread runs already; else `tasks` are dropped
/// unrun here (no thread is started for them).
pub fn in_background_if_started(
    tasks: impl IntoIterator<Item = Box<dyn FnOnce() + Send + 'static>>,
) {
    if let Some(worker) = started_worker() {
        worker.leave(tasks);
    }
}

/// Drops the tasks that [`in_background`] left and the second core has not started.
pub fn drop_background() {
    if let Some(worker) = started_worker() {
        worker.drop_left();
    }
}

/// A flag that one thread raises once and others wait for.
#[derive(Default)]
struct Latch {
    open: std::sync::Mutex<bool>,
    opened: std::sync::Condvar,
}

impl Latch {
    fn open(&self) {
        *lock(&self.open) = true;
        self.opened.notify_all();
    }

    fn wait(&self) {
        let mut open = lock(&self.open);
        while !*open {
            open = self.opened.wait(open).unwrap_or_else(|p| p.into_inner());
        }
    }
}

/// Waits for a latch when dropped, also while unwinding.
struct WaitOnDrop<'a>(&'a Latch);

impl Drop for WaitOnDrop<'_> {
    fn drop(&mut self) {
        self.0.wait();
    }
}

/// A result that a second core computes ahead ([`ahead`]): [`Ready::take`] waits for it and hands
/// it over once (`None` after, and `None` on one core, where it is not computed and the caller
/// builds what it needs itself).
pub struct Ready<T> {
    receive: Option<std::sync::mpsc::Receiver<T>>,
    taken: std::cell::Cell<bool>,
}

impl<T> Ready<T> {
    /// Waits for the result and hands it over, the first time only.
    pub fn take(&self) -> Option<T> {
        self.take_or(|| ())
    }

    /// [`Ready::take`], with `meanwhile` run on this thread first where the result has not
    /// come yet (not where none will come: on one core, or after the first time).
    pub fn take_or(&self, meanwhile: impl FnOnce()) -> Option<T> {
        if self.taken.replace(true) {
            return None;
        }
        let receive = self.receive.as_ref()?;
        match receive.try_recv() {
            Ok(t) => Some(t),
            Err(std::sync::mpsc::TryRecvError::Disconnected) => None,
            Err(std::sync::mpsc::TryRecvError::Empty) => {
                meanwhile();
                receive.recv().ok()
            }
        }
    }
}

/// A task that whichever thread comes to it first computes ([`ahead`], [`spare`]): the second
/// core once it has built what it builds ahead, unless this thread has claimed the task by then.
pub struct Spare<T> {
    claimed: std::sync::Arc<std::sync::atomic::AtomicBool>,
    receive: Option<std::sync::mpsc::Receiver<T>>,
}

impl<T> Spare<T> {
    /// The task's result (asked for once): computed here by `compute` if the second core has not
    /// claimed the task, else the second core's, waited for.
    pub fn take(&self, compute: impl FnOnce() -> T) -> T {
        if claim(&self.claimed) {
            return compute();
        }
        match self.receive.as_ref().and_then(|r| r.recv().ok()) {
            Some(t) => t,
            None => compute(),
        }
    }

    /// Claims the task without asking for its result: unless the other side has claimed it
    /// already, it is not computed at all.
    pub fn forgo(&self) {
        claim(&self.claimed);
    }
}

/// Claims a [`Spare`] task; the claim that comes first wins.
fn claim(claimed: &std::sync::atomic::AtomicBool) -> bool {
    !claimed.swap(true, std::sync::atomic::Ordering::AcqRel)
}

/// The second core's side of a [`Spare`] task made by [`spare`].
pub struct SpareTask<T> {
    claimed: std::sync::Arc<std::sync::atomic::AtomicBool>,
    send: std::sync::mpsc::Sender<T>,
}

impl<T> SpareTask<T> {
    /// Computes the task and hands its result over, unless the other side has claimed it first
    /// (then nothing is computed here).
    pub fn run(self, task: impl FnOnce() -> T) {
        if claim(&self.claimed) {
            // A closed channel only means that the other side no longer waits for it.
            let _ = self.send.send(task());
        }
    }
}

/// A task that whichever of two threads comes to it first computes: [`SpareTask::run`] on the
/// second core, [`Spare::take`] where its result is needed. Run on one thread, where `take`
/// comes first, `take` computes it.
pub fn spare<T>() -> (SpareTask<T>, Spare<T>) {
    let claimed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (send, receive) = std::sync::mpsc::channel();
    (
        SpareTask {
            claimed: claimed.clone(),
            send,
        },
        Spare {
            claimed,
            receive: Some(receive),
        },
    )
}

/// `(f(0..n/2), f(n/2..n))`: the upper half on the second core where it is idle
/// ([`second_core_idle`]) and `n` is at least `min`, else both here, lower first. For items
/// computed each by itself whose results the caller joins in order (the lower half's, then the
/// upper half's): the same split on one core or two, so the same results.
pub fn halves<R: Send>(
    n: usize,
    min: usize,
    f: impl Fn(std::ops::Range<usize>) -> R + Sync,
) -> (R, R) {
    let mid = n / 2;
    if n >= min && second_core_idle() {
        join(|| f(0..mid), || f(mid..n))
    } else {
        (f(0..mid), f(mid..n))
    }
}

/// A task for the second core's idle time ([`when_idle`]): started there once a solver lets it
/// ([`let_idle_tasks_start`]), or never; [`Idle::take`] hands its result over.
pub struct Idle<T> {
    shared: Option<std::sync::Arc<IdleShared<T>>>,
}

struct IdleShared<T> {
    state: std::sync::Mutex<IdleState<T>>,
    done: std::sync::Condvar,
}

enum IdleState<T> {
    Pending(Box<dyn FnOnce() -> T + Send>),
    Running,
    Done(T),
    Forgone,
}

/// The runners of the tasks given to [`when_idle`] and not started yet.
type Runner = Box<dyn FnOnce() + Send>;
static IDLE: std::sync::Mutex<Vec<Runner>> = std::sync::Mutex::new(Vec::new());

/// Leaves `task` for the second core to run once a solver lets it start
/// ([`let_idle_tasks_start`]: its work built [`ahead`] done, the core idle while this thread
/// descends or certifies), on the second core's thread, counted busy meanwhile
/// ([`second_core_idle`] is false while it runs). For work whose result is wanted only at the
/// end, such as the lines of the output that the solve does not change. Nothing is registered
/// on one core; where no solver lets it start, the task is never run, and [`Idle::take`] says
/// so: the caller then computes the result itself, the same bits.
pub fn when_idle<T: Send + 'static>(task: impl FnOnce() -> T + Send + 'static) -> Idle<T> {
    if !second_core() {
        return Idle { shared: None };
    }
    let shared = std::sync::Arc::new(IdleShared {
        state: std::sync::Mutex::new(IdleState::Pending(Box::new(task))),
        done: std::sync::Condvar::new(),
    });
    let runner = {
        let shared = shared.clone();
        Box::new(move || {
            let task = {
                let mut state = lock(&shared.state);
                match std::mem::replace(&mut *state, IdleState::Running) {
                    IdleState::Pending(task) => task,
                    other => {
                        *state = other;
                        return;
                    }
                }
            };
            // The task (and what it holds) is gone before its result is handed over; one that
            // panics leaves the result to the caller (`take` answers `None`).
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(task));
            *lock(&shared.state) = match result {
                Ok(result) => IdleState::Done(result),
                Err(_) => IdleState::Forgone,
            };
            shared.done.notify_all();
        })
    };
    lock(&IDLE).push(runner);
    Idle {
        shared: Some(shared),
    }
}

impl<T> Idle<T> {
    /// The task's result, after waiting for it if it is running; `None` if it was not started
    /// (it never will be then) or panicked.
    pub fn take(mut self) -> Option<T> {
        let shared = self.shared.take()?;
        let mut state = lock(&shared.state);
        loop {
            match std::mem::replace(&mut *state, IdleState::Forgone) {
                IdleState::Done(result) => return Some(result),
                IdleState::Running => {
                    *state = IdleState::Running;
                    state = shared.done.wait(state).unwrap_or_else(|p| p.into_inner());
                }
                // Pending (dropped here) or already forgone.
                _ => return None,
            }
        }
    }
}

impl<T> Drop for Idle<T> {
    /// A task not started is forgone (and what it holds dropped): nobody would take its result.
    fn drop(&mut self) {
        if let Some(shared) = self.shared.take() {
            let mut state = lock(&shared.state);
            if matches!(*state, IdleState::Pending(_)) {
                *state = IdleState::Forgone;
            }
        }
    }
}

/// Lets the tasks left by [`when_idle`] start on the second core's thread once it is free: for
/// a solver to call where that core would otherwise idle (its work built [`ahead`] done, and no
/// factorization to come that splits itself between the cores). Tasks left after this call wait
/// for the next one.
pub fn let_idle_tasks_start() {
    if let Some(worker) = worker() {
        worker.idle_ready();
    }
}

/// Runs the tasks left by [`when_idle`], in the order given, the core counted busy meanwhile.
fn run_idle_runners() {
    let runners = std::mem::take(&mut *lock(&IDLE));
    if runners.is_empty() {
        return;
    }
    let _busy = Busy::new();
    for run in runners {
        run();
    }
}

/// `(main(ready, spare), then())` with `first`, then `spare_task` unless `main` has claimed it
/// first ([`Spare`]), then `then` in that order on a second core when [`second_core`]:
/// `ready.take()` waits for `first`'s result and hands it over ([`Ready`]); on one core neither
/// is run, `main` builds what it needs itself and `then` runs after `main`. For work that
/// depends on a problem's pattern alone, built ahead while this thread starts and descends. A
/// panic on the second thread is resumed here.
pub fn ahead<S: Send, A: Send, C: Send, R>(
    first: impl FnOnce() -> S + Send,
    spare_task: impl FnOnce() -> A + Send,
    then: impl FnOnce() -> C + Send,
    main: impl FnOnce(&Ready<S>, &Spare<A>) -> R,
) -> (R, C) {
    if !second_core() {
        let ready = Ready {
            receive: None,
            taken: std::cell::Cell::new(false),
        };
        let spare = Spare {
            claimed: Default::default(),
            receive: None,
        };
        let r = main(&ready, &spare);
        return (r, then());
    }
    let (run_spare, spare) = self::spare();
    let (send, receive) = std::sync::mpsc::channel();
    let busy = Busy::new();
    let ready = Ready {
        receive: Some(receive),
        taken: std::cell::Cell::new(false),
    };
    beside(
        || main(&ready, &spare),
        move || {
            let _busy = busy;
            // A closed channel only means that `main` did not wait for the result.
            let _ = send.send(first());
            run_spare.run(spare_task);
            let c = then();
            // A task offered after the work's last pause ([`join_or_offer`]: a split
            // factorization's second side, offered while this core was busy) runs here before the
            // core counts as idle, instead of waiting on offer for this thread to take it back.
            take_offer();
            c
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both results, each from its own closure, whatever the thread count.
    #[test]
    fn join_returns_both_results_in_order() {
        let data: Vec<u64> = (1..=1000).collect();
        let (sum, squares) = join(
            || data.iter().sum::<u64>(),
            || data.iter().map(|x| x * x).sum::<u64>(),
        );
        assert_eq!(sum, 500_500);
        assert_eq!(squares, 1000 * 1001 * 2001 / 6);
    }

    /// `main` receives `first`'s result once (none on one core), the spare task's result from
    /// whichever thread computed it, and `then`'s comes back beside `main`'s.
    #[test]
    fn ahead_hands_over_the_first_result_once_and_the_spare_one() {
        let ((got, again, spare), then) = ahead(
            || 41,
            || "spare",
            || "then",
            |ready, spare| (ready.take(), ready.take(), spare.take(|| "spare")),
        );
        assert_eq!(then, "then");
        assert_eq!(again, None);
        assert_eq!(got, second_core().then_some(41));
        assert_eq!(spare, "spare");
    }

    /// `take_or` runs its `meanwhile` here where the result has not come yet (the first task
    /// waits for it), then hands the result over; on one core nothing comes and nothing runs.
    #[test]
    fn take_or_runs_meanwhile_while_the_result_is_to_come() {
        let (go, wait) = std::sync::mpsc::channel::<()>();
        let ((got, ran), ()) = ahead(
            move || {
                // Not for ever where `meanwhile` never runs: the assertions then fail.
                let _ = wait.recv_timeout(std::time::Duration::from_secs(10));
                41
            },
            || (),
            || (),
            |ready, _| {
                let ran = std::cell::Cell::new(false);
                let got = ready.take_or(|| {
                    ran.set(true);
                    let _ = go.send(());
                });
                (got, ran.get())
            },
        );
        assert_eq!(got, second_core().then_some(41));
        assert_eq!(ran, second_core());
    }

    /// Whichever thread claims the spare task first computes it, and only that one.
    #[test]
    fn the_spare_task_runs_once() {
        let runs = std::sync::atomic::AtomicUsize::new(0);
        let count = || {
            runs.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        };
        let (_, ()) = ahead(|| (), count, || (), |_, spare| spare.take(count));
        assert_eq!(runs.load(std::sync::atomic::Ordering::SeqCst), 1);
    }

    /// A spare task of its own ([`spare`]): computed by the side that claims it first, on
    /// whichever thread, and by neither once forgone.
    #[test]
    fn a_spare_task_runs_on_the_side_that_claims_it_or_not_at_all() {
        let (task, result) = spare::<u32>();
        assert_eq!(result.take(|| 1), 1);
        task.run(|| panic!("claimed by take already"));
        let (task, result) = spare::<u32>();
        std::thread::scope(|scope| {
            scope.spawn(move || task.run(|| 2)).join().unwrap();
        });
        assert_eq!(result.take(|| panic!("run on the other thread already")), 2);
        let (task, result) = spare::<u32>();
        result.forgo();
        task.run(|| panic!("forgone"));
    }

    /// While [`ahead`] runs a task on the second core, that core does not count as idle (for
    /// computations that would split themselves over both).
    #[test]
    fn the_second_core_is_busy_while_a_task_runs_ahead_there() {
        let (go, wait) = std::sync::mpsc::channel::<()>();
        let (busy, ()) = ahead(
            move || {
                let _ = wait.recv();
            },
            || (),
            || (),
            |_, _| {
                let busy = !second_core_idle();
                let _ = go.send(());
                busy
            },
        );
        assert!(busy);
    }

    /// A task offered while work built ahead runs, after that work's last pause, is run by the
    /// second core once the work is done, not left on offer for this thread to take back: `a`
    /// waits (up to a minute) for `b` to start elsewhere, and `b` runs on another thread.
    #[test]
    fn an_offer_left_after_the_last_pause_runs_on_the_second_core() {
        if !second_core() {
            return;
        }
        let caller = std::thread::current().id();
        let (offered, wait_offered) = std::sync::mpsc::channel::<()>();
        let (started, wait_started) = std::sync::mpsc::channel::<()>();
        let ((b_started_first, b_thread), ()) = ahead(
            || (),
            || (),
            move || {
                let _ = wait_offered.recv();
            },
            |_, _| {
                join_or_offer(
                    || {
                        let _ = offered.send(());
                        wait_started
                            .recv_timeout(std::time::Duration::from_secs(60))
                            .is_ok()
                    },
                    move || {
                        let _ = started.send(());
                        std::thread::current().id()
                    },
                )
            },
        );
        assert!(b_started_first);
        assert_ne!(b_thread, caller);
    }

    /// An offer taken at a pause runs on the thread that paused, while `a` still runs here, and
    /// its result comes back here in order; one not taken runs here after `a`.
    #[test]
    fn an_offer_runs_where_it_is_taken_else_here() {
        let caller = std::thread::current().id();
        let offers: Offers = std::sync::Mutex::new(None);
        let (offered, pause) = std::sync::mpsc::channel::<()>();
        let (ran, wait_ran) = std::sync::mpsc::channel::<()>();
        let (a_saw_b, (value, thread), taker) = std::thread::scope(|scope| {
            let offers = &offers;
            let taker = scope.spawn(move || {
                pause.recv().expect("the offer is made");
                take_offer_from(offers);
                std::thread::current().id()
            });
            let (a_saw_b, b) = offer_in(
                offers,
                || {
                    offered.send(()).expect("the taker waits");
                    wait_ran.recv().is_ok()
                },
                move || {
                    let _ = ran.send(());
                    (6 * 7, std::thread::current().id())
                },
            );
            (a_saw_b, b, taker.join().expect("the taker ends"))
        });
        assert!(a_saw_b);
        assert_eq!(value, 42);
        assert_eq!(thread, taker);
        assert_ne!(thread, caller);
        assert!(lock(&offers).is_none());
        // Nobody pauses: `b` runs here, after `a`.
        let order = std::sync::Mutex::new(Vec::new());
        let ((), thread) = offer_in(
            &offers,
            || lock(&order).push("a"),
            || {
                lock(&order).push("b");
                std::thread::current().id()
            },
        );
        assert_eq!(thread, caller);
        assert_eq!(*lock(&order), ["a", "b"]);
        assert!(lock(&offers).is_none());
    }

    /// A panic in `a` takes the offer back unrun; a panic in `b`, run by the thread that took
    /// it, is resumed here; the slot is empty after either.
    #[test]
    fn panics_on_either_side_of_an_offer_end_here() {
        let offers: Offers = std::sync::Mutex::new(None);
        let b_ran = std::sync::atomic::AtomicBool::new(false);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            offer_in(
                &offers,
                || panic!("a panics"),
                || b_ran.store(true, std::sync::atomic::Ordering::SeqCst),
            )
        }));
        assert!(result.is_err());
        assert!(!b_ran.load(std::sync::atomic::Ordering::SeqCst));
        assert!(lock(&offers).is_none());
        let (offered, pause) = std::sync::mpsc::channel::<()>();
        let result = std::thread::scope(|scope| {
            let offers = &offers;
            let taker = scope.spawn(move || {
                pause.recv().expect("the offer is made");
                take_offer_from(offers);
            });
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                offer_in(
                    offers,
                    || {
                        offered.send(()).expect("the taker waits");
                        taker.join().expect("the job catches its panic");
                    },
                    || -> u32 { panic!("b panics") },
                )
            }))
        });
        assert!(result.is_err());
        assert!(lock(&offers).is_none());
    }

    /// A task left for the idle time runs once [`ahead`]'s work is done and lets it start, on
    /// another thread than the caller's (the second core's), and `take` hands its result over
    /// (on one core it is never run, and `take` says so); one that panics leaves `take` with
    /// `None` instead of waiting.
    #[test]
    fn an_idle_task_runs_after_the_work_ahead() {
        let caller = std::thread::current().id();
        let panics = when_idle(|| -> u32 { panic!("an idle task that panics") });
        let (started, wait) = std::sync::mpsc::channel();
        let idle = when_idle(move || {
            let _ = started.send(());
            (6 * 7, std::thread::current().id())
        });
        // Started (not yet finished) when `take` comes: a task not started by then is left to
        // the caller.
        let ((), ()) = ahead(
            || (),
            || (),
            let_idle_tasks_start,
            |_, _| {
                if second_core() {
                    wait.recv().expect("the idle task starts");
                }
            },
        );
        match idle.take() {
            Some((value, thread)) => {
                assert!(second_core());
                assert_eq!(value, 42);
                assert_ne!(thread, caller);
            }
            None => assert!(!second_core()),
        }
        assert_eq!(panics.take(), None);
    }

    /// `take`: a task not started is forgone and dropped (`None`), a running one waited for, a
    /// finished one's result handed over; dropping the handle forgoes a task not started. (The
    /// states set by hand: the runner's part is the test above.)
    #[test]
    fn an_idle_task_not_started_is_forgone_and_a_running_one_waited_for() {
        let held = std::sync::Arc::new(());
        let idle = |state: IdleState<u32>| Idle {
            shared: Some(std::sync::Arc::new(IdleShared {
                state: std::sync::Mutex::new(state),
                done: std::sync::Condvar::new(),
            })),
        };
        let pending = |held: &std::sync::Arc<()>| {
            let held = held.clone();
            IdleState::Pending(Box::new(move || {
                drop(held);
                1
            }))
        };
        assert_eq!(idle(pending(&held)).take(), None);
        assert_eq!(
            std::sync::Arc::strong_count(&held),
            1,
            "the task is dropped"
        );
        drop(idle(pending(&held)));
        assert_eq!(
            std::sync::Arc::strong_count(&held),
            1,
            "the task is dropped"
        );
        assert_eq!(idle(IdleState::Done(5)).take(), Some(5));
        let running = idle(IdleState::Running);
        let shared = running.shared.clone().unwrap();
        let finisher = std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(20));
            *shared.state.lock().unwrap() = IdleState::Done(9);
            shared.done.notify_all();
        });
        assert_eq!(running.take(), Some(9));
        finisher.join().unwrap();
    }

    /// Both halves of the range, each once, lower first, whatever the threshold and the core
    /// count.
    #[test]
    fn halves_cover_the_range_in_order() {
        for (n, min) in [(0, 0), (1, 0), (7, 0), (1000, 0), (1000, usize::MAX)] {
            let (lower, upper) = halves(n, min, |r| r.collect::<Vec<_>>());
            assert_eq!(lower.len(), n / 2);
            let all: Vec<usize> = lower.into_iter().chain(upper).collect();
            assert_eq!(all, (0..n).collect::<Vec<_>>());
        }
    }

    /// Inside [`alone`] every task runs on the calling thread and no second core is seen; the
    /// thread's setting comes back after it, also after a panic inside.
    #[test]
    fn alone_keeps_every_task_on_this_thread() {
        let here = std::thread::current().id();
        let ((a, b), second) = alone(|| {
            (
                join(
                    || std::thread::current().id(),
                    || std::thread::current().id(),
                ),
                second_core(),
            )
        });
        assert_eq!((a, b), (here, here));
        assert!(!second);
        let ((), ran_on) = alone(|| {
            ahead(
                || (),
                || (),
                || std::thread::current().id(),
                |ready, _| assert_eq!(ready.take(), None),
            )
        });
        assert_eq!(ran_on, here);
        let unwound = std::panic::catch_unwind(|| alone(|| panic!("inside alone")));
        assert!(unwound.is_err());
        assert_eq!(
            second_core(),
            std::thread::available_parallelism().is_ok_and(|c| c.get() > 1)
        );
    }

    /// Background tasks run on the second core's thread one after the other, in the order left;
    /// a job given while one runs finds the thread free to claim and runs there next (not on a
    /// thread of its own); a task that panics does not stop the next; tasks dropped before they
    /// start never run. On a worker of the test's own, so that no other test's tasks mix in.
    #[test]
    fn background_tasks_run_in_order_between_jobs_until_dropped() {
        let worker: &'static Worker = Box::leak(Box::new(Worker {
            state: std::sync::Mutex::new(WorkerState::default()),
            wake: std::sync::Condvar::new(),
        }));
        // The thread serves for the rest of the test process.
        let served_by = std::thread::spawn(|| worker.serve()).thread().id();
        let (ran, heard) = std::sync::mpsc::channel::<(&'static str, std::thread::ThreadId)>();
        let next = || {
            heard
                .recv_timeout(std::time::Duration::from_secs(20))
                .expect("a task ran")
        };
        let task = |name: &'static str| -> Box<dyn FnOnce() + Send> {
            let ran = ran.clone();
            Box::new(move || ran.send((name, std::thread::current().id())).unwrap())
        };
        let gate = || -> (std::sync::mpsc::Sender<()>, Box<dyn FnOnce() + Send>) {
            let (open, wait) = std::sync::mpsc::channel::<()>();
            let ran = ran.clone();
            let task = Box::new(move || {
                ran.send(("gate", std::thread::current().id())).unwrap();
                wait.recv().unwrap();
            });
            (open, task)
        };
        let (open, first) = gate();
        let panics: Box<dyn FnOnce() + Send> = Box::new(|| panic!("a background task that panics"));
        worker.leave([first, task("1"), task("2"), panics, task("4")]);
        assert_eq!(next(), ("gate", served_by));
        assert!(worker.claim(), "a background task leaves the thread free");
        worker.give({
            let ran = ran.clone();
            Box::new(move || {
                ran.send(("job", std::thread::current().id())).unwrap();
                worker.release();
            })
        });
        open.send(()).unwrap();
        for name in ["job", "1", "2", "4"] {
            assert_eq!(next(), (name, served_by));
        }
        let (open, second) = gate();
        worker.leave([second, task("dropped"), task("dropped too")]);
        assert_eq!(next().0, "gate");
        worker.drop_left();
        worker.leave([task("after")]);
        open.send(()).unwrap();
        assert_eq!(next(), ("after", served_by));
    }

    /// A panic on the second thread reaches the caller.
    #[test]
    #[should_panic(expected = "from b")]
    fn a_panic_in_b_is_resumed() {
        join(|| 1, || -> u32 { panic!("from b") });
    }

    /// A join inside a task of the second core's thread finds that thread busy and runs its
    /// `b` on a thread of its own instead of waiting for itself (with the check removed, this
    /// test never ends); after a panic in a task, the next task still runs.
    #[test]
    fn the_second_cores_thread_is_kept_and_never_waits_for_itself() {
        if !second_core() {
            return;
        }
        let here = std::thread::current().id();
        let inner = || {
            let outer = std::thread::current().id();
            let (a, b) = join(
                || std::thread::current().id(),
                || std::thread::current().id(),
            );
            (outer, a, b)
        };
        let ((), (outer, a, b)) = join(|| (), inner);
        assert_ne!(outer, here);
        assert_eq!(a, outer);
        assert!(
            b != outer && b != here,
            "the inner join's task has a thread of its own"
        );
        let panicked = std::panic::catch_unwind(|| join(|| (), || -> u32 { panic!("in b") }));
        assert!(panicked.is_err());
        let (_, again) = join(|| (), || 6 * 7);
        assert_eq!(again, 42);
    }

    /// When `a` panics while `b` runs on the second core's thread, `b` still finishes with the
    /// data it borrows before the panic goes on.
    #[test]
    fn a_panic_in_a_waits_for_b() {
        let finished = std::sync::atomic::AtomicBool::new(false);
        let data = vec![1u64; 1000];
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            join(
                || -> u64 { panic!("in a") },
                || {
                    std::thread::sleep(std::time::Duration::from_millis(20));
                    let sum: u64 = data.iter().sum();
                    finished.store(true, std::sync::atomic::Ordering::SeqCst);
                    sum
                },
            )
        }));
        assert!(result.is_err());
        assert!(finished.load(std::sync::atomic::Ordering::SeqCst));
    }
}
