//! The estimate before its certificate: the staircase offers the rank-1 point it is about to
//! certify ([`offer`]), and a caller that left a taker on its thread ([`offering`]) gets it as
//! the poses of the component, to start work that depends only on the estimate (the output
//! file, written on the second core beside the certificate) while the certificate is computed.
//! What the taker gets is a candidate: the solve may end elsewhere (a polish after a bound that
//! fell short, the staircase), so its user compares it with the solution's estimate and keeps
//! the work only where the two are the same bits.

use crate::graph::Pose2;
use std::cell::RefCell;

/// A taker of the component's poses (the graph's order, the solver's gauge: pose 0 where the
/// input has it).
pub type Taker = Box<dyn FnMut(&[Pose2])>;

thread_local! {
    /// The taker of this thread's staircase, if any ([`offering`]).
    static TAKER: RefCell<Option<Taker>> = const { RefCell::new(None) };
}

/// `work()` with `taker` receiving each estimate that the staircase run by `work` on this thread
/// is about to certify; the taker before it is restored after (also while unwinding).
pub fn offering<R>(taker: Taker, work: impl FnOnce() -> R) -> R {
    /// Puts back the taker that `offering` replaced.
    struct Restore(Option<Taker>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let before = self.0.take();
            TAKER.with(|t| *t.borrow_mut() = before);
        }
    }
    let _restore = Restore(TAKER.with(|t| t.borrow_mut().replace(taker)));
    work()
}

/// Hands `poses()`, computed only where a taker is there, to this thread's taker; whether there
/// was one.
pub(crate) fn offer(poses: impl FnOnce() -> Vec<Pose2>) -> bool {
    // Out of its cell while it runs: a taker that offered in turn would find none.
    let Some(mut taker) = TAKER.with(|t| t.borrow_mut().take()) else {
        return false;
    };
    taker(&poses());
    TAKER.with(|t| *t.borrow_mut() = Some(taker));
    true
}
