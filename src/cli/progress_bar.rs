//! The progress display on stderr: what the tool is doing (reading, initialization, Newton steps
//! with their cost and gradient norm, the certificate, the staircase's rank, the dual SDP's gap,
//! writing), as one line that updates itself (indicatif) when stderr is a terminal, and nothing
//! when it is not, so that logs, pipes and tests see the same bytes as before. `-q/--quiet`
//! turns it off; `--progress` forces it on a stderr that is not a terminal, as plain lines (one
//! per update), for logs.
//!
//! It watches the library's reports ([`crate::progress`]: iterations and phases) from the cli
//! layer; the library has no terminal code and computes the same numbers watched or not.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::cell::RefCell;
use std::io::{IsTerminal, Write};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The progress flags of the tools that compute (pgo-solve, pgo-certify, pgo-spectrum).
#[derive(Debug, Clone, clap::Args)]
pub struct ProgressArgs {
    /// No progress display (shown on stderr only when stderr is a terminal)
    #[arg(short, long)]
    pub quiet: bool,

    /// Show the progress even when stderr is not a terminal, as plain lines (for logs)
    #[arg(long, conflicts_with = "quiet")]
    pub progress: bool,
}

impl ProgressArgs {
    pub fn start(&self, tool: &'static str) -> Progress {
        Progress::start(tool, self.quiet, self.progress)
    }
}

/// Whether a terminal line of progress is drawn now (cleared by [`clear_after_interrupt`]).
static DRAWN: AtomicBool = AtomicBool::new(false);

/// Erases the progress line of a terminal, for the interrupt handler (the process ends next):
/// one write(2), async-signal-safe, past stderr's lock (which the interrupted code may hold).
pub fn clear_after_interrupt() {
    #[cfg(unix)]
    if DRAWN.load(Ordering::Relaxed) {
        const CLEAR: &[u8] = b"\r\x1b[2K";
        // SAFETY: write(2) reads CLEAR's bytes only.
        let _ = unsafe { libc::write(libc::STDERR_FILENO, CLEAR.as_ptr().cast(), CLEAR.len()) };
    }
}

enum Sink {
    /// Nothing shown.
    Off,
    /// A self-updating line on a terminal.
    Terminal(ProgressBar),
    /// One line per update on a stderr that is not a terminal (`--progress`).
    Lines(&'static str),
}

/// What is shown: the phase and the last iteration's figures.
#[derive(Default)]
struct State {
    phase: String,
    detail: String,
}

/// The progress display of one tool run. Dropping it erases the line.
pub struct Progress {
    sink: Rc<Sink>,
    state: Rc<RefCell<State>>,
}

impl Progress {
    /// A display on stderr: on when stderr is a terminal (or `force`), off when `quiet`.
    pub fn start(tool: &'static str, quiet: bool, force: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let sink = if quiet || !(terminal || force) {
            Sink::Off
        } else if terminal {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr_with_hz(10));
            bar.set_style(
                ProgressStyle::with_template("{spinner} {prefix}: {wide_msg} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            bar.set_prefix(tool);
            bar.enable_steady_tick(Duration::from_millis(100));
            DRAWN.store(true, Ordering::Relaxed);
            Sink::Terminal(bar)
        } else {
            Sink::Lines(tool)
        };
        Progress {
            sink: Rc::new(sink),
            state: Rc::default(),
        }
    }

    /// A display that shows nothing.
    pub fn off() -> Self {
        Progress {
            sink: Rc::new(Sink::Off),
            state: Rc::default(),
        }
    }

    fn is_on(&self) -> bool {
        !matches!(*self.sink, Sink::Off)
    }

    /// Enters a phase ("reading MIT.g2o", "writing out.g2o").
    pub fn phase(&self, name: &str) {
        show_phase(&self.sink, &self.state, name);
    }

