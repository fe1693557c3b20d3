//! The command-line tools: their flags (clap definitions, also used to generate the man pages) and
//! their entry points. Exit status: 0 success, 1 a negative answer (e.g. not certified), 2 an
//! error in the input or the request (docs/method.md §4), 141 a closed pipe on stdout (silently);
//! SIGINT, SIGTERM and SIGHUP remove the temporary output files and end the tool by the signal
//! (the shell reports 130, 143, 129): [`signals`].

pub mod certify;
pub mod common;
pub mod convert;
pub mod eval;
pub mod memory;
pub mod progress_bar;
pub mod signals;
pub mod simulate;
pub mod solve;
pub mod spectrum;

use std::process::ExitCode;

/// The clap definition of every tool, for man pages and shell completions.
pub fn commands() -> Vec<clap::Command> {
    use clap::CommandFactory;
    vec![
        convert::Args::command(),
        solve::Args::command(),
        spectrum::Args::command(),
        certify::Args::command(),
        simulate::Args::command(),
        eval::Args::command(),
    ]
}

/// Exit status for errors in the input or the request.
pub const EXIT_ERROR: u8 = 2;

/// What every tool's help says after its examples: closed pipes, interrupts, the progress
/// display.
pub const SHARED_HELP: &str = "\
A closed pipe on stdout (| head) ends the tool with exit status 141 (128 + SIGPIPE, as the shell
reports a tool killed by SIGPIPE), without a message. SIGINT, SIGTERM and SIGHUP remove the
temporary file of an output being written and end the tool by the signal (the shell reports 130,
143, 129). Outputs are checked before the work starts (the directory exists and takes a file, the
path is no directory), and written to a temporary file renamed into place when complete.";

/// A tool's `after_help`: its examples, then [`SHARED_HELP`].
pub fn after_help(examples: &str) -> String {
    format!("{examples}\n\n{SHARED_HELP}")
}

/// Runs a tool body: prints an error as `pgo-TOOL: message` (input errors already carry
/// `PATH:LINE:COL`) and maps it to exit status 2; a closed pipe is status 141, silently.
/// Interrupts are handled from here on ([`signals::install`]), the allocator keeps freed
/// blocks for reuse ([`memory::tune`]), and an output's rename leaves the file it replaces to be
/// closed beside ([`close_beside`]).
pub fn run_tool(name: &str, body: impl FnOnce() -> crate::Result<ExitCode>) -> ExitCode {
    memory::tune();
    signals::install();
    crate::io::hand_replaced_files_to(close_beside);
    match body() {
        Ok(code) => code,
        Err(crate::Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::BrokenPipe => {
            // A closed pipe downstream (`| head`) is not an error to print, and not a success:
            // the status a tool killed by SIGPIPE has in the shell.
            ExitCode::from(signals::BROKEN_PIPE)
        }
        // Input errors read `PATH:LINE:COL: error: message`, as compilers print them.
        Err(crate::Error::Parse(e)) => {
            eprintln!("{}: error: {}", e.location, e.kind);
            ExitCode::from(EXIT_ERROR)
        }
        Err(e) => {
            eprintln!("{name}: error: {e}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

/// Closes an output file that a rename replaced ([`crate::io::hand_replaced_files_to`]) on the
/// second core's thread where it runs, which then frees the file's data (0.2 to 0.4 ms on ext4
/// for 130 to 690 KB) while this thread reports and ends the tool; here where it does not.
fn close_beside(replaced: std::fs::File) {
    crate::linalg::parallel::in_background_if_started([
        Box::new(move || drop(replaced)) as Box<dyn FnOnce() + Send>
    ]);
}

/// Prints the reader's warnings on stderr.
pub fn print_warnings(warnings: &[crate::error::Warning]) {
    for w in warnings {
        eprintln!("{w}");
    }
}
