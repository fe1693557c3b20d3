//! The command-line tools: their flags (clap definitions, also used to generate the man pages) and
//! their entry points. Exit status: 0 success, 1 a negative answer (e.g. not certified), 2 an
//! error in the input or the request (docs/method.md §4).

pub mod certify;
pub mod common;
pub mod convert;
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
    ]
}

/// Exit status for errors in the input or the request.
pub const EXIT_ERROR: u8 = 2;

/// Runs a tool body: prints an error as `pgo-TOOL: message` (input errors already carry
/// `PATH:LINE:COL`) and maps it to exit status 2.
pub fn run_tool(name: &str, body: impl FnOnce() -> crate::Result<ExitCode>) -> ExitCode {
    match body() {
        Ok(code) => code,
        Err(crate::Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::BrokenPipe => {
            // A closed pipe downstream (`| head`) is not an error of ours.
            ExitCode::SUCCESS
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

/// Prints the reader's warnings on stderr.
pub fn print_warnings(warnings: &[crate::error::Warning]) {
    for w in warnings {
        eprintln!("{w}");
    }
}
