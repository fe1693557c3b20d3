//! Interrupts and closed pipes, as the shell tools handle them.
//!
//! - SIGINT, SIGTERM, SIGHUP: a thread of the tool's own receives them, removes the temporary
//!   files being written (the output's hidden `.pgo-*.tmp` beside it, listed by the file layer:
//!   [`crate::io::remove_temporary_files`]), clears the progress line, and ends the tool by the
//!   same signal with its default action, so that the shell sees status 130, 143 or 129 and a
//!   loop in a script stops on Ctrl-C. A signal the tool was started with ignored (SIGHUP under
//!   `nohup`, SIGINT for `cmd &` in a script) stays ignored.
//! - A closed pipe on stdout (`pgo-solve big.g2o | head -1`): Rust ignores SIGPIPE, so the write
//!   fails with EPIPE and the tool exits with status 141 (128 + SIGPIPE, what `cat` or `seq`
//!   report when killed by SIGPIPE), silently: [`BROKEN_PIPE`], in `run_tool`.

/// Exit status on a closed pipe (128 + SIGPIPE), without a message.
pub const BROKEN_PIPE: u8 = 141;

/// Starts the thread that handles SIGINT, SIGTERM and SIGHUP (once per process; nothing on
/// platforms without POSIX signals).
pub fn install() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        use std::sync::Once;
        static INSTALLED: Once = Once::new();
        INSTALLED.call_once(|| {
            let handled = [SIGINT, SIGTERM, SIGHUP]
                .into_iter()
                .filter(|&s| !ignored(s));
            let Ok(mut signals) = signal_hook::iterator::Signals::new(handled) else {
                // Without the handler the default actions stay: the tool still ends, leaving at
                // most one temporary file.
                return;
            };
            let _ = std::thread::Builder::new()
                .name("signals".into())
                .spawn(move || {
                    if let Some(signal) = signals.forever().next() {
                        crate::io::remove_temporary_files();
                        super::progress_bar::clear_after_interrupt();
                        let _ = signal_hook::low_level::emulate_default_handler(signal);
                        // Not reached: the default action of these signals ends the process.
                        std::process::exit(128 + signal);
                    }
                });
        });
    }
}

/// Whether `signal` is ignored now (as inherited from the parent).
#[cfg(unix)]
fn ignored(signal: i32) -> bool {
    // SAFETY: sigaction with a null new action only reads the current one into `old`, a
    // zero-initialized sigaction (a valid value of the plain C struct).
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(signal, std::ptr::null(), &mut old) == 0
            && old.sa_sigaction == libc::SIG_IGN
    }
}
