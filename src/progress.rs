//! Progress of iterative solvers, for whoever watches (the rerun recording of `pgo-solve`,
//! see [`crate::viz`]).
//!
//! A solver reports each iteration with [`iteration`]: its step number and named values (cost,
//! gradient norm, rank, trust-region radius, duality gap...). Nothing happens unless the calling
//! thread runs inside [`observe`], so solvers need no handle passed down through their callers
//! and their results never depend on being watched. Values are reported in the units of the
//! problem (e.g. the cost f of eq. (8)), not in a solver's internal scaling.

use std::cell::RefCell;

/// Receives the iterations reported on this thread inside [`observe`]: step number and
/// `(name, value)` pairs.
pub type Observer = Box<dyn FnMut(u64, &[(&str, f64)])>;

thread_local! {
    static OBSERVER: RefCell<Option<Observer>> = const { RefCell::new(None) };
}

/// Reports one iteration of a solver to the observer of this thread, if any. Cheap when there
/// is none. A report made from inside the observer itself is dropped.
pub fn iteration(step: u64, values: &[(&str, f64)]) {
    OBSERVER.with(|cell| {
        if let Ok(mut slot) = cell.try_borrow_mut()
            && let Some(observer) = slot.as_mut()
        {
            observer(step, values);
        }
    });
}

/// Whether this thread has an observer: lets a solver skip computing values only reported.
pub fn observed() -> bool {
    OBSERVER.with(|cell| cell.try_borrow().is_ok_and(|slot| slot.is_some()))
}

/// Runs `body` with `observer` receiving the iterations reported on this thread; the previous
/// observer (if any) is restored afterwards, also when `body` unwinds.
pub fn observe<T>(observer: Observer, body: impl FnOnce() -> T) -> T {
    struct Restore(Option<Observer>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            OBSERVER.with(|cell| {
                if let Ok(mut slot) = cell.try_borrow_mut() {
                    *slot = previous;
                }
            });
        }
    }
    let previous = OBSERVER.with(|cell| match cell.try_borrow_mut() {
        Ok(mut slot) => slot.replace(observer),
        // Called from inside an observer: leave that one in place.
        Err(_) => None,
    });
    let _restore = Restore(previous);
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
    fn nested_observers_are_restored() {
        let outer = Arc::new(Mutex::new(0u32));
        let inner = Arc::new(Mutex::new(0u32));
        let (o, i) = (outer.clone(), inner.clone());
        observe(Box::new(move |_, _| *o.lock().unwrap() += 1), || {
            iteration(0, &[]);
            observe(Box::new(move |_, _| *i.lock().unwrap() += 1), || {
                iteration(0, &[]);
            });
            iteration(1, &[]);
        });
        assert_eq!((*outer.lock().unwrap(), *inner.lock().unwrap()), (2, 1));
    }
}
