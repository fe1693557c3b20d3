//! Progress of long computations, for whoever watches (the rerun recording of the tools, see
//! [`crate::viz`], and the progress display on a terminal, `cli::progress_bar`).
//!
//! A solver reports each iteration with [`iteration`]: its step number and named values (cost,
//! gradient norm, rank, trust-region radius, duality gap...); a job announces the phase it enters
//! with [`phase`] ("initialization", "certificate"...). Nothing happens unless the calling thread
//! runs inside [`observe`] or [`watch`], so solvers need no handle passed down through their
//! callers and their results never depend on being watched. Watchers nest: every report reaches
//! every watcher of the thread, outermost first (a recording and a display at once). Values are
//! reported in the units of the problem (e.g. the cost f of eq. (8)), not in a solver's internal
//! scaling.

use std::cell::RefCell;

/// Receives the iterations reported on this thread inside [`observe`]: step number and
/// `(name, value)` pairs.
pub type Observer = Box<dyn FnMut(u64, &[(&str, f64)])>;

/// Receives the phases announced on this thread inside [`watch`].
pub type PhaseObserver = Box<dyn FnMut(&str)>;

struct Watcher {
    iteration: Observer,
    phase: Option<PhaseObserver>,
}

thread_local! {
    static WATCHERS: RefCell<Vec<Watcher>> = const { RefCell::new(Vec::new()) };
}

/// Reports one iteration of a solver to the watchers of this thread, if any. Cheap when there
/// is none. A report made from inside a watcher itself is dropped.
pub fn iteration(step: u64, values: &[(&str, f64)]) {
    WATCHERS.with(|cell| {
        if let Ok(mut watchers) = cell.try_borrow_mut() {
            for w in watchers.iter_mut() {
                (w.iteration)(step, values);
            }
        }
    });
}

/// Announces the phase a job enters ("initialization", "certificate", "staircase rank 2"...) to
/// the watchers of this thread that asked for phases ([`watch`]). Cheap when there is none.
pub fn phase(name: &str) {
    WATCHERS.with(|cell| {
        if let Ok(mut watchers) = cell.try_borrow_mut() {
            for w in watchers.iter_mut() {
                if let Some(phase) = w.phase.as_mut() {
                    phase(name);
                }
            }
        }
    });
}

/// Whether this thread has a watcher: lets a solver skip computing values only reported.
pub fn observed() -> bool {
    WATCHERS.with(|cell| cell.try_borrow().is_ok_and(|w| !w.is_empty()))
}

/// Runs `body` with `observer` receiving the iterations reported on this thread (as well as the
/// watchers already there); it is removed afterwards, also when `body` unwinds.
pub fn observe<T>(observer: Observer, body: impl FnOnce() -> T) -> T {
    with_watcher(
        Watcher {
            iteration: observer,
            phase: None,
        },
        body,
    )
}

/// [`observe`] with the phases as well.
pub fn watch<T>(observer: Observer, phases: PhaseObserver, body: impl FnOnce() -> T) -> T {
    with_watcher(
        Watcher {
            iteration: observer,
            phase: Some(phases),
        },
        body,
    )
}

fn with_watcher<T>(watcher: Watcher, body: impl FnOnce() -> T) -> T {
    struct Remove(bool);
    impl Drop for Remove {
        fn drop(&mut self) {
            if self.0 {
                WATCHERS.with(|cell| {
                    if let Ok(mut watchers) = cell.try_borrow_mut() {
                        watchers.pop();
                    }
                });
            }
        }
    }
    let pushed = WATCHERS.with(|cell| match cell.try_borrow_mut() {
        Ok(mut watchers) => {
            watchers.push(watcher);
            true
        }
        // Called from inside a watcher: leave the watchers as they are.
        Err(_) => false,
    });
    let _remove = Remove(pushed);
    body()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[test]
    fn reports_reach_the_observer_only_inside_observe() {
        iteration(0, &[("cost", 1.0)]); // nobody watching: nothing happens
        let seen = Arc::new(Mutex::new(Vec::new()));
        let sink = seen.clone();
        let out = observe(
            Box::new(move |step, values| {
                if let Ok(mut v) = sink.lock() {
                    v.push((step, values[0].0.to_string(), values[0].1));
                }
            }),
            || {
                iteration(3, &[("cost", 2.5)]);
                iteration(4, &[("gap", 0.5)]);
                phase("ignored: observe takes no phases");
                7
            },
        );
        iteration(5, &[("cost", 9.0)]);
        assert_eq!(out, 7);
        let seen = seen.lock().unwrap();
        assert_eq!(
            *seen,
            vec![(3, "cost".to_string(), 2.5), (4, "gap".to_string(), 0.5)]
        );
    }

    #[test]
    fn nested_watchers_all_receive_and_are_removed() {
        // A recording and a display watch the same solve: both see what is reported while both
        // are there.
        let outer = Arc::new(Mutex::new(0u32));
        let inner = Arc::new(Mutex::new(0u32));
        let phases = Arc::new(Mutex::new(Vec::new()));
        let (o, i, p) = (outer.clone(), inner.clone(), phases.clone());
        observe(Box::new(move |_, _| *o.lock().unwrap() += 1), || {
            iteration(0, &[]);
            watch(
                Box::new(move |_, _| *i.lock().unwrap() += 1),
                Box::new(move |name| p.lock().unwrap().push(name.to_string())),
                || {
                    phase("certificate");
                    iteration(0, &[]);
                },
            );
            iteration(1, &[]);
            phase("not watched");
        });
        assert!(!observed());
        assert_eq!((*outer.lock().unwrap(), *inner.lock().unwrap()), (3, 1));
        assert_eq!(*phases.lock().unwrap(), ["certificate"]);
    }

    #[test]
    fn a_report_from_inside_a_watcher_is_dropped() {
        let count = Arc::new(Mutex::new(0u32));
        let c = count.clone();
        observe(
            Box::new(move |_, _| {
                *c.lock().unwrap() += 1;
                iteration(9, &[]); // re-entrant: dropped, no deadlock, no panic
            }),
            || iteration(0, &[]),
        );
        assert_eq!(*count.lock().unwrap(), 1);
    }
}
