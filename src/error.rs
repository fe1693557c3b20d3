//! Typed errors. Every input error carries `PATH:LINE:COL` (docs/method.md §4); tools print them on
//! stderr and exit with status 2. The input errors and warnings are those of the file layer
//! (`pgo-io`), re-exported here.

use thiserror::Error;

pub use pgo_io::error::{Location, ParseError, ParseErrorKind, Warning};

/// Everything the library can fail with.
#[derive(Debug, Error)]
pub enum Error {
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// A request that cannot be carried out (bad combination of flags, unwritable value...).
    #[error("{0}")]
    Invalid(String),
}

impl Error {
    pub fn io(path: impl Into<String>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// What reading or writing a file failed with, variant for variant (same messages).
impl From<pgo_io::Error> for Error {
    fn from(e: pgo_io::Error) -> Self {
        match e {
            pgo_io::Error::Parse(e) => Error::Parse(e),
            pgo_io::Error::Io { path, source } => Error::Io { path, source },
            pgo_io::Error::Invalid(msg) => Error::Invalid(msg),
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
