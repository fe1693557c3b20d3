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

    /// A panic on the second thread reaches the caller.
    #[test]
    #[should_panic(expected = "from b")]
    fn a_panic_in_b_is_resumed() {
        join(|| 1, || -> u32 { panic!("from b") });
    }
}