    /// Runs `body` with the library's reports of this thread shown.
    pub fn watch<T>(&self, body: impl FnOnce() -> T) -> T {
        if !self.is_on() {
            return body();
        }
        let (sink, state) = (self.sink.clone(), self.state.clone());
        let (phase_sink, phase_state) = (self.sink.clone(), self.state.clone());
        crate::progress::watch(
            Box::new(move |step, values| {
                state.borrow_mut().detail = describe_iteration(step, values);
                show(&sink, &state.borrow());
            }),
            Box::new(move |name| show_phase(&phase_sink, &phase_state, name)),
            body,
        )
    }

    /// Runs `f` (which prints on stderr) with the line erased meanwhile.
    pub fn suspend<T>(&self, f: impl FnOnce() -> T) -> T {
        match &*self.sink {
            Sink::Terminal(bar) => bar.suspend(f),
            _ => f(),
        }
    }

    /// Erases the line, before the tool's own report on stderr.
    pub fn finish(&self) {
        if let Sink::Terminal(bar) = &*self.sink {
            bar.finish_and_clear();
            DRAWN.store(false, Ordering::Relaxed);
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

fn show_phase(sink: &Sink, state: &RefCell<State>, name: &str) {
    {
        let mut s = state.borrow_mut();
        s.phase = name.to_string();
        s.detail.clear();
    }
    show(sink, &state.borrow());
}

fn show(sink: &Sink, state: &State) {
    let message = message(state);
    match sink {
        Sink::Off => {}
        Sink::Terminal(bar) => bar.set_message(message),
        Sink::Lines(tool) => {
            let _ = writeln!(std::io::stderr().lock(), "{tool}: {message}");
        }
    }
}

fn message(state: &State) -> String {
    match (state.phase.is_empty(), state.detail.is_empty()) {
        (_, true) => state.phase.clone(),
        (true, false) => state.detail.clone(),
        (false, false) => format!("{}: {}", state.phase, state.detail),
    }
}

/// One iteration in words: a Newton step of the staircase (cost, gradient norm, rank), an
/// iteration of the dual SDP (duality gap, dual objective), or the reported values as they come.
pub fn describe_iteration(step: u64, values: &[(&str, f64)]) -> String {
    let get = |name: &str| values.iter().find(|(n, _)| *n == name).map(|&(_, v)| v);
    if let (Some(cost), Some(gradient)) = (get("cost"), get("gradient_norm")) {
        let rank = get("rank").map_or(String::new(), |r| format!(", rank {r}"));
        format!("step {step}{rank}: cost {cost:.6e}, gradient {gradient:.2e}")
    } else if let Some(gap) = get("relative_gap") {
        let dual = get("dual_objective").map_or(String::new(), |d| format!(", dual {d:.6e}"));
        format!("iteration {step}: gap {gap:.2e}{dual}")
    } else {
        let figures: Vec<String> = values.iter().map(|(n, v)| format!("{n} {v:.3e}")).collect();
        format!("step {step}: {}", figures.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iterations_are_described_by_what_they_report() {
        assert_eq!(
            describe_iteration(
                7,
                &[
                    ("cost", 52.3456789),
                    ("gradient_norm", 0.000123),
                    ("rank", 2.0),
                    ("damping", 1e-3)
                ]
            ),
            "step 7, rank 2: cost 5.234568e1, gradient 1.23e-4"
        );
        assert_eq!(
            describe_iteration(
                3,
                &[
                    ("primal_objective", 2.0),
                    ("dual_objective", 1.5),
                    ("relative_gap", 0.25),
                    ("mu", 1.0)
                ]
            ),
            "iteration 3: gap 2.50e-1, dual 1.500000e0"
        );
        assert_eq!(
            describe_iteration(1, &[("chi2", 45.0)]),
            "step 1: chi2 4.500e1"
        );
    }

    #[test]
    fn the_message_is_the_phase_and_the_last_iteration() {
        let mut s = State {
            phase: "certificate".into(),
            ..Default::default()
        };
        assert_eq!(message(&s), "certificate");
        s.detail = "step 1".into();
        assert_eq!(message(&s), "certificate: step 1");
    }

    #[test]
    fn off_shows_nothing_and_watches_nothing() {
        let p = Progress::off();
        p.phase("reading");
        p.watch(|| assert!(!crate::progress::observed()));
    }
}
