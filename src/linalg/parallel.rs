//! Both cores, the same bits as one: independent computations side by side on a scoped thread,
//! each computed exactly as it would be alone, so that no result depends on the thread count.
//! Only whole tasks run in parallel (an analysis beside a descent, an ordering beside an
//! assembly); no sum is ever split between threads.

use std::sync::OnceLock;

/// Whether a second thread can run beside this one: more than one CPU available to the process
/// (its affinity and cgroup quota included), asked once.
pub fn second_core() -> bool {
    static SECOND: OnceLock<bool> = OnceLock::new();
    *SECOND.get_or_init(|| std::thread::available_parallelism().is_ok_and(|c| c.get() > 1))
}

/// Starts faer's dense products on a detached thread of the second core, so that their one-time
/// set-up is done while this thread parses and reads. Above nano-gemm's sizes (16³ multiply-adds),
/// faer's first dense product reads the processor's cache sizes from the operating system (on
/// Linux, a hundred opens and reads under `/sys/devices/system/cpu`): about 1.4 ms on a 2-core
/// VM, a fifth of a 9-pose 3D solve's whole process, paid at the first supernodal update of any
/// factorization. The sizes read are the same whichever thread reads them, so are the blockings
/// and every result. On one core nothing is started: the first product pays, as before. The
/// thread ends with the process if it is still running then.
pub fn warm_dense_products() {
    if !second_core() {
        return;
    }
    // A thread that cannot be started only means that the first product pays.
    let _ = std::thread::Builder::new()
        .name("warm-gemm".into())
        .spawn(|| {
            let n = 17; // the smallest square product past nano-gemm's threshold
            let a = faer::Mat::<f64>::identity(n, n);
            let mut c = faer::Mat::<f64>::zeros(n, n);
            faer::linalg::matmul::matmul(
                c.as_mut(),
                faer::Accum::Replace,
                a.as_ref(),
                a.as_ref(),
                1.0,
                faer::Par::Seq,
            );
            std::hint::black_box(&c);
        });
}

/// `(a(), b())`: `b` on a second thread when [`second_core`], else after `a` on this one. A panic
/// in `b` is resumed here.
pub fn join<RA, RB: Send>(a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> (RA, RB) {
    if !second_core() {
        let ra = a();
        return (ra, b());
    }
    std::thread::scope(|scope| {
        let hb = scope.spawn(b);
        let ra = a();
        let rb = hb
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (ra, rb)
    })
}

/// `(main(ready), then())` with `first` and then `then` on a second core when [`second_core`]:
/// `ready()` waits for `first`'s result and hands it over (once; `None` after, and `None` on one
/// core, where `first` is not run and `main` builds what it needs itself, and `then` runs after
/// `main`). For work that depends on a problem's pattern alone, built ahead while this thread
/// starts and descends. A panic in `first` or `then` is resumed here.
pub fn ahead<S: Send, C: Send, R>(
    first: impl FnOnce() -> S + Send,
    then: impl FnOnce() -> C + Send,
    main: impl FnOnce(&dyn Fn() -> Option<S>) -> R,
) -> (R, C) {
    if !second_core() {
        let r = main(&|| None);
        return (r, then());
    }
    std::thread::scope(|scope| {
        let (send, receive) = std::sync::mpsc::channel();
        let helper = scope.spawn(move || {
            // A closed channel only means that `main` did not wait for `first`.
            let _ = send.send(first());
            then()
        });
        let taken = std::cell::Cell::new(false);
        let r = main(&|| {
            if taken.replace(true) {
                None
            } else {
                receive.recv().ok()
            }
        });
        let c = helper
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (r, c)
    })
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

    /// `main` receives `first`'s result once (none on one core) and `then`'s comes back beside
    /// `main`'s.
    #[test]
    fn ahead_hands_over_the_first_result_once() {
        let ((got, again), then) = ahead(|| 41, || "then", |ready| (ready(), ready()));
        assert_eq!(then, "then");
        assert_eq!(again, None);
        assert_eq!(got, second_core().then_some(41));
    }

    /// A panic on the second thread reaches the caller.
    #[test]
    #[should_panic(expected = "from b")]
    fn a_panic_in_b_is_resumed() {
        join(|| 1, || -> u32 { panic!("from b") });
    }
}
